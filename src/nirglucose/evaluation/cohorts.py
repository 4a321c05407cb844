"""Cohorts judged against their own mean: does a model's skill survive inside each group?

A file that pools groups whose glucose differs (people with and without diabetes, two
sites, two devices, two visits) lets a model look skilled by learning the offset
between the groups alone: against the *pooled* training mean (no skill) every group's
error falls, although inside each group the model may do no better than predicting
that group's own mean. This module scores each group against its own training mean
and says when the pooled skill is mostly between-group offset.

The decomposition is the law of total variance (the between-group part of the mean
squared error of the pooled mean, e.g. Snedecor & Cochran, *Statistical Methods*, 8th
ed., 1989, ch. 13): the pooled no-skill MSE minus the own-group no-skill MSE is what
knowing the group alone removes. Its share of the model's MSE reduction is
:func:`offset_share`; above :data:`OFFSET_SHARE_LIMIT` the pooled skill is "mostly"
offset.

Examples
--------
>>> import numpy as np
>>> y = np.array([100.0, 110.0, 200.0, 210.0])
>>> pred = np.array([104.0, 106.0, 204.0, 206.0])  # the group offset, nothing more
>>> pooled = np.full(4, 155.0)
>>> own = np.array([105.0, 105.0, 205.0, 205.0])
>>> round(offset_share(y, pred, pooled, own), 3)
0.996
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence

import numpy as np
import pandas as pd

__all__ = [
    "GROUP_COLUMN_NAMES",
    "OFFSET_SHARE_LIMIT",
    "detect_group_column",
    "own_group_baseline",
    "offset_share",
    "group_skill_table",
    "offset_message",
    "carrier_channel",
    "cohort_errors",
]

#: Column names read as a grouping of subjects (case-folded): cohorts, sites, devices,
#: visits and diabetes status. A column is a grouping only when it has 2 to
#: :data:`_MAX_GROUPS` distinct values.
GROUP_COLUMN_NAMES = ("cohort", "group", "site", "study_arm", "arm", "device", "device_id",
                      "visit", "diabetes_status", "diabetic", "diabetes", "diabetes_type")
#: Most distinct values a detected grouping column may have (more is an identifier or
#: a measurement, not a cohort). [-]
_MAX_GROUPS = 10
#: Share of a model's pooled MSE reduction above which it is called mostly
#: between-group offset: more than half of the skill is what the group alone gives. [-]
OFFSET_SHARE_LIMIT = 0.5


def detect_group_column(frame: pd.DataFrame, declared: str | None = None) -> str | None:
    """The grouping column of ``frame``: ``declared`` (checked), else the first column
    named in :data:`GROUP_COLUMN_NAMES` with 2 to 10 distinct values, else None.

    Raises
    ------
    ValueError
        ``declared`` is not a column of ``frame`` (the columns are listed).

    Examples
    --------
    >>> detect_group_column(pd.DataFrame({"Site": ["a", "b"], "adc_940": [1, 2]}))
    'Site'
    """
    if declared is not None:
        if declared not in frame.columns:
            cols = ", ".join(repr(str(c)) for c in list(frame.columns)[:12])
            raise ValueError(f"group column {declared!r} is not in the file; columns: {cols}")
        return declared
    for c in frame.columns:
        if str(c).strip().casefold() in GROUP_COLUMN_NAMES:
            n = frame[c].nunique(dropna=True)
            if 2 <= n <= _MAX_GROUPS:
                return c
    return None


def own_group_baseline(y: np.ndarray, groups: np.ndarray,
                       splits: Iterable[tuple[np.ndarray, np.ndarray]]) -> np.ndarray:
    """Per row, the mean of ``y`` over the *training* rows of the same group in the split
    that tested it (the pooled training mean where the training rows hold none of its
    group).

    Parameters
    ----------
    y : numpy.ndarray
        Reference glucose. [mg/dL]
    groups : numpy.ndarray
        Each row's group label.
    splits : iterable of (train index, test index)
        Disjoint test sets covering the rows scored (rows never tested stay NaN).

    Returns
    -------
    numpy.ndarray
        The own-group no-skill prediction. [mg/dL]
    """
    y = np.asarray(y, dtype=float)
    groups = np.asarray(groups, dtype=object).astype(str)
    out = np.full(len(y), np.nan)
    for tr, te in splits:
        pooled = float(y[tr].mean())
        for g in np.unique(groups[te]):
            in_tr = tr[groups[tr] == g]
            out[te[groups[te] == g]] = float(y[in_tr].mean()) if len(in_tr) else pooled
    return out


def _mse(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.mean((np.asarray(a, float) - np.asarray(b, float)) ** 2))


def offset_share(y: np.ndarray, pred: np.ndarray, pooled_base: np.ndarray,
                 group_base: np.ndarray) -> float:
    """The share of the model's MSE reduction over the pooled mean that the own-group
    means alone achieve (law of total variance): ``(MSE(pooled) - MSE(own group)) /
    (MSE(pooled) - MSE(model))``; NaN when the model has no pooled skill. [-]"""
    gain = _mse(y, pooled_base) - _mse(y, pred)
    if not gain > 0:
        return float("nan")
    return (_mse(y, pooled_base) - _mse(y, group_base)) / gain


def group_skill_table(y: np.ndarray, pred: np.ndarray, pooled_base: np.ndarray,
                      group_base: np.ndarray, groups: np.ndarray,
                      subjects: np.ndarray | None = None) -> pd.DataFrame:
    """Per group: readings, subjects, the model's RMSE, and no skill against the pooled
    training mean and against the group's own training mean. [mg/dL]

    Returns
    -------
    pandas.DataFrame
        ``group``, ``n_readings``, ``n_subjects``, ``rmse_mgdl``,
        ``no_skill_pooled_mgdl``, ``no_skill_own_mgdl``, ``beats_own_mean``.
    """
    groups = np.asarray(groups, dtype=object).astype(str)
    rows = []
    for g in sorted(np.unique(groups)):
        m = groups == g
        rmse = float(np.sqrt(_mse(y[m], pred[m])))
        own = float(np.sqrt(_mse(y[m], group_base[m])))
        rows.append({
            "group": g, "n_readings": int(m.sum()),
            "n_subjects": int(len(np.unique(subjects[m]))) if subjects is not None
            else int(m.sum()),
            "rmse_mgdl": rmse,
            "no_skill_pooled_mgdl": float(np.sqrt(_mse(y[m], pooled_base[m]))),
            "no_skill_own_mgdl": own,
            "beats_own_mean": bool(rmse < own),
        })
    return pd.DataFrame(rows)


def offset_message(column: str, share: float, table: pd.DataFrame) -> str | None:
    """One line when the pooled skill is mostly between-group offset (``share`` above
    :data:`OFFSET_SHARE_LIMIT`), else None."""
    if not np.isfinite(share) or share <= OFFSET_SHARE_LIMIT:
        return None
    worse = table.loc[~table["beats_own_mean"], "group"].astype(str).tolist()
    inside = (f"; inside {column} {', '.join(worse)} it does no better than that group's own "
              "mean" if worse else "")
    alone = ("predict better than the model does" if share >= 1 else
             f"give {share:.0%} of the model's error reduction over the pooled mean")
    return (f"the pooled skill is mostly the offset between {column} groups: their own "
            f"training means alone {alone}{inside}")


def carrier_channel(frame: pd.DataFrame, y: np.ndarray, channels: Sequence[str]) -> str:
    """The channel whose pooled correlation with ``y`` is strongest in magnitude (the one
    that carries the pooled skill; the first on ties or when none varies)."""
    best, best_r = channels[0], -1.0
    for c in channels:
        v = frame[c].to_numpy(float)
        r = abs(float(np.corrcoef(v, y)[0, 1])) if np.std(v) and np.std(y) else -1.0
        if np.isfinite(r) and r > best_r:
            best, best_r = c, r
    return best


def _subject_group(frame: pd.DataFrame, column: str) -> pd.Series:
    """Each subject's group (its most frequent value), indexed by subject id."""
    g = frame[["subject_id", column]].dropna()
    return g.groupby("subject_id")[column].agg(lambda s: str(s.mode().iloc[0]))


