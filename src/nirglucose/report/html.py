"""The HTML report: one self-contained page from a benchmark results directory.

The page holds the reproduced table (ours, with 95 % confidence intervals, next to the
study's Table 1), the significance statements, the run's configuration, seed, dataset
hash and package version, and every figure with a one-sentence caption. Figures are
embedded as base64 PNG; the style sheet is inline; the page loads nothing from the
network and runs no script. It is written atomically.
"""

from __future__ import annotations

import base64
import datetime as _dt
import html
import json
import math
import re
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from ..exceptions import DataError
from .figures import RenderedFigure, Results, load_results, render_figures

__all__ = ["build_report", "render_html", "markdown_to_html", "REPORT_TITLE"]

#: Title of the page.
REPORT_TITLE = "nirglucose benchmark report"

_CSS = """
:root { --fg: #1b1b1b; --muted: #5a5a5a; --line: #d0d0d0; --accent: #0072B2; }
* { box-sizing: border-box; }
body { font-family: system-ui, -apple-system, "Segoe UI", Roboto, "DejaVu Sans", sans-serif;
       color: var(--fg); margin: 0 auto; max-width: 1280px; padding: 1.5rem 2rem 4rem;
       line-height: 1.45; font-size: 15px; background: #fff; }
h1 { font-size: 1.6rem; margin: 0 0 .3rem; }
h2 { font-size: 1.25rem; margin: 2.2rem 0 .6rem; border-bottom: 1px solid var(--line);
     padding-bottom: .2rem; }
h3 { font-size: 1.05rem; margin: 1.4rem 0 .4rem; }
p.sub { color: var(--muted); margin: 0 0 1rem; }
nav ol { margin: .3rem 0; }
nav ul.figs { columns: 3; padding-left: 1.4rem; list-style: none; }
.side { display: grid; grid-template-columns: repeat(auto-fit, minmax(0, 1fr)); gap: 1rem; }
.side > div { min-width: 0; }
table { border-collapse: collapse; margin: .6rem 0 1rem; font-size: 13px; }
th, td { border: 1px solid var(--line); padding: .25rem .45rem; text-align: right;
         vertical-align: top; }
th { background: #f3f6f9; text-align: center; }
td { white-space: nowrap; }
td:first-child, th:first-child { text-align: left; }
td.study { background: #fafafa; color: var(--muted); }
.scroll { overflow-x: auto; }
figure { margin: 1.2rem 0 2rem; }
figure img { max-width: 100%; height: auto; border: 1px solid #eee; }
.zoom-hint { display: none; color: var(--muted); font-size: .85em; margin: .2rem 0 0; }
@media screen and (max-width: 760px) {
  body { padding: 1rem .8rem 3rem; }
  /* on a phone every figure opens at full size in its own box: scroll it sideways */
  figure .zoom { overflow-x: auto; border: 1px solid #eee; }
  figure .zoom img { max-width: none; width: auto; border: 0; }
  .zoom-hint { display: block; }
}
figcaption { color: var(--fg); margin-top: .35rem; max-width: 70rem; }
figcaption b { color: var(--accent); }
.note { border-left: 4px solid #E69F00; background: #fff8e8; padding: .45rem .8rem;
        margin: .6rem 0; }
dl.meta { display: grid; grid-template-columns: max-content auto; gap: .15rem 1rem; }
dl.meta dt { font-weight: 600; }
dl.meta dd { margin: 0; font-family: ui-monospace, "DejaVu Sans Mono", monospace;
             font-size: 13px; overflow-wrap: anywhere; }
pre { background: #f6f8fa; padding: .7rem; overflow-x: auto; font-size: 12px; }
code { font-family: ui-monospace, "DejaVu Sans Mono", monospace; font-size: .92em; }
details summary { cursor: pointer; color: var(--accent); }
.sig { color: #D55E00; font-weight: 600; }
section#findings ul.findings li { margin: .3rem 0; }
span.v { border-bottom: 1px dotted var(--muted); }
a.ev { font-size: .85em; white-space: nowrap; }
a.mark { text-decoration: none; margin-left: .1em; }
td.untested { color: var(--muted); font-style: italic; text-align: center; }
td.off { color: var(--muted); font-style: italic; }
details.more { margin: -.4rem 0 1rem; }
@media print {
  @page { size: A4; margin: 10mm; }
  body { max-width: none; padding: 0; font-size: 10px; }
  details > * { display: block; }
  details::details-content { content-visibility: visible; display: contents; }
  .scroll { overflow: visible; }
  table { font-size: 7px; width: 100%; }
  th, td { white-space: normal; padding: .1rem .2rem; }
  figure { break-inside: avoid; }
  figure img { max-width: 100%; }
  nav ul.figs { columns: 2; }
}
"""

