"""The subgroups section: error by diabetes status and by Fitzpatrick type, per preset.

The numbers are computed by :mod:`nirglucose.evaluation.benchmark.subgroups` (cluster bootstrap
over each subgroup's subjects); this module only renders them.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING

import pandas as pd

from ..evaluation.benchmark.subgroups import SUBGROUP_COLUMNS, SUBGROUP_LABELS, subgroup_errors
from ..formatting import MISSING, format_ci
from .figures.inputs import competitors
from .markup import esc as _esc
from .markup import model_label as _model_label
from .markup import preset_of

if TYPE_CHECKING:
    from .figures import Results

__all__ = ["subgroup_tables", "subgroups_section"]


def subgroup_tables(runs: Sequence[Results], *, n_boot: int = 2000) -> dict[str, pd.DataFrame]:
    """Each preset's :func:`~nirglucose.evaluation.benchmark.subgroups.subgroup_errors`, all
    groupings.

    Competitors only (no oracle, no-skill or ablation rows); a run without its dataset
    (or without the grouping columns) has no entry.
    """
    out = {}
    for res in runs:
        ds = res.dataset
        if ds is None or "subject_id" not in res.predictions.columns:
            continue
        frame = ds.frame
        models = [m for m in competitors(res.models) if m in set(res.predictions["model"])]
        parts = [subgroup_errors(res.predictions, frame, by, models, n_boot=n_boot)
                 for by in SUBGROUP_COLUMNS if by in frame.columns]
        parts = [p for p in parts if len(p)]
        if parts:
            out[preset_of(res)] = pd.concat(parts, ignore_index=True)
    return out


def _table(t: pd.DataFrame, by: str, preset: str, order: list[str]) -> str:
    part = t[t["by"] == by]
    groups = sorted(set(part["group"]), key=lambda g: (len(g), g))
    n = part.drop_duplicates("group").set_index("group")["n_subjects"]
    what = "type " if by == "fitzpatrick_type" else ""
    head = "<th>Model</th>" + "".join(
        f"<th>{_esc(what + g)} ({int(n[g])} subj.)</th>" for g in groups)
    rows = []
    for m in [m for m in order if m in set(part["model"])]:
        r = part[part["model"] == m].set_index("group")
        cells = "".join(
            f"<td>{format_ci(*r.loc[g, ['rmse_mgdl', 'rmse_ci_low', 'rmse_ci_high']])}</td>"
            if g in r.index else f"<td>{MISSING}</td>"
            for g in groups)
        rows.append(f"<tr><td>{_esc(_model_label(m))}</td>{cells}</tr>")
    return (f"<h4>RMSE [mg/dL, 95 % CI] by {_esc(SUBGROUP_LABELS[by])} on "
            f"<code>{_esc(preset)}</code></h4>"
            f'<div class="scroll"><table id="subgroups-{_esc(preset)}-{_esc(by)}">'
            f"<thead><tr>{head}</tr></thead><tbody>{''.join(rows)}</tbody></table></div>")


def subgroups_section(runs: Sequence[Results], tables: Mapping[str, pd.DataFrame]) -> str:
    """HTML of the subgroups section ("" when no run has its dataset)."""
    if not tables:
        return ""
    parts = ['<h2 id="subgroups">Subgroups</h2><p>Each competitor\'s RMSE within each '
             "diabetes status and each Fitzpatrick skin type, computed like the table's "
             "(per repeat, averaged over repeats) on that subgroup's subjects, with a 95 % "
             "percentile cluster bootstrap over those subjects (2,000 resamples). Small "
             "subgroups give wide intervals; overlapping intervals do not show equality, "
             "only that this run cannot tell the subgroups apart.</p>"]
    for res in runs:
        p = preset_of(res)
        if p not in tables:
            continue
        t = tables[p]
        order = (res.metrics.sort_values("rmse_mgdl")["model"].astype(str).tolist())
        inner = "".join(_table(t, by, p, order) for by in SUBGROUP_COLUMNS
                        if (t["by"] == by).any())
        parts.append(f'<div id="subgroups-{_esc(p)}"><h3>On <code>{_esc(p)}</code></h3>'
                     f"{inner}</div>")
    return "\n".join(parts)
