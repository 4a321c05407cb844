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
import re
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from .._version import __version__
from ..dataset import atomic_write
from ..exceptions import DataError
from .cohorts import cohorts_section
from .figures import RenderedFigure, Results, load_results, render_figures
from .figures.inputs import latency_resolution
from .findings import computed_findings, findings_section
from .inverse import inverse_section
from .limits import limits_section
from .markup import esc as _esc
from .markup import markdown_to_html, preset_of
from .params import hyperparameter_section
from .presets import ablation_section, preset_dirs, presets_section
from .subgroups import subgroup_tables, subgroups_section
from .sweep import sweep_section
from .tables import extra_table as _extra_table
from .tables import glucose_coverage, hypo_note, main_table, table_title
from .tables import significance as _significance

__all__ = ["build_report", "render_html", "markdown_to_html", "REPORT_TITLE", "glucose_coverage",
           "FIGURE_SLOTS", "figure_slot"]

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
section#limits .limits { display: grid; gap: .6rem;
  grid-template-columns: repeat(auto-fit, minmax(18rem, 1fr)); }
section#limits .limit { border: 1px solid var(--line); border-left: 4px solid #E69F00;
  background: #fffaf0; padding: .3rem .7rem; font-size: 13px; }
section#limits .limit h3 { margin: .2rem 0; font-size: .98rem; }
section#limits .limit ul { margin: .2rem 0; padding-left: 1.1rem; }
section#limits ul.answer li { margin: .25rem 0; }
tr.ref td { color: var(--muted); font-style: italic; }
tr.ref-head td { background: #f3f3f3; color: var(--muted); text-align: left; }
h2.figs { font-size: 1.1rem; }
@media print {
  /* raw JSON is for the screen: on paper it is pages of braces */
  details.json, pre { display: none !important; }
  @page { size: A4; margin: 10mm; }
  body { max-width: none; padding: 0; font-size: 10px; }
  details > * { display: block; }
  details::details-content { content-visibility: visible; display: contents; }
  .scroll { overflow: visible; }
  table { font-size: 7px; width: 100%; }
  th, td { white-space: normal; padding: .1rem .2rem; }
  figure { break-inside: avoid; }
  figure img { max-width: 100%; }
  nav ul.figs, nav details.figlist { display: none; }
}
"""

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
        out.append(f'<details class="json"><summary>Resolved configuration (JSON)</summary>'
                   f'<pre id="config">{_esc(cfg_json)}</pre></details>')
    else:
        out.append('<p class="note">' + (
            "Your data were measured, not simulated: there is no simulator configuration."
            if results.user_data else
            "The resolved configuration is not recorded in these results.") + "</p>")
    rest = {k: v for k, v in meta.items() if k != "config"}
    if rest:
        out.append(f'<details class="json"><summary>All run metadata (JSON)</summary>'
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


#: Where each figure sits: beside the text that cites it. Slot -> (heading, figure keys
#: without their preset suffix). Figures are numbered in this order
#: (:mod:`nirglucose.report.figures.sections`).
FIGURE_SLOTS: dict[str, tuple[str, tuple[str, ...]]] = {
    "leds": ("Figures: what each LED adds", ("wavelengths",)),
    "accuracy": ("Figures: accuracy and agreement", (
        "forest", "performance", "scatter", "bland_altman", "residuals", "fold_spread")),
    "physics": ("Figures: the networks and their physics terms", (
        "training", "physics_weight", "architecture")),
    "tradeoffs": ("Figures: accuracy against physics depth and cost", (
        "radar", "physics_depth", "efficiency")),
    "data": ("Figures: the data and how it was made", (
        "data", "environment", "physiology", "pipeline", "features")),
}


def figure_slot(key: str) -> str:
    """The slot of a figure key (``"other"`` when none claims it).

    >>> figure_slot("forest_wearable"), figure_slot("physics_depth"), figure_slot("x")
    ('accuracy', 'tradeoffs', 'other')
    """
    for slot, (_, keys) in FIGURE_SLOTS.items():
        if any(key == k or key.startswith(k + "_") for k in keys):
            return slot
    return "other"


def _slot_html(slot: str, figures: Sequence[RenderedFigure]) -> str:
    """One slot's heading and figures ("" when it has none)."""
    figs = [f for f in figures if figure_slot(f.key) == slot]
    if not figs:
        return ""
    title = FIGURE_SLOTS[slot][0] if slot in FIGURE_SLOTS else "Figures: other"
    return (f'<h2 class="figs" id="figs-{slot}">{_esc(title)}</h2>\n'
            + "\n".join(_figure_html(f) for f in figs))


#: Contents entries of optional sections: (element id, title).
_OPTIONAL_CONTENTS = (("limits", "What these results rest on"), ("answer", "Does physics help?"),
                      ("findings", "Findings"), ("fig-headline", "Headline figure"),
                      ("distance-table", "Distance from no skill and the oracle"),
                      ("figs-leds", "Figures: what each LED adds"))
_MIDDLE_CONTENTS = (("presets", "Presets compared"), ("presets-table", "Key metrics by preset"),
                    ("separation", "What separates the presets"),
                    ("ablations", "Physics ablation"),
                    ("figs-physics", "Figures: the networks and their physics terms"),
                    ("figs-tradeoffs", "Figures: accuracy against physics depth and cost"),
                    ("subgroups", "Subgroups"),
                    ("cohorts", "Cohorts against their own mean"),
                    ("hyperparameters", "Hyper-parameters"))


def _contents(figures: Sequence[RenderedFigure], top: Sequence[str], middle: Sequence[str],
              extra: Sequence[str], table: str = "Reproduced table") -> str:
    """The contents list: every section present on the page, and (folded) every figure."""
    def have(sections: Sequence[str], anchor: str) -> bool:
        return any(f'id="{anchor}"' in x for x in sections)

    items = [(a, t) for a, t in _OPTIONAL_CONTENTS if have(top, a)]
    items += [("table", table), ("further", "Further metrics")]
    if have(top, "figs-accuracy"):
        items.append(("figs-accuracy", "Figures: accuracy and agreement"))
    items.append(("significance", "Significance"))
    items += [(a, t) for a, t in _MIDDLE_CONTENTS if have(middle, a)]
    if not have(middle, "ablations"):  # one preset: its own ablation heading
        items += [(m.group(1), "Physics ablation") for x in middle
                  for m in re.finditer(r'<h3 id="(ablation-[^"]+)"', x)]
    items += [("run", "Configuration and provenance")]
    items += [(a, t) for a, t in (("figs-data", "Figures: the data and how it was made"),
                                  ("figs-other", "Figures: other")) if have(extra, a)]
    items += [(m.group(1), html.unescape(m.group(2))) for x in extra
              for m in re.finditer(r'<h2 id="([^"]+)">([^<]+)</h2>', x)]
    toc = "".join(f'<li><a href="#{_esc(a)}">{_esc(t)}</a></li>' for a, t in items)
    toc_figs = "".join(f'<li><a href="#fig-{_esc(f.key)}">Figure {_esc(f.number)}: '
                       f"{_esc(f.title)}</a></li>" for f in figures)
    figs = (f'<details class="figlist"><summary>All {len(figures)} figures</summary>'
            f'<ul class="figs">{toc_figs}</ul></details>') if figures else ""
    return f'<nav><b>Contents</b><ol>{toc}</ol>{figs}</nav>'


def _folds_text(meta: dict[str, Any]) -> str:
    """`` (5 folds × 1 repeat)`` from ``meta.json`` (the run line says a reduced protocol;
    empty when not recorded)."""
    folds, repeats = meta.get("n_splits"), meta.get("repeats")
    if folds is None or repeats is None:
        return ""
    return (f" ({folds} fold{'s' if folds != 1 else ''} × {repeats} "
            f"repeat{'s' if repeats != 1 else ''})")


def _latency_note(results: Results, peers: Sequence[Results] = ()) -> str:
    """How far the latencies can be trusted (shown under the main table)."""
    res = latency_resolution(results.metrics, [p.metrics for p in peers])
    return f'<p class="note" id="latency-note">{_esc(res["text"])}</p>' if res else ""


def render_html(results: Results, figures: Sequence[RenderedFigure], *,
                title: str = REPORT_TITLE, extra_sections: Sequence[str] = (),
                middle_sections: Sequence[str] = (), top_sections: Sequence[str] = (),
                peers: Sequence[Results] = (), limits: str = "") -> str:
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
    limits : str
        The limits box and the one-line answers (:mod:`~nirglucose.report.limits`):
        the first screen, above the contents.

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
        f"protocol {meta['protocol']}{_folds_text(meta)}" if meta.get("protocol") else "",
        f"{len(results.models)} models",
        f"generated {_dt.datetime.now(_dt.UTC).strftime('%Y-%m-%d %H:%M UTC')}",
    ) if p)
    notes = "".join(f'<p class="note">{_esc(n)}</p>' for n in results.notes)
    # each figure beside the text that cites it (FIGURE_SLOTS)
    top = [*top_sections, _slot_html("leds", figures)]
    accuracy = _slot_html("accuracy", figures)
    middle = list(middle_sections)
    physics = [_slot_html("physics", figures), _slot_html("tradeoffs", figures)]
    middle[1:1] = physics  # after the ablation (or the presets compared), before the rest
    tail = [_slot_html("data", figures), _slot_html("other", figures)]
    sections = [
        f"<h1>{_esc(title)}</h1>",
        f'<p class="sub">{_esc(sub)}</p>',
        limits,
        notes,
        _contents(figures, [limits, *top, accuracy], middle, [*tail, *extra_sections],
                  table_title(results)),
        *top,
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
        accuracy,
        '<h2 id="significance">Significance</h2>',
        _significance(results),
        *middle,
        '<h2 id="run">Configuration and provenance</h2>',
        _run_info(results),
        *tail,
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
                 sweep_dirs: Sequence[str | Path] = (), jobs: int = 1) -> Path:
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
    jobs : int
        Processes drawing the figures (:func:`~nirglucose.report.figures.render_figures`);
        the page is the same for any number. [-]

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
    out_path = Path(out_path)
    if not out_path.parent.exists():
        raise DataError(f"output directory {str(out_path.parent)!r} does not exist; "
                        "create it first")
    dirs = preset_dirs(results_dir)
    primary = dirs[0] if dirs else Path(results_dir)
    runs = [load_results(d) for d in dirs] if dirs else [load_results(primary)]
    results = runs[0]
    compare = None
    if len(runs) > 1:  # every preset on the performance panel's shared axes
        compare = {str(r.meta.get("preset") or r.directory.name): r.metrics for r in runs}
    figures = render_figures(results, figures_dir, compare=compare, peers=runs[1:],
                             jobs=jobs)
    # several presets: the ablations are shown side by side in the presets section
    middle = ([presets_section(runs)] if len(runs) > 1 else
              [ablation_section(primary, preset=preset_of(results))])
    groups = subgroup_tables(runs)
    middle.append(subgroups_section(runs, groups))
    middle.append(cohorts_section(runs))
    middle.append(hyperparameter_section(runs))
    middle.append(inverse_section(runs))
    computed = computed_findings(runs)
    if results.user_data:  # the study's numbers were measured on other data
        computed = (computed[0], [f for f in computed[1] if f.topic != "claims"], computed[2])
    top = [findings_section(runs, subgroups=groups, computed=computed)]
    if results.user_data and results.meta.get("significance_withheld"):
        # too few test subjects for any comparison: the limits box says so, no findings
        top, computed = [], (computed[0], [], computed[2])
    limits = limits_section(runs, computed[0], computed[1])
    page = render_html(results, figures, extra_sections=[sweep_section(d) for d in sweep_dirs],
                       middle_sections=middle, top_sections=top, peers=runs[1:],
                       limits=limits)
    path = atomic_write(out_path, lambda tmp: Path(tmp).write_text(page, encoding="utf-8"))
    path.chmod(0o644)  # the temporary file was private; a report is for reading
    return path