# (metrics column, ci stem, study column, header, digits)
_TABLE_COLUMNS: tuple[tuple[str, str | None, str | None, str, int], ...] = (
    ("rmse_mgdl", "rmse", "rmse_mgdl", "RMSE [mg/dL]", 1),
    ("mard_pct", "mard", "mard_pct", "MARD [%]", 1),
    ("clarke_a_pct", "clarke_a", "clarke_a_pct", "Clarke A [%]", 1),
    ("within15_pct", "within15", "within15_pct", "±15 % [%]", 1),
    ("n_parameters", None, "n_parameters", "Parameters", 0),
    ("macs_per_prediction", None, None, "MACs / prediction", 0),
    ("latency_single_ms", None, "latency_single_ms", "Latency median [ms]", 3),
    ("latency_single_p90_ms", None, None, "Latency p90 [ms]", 3),
)

_EXTRA_COLUMNS: tuple[tuple[str, str, int], ...] = (
    ("clarke_ab_pct", "Clarke A+B [%]", 1),
    ("parkes_a_pct", "Parkes A [%]", 1),
    ("iso15197_pct", "ISO 15197 [%]", 1),
    ("bias_mgdl", "bias [mg/dL]", 1),
    ("loa_low_mgdl", "LoA low [mg/dL]", 1),
    ("loa_high_mgdl", "LoA high [mg/dL]", 1),
    ("throughput_per_s", "throughput [1/s]", 0),
    ("rmse_vs_oracle", "RMSE / oracle [-]", 2),
    ("n_predictions", "predictions [-]", 0),
)


def _esc(x: Any) -> str:
    return html.escape(str(x), quote=True)


def _num(v: Any, digits: int = 1) -> str:
    try:
        f = float(v)
    except (TypeError, ValueError):
        return "–" if v is None or v == "" else _esc(v)
    if not math.isfinite(f):
        return "–"
    if digits == 0:
        return f"{f:,.0f}"
    if digits == 3:  # latencies span 0.001-100 ms
        return f"{f:.3f}" if abs(f) < 0.1 else f"{f:.2f}" if abs(f) < 10 else f"{f:.1f}"
    return f"{f:,.{digits}f}"


def _pval(v: Any) -> str:
    try:
        f = float(v)
    except (TypeError, ValueError):
        return "–"
    return f"{f:.3g}" if math.isfinite(f) else "–"


def _inline_md(text: str) -> str:
    out = _esc(text)
    out = re.sub(r"`([^`]+)`", r"<code>\1</code>", out)
    out = re.sub(r"\*\*([^*]+)\*\*", r"<b>\1</b>", out)
    return out


