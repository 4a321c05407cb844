"""The benchmark tables of the report page: the reproduced table (ours beside the
study's), further metrics, the hypoglycaemia caveat of the error-grid columns and the
significance statements."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np
import pandas as pd

from ..constants import MGDL_PER_MMOLL_GLUCOSE
from ..evaluation.reference import STUDY_TABLE
from ..formatting import format_number
from ..models.labels import knows, row_privilege
from .markup import esc as _esc
from .markup import markdown_to_html, physics_off_models, preset_of, strip_ablation, user_data_md
from .markup import model_label as _model_label
from .markup import num as _num
from .markup import pval as _pval

if TYPE_CHECKING:
    from .figures import Results

__all__ = ["glucose_coverage", "hypo_note", "table_title", "main_table", "extra_table",
           "significance"]

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


#: Prediction-interval columns shown beside RMSE when the benchmark wrote them
#: (metrics column, ci stem, header, digits).
_INTERVAL_COLUMNS: tuple[tuple[str, str | None, str, int], ...] = (
    ("coverage90_pct", "coverage90", "90 % interval coverage [%]", 1),
    ("width90_mgdl", None, "90 % interval width [mg/dL]", 1),
    ("coverage80_pct", None, "80 % interval coverage [%]", 1),
    ("width80_mgdl", None, "80 % interval width [mg/dL]", 1),
)


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
    per_mgdl = _per_mgdl(results)
    if per_mgdl != 1.0:  # a user's mmol/L file: its glucose columns in mmol/L (issue 43)
        head1 = head1.replace("[mg/dL]", "[mmol/L]")
    off = physics_off_models(results.meta)
    for model in results.models:
        r = m.loc[model]
        s = study.get(model, {})
        cells = [f"<td>{_esc(_model_label(model, r, model in off))}</td>"]
        for col, stem, scol, _, digits in columns:
            f = per_mgdl if col.endswith("_mgdl") else 1.0
            digits = digits + 1 if f != 1.0 else digits

            def val(v, f=f):
                return v * f if isinstance(v, int | float) and f != 1.0 else v

            ours = _num(val(r.get(col)), digits)
            if stem and f"{stem}_ci_low" in r.index and f"{stem}_ci_high" in r.index:
                lo, hi = r.get(f"{stem}_ci_low"), r.get(f"{stem}_ci_high")
                if _num(lo) != "–":
                    ours += f" [{_num(val(lo), digits)}, {_num(val(hi), digits)}]"
            cells.append(f"<td>{ours}</td>")
            if with_study and scol:
                cells.append(f'<td class="study">{_num(s.get(scol), digits) if s else "–"}'
                             "</td>")
        rows.append("<tr>" + "".join(cells) + "</tr>")
    tid = table_id or f"reproduced-table{'-full' if full else ''}-{preset_of(results)}"
    return (f'<div class="scroll"><table id="{_esc(tid)}"><thead><tr>{head1}</tr>'
            f"<tr>{head2}</tr></thead><tbody>{''.join(rows)}</tbody></table></div>")


def _per_mgdl(results: Results) -> float:
    """The factor from mg/dL to the unit of a user's reference column (1 for mg/dL and for
    every simulated run, which is mg/dL)."""
    ds = results.dataset
    if not results.user_data or ds is None or ds.metadata.get("glucose_unit") != "mmol/L":
        return 1.0
    return 1.0 / MGDL_PER_MMOLL_GLUCOSE


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
                f"is below 70 mg/dL (reference glucose {format_number(lo, 0)}–"
                f"{format_number(hi, 0)} mg/dL, {format_number(n, 0, thousands=True)} "
                "readings), so these shares say nothing about hypoglycaemia, where an "
                "error matters most.")
    else:
        text = (f"† Error-grid columns (Clarke, Parkes, ISO 15197): "
                f"{format_number(n_hypo, 0, thousands=True)} of the "
                f"{format_number(n, 0, thousands=True)} readings are below 70 mg/dL (reference "
                f"glucose {format_number(lo, 0)}–{format_number(hi, 0)} mg/dL).")
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


def extra_table(results: Results) -> str:
    m = results.metrics.drop_duplicates("model").set_index("model")
    cols = [c for c in _EXTRA_COLUMNS if c[0] in m.columns]
    if not cols:
        return ""
    mark = _hypo_mark(results)
    head = "<th>Model</th>" + "".join(
        f"<th>{_esc(h)}{mark if c in _ZONE_COLUMNS else ''}</th>" for c, h, _ in cols)
    rows = []
    off = physics_off_models(results.meta)
    for model in results.models:
        r = m.loc[model]
        rows.append(f"<tr><td>{_esc(_model_label(model, r, model in off))}</td>" + "".join(
            f"<td>{_num(r.get(c), d)}</td>" for c, _, d in cols) + "</tr>")
    return (f'<div class="scroll"><table id="extra-table-{_esc(preset_of(results))}">'
            f"<thead><tr>{head}</tr></thead>"
            f"<tbody>{''.join(rows)}</tbody></table></div>")


def significance(results: Results) -> str:
    parts = []
    c = results.comparisons
    if c is not None and len(c) and "family" in c and (c["family"] == "vs_best").any():
        ref = str(c.loc[c["family"] == "vs_best", "reference_model"].iloc[0])
        if row_privilege(ref) is not None or ref == "oracle":
            parts.append(
                '<p class="note">These results were written before the benchmark set '
                f"privileged rows apart: they rank {_esc(_model_label(ref))}, which "
                f"{_esc(knows(row_privilege(ref) or 'the true nuisances'))}, as the best. It is "
                "a reference, not a competitor; the findings above name the best deployable "
                "model. Rerun the benchmark for statements that set it apart.</p>")
    if results.table_md:
        md = strip_ablation(results.table_md)
        if results.user_data:
            md = user_data_md(md)
        parts.append(markdown_to_html(md, skip_tables=True, skip_h1=True))
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