def cohort_errors(predictions: pd.DataFrame, frame: pd.DataFrame, column: str,
                  models: Sequence[str]) -> pd.DataFrame:
    """Each model's error in each group of ``column`` beside no skill against the pooled
    training mean and against the group's own training mean, from a benchmark's
    predictions (``model``, ``subject_id``, ``repeat``, ``fold``, ``reference_mgdl``,
    ``predicted_mgdl``) and its dataset (``subject_id``, ``glucose_mgdl``, ``column``).

    The training rows of a (repeat, fold) are the dataset's rows whose subjects it does
    not test. Repeats are pooled (each scores every subject once under grouped CV).

    Returns
    -------
    pandas.DataFrame
        One row per (model, group): ``model``, ``by``, ``group``, ``n_subjects``,
        ``n_readings``, ``rmse_mgdl``, ``no_skill_pooled_mgdl``, ``no_skill_own_mgdl``,
        ``beats_own_mean``, and the model's :func:`offset_share` (``offset_share``).
    """
    groups = _subject_group(frame, column)
    sid = frame["subject_id"].to_numpy()
    y_all = frame["glucose_mgdl"].to_numpy(float)
    g_all = frame["subject_id"].map(groups).astype(str).to_numpy()
    p = predictions[predictions["model"].isin(list(models))].copy()
    p["_group"] = p["subject_id"].map(groups).astype(str)
    p["_pooled"] = np.nan
    p["_own"] = np.nan
    keys = ["repeat", "fold"] if "repeat" in p.columns else ["fold"]
    for _, part in p.groupby(keys, sort=False):
        train = ~np.isin(sid, part["subject_id"].unique())
        pooled = float(y_all[train].mean())
        p.loc[part.index, "_pooled"] = pooled
        own = {g: float(y_all[train & (g_all == g)].mean())
               for g in part["_group"].unique() if (train & (g_all == g)).any()}
        p.loc[part.index, "_own"] = part["_group"].map(own).fillna(pooled).to_numpy()
    rows = []
    for model, pm in p.groupby("model", sort=False):
        y, pred = pm["reference_mgdl"].to_numpy(float), pm["predicted_mgdl"].to_numpy(float)
        pooled, own = pm["_pooled"].to_numpy(float), pm["_own"].to_numpy(float)
        share = offset_share(y, pred, pooled, own)
        t = group_skill_table(y, pred, pooled, own, pm["_group"].to_numpy(),
                              pm["subject_id"].to_numpy())
        rows.append(t.assign(model=model, by=column, offset_share=share))
    cols = ["model", "by", "group", "n_subjects", "n_readings", "rmse_mgdl",
            "no_skill_pooled_mgdl", "no_skill_own_mgdl", "beats_own_mean", "offset_share"]
    return (pd.concat(rows, ignore_index=True)[cols] if rows
            else pd.DataFrame(columns=cols))