def markdown_to_html(text: str, *, skip_tables: bool = False, skip_h1: bool = False) -> str:
    """Render the small Markdown subset the benchmark writes (headings, tables, lists).

    Everything is HTML-escaped first; only headings, pipe tables, ``-`` lists,
    paragraphs, ``code`` and ``**bold**`` are recognised.

    Examples
    --------
    >>> markdown_to_html("# T\\n\\nA `x` <b>\\n\\n- one")
    '<h3>T</h3>\\n<p>A <code>x</code> &lt;b&gt;</p>\\n<ul><li>one</li></ul>'
    """
    blocks: list[str] = []
    lines = text.splitlines()
    i = 0
    while i < len(lines):
        line = lines[i].rstrip()
        if not line.strip():
            i += 1
            continue
        if line.startswith("#"):
            level = len(line) - len(line.lstrip("#"))
            if not (skip_h1 and level == 1):
                h = min(6, level + 2)
                blocks.append(f"<h{h}>{_inline_md(line.lstrip('#').strip())}</h{h}>")
            i += 1
        elif line.lstrip().startswith("|"):
            rows = []
            while i < len(lines) and lines[i].lstrip().startswith("|"):
                rows.append(lines[i].strip().strip("|").split("|"))
                i += 1
            if skip_tables:
                continue
            body = [r for r in rows if not all(re.fullmatch(r"\s*:?-+:?\s*", c) for c in r)]
            if not body:
                continue
            head = "".join(f"<th>{_inline_md(c.strip())}</th>" for c in body[0])
            trs = "".join("<tr>" + "".join(f"<td>{_inline_md(c.strip())}</td>" for c in r)
                          + "</tr>" for r in body[1:])
            blocks.append(f'<div class="scroll"><table><thead><tr>{head}</tr></thead>'
                          f"<tbody>{trs}</tbody></table></div>")
        elif re.match(r"\s*[-*] ", line):
            items = []
            while i < len(lines) and re.match(r"\s*[-*] ", lines[i]):
                item = re.sub(r"^\s*[-*] ", "", lines[i])
                items.append(f"<li>{_inline_md(item)}</li>")
                i += 1
            blocks.append(f"<ul>{''.join(items)}</ul>")
        else:
            para = []
            while (i < len(lines) and lines[i].strip() and not lines[i].startswith("#")
                   and not lines[i].lstrip().startswith("|")
                   and not re.match(r"\s*[-*] ", lines[i])):
                para.append(lines[i].strip())
                i += 1
            blocks.append(f"<p>{_inline_md(' '.join(para))}</p>")
    return "\n".join(blocks)


def _model_label(model: str, metrics_row: pd.Series | None = None) -> str:
    from ..plots.style import model_label

    if metrics_row is not None and isinstance(metrics_row.get("label"), str):
        return metrics_row["label"]
    return model_label(model)


#: Prediction-interval columns shown beside RMSE when the benchmark wrote them
#: (metrics column, ci stem, header, digits).
_INTERVAL_COLUMNS: tuple[tuple[str, str | None, str, int], ...] = (
    ("coverage90_pct", "coverage90", "90 % interval coverage [%]", 1),
    ("width90_mgdl", None, "90 % interval width [mg/dL]", 1),
    ("coverage80_pct", None, "80 % interval coverage [%]", 1),
    ("width80_mgdl", None, "80 % interval width [mg/dL]", 1),
)


def _user_data_md(md: str) -> str:
    """The benchmark's table.md text for a user's data: no preset, no study protocol.

    The benchmark writes one paragraph for every run; on measured data its preset is
    ``None`` and the study it compares against was measured on another device.
    """
    md = re.sub(r",? preset `(None|null)`", "", md)
    return re.sub(r" ?Study: [^.]*?test n = \d+\.", "", md)


def preset_of(results: Results) -> str:
    """The preset name of a run (its directory's name when none is recorded)."""
    p = results.meta.get("preset")
    return str(p) if p not in (None, "", "None") else results.directory.name or "run"


#: Columns of the main table shown without opening the toggle (metrics columns); the
#: study's value is shown beside ours for RMSE only.
_ESSENTIAL: tuple[str, ...] = ("rmse_mgdl", "mard_pct", "clarke_a_pct", "within15_pct",
                               "coverage90_pct", "n_parameters", "macs_per_prediction")


def _table_columns(m: pd.DataFrame) -> list[tuple[str, str | None, str | None, str, int]]:
    base = list(_TABLE_COLUMNS)
    intervals = [c for c in _INTERVAL_COLUMNS if c[0] in m.columns]
    return base[:1] + [(c, stem, None, h, d) for c, stem, h, d in intervals] + base[1:]


