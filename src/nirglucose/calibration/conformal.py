"""Subject-grouped conformal prediction intervals for every estimator.

A prediction interval here answers: for a **new person**, how far from the reading can
their glucose be, at a stated coverage? Readings of one person are not exchangeable
with each other's errors across people (a person's offset is shared by all their
readings), so every calibration set is chosen **by subject** and the conformal quantile
is taken over subjects, each subject weighing the same.

Two ways, both model-agnostic (any estimator with ``fit``/``predict``):

:func:`split_conformal`
    Split conformal (Papadopoulos et al. 2002; Lei et al. 2018, J. Am. Stat. Assoc.
    113:1094): a share of the *subjects* is held out, the model is fitted on the rest,
    and the absolute residuals of the held-out subjects give one half-width per level:
    the interval is ``prediction ± q`` (constant width, so an exported C model can
    return it). ``nirglucose fit`` uses this; the calibration travels in the model file
    (:func:`attach` / :func:`calibration_of`).
:func:`out_of_fold_intervals`
    Used by the benchmark, at no extra fit: under grouped K-fold CV the held-out
    residuals of the *other* folds of the same repeat calibrate each test fold (under
    ``paper-split``: the residuals of the validation subjects). Every calibration
    residual is out-of-sample for the model that made it, but comes from a different
    fit than the test fold's model, so the finite-sample guarantee of split conformal
    does not strictly hold (as with CV+, Barber et al. 2021, Ann. Stat. 49:486); the
    benchmark therefore *measures* coverage on held-out subjects instead of assuming it.

Why not MAPIE or crepes: both wrap scikit-learn ``fit(X, y)`` estimators and refit
them per fold (MAPIE's ``CrossConformalRegressor(cv=GroupKFold)``); the benchmark
already has the grouped out-of-fold predictions of every model and must not multiply
the network fits, and the exported C needs one constant half-width. The grouped
quantile below is a few lines and weighs subjects, not readings, equally.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pandas as pd

from ..dataset import Dataset
from ..exceptions import ConfigError, DataError
from ..metrics.resampling import repeat_subject_cells, resampled_ratios, subject_draws
from ..models._validate import check_calibration_doc

__all__ = [
    "LEVELS",
    "DEFAULT_CALIBRATION_SHARE",
    "grouped_conformal_quantile",
    "calibration_subjects",
    "split_conformal",
    "attach",
    "calibration_of",
    "interval",
    "out_of_fold_intervals",
    "coverage_summary",
    "check_calibration_doc",  # defined in models._validate (model files read it)
]

#: Nominal coverages reported everywhere (90 % and 80 %).
LEVELS = (0.9, 0.8)
#: Share of subjects held out to calibrate a split-conformal model (as the study's
#: 20 % validation part, PAPER_FRACTIONS in splits.py).
DEFAULT_CALIBRATION_SHARE = 0.2

_CAL_STREAM = 0xC0F0  # separates the calibration-subject draw from other uses of the seed


def _level_key(level: float) -> str:
    return f"{round(100 * level)}"


def grouped_conformal_quantile(
    abs_residuals_mgdl: np.ndarray, groups: np.ndarray, level: float
) -> float:
    """Conformal half-width at ``level`` with every subject weighing the same.

    Each reading of subject *s* gets weight ``1 / (n_subjects * n_s)``; the half-width
    is the smallest residual whose weighted cumulative share reaches
    ``ceil((n + 1) level) / n`` with ``n`` subjects, the finite-sample correction of
    split conformal (Lei et al. 2018, J. Am. Stat. Assoc. 113:1094, Thm 2.1) counted in
    subjects, the exchangeable unit.

    Parameters
    ----------
    abs_residuals_mgdl : numpy.ndarray
        Absolute calibration residuals [mg/dL].
    groups : numpy.ndarray
        Subject of each residual.
    level : float
        Nominal coverage in (0, 1).

    Returns
    -------
    float
        Half-width [mg/dL]; ``inf`` when too few subjects calibrate this level.
    """
    r = np.asarray(abs_residuals_mgdl, dtype=float).ravel()
    g = np.asarray(groups).ravel()
    if len(r) != len(g) or len(r) == 0:
        raise DataError("conformal calibration needs one subject per residual and >= 1 residual")
    if not 0.0 < level < 1.0:
        raise ConfigError(f"coverage level must lie in (0, 1), got {level!r}")
    if not np.all(np.isfinite(r)):
        raise DataError("conformal calibration residuals must be finite")
    _, inv, counts = np.unique(g, return_inverse=True, return_counts=True)
    n = len(counts)
    target = math.ceil((n + 1) * level) / n
    if target > 1.0:
        return math.inf
    w = 1.0 / (n * counts[inv])
    order = np.argsort(r, kind="stable")
    cum = np.cumsum(w[order])
    k = int(np.searchsorted(cum, target - 1e-12, side="left"))
    return float(r[order][min(k, len(r) - 1)])


def calibration_subjects(subjects: np.ndarray, share: float, seed: int) -> np.ndarray:
    """Boolean mask of the rows whose subject calibrates (a seeded draw of subjects)."""
    if not 0.0 < share < 1.0:
        raise ConfigError(f"calibration share must lie in (0, 1), got {share!r}")
    subjects = np.asarray(subjects)
    uniq = np.unique(subjects)
    n_cal = int(round(share * len(uniq)))
    if n_cal < 1 or n_cal >= len(uniq):
        raise DataError(
            f"{len(uniq)} subjects cannot be split into a fitting and a calibration part "
            f"(share {share}); give more subjects"
        )
    rng = np.random.default_rng(np.random.SeedSequence([int(seed), _CAL_STREAM]))
    cal = rng.choice(uniq, size=n_cal, replace=False)
    return np.isin(subjects, cal)


def _frame_of(data) -> pd.DataFrame:
    frame = getattr(data, "frame", data)
    if not isinstance(frame, pd.DataFrame):
        raise DataError("conformal calibration needs a Dataset or DataFrame with subject_id")
    for col in ("subject_id", "glucose_mgdl"):
        if col not in frame.columns:
            raise DataError(f"conformal calibration needs a {col!r} column")
    return frame


def _subset(data, mask: np.ndarray):
    if isinstance(data, Dataset):
        return data.rows(mask)
    return _frame_of(data).loc[mask].reset_index(drop=True)


def _first_reading_residuals(frame: pd.DataFrame, resid: np.ndarray) -> tuple:
    """Residual minus the subject's first residual, for the later readings (offset k=1)."""
    order = _reading_order(frame)
    sid = frame["subject_id"].to_numpy()[order]
    r = resid[order]
    first = ~pd.Series(sid).duplicated().to_numpy()
    base = pd.Series(np.where(first, r, np.nan)).groupby(sid).transform("max").to_numpy()
    later = ~first
    return np.abs(r[later] - base[later]), sid[later]


