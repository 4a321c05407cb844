"""The cohorts section of a report on a team's own data: each group's error against the
group's own training mean (:mod:`nirglucose.evaluation.cohorts` computes it from the
benchmark's predictions and ``dataset.parquet``; this module renders it), in the unit
of the file's reference column."""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

from ..dataset.files import glucose_to_unit
from ..evaluation.cohorts import cohort_errors, detect_group_column, offset_message
from ..models.registry import privileged_knowledge
from .figures.inputs import competitors
from .markup import esc as _esc
from .markup import model_label as _model_label
from .markup import preset_of

if TYPE_CHECKING:
    from .figures import Results

__all__ = ["cohorts_section"]


def _deployable(names: Sequence[str]) -> list[str]:
    out = []
    for n in names:
        try:
            if privileged_knowledge(n) is not None:
                continue
        except (KeyError, ValueError, TypeError):
            pass
        out.append(n)
    return out


def _group_column(res: Results) -> str | None:
    ds = res.dataset
    if ds is None or not res.user_data or "fold" not in res.predictions.columns:
        return None
    frame = ds.frame
    declared = ds.metadata.get("group_by")
    if declared is not None and declared not in frame.columns:
        return None
    return detect_group_column(frame, declared)


def cohorts_section(runs: Sequence[Results]) -> str:
    """HTML of the cohorts section ("" when no run on a user's file has a grouping
    column)."""
    parts = []
    for res in runs:
        gcol = _group_column(res)
        if gcol is None:
            continue
        models = [m for m in _deployable(competitors(res.models))
                  if m in set(res.predictions["model"])]
        t = cohort_errors(res.predictions, res.dataset.frame, gcol, models)
        if not len(t):
            continue
        unit = res.dataset.metadata.get("glucose_unit") or "mg/dL"
        d = 2 if unit == "mmol/L" else 1

        def g(v: float, unit: str = unit, d: int = d) -> str:
            return f"{float(glucose_to_unit(v, unit)):.{d}f}"

        order = res.metrics.sort_values("rmse_mgdl")["model"].astype(str).tolist()
        rows = []
        for m in [m for m in order if m in set(t["model"])]:
            for _, r in t[t["model"] == m].iterrows():
                rows.append(f"<tr><td>{_esc(_model_label(m))}</td><td>{_esc(r['group'])}</td>"
                            f"<td>{r['n_subjects']}</td><td>{g(r['rmse_mgdl'])}</td>"
                            f"<td>{g(r['no_skill_own_mgdl'])}</td>"
                            f"<td>{g(r['no_skill_pooled_mgdl'])}</td></tr>")
        best = next(m for m in order if m in set(t["model"]))
        tb = t[t["model"] == best]
        msg = offset_message(gcol, float(tb["offset_share"].iloc[0]), tb)
        warn = (f'<p class="note"><b>{_esc(_model_label(best))}</b>: {_esc(msg)}.</p>'
                if msg else "")
        p = preset_of(res)
        parts.append(
            f'<div id="cohorts-{_esc(p)}"><p>Grouping column <code>{_esc(gcol)}</code>. '
            f"RMSE [{_esc(unit)}] of each competitor inside each group, beside no skill "
            "against that group's own training mean and against the pooled one: a model "
            "that beats the pooled mean but not the group's own has learnt the offset "
            f"between the groups, not glucose.</p>{warn}"
            f'<div class="scroll"><table id="cohorts-table-{_esc(p)}"><thead><tr>'
            f"<th>Model</th><th>{_esc(gcol)}</th><th>subjects</th><th>RMSE</th>"
            "<th>no skill (own mean)</th><th>no skill (pooled mean)</th></tr></thead>"
            f"<tbody>{''.join(rows)}</tbody></table></div></div>")
    if not parts:
        return ""
    return '<h2 id="cohorts">Cohorts against their own mean</h2>' + "\n".join(parts)