def _reproduced_table(results: Results, *, full: bool = True, table_id: str | None = None
                      ) -> str:
    """The main table: every column (``full``) or the essentials (RMSE with the study's)."""
    from ..evaluation.reference import STUDY_TABLE

    with_study = not results.user_data
    study = {str(r["model"]): r for r in STUDY_TABLE} if with_study else {}
    m = results.metrics.drop_duplicates("model").set_index("model")
    columns = _table_columns(m)
    if not full:
        columns = [c for c in columns if c[0] in _ESSENTIAL]
        columns = [(c, stem, scol if c == "rmse_mgdl" else None, h, d)
                   for c, stem, scol, h, d in columns]
    span = 2 if with_study else 1
    mark = _hypo_mark(results)
    head1 = "<th rowspan=2>Model</th>" + "".join(
        f"<th colspan={span if scol else 1}>{_esc(h)}{mark if c in _ZONE_COLUMNS else ''}"
        "</th>" for c, _, scol, h, _ in columns)
    head2 = "".join(f"<th>{'ours [95 % CI]' if stem else 'ours'}</th>"
                    + ("<th>study</th>" if with_study and scol else "")
                    for _, stem, scol, _, _ in columns)
    rows = []
    for model in results.models:
        r = m.loc[model]
        s = study.get(model, {})
        cells = [f"<td>{_esc(_model_label(model, r))}</td>"]
        for col, stem, scol, _, digits in columns:
            ours = _num(r.get(col), digits)
            if stem and f"{stem}_ci_low" in r.index and f"{stem}_ci_high" in r.index:
                lo, hi = r.get(f"{stem}_ci_low"), r.get(f"{stem}_ci_high")
                if _num(lo) != "–":
                    ours += f" [{_num(lo, digits)}, {_num(hi, digits)}]"
            cells.append(f"<td>{ours}</td>")
            if with_study and scol:
                cells.append(f'<td class="study">{_num(s.get(scol), digits) if s else "–"}'
                             "</td>")
        rows.append("<tr>" + "".join(cells) + "</tr>")
    tid = table_id or f"reproduced-table{'-full' if full else ''}-{preset_of(results)}"
    return (f'<div class="scroll"><table id="{_esc(tid)}"><thead><tr>{head1}</tr>'
            f"<tr>{head2}</tr></thead><tbody>{''.join(rows)}</tbody></table></div>")


#: Columns of error-grid shares: their header carries the hypoglycaemia caveat's mark.
_ZONE_COLUMNS: tuple[str, ...] = ("clarke_a_pct", "clarke_ab_pct", "parkes_a_pct",
                                  "iso15197_pct")


def glucose_coverage(results: Results) -> tuple[float, float, int, int] | None:
    """Reference glucose of the run: (min, max, readings, readings below 70 mg/dL).

    Each snapshot counted once (by ``measurement_id`` when recorded); None without
    predictions.
    """
    p = results.predictions
    if p is None or not len(p) or "reference_mgdl" not in p.columns:
        return None
    if "measurement_id" in p.columns:
        p = p.drop_duplicates("measurement_id")
    ref = p["reference_mgdl"].to_numpy(float)
    ref = ref[np.isfinite(ref)]
    if not ref.size:
        return None
    return float(ref.min()), float(ref.max()), int(ref.size), int((ref < 70.0).sum())


def _hypo_id(results: Results) -> str:
    return f"hypo-note-{preset_of(results)}"


def _hypo_mark(results: Results) -> str:
    """The † after an error-grid column's header, linked to :func:`hypo_note`."""
    return (f'<a class="mark" href="#{_esc(_hypo_id(results))}" title="glucose range '
            'caveat">†</a>' if glucose_coverage(results) else "")


def hypo_note(results: Results) -> str:
    """The caveat beside the error-grid columns: what range of glucose they tested."""
    cov = glucose_coverage(results)
    if cov is None:
        return ""
    lo, hi, n, n_hypo = cov
    if n_hypo == 0:
        text = (f"† Error-grid columns (Clarke, Parkes, ISO 15197): no reading of this run "
                f"is below 70 mg/dL (reference glucose {lo:.0f}–{hi:.0f} mg/dL, {n:,} "
                "readings), so these shares say nothing about hypoglycaemia, where an "
                "error matters most.")
    else:
        text = (f"† Error-grid columns (Clarke, Parkes, ISO 15197): {n_hypo:,} of the "
                f"{n:,} readings are below 70 mg/dL (reference glucose {lo:.0f}–{hi:.0f} "
                "mg/dL).")
    return f'<p class="note" id="{_esc(_hypo_id(results))}">{_esc(text)}</p>'


