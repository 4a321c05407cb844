"""Error by subgroup (diabetes status, Fitzpatrick skin type), with subject-bootstrap CIs.

An optical sensor has to show that it does not fail darker skin, and a glucose sensor
that it does not fail the people who need it most. Each subgroup's metrics are computed
like the benchmark's (per repeat, averaged over repeats) on the snapshots of that
subgroup's subjects, with a percentile cluster bootstrap that resamples *those*
subjects (:func:`~nirglucose.metrics.resampling.cluster_bootstrap_metrics`).

A subgroup holds whole subjects: the grouping columns are traits of the subject
(one diabetes status and one skin type per subject); a subject whose snapshots disagree
is assigned its most frequent value.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Final

import numpy as np
import pandas as pd

from ...exceptions import DataError
from ...metrics.resampling import DEFAULT_N_BOOT, cluster_bootstrap_metrics
from .findings import Finding, Value, label

__all__ = ["SUBGROUP_COLUMNS", "SUBGROUP_LABELS", "subgroup_errors", "subject_groups",
           "subgroup_findings"]

#: Dataset columns that define subgroups, and how the report names them.
SUBGROUP_COLUMNS: Final = ("diabetes_status", "fitzpatrick_type")
SUBGROUP_LABELS: Final = {"diabetes_status": "diabetes status",
                          "fitzpatrick_type": "Fitzpatrick skin type"}


def subject_groups(frame: pd.DataFrame, by: str) -> pd.Series:
    """Each subject's group (its most frequent value of ``by``), indexed by subject id.

    Examples
    --------
    >>> f = pd.DataFrame({"subject_id": [0, 0, 1], "fitzpatrick_type": [2, 2, 5]})
    >>> subject_groups(f, "fitzpatrick_type").to_dict()
    {0: '2', 1: '5'}
    """
    if by not in frame.columns or "subject_id" not in frame.columns:
        raise DataError(f"the dataset has no {by!r} or subject_id column")
    g = frame[["subject_id", by]].dropna()
    return g.groupby("subject_id")[by].agg(lambda s: str(s.mode().iloc[0]))


def subgroup_errors(predictions: pd.DataFrame, frame: pd.DataFrame, by: str,
                    models: Sequence[str], *, n_boot: int = DEFAULT_N_BOOT, seed: int = 0,
                    level: float = 0.95) -> pd.DataFrame:
    """RMSE, MARD and bias of each model in each subgroup, with cluster-bootstrap CIs.

    Parameters
    ----------
    predictions : pandas.DataFrame
        The benchmark's predictions (``model``, ``subject_id``, ``reference_mgdl``,
        ``scored_mgdl`` or ``predicted_mgdl``, optionally ``repeat``).
    frame : pandas.DataFrame
        The dataset (``subject_id`` and ``by``).
    by : str
        Grouping column, one of :data:`SUBGROUP_COLUMNS` (any subject-level column works).
    models : sequence of str
        Models to score.
    n_boot, seed : int
        Resamples and seed of each interval. [-]
    level : float
        Confidence level. [-]

    Returns
    -------
    pandas.DataFrame
        One row per (model, group): ``model``, ``by``, ``group``, ``n_subjects``,
        ``n_snapshots``, ``rmse_mgdl``, ``rmse_ci_low``, ``rmse_ci_high``, ``mard_pct``,
        ``bias_mgdl``, ``bias_ci_low``, ``bias_ci_high``.
    """
    groups = subject_groups(frame, by)
    col = "scored_mgdl" if "scored_mgdl" in predictions.columns else "predicted_mgdl"
    p = predictions.assign(_group=predictions["subject_id"].map(groups))
    rows = []
    for model in models:
        pm = p[(p["model"] == model) & p["_group"].notna()]
        for g, part in pm.groupby("_group", sort=True):
            if part["subject_id"].nunique() < 2:
                continue  # no interval from one subject
            ci = cluster_bootstrap_metrics(
                part["reference_mgdl"].to_numpy(float),
                np.maximum(part[col].to_numpy(float), 0.0), part["subject_id"].to_numpy(),
                part["repeat"].to_numpy() if "repeat" in part.columns else None,
                n_boot=n_boot, seed=seed, level=level)
            n_snap = (part["measurement_id"].nunique() if "measurement_id" in part.columns
                      else len(part))
            rows.append({"model": model, "by": by, "group": str(g),
                         "n_subjects": int(part["subject_id"].nunique()),
                         "n_snapshots": int(n_snap),
                         **{k: ci[k] for k in ("rmse_mgdl", "rmse_ci_low", "rmse_ci_high",
                                               "mard_pct", "bias_mgdl", "bias_ci_low",
                                               "bias_ci_high")}})
    return pd.DataFrame(rows)


def subgroup_findings(preset: str, best: str | None, table: pd.DataFrame) -> list:
    """Findings on the subgroups of one preset: the best model's spread per grouping.

    ``table`` is the concatenation of :func:`subgroup_errors` over
    :data:`SUBGROUP_COLUMNS`; the sources name ``<preset>/subgroups`` (this module's
    computation from the predictions and the dataset) with the model, grouping and group.
    """
    if best is None or not len(table):
        return []
    out = []
    for by in SUBGROUP_COLUMNS:
        t = table[(table["model"] == best) & (table["by"] == by)]
        if len(t) < 2:
            continue
        lo, hi = t.loc[t["rmse_mgdl"].idxmin()], t.loc[t["rmse_mgdl"].idxmax()]

        def v(row: pd.Series, col: str, digits: int = 1, by: str = by) -> Value:
            return Value(float(row[col]), digits,
                         (f"{preset}/subgroups:{best}:{by}={row['group']}:{col}",))

        small = t.loc[t["n_subjects"].idxmin()]
        vals = (v(lo, "rmse_mgdl"), v(lo, "rmse_ci_low"), v(lo, "rmse_ci_high"),
                v(lo, "n_subjects", 0), v(hi, "rmse_mgdl"), v(hi, "rmse_ci_low"),
                v(hi, "rmse_ci_high"), v(hi, "n_subjects", 0), v(small, "n_subjects", 0))
        what = "type " if by == "fitzpatrick_type" else ""
        text = (f"On {preset}, {label(best)}'s RMSE by {SUBGROUP_LABELS[by]} ranges from {{}} "
                f"mg/dL [95 % CI {{}}, {{}}] ({what}{lo['group']}, {{}} subjects) to {{}} mg/dL "
                f"[{{}}, {{}}] ({what}{hi['group']}, {{}} subjects)"
                + ("; the intervals overlap, so no subgroup is shown to fare worse"
                   if float(lo["rmse_ci_high"]) >= float(hi["rmse_ci_low"]) else
                   f"; the intervals do not overlap (a screen, not a test: unadjusted for "
                   f"the {len(t)} subgroups compared)")
                + " (the smallest subgroup has {} subjects).")
        out.append(Finding("subgroups", preset, text, vals, f"subgroups-{preset}"))
    return out