def _reading_order(frame: pd.DataFrame) -> np.ndarray:
    """Row order by subject, then by reading (``measurement_id`` when present)."""
    keys = ["subject_id"] + (["measurement_id"] if "measurement_id" in frame.columns else [])
    return frame.reset_index(drop=True).sort_values(keys, kind="stable").index.to_numpy()


def split_conformal(
    model,
    data,
    *,
    share: float = DEFAULT_CALIBRATION_SHARE,
    seed: int = 0,
    levels: tuple[float, ...] = LEVELS,
):
    """Fit ``model`` on most subjects and calibrate its intervals on the rest.

    Parameters
    ----------
    model : estimator
        An unfitted nirglucose estimator.
    data : Dataset or pandas.DataFrame
        Measurements with ``subject_id`` and ``glucose_mgdl``.
    share : float
        Share of the subjects held out to calibrate (never used for fitting).
    seed : int
        Seed of the draw of calibration subjects.
    levels : tuple of float
        Nominal coverages.

    Returns
    -------
    estimator
        ``model``, fitted on the other subjects, carrying ``conformal_`` (:func:`attach`).
    """
    frame = _frame_of(data)
    cal = calibration_subjects(frame["subject_id"].to_numpy(), share, seed)
    model.fit(_subset(data, ~cal))
    cal_data = _subset(data, cal)
    cal_frame = _frame_of(cal_data)
    pred = np.asarray(model.predict(cal_data), dtype=float).ravel()
    if not np.all(np.isfinite(pred)):
        raise DataError("the model predicts non-finite glucose on the calibration subjects")
    resid = cal_frame["glucose_mgdl"].to_numpy(float) - pred
    sid = cal_frame["subject_id"].to_numpy()
    half = {_level_key(a): grouped_conformal_quantile(np.abs(resid), sid, a) for a in levels}
    d_abs, d_sid = _first_reading_residuals(cal_frame, resid)
    half_cal = {
        _level_key(a): (grouped_conformal_quantile(d_abs, d_sid, a) if len(d_abs) else math.inf)
        for a in levels
    }
    bad = [k for k, v in half.items() if not math.isfinite(v)]
    if bad:
        raise DataError(
            f"{len(np.unique(sid))} calibration subjects are too few for a {bad[0]} % "
            "interval; give more subjects or a larger calibration share"
        )
    return attach(
        model,
        {
            "method": "split",
            "grouping": "subject",
            "levels_pct": [round(100 * a) for a in levels],
            "half_width_mgdl": half,
            "half_width_offset1_mgdl": {
                k: (v if math.isfinite(v) else None) for k, v in half_cal.items()
            },
            "n_calibration_subjects": int(len(np.unique(sid))),
            "n_calibration_readings": int(len(sid)),
            "calibration_share": float(share),
            "seed": int(seed),
        },
    )