def table_title(results: Results) -> str:
    """The main table's heading: nothing is reproduced on a user's own data."""
    return "Results table" if results.user_data else "Reproduced table"


def main_table(results: Results) -> str:
    """The essentials, then every column behind a toggle (opened in print)."""
    study = "" if results.user_data else "the study's value beside each metric, "
    return (_reproduced_table(results, full=False)
            + f'<details class="more"><summary>Every column: {study}'
            "prediction intervals, latency</summary>"
            + _reproduced_table(results, full=True) + "</details>")


def _extra_table(results: Results) -> str:
    m = results.metrics.drop_duplicates("model").set_index("model")
    cols = [c for c in _EXTRA_COLUMNS if c[0] in m.columns]
    if not cols:
        return ""
    mark = _hypo_mark(results)
    head = "<th>Model</th>" + "".join(
        f"<th>{_esc(h)}{mark if c in _ZONE_COLUMNS else ''}</th>" for c, h, _ in cols)
    rows = []
    for model in results.models:
        r = m.loc[model]
        rows.append(f"<tr><td>{_esc(_model_label(model, r))}</td>" + "".join(
            f"<td>{_num(r.get(c), d)}</td>" for c, _, d in cols) + "</tr>")
    return (f'<div class="scroll"><table id="extra-table-{_esc(preset_of(results))}">'
            f"<thead><tr>{head}</tr></thead>"
            f"<tbody>{''.join(rows)}</tbody></table></div>")


def _significance(results: Results) -> str:
    parts = []
    if results.table_md:
        from .presets import strip_ablation

        md = strip_ablation(results.table_md)
        if results.user_data:
            md = _user_data_md(md)
        parts.append(markdown_to_html(md, skip_tables=True, skip_h1=True))
    c = results.comparisons
    if c is not None and len(c):
        if not results.table_md:
            lines = []
            for _, r in c.iterrows():
                sig = bool(r.get("significant")) if pd.notna(r.get("significant")) else False
                lines.append(
                    f"<li>{_esc(_model_label(str(r['model'])))} vs "
                    f"{_esc(_model_label(str(r['reference_model'])))}: RMSE difference "
                    f"{_num(r.get('rmse_diff_mgdl'))} mg/dL [{_num(r.get('ci_low'))}, "
                    f"{_num(r.get('ci_high'))}], p (Holm) = {_pval(r.get('p_holm'))}: "
                    + ('<span class="sig">significant</span>' if sig else "not significant")
                    + "</li>")
            parts.append(f"<ul>{''.join(lines)}</ul>")
        cols = [k for k in ("family", "model", "reference_model", "rmse_diff_mgdl", "ci_low",
                            "ci_high", "p_value", "p_holm", "significant") if k in c.columns]
        names = {"family": "family", "model": "model", "reference_model": "against",
                 "rmse_diff_mgdl": "Δ RMSE [mg/dL]", "ci_low": "95 % CI low",
                 "ci_high": "95 % CI high", "p_value": "p", "p_holm": "p (Holm)",
                 "significant": "significant"}
        head = "".join(f"<th>{_esc(names.get(k, k))}</th>" for k in cols)

        def cell(k: str, v: Any) -> str:
            if k.startswith("p_"):
                return _pval(v)
            if k in ("rmse_diff_mgdl", "ci_low", "ci_high"):
                return _num(v)
            if k in ("model", "reference_model"):
                return _esc(_model_label(str(v)))
            return _esc(v)

        body = "".join("<tr>" + "".join(f"<td>{cell(k, r[k])}</td>" for k in cols) + "</tr>"
                       for _, r in c.iterrows())
        parts.append(f"<details><summary>All paired comparisons (comparisons.csv, "
                     f"{len(c)} rows)</summary><div class=\"scroll\">"
                     f"<table id=\"comparisons-{_esc(preset_of(results))}\">"
                     f"<thead><tr>{head}</tr></thead><tbody>{body}</tbody></table></div>"
                     f"</details>")
    if not parts:
        parts.append('<p class="note">No significance statements: neither table.md nor '
                     "comparisons.csv is in the results directory.</p>")
    return (f'<div id="study-orderings-{_esc(preset_of(results))}">' + "\n".join(parts)
            + "</div>")


def _machine_text(machine: Any) -> str | None:
    """``timing_machine`` of ``meta.json`` in one line (None when not recorded)."""
    if not isinstance(machine, dict):
        return None
    cores = machine.get("cores")
    usable = machine.get("cores_usable")
    core_txt = f"{cores} logical cores" + (f" ({usable} usable)" if usable not in (None, cores)
                                           else "")
    return (f"{machine.get('cpu', '?')}, {core_txt}; Python {machine.get('python', '?')}, "
            f"NumPy {machine.get('numpy', '?')}, PyTorch {machine.get('torch', '?')}")


def _run_info(results: Results) -> str:
    from .. import __version__

    meta = results.meta
    ds = results.dataset
    dataset_hash = meta.get("dataset_hash") or meta.get("dataset_sha256")
    if not dataset_hash and ds is not None:
        dataset_hash = f"{ds.content_hash()} (computed from dataset.parquet)"
    items = [
        ("protocol", meta.get("protocol")),
        ("seed", meta.get("seed")),
        ("preset", meta.get("preset")),
        ("dataset hash", dataset_hash),
        ("dataset seed", meta.get("dataset_seed", getattr(ds, "seed", None))),
        ("subjects / snapshots",
         f"{meta['n_subjects']} / {meta['n_snapshots']}" if "n_subjects" in meta
         and "n_snapshots" in meta else None),
        ("folds × repeats",
         f"{meta['n_splits']} × {meta['repeats']}" if "n_splits" in meta and "repeats" in meta
         else None),
        ("package version (benchmark)", meta.get("version") or meta.get("package_version")),
        ("package version (report)", __version__),
        ("confidence intervals", meta.get("ci_method")),
        ("comparisons", meta.get("comparison_method")),
        ("timing", meta.get("timing_method")),
        ("timing machine", _machine_text(meta.get("timing_machine"))),
        ("results directory", str(results.directory)),
    ]
    dl = "".join(f"<dt>{_esc(k)}</dt><dd>{_esc(v)}</dd>" for k, v in items
                 if v is not None and v != "")
    out = [f'<dl class="meta" id="run-info">{dl}</dl>']
    cfg = results.config
    if cfg is not None:
        cfg_json = json.dumps(cfg.model_dump(mode="json"), indent=2, sort_keys=True)
        out.append(f"<details><summary>Resolved configuration (JSON)</summary>"
                   f'<pre id="config">{_esc(cfg_json)}</pre></details>')
    else:
        out.append('<p class="note">' + (
            "Your data were measured, not simulated: there is no simulator configuration."
            if results.user_data else
            "The resolved configuration is not recorded in these results.") + "</p>")
    rest = {k: v for k, v in meta.items() if k != "config"}
    if rest:
        out.append(f"<details><summary>All run metadata (JSON)</summary>"
                   f"<pre>{_esc(json.dumps(rest, indent=2, sort_keys=True, default=str))}"
                   f"</pre></details>")
    return "\n".join(out)


def _figure_html(f: RenderedFigure) -> str:
    anchor = f"fig-{_esc(f.key)}"
    cap = f"<b>Figure {_esc(f.number)}. {_esc(f.title)}.</b> {_esc(f.caption)}"
    note = f'<p class="note">{_esc(f.note)}</p>' if f.note else ""
    if not f.png:
        return f'<figure id="{anchor}">{note}<figcaption>{cap}</figcaption></figure>'
    data = base64.b64encode(f.png).decode("ascii")
    return (f'<figure id="{anchor}"><div class="zoom"><img src="data:image/png;base64,{data}" '
            f'alt="Figure {_esc(f.number)}: {_esc(f.title)}. {_esc(f.caption)}"></div>'
            f'<p class="zoom-hint">Full size: scroll the figure sideways.</p>{note}'
            f"<figcaption>{cap}</figcaption></figure>")