def attach(model, calibration: dict[str, Any]):
    """Store a calibration on a fitted model as ``conformal_`` (saved with it)."""
    model.conformal_ = check_calibration_doc(calibration, "calibration")
    return model


def calibration_of(model) -> dict[str, Any] | None:
    """The model's conformal calibration, or None."""
    return getattr(model, "conformal_", None)


def interval(
    model, predicted_mgdl, level: float = 0.9, *, offset_calibrated: bool = False
) -> tuple[np.ndarray, np.ndarray]:
    """``(lower, upper)`` [mg/dL] around predictions of a calibrated model.

    ``offset_calibrated`` uses the half-width of readings corrected by a person's
    one-point offset (their later readings minus their first), when stored.
    """
    cal = calibration_of(model)
    if cal is None:
        raise DataError("this model carries no conformal calibration; refit it with intervals")
    key = _level_key(level)
    table = cal.get("half_width_offset1_mgdl" if offset_calibrated else "half_width_mgdl") or {}
    q = table.get(key)
    if q is None:
        raise DataError(f"this model's calibration has no {key} % interval")
    p = np.asarray(predicted_mgdl, dtype=float)
    return p - q, p + q


# --------------------------------------------------------------------------- benchmark
def out_of_fold_intervals(
    predictions: pd.DataFrame,
    calibration: pd.DataFrame | None = None,
    levels: tuple[float, ...] = LEVELS,
) -> pd.DataFrame:
    """Half-widths for every held-out prediction of the benchmark, at no extra fit.

    Parameters
    ----------
    predictions : pandas.DataFrame
        ``model, subject_id, repeat, fold, reference_mgdl, scored_mgdl``.
    calibration : pandas.DataFrame, optional
        Extra calibration residuals by ``model, repeat, fold, subject_id,
        reference_mgdl, scored_mgdl`` (the validation subjects of ``paper-split``);
        when given, they calibrate their own fold instead of the other folds.
    levels : tuple of float
        Nominal coverages.

    Returns
    -------
    pandas.DataFrame
        ``predictions`` with ``half<L>_mgdl`` per level (NaN where nothing calibrates).
    """
    out = predictions.copy()
    resid = (out["reference_mgdl"] - out["scored_mgdl"]).abs().to_numpy()
    for a in levels:
        out[f"half{_level_key(a)}_mgdl"] = np.nan
    for (_model, _rep), g in out.groupby(["model", "repeat"], sort=False):
        for fold in g["fold"].unique():
            test = g.index[g["fold"] == fold]
            if calibration is not None and len(calibration):
                c = calibration[
                    (calibration["model"] == _model)
                    & (calibration["repeat"] == _rep)
                    & (calibration["fold"] == fold)
                ]
                r = (c["reference_mgdl"] - c["scored_mgdl"]).abs().to_numpy()
                s = c["subject_id"].to_numpy()
            else:
                other = g.index[g["fold"] != fold]
                r = resid[out.index.get_indexer(other)]
                s = out.loc[other, "subject_id"].to_numpy()
            if len(r) == 0:
                continue
            for a in levels:
                q = grouped_conformal_quantile(r, s, a)
                out.loc[test, f"half{_level_key(a)}_mgdl"] = q if math.isfinite(q) else np.nan
    return out


def coverage_summary(
    p: pd.DataFrame, level: float, *, n_boot: int = 1000, seed: int = 0, ci: float = 0.95
) -> dict[str, float]:
    """Coverage [%] with a cluster-bootstrap CI over subjects, and mean width [mg/dL].

    Coverage is computed per repeat and averaged; the CI resamples subjects (the same
    ones in every repeat), as the benchmark's other intervals.
    """
    key = _level_key(level)
    half = p[f"half{key}_mgdl"].to_numpy(float)
    ok = np.isfinite(half)
    if not ok.any():
        return {"coverage": np.nan, "ci_low": np.nan, "ci_high": np.nan, "width": np.nan}
    q = p.loc[ok]
    err = (q["reference_mgdl"] - q["scored_mgdl"]).abs().to_numpy()
    hit = (err <= half[ok]).astype(float)
    sid = q["subject_id"].to_numpy()
    rep = q["repeat"].to_numpy()
    subjects, s_idx = np.unique(sid, return_inverse=True)
    reps, r_idx = np.unique(rep, return_inverse=True)
    hits, cnt = repeat_subject_cells(hit, r_idx, s_idx, (len(reps), len(subjects)))
    point = float(np.mean(hits.sum(1) / cnt.sum(1)))
    draws = subject_draws(len(subjects), n_boot, (seed, _CAL_STREAM, 1))
    boot = np.mean(resampled_ratios(hits, cnt, draws), axis=0)
    lo, hi = np.quantile(boot, [(1 - ci) / 2, (1 + ci) / 2])
    return {
        "coverage": 100 * point,
        "ci_low": 100 * float(lo),
        "ci_high": 100 * float(hi),
        "width": float(np.mean(2 * half[ok])),
    }