#: Contents entries of optional sections: (element id, title).
_OPTIONAL_CONTENTS = (("findings", "Findings"), ("fig-headline", "Headline figure"),
                      ("distance-table", "Distance from no skill and the oracle"))
_MIDDLE_CONTENTS = (("presets", "Presets compared"), ("presets-table", "Key metrics by preset"),
                    ("separation", "What separates the presets"),
                    ("ablations", "Physics ablation"), ("subgroups", "Subgroups"),
                    ("hyperparameters", "Hyper-parameters"))


def _contents(figures: Sequence[RenderedFigure], top: Sequence[str], middle: Sequence[str],
              extra: Sequence[str], table: str = "Reproduced table") -> str:
    """The contents list: every section present on the page, and every figure."""
    def have(sections: Sequence[str], anchor: str) -> bool:
        return any(f'id="{anchor}"' in x for x in sections)

    items = [(a, t) for a, t in _OPTIONAL_CONTENTS if have(top, a)]
    items += [("table", table), ("further", "Further metrics"),
              ("significance", "Significance")]
    items += [(a, t) for a, t in _MIDDLE_CONTENTS if have(middle, a)]
    if not have(middle, "ablations"):  # one preset: its own ablation heading
        items += [(m.group(1), "Physics ablation") for x in middle
                  for m in re.finditer(r'<h3 id="(ablation-[^"]+)"', x)]
    items += [("run", "Configuration and provenance"), ("figures", "Figures")]
    items += [(m.group(1), html.unescape(m.group(2))) for x in extra
              for m in re.finditer(r'<h2 id="([^"]+)">([^<]+)</h2>', x)]
    toc = "".join(f'<li><a href="#{_esc(a)}">{_esc(t)}</a></li>' for a, t in items)
    toc_figs = "".join(f'<li><a href="#fig-{_esc(f.key)}">Figure {_esc(f.number)}: '
                       f"{_esc(f.title)}</a></li>" for f in figures)
    return f'<nav><b>Contents</b><ol>{toc}</ol><ul class="figs">{toc_figs}</ul></nav>'


def _latency_note(results: Results, peers: Sequence[Results] = ()) -> str:
    """How far the latencies can be trusted (shown under the main table)."""
    from .figures.inputs import latency_resolution

    res = latency_resolution(results.metrics, [p.metrics for p in peers])
    return f'<p class="note" id="latency-note">{_esc(res["text"])}</p>' if res else ""


def render_html(results: Results, figures: Sequence[RenderedFigure], *,
                title: str = REPORT_TITLE, extra_sections: Sequence[str] = (),
                middle_sections: Sequence[str] = (), top_sections: Sequence[str] = (),
                peers: Sequence[Results] = ()) -> str:
    """The report page as a string (no I/O).

    Parameters
    ----------
    results : Results
        Loaded results (:func:`nirglucose.report.figures.load_results`).
    figures : sequence of RenderedFigure
        Rendered figures (:func:`nirglucose.report.figures.render_figures`).
    title : str
        Page title.
    extra_sections, middle_sections, top_sections : sequence of str
        HTML added after the figures / after the significance section / before the
        table (the findings).
    peers : sequence of Results
        The other presets' runs of the same benchmark (their timings measure the noise
        of the latencies).

    Returns
    -------
    str
        A complete, self-contained HTML document.
    """
    meta = results.meta
    sub = ", ".join(p for p in (
        f"preset {meta['preset']}" if meta.get("preset") not in (None, "", "None")
        else "your data",
        f"seed {meta['seed']}" if meta.get("seed") is not None else "",
        f"protocol {meta['protocol']}" if meta.get("protocol") else "",
        f"{len(results.models)} models",
        f"generated {_dt.datetime.now(_dt.UTC).strftime('%Y-%m-%d %H:%M UTC')}",
    ) if p)
    notes = "".join(f'<p class="note">{_esc(n)}</p>' for n in results.notes)
    sections = [
        f"<h1>{_esc(title)}</h1>",
        f'<p class="sub">{_esc(sub)}</p>',
        notes,
        _contents(figures, top_sections, middle_sections, extra_sections,
                  table_title(results)),
        *top_sections,
        f'<h2 id="table">{table_title(results)}</h2>',
        ("<p>This run's metrics with 95 % confidence intervals on your data. The study's "
         "Table 1 is left out: it was measured on other data.</p>" if results.user_data else
         "<p>This run's metrics with 95 % confidence intervals next to the study's Table 1 "
         "(single 60/20/20 split by subject, test n = 48; no intervals reported).</p>"),
        main_table(results),
        hypo_note(results),
        _latency_note(results, peers),
        '<h3 id="further">Further metrics</h3>',
        _extra_table(results),
        '<h2 id="significance">Significance</h2>',
        _significance(results),
        *middle_sections,
        '<h2 id="run">Configuration and provenance</h2>',
        _run_info(results),
        '<h2 id="figures">Figures</h2>',
        *(_figure_html(f) for f in figures),
        *extra_sections,
    ]
    body = "\n".join(s for s in sections if s)
    return (
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
        "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n"
        "<meta http-equiv=\"Content-Security-Policy\" content=\"default-src 'none'; "
        "img-src data:; style-src 'unsafe-inline'\">\n"
        "<link rel=\"icon\" href=\"data:,\">\n"
        f"<title>{_esc(title)}</title>\n<style>{_CSS}</style>\n</head>\n<body>\n{body}\n"
        "</body>\n</html>\n"
    )


def build_report(results_dir: str | Path, out_path: str | Path, *,
                 figures_dir: str | Path | None = None,
                 sweep_dirs: Sequence[str | Path] = ()) -> Path:
    """Build the HTML report of a benchmark results directory.

    Parameters
    ----------
    results_dir : str or path
        Directory written by ``nirglucose benchmark --out``; one written with several
        presets (``results_dir/<preset>/``) gives one report: the ``paper`` run in
        full, then the presets compared (:mod:`~nirglucose.report.presets`).
    out_path : str or path
        The HTML file to write (atomically); its directory must exist.
    figures_dir : str or path, optional
        Also write every figure there as PNG and SVG.
    sweep_dirs : sequence of str or path, optional
        Directories written by ``nirglucose sweep``; each adds a section with its
        degradation curves or ablation effects.

    Returns
    -------
    pathlib.Path
        ``out_path``.

    Raises
    ------
    DataError
        If the results directory is missing or incomplete, or the output directory
        does not exist.

    Examples
    --------
    >>> build_report("results/", "results/report.html")  # doctest: +SKIP
    PosixPath('results/report.html')
    """
    from ..dataset import atomic_write

    out_path = Path(out_path)
    if not out_path.parent.exists():
        raise DataError(f"output directory {str(out_path.parent)!r} does not exist; "
                        "create it first")
    from .presets import ablation_section, preset_dirs, presets_section

    dirs = preset_dirs(results_dir)
    primary = dirs[0] if dirs else Path(results_dir)
    runs = [load_results(d) for d in dirs] if dirs else [load_results(primary)]
    results = runs[0]
    compare = None
    if len(runs) > 1:  # every preset on the performance panel's shared axes
        compare = {str(r.meta.get("preset") or r.directory.name): r.metrics for r in runs}
    figures = render_figures(results, figures_dir, compare=compare, peers=runs[1:])
    from .findings import findings_section
    from .sweep import sweep_section

    # several presets: the ablations are shown side by side in the presets section
    middle = ([presets_section(runs)] if len(runs) > 1 else
              [ablation_section(primary, preset=preset_of(results))])
    from .subgroups import subgroup_tables, subgroups_section

    groups = subgroup_tables(runs)
    middle.append(subgroups_section(runs, groups))
    from .params import hyperparameter_section

    middle.append(hyperparameter_section(runs))
    from .inverse import inverse_section  # lazy, as subgroups: it imports html
    middle.append(inverse_section(runs))
    top = [] if results.user_data else [findings_section(runs, subgroups=groups)]
    page = render_html(results, figures, extra_sections=[sweep_section(d) for d in sweep_dirs],
                       middle_sections=middle, top_sections=top, peers=runs[1:])
    path = atomic_write(out_path, lambda tmp: Path(tmp).write_text(page, encoding="utf-8"))
    path.chmod(0o644)  # the temporary file was private; a report is for reading
    return path
