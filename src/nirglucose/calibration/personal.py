"""Personal calibration: a person's first readings with a fingerstick calibrate the rest.

Every non-invasive glucose device that reached people was calibrated per person. The
protocol here: each *test* subject's first ``k`` readings (by ``measurement_id``), with
their reference glucose, calibrate that person; only their later readings are scored,
for every method on the same readings:

``none``
    The model's prediction, uncalibrated (the baseline on the same later readings).
``offset``
    The model's prediction plus the person's mean calibration error
    ``mean(y_c - f(x_c))`` (a one-point offset in glucose for ``k = 1``).
``carry-forward``
    The calibration glucose itself, carried forward (no sensor at all): what the
    sensor must beat to add anything.
``difference-ridge``
    ``mean(y_c) + g(F(x) - mean F(x_c))``: a ridge ``g`` on within-subject differences
    of the Enhanced Beer–Lambert features ``F`` (the reading minus the person's
    calibration reading), learned on the *training* subjects with their own first
    ``k`` readings as calibration (Hoerl & Kennard 1970, Technometrics 12:55).

Assumption: nothing drifts between the calibration and the later readings (the
simulator's snapshots of a person are independent draws around the same person), so
the protocol cannot show how fast a calibration goes stale.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from ..exceptions import ConfigError, DataError
from ..features import EnhancedBeerLambertFeatures
from ..metrics.resampling import repeat_subject_cells, resampled_ratios, subject_draws

__all__ = [
    "CALIBRATION_COLUMNS",
    "MAX_CALIBRATION_READINGS",
    "calibration_mask",
    "apply_offset",
    "personal_calibration",
]

#: The protocol's calibration readings per person (the issue asks for k = 1 or 2).
MAX_CALIBRATION_READINGS = 2
#: Columns of ``calibration.csv``.
CALIBRATION_COLUMNS = (
    "model",
    "method",
    "k",
    "rmse_mgdl",
    "rmse_ci_low",
    "rmse_ci_high",
    "baseline",
    "gain_mgdl",
    "gain_ci_low",
    "gain_ci_high",
    "n_scored",
)
#: Ridge penalties searched by RidgeCV (a decade grid around the standardised scale).
_ALPHAS = np.logspace(-3, 3, 13)
_BOOT_STREAM = 0xCA1B


def check_k(k) -> int:
    """``k`` if it is 1 or 2 (0: no calibration), else ConfigError."""
    if (
        isinstance(k, bool)
        or not isinstance(k, int | np.integer)
        or not (0 <= k <= MAX_CALIBRATION_READINGS)
    ):
        raise ConfigError(
            f"calibration readings per person must be 0, 1 or {MAX_CALIBRATION_READINGS}, got {k!r}"
        )
    return int(k)


def calibration_mask(frame: pd.DataFrame, k: int) -> np.ndarray:
    """True for each subject's first ``k`` readings (by ``measurement_id``, else row order)."""
    f = frame.reset_index(drop=True)
    if "measurement_id" in f.columns:
        rank = f.groupby("subject_id", sort=False)["measurement_id"].rank(method="first")
    else:
        rank = f.groupby("subject_id", sort=False).cumcount() + 1
    return rank.to_numpy() <= k


def apply_offset(
    predicted_mgdl: np.ndarray,
    subjects: np.ndarray,
    cal_predicted_mgdl: np.ndarray,
    cal_reference_mgdl: np.ndarray,
    cal_subjects: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """Predictions plus their person's mean calibration error.

    Returns
    -------
    tuple of numpy.ndarray
        The corrected predictions [mg/dL] and a boolean mask of those whose person had
        calibration readings (the others are returned unchanged).
    """
    err = pd.Series(np.asarray(cal_reference_mgdl, float) - np.asarray(cal_predicted_mgdl, float))
    offset = err.groupby(np.asarray(cal_subjects)).mean()
    o = pd.Series(np.asarray(subjects)).map(offset).to_numpy(float)
    has = np.isfinite(o)
    out = np.asarray(predicted_mgdl, float) + np.where(has, o, 0.0)
    return out, has


def _pairs(frame: pd.DataFrame, F: np.ndarray, k: int):
    """(ΔF, Δy or None, y_c per row, later mask) of a frame's later readings."""
    cal = calibration_mask(frame, k)
    sid = frame["subject_id"].to_numpy()
    y = frame["glucose_mgdl"].to_numpy(float)
    fc = pd.DataFrame(F[cal]).groupby(sid[cal]).mean()
    yc = pd.Series(y[cal]).groupby(sid[cal]).mean()
    later = ~cal & pd.Series(sid).isin(yc.index).to_numpy()
    base_f = fc.loc[sid[later]].to_numpy()
    base_y = yc.loc[sid[later]].to_numpy()
    return F[later] - base_f, y[later] - base_y, base_y, later


def _difference_ridge(train: pd.DataFrame, test: pd.DataFrame, k: int) -> np.ndarray:
    from sklearn.linear_model import RidgeCV
    from sklearn.pipeline import make_pipeline
    from sklearn.preprocessing import StandardScaler


    feats = EnhancedBeerLambertFeatures().fit(train)
    dF, dy, _, _ = _pairs(train, feats.transform(train), k)
    if len(dy) < 2:
        raise DataError("difference-ridge calibration needs training subjects with > k readings")
    ridge = make_pipeline(StandardScaler(), RidgeCV(alphas=_ALPHAS)).fit(dF, dy)
    dF_t, _, yc_t, later = _pairs(test, feats.transform(test), k)
    out = np.full(len(test), np.nan)
    out[later] = yc_t + ridge.predict(dF_t)
    return out


def _rmse_boot(sq: np.ndarray, cnt: np.ndarray, draws: np.ndarray) -> np.ndarray:
    """Per-repeat RMSE averaged over repeats; sq/cnt (repeats, subjects); draws (B, n)."""
    return np.mean(np.sqrt(resampled_ratios(sq, cnt, draws)), axis=0)


def personal_calibration(
    dataset,
    predictions: pd.DataFrame,
    splits,
    k: int,
    *,
    n_boot: int = 1000,
    seed: int = 0,
) -> pd.DataFrame:
    """Score every model and method on the test subjects' later readings.

    Parameters
    ----------
    dataset : Dataset
        The benchmarked data.
    predictions : pandas.DataFrame
        The benchmark's held-out predictions (``model, subject_id, measurement_id,
        repeat, fold, reference_mgdl, scored_mgdl``).
    splits : sequence of Split
        The benchmark's splits (the difference ridge is fitted on each training part).
    k : int
        Calibration readings per test subject (1 or 2).
    n_boot : int
        Cluster-bootstrap resamples of subjects for the CIs.
    seed : int
        Bootstrap seed.

    Returns
    -------
    pandas.DataFrame
        :data:`CALIBRATION_COLUMNS`; ``gain_mgdl`` is the baseline's RMSE minus this
        row's (positive: calibration helps) on the same readings, paired over subjects.
    """
    k = check_k(k)
    if k == 0:
        return pd.DataFrame(columns=list(CALIBRATION_COLUMNS))
    frame = dataset.frame.reset_index(drop=True)
    indep = _independent_predictions(frame, splits, k)
    rows = [_offset_predictions(name, p, k) for name, p in predictions.groupby("model", sort=False)]
    allp = pd.concat([*rows, *indep], ignore_index=True)
    if not len(allp):
        raise DataError(
            f"no test subject has more than {k} readings: personal calibration needs "
            "per_subject > k (use per_subject >= 3)"
        )
    allp = allp[np.isfinite(allp["calibrated_mgdl"])]
    stats = _rmse_draws(allp, n_boot, seed)
    n_reps = len(np.unique(allp["repeat"]))
    return pd.DataFrame(_summary_rows(stats, k, n_reps))[list(CALIBRATION_COLUMNS)]


def _later_readings(model: str, method: str, later: dict, calibrated_mgdl) -> pd.DataFrame:
    """One method's calibrated predictions of the later readings (``later`` columns)."""
    return pd.DataFrame(
        {
            "model": model,
            "method": method,
            "subject_id": later["subject_id"],
            "measurement_id": later["measurement_id"],
            "repeat": later["repeat"],
            "reference_mgdl": later["reference_mgdl"],
            "calibrated_mgdl": np.asarray(calibrated_mgdl, float),
        }
    )


def _independent_predictions(frame: pd.DataFrame, splits, k: int) -> list[pd.DataFrame]:
    """Carry-forward and difference-ridge on each split's test part's later readings.

    These do not depend on any benchmarked model; the difference ridge is fitted on the
    split's training part.
    """
    mid = frame["measurement_id"].to_numpy() if "measurement_id" in frame else np.arange(len(frame))
    indep = []
    for split in splits:
        test = frame.iloc[split.test].reset_index(drop=True)
        train = frame.iloc[split.train].reset_index(drop=True)
        cal = calibration_mask(test, k)
        sid = test["subject_id"].to_numpy()
        y = test["glucose_mgdl"].to_numpy(float)
        yc = pd.Series(y[cal]).groupby(sid[cal]).mean()
        carry = pd.Series(sid).map(yc).to_numpy(float)
        ridge = _difference_ridge(train, test, k)
        later = {
            "subject_id": sid[~cal],
            "measurement_id": mid[split.test][~cal],
            "repeat": split.repeat,
            "reference_mgdl": y[~cal],
        }
        for method, pred in (("carry-forward", carry), ("difference-ridge", ridge)):
            indep.append(_later_readings(method, method, later, pred[~cal]))
    return indep


def _offset_predictions(name: str, predictions: pd.DataFrame, k: int) -> pd.DataFrame:
    """One model's later readings, uncalibrated (``none``) and ``offset``, per fold."""
    parts = []
    for _, g in predictions.groupby(["repeat", "fold"], sort=False):
        g = g.reset_index(drop=True)
        cal = calibration_mask(g, k)
        fixed, _ = apply_offset(
            g["scored_mgdl"].to_numpy(),
            g["subject_id"].to_numpy(),
            g.loc[cal, "scored_mgdl"].to_numpy(),
            g.loc[cal, "reference_mgdl"].to_numpy(),
            g.loc[cal, "subject_id"].to_numpy(),
        )
        later_g = g.loc[~cal]
        later = {c: later_g[c].to_numpy() for c in
                 ("subject_id", "measurement_id", "repeat", "reference_mgdl")}
        for method, vals in (("none", later_g["scored_mgdl"]), ("offset", fixed[~cal])):
            parts.append(_later_readings(name, method, later, vals))
    return pd.concat(parts, ignore_index=True)


def _rmse_draws(allp: pd.DataFrame, n_boot: int, seed: int) -> dict:
    """(model, method) -> (sq, cnt, RMSE, bootstrap RMSEs) over resampled subjects.

    ``sq`` and ``cnt`` are (repeats, subjects) sums of squared errors and counts; the
    same subject resamples serve every (model, method), so gains are paired.
    """
    subjects = np.unique(allp["subject_id"])
    reps = np.unique(allp["repeat"])
    s_pos = {s: i for i, s in enumerate(subjects)}
    r_pos = {r: i for i, r in enumerate(reps)}
    draws = subject_draws(len(subjects), n_boot, (seed, _BOOT_STREAM))
    ident = np.arange(len(subjects))[None, :]
    stats = {}
    for (name, method), g in allp.groupby(["model", "method"], sort=False):
        si = g["subject_id"].map(s_pos).to_numpy()
        ri = g["repeat"].map(r_pos).to_numpy()
        err2 = (g["reference_mgdl"] - g["calibrated_mgdl"]).to_numpy() ** 2
        sq, cnt = repeat_subject_cells(err2, ri, si, (len(reps), len(subjects)))
        sq = np.nan_to_num(sq)
        stats[(name, method)] = (sq, cnt, _rmse_boot(sq, cnt, ident)[0], _rmse_boot(sq, cnt, draws))
    return stats


def _summary_rows(stats: dict, k: int, n_reps: int) -> list[dict]:
    """One :data:`CALIBRATION_COLUMNS` row per (model, method), with its paired gain.

    The baseline is the model's own ``none``; carry-forward and difference-ridge are
    compared with EBL's ``none`` where EBL was benchmarked.
    """
    base_for_indep = "ebl" if ("ebl", "none") in stats else None
    out = []
    for (name, method), (_sq, cnt, point, boot) in stats.items():
        if method == "none":
            baseline = None
        elif name in ("carry-forward", "difference-ridge"):
            baseline = base_for_indep
        else:
            baseline = name
        if baseline is not None:
            b = stats[(baseline, "none")]
            gain, gboot = b[2] - point, b[3] - boot
            glo, ghi = np.nanquantile(gboot, [0.025, 0.975])
        else:
            gain = glo = ghi = np.nan
        lo, hi = np.nanquantile(boot, [0.025, 0.975])
        out.append(
            {
                "model": name,
                "method": method,
                "k": k,
                "rmse_mgdl": float(point),
                "rmse_ci_low": float(lo),
                "rmse_ci_high": float(hi),
                "baseline": f"{baseline}/none" if baseline else "",
                "gain_mgdl": float(gain),
                "gain_ci_low": float(glo),
                "gain_ci_high": float(ghi),
                "n_scored": int(cnt.sum() / max(n_reps, 1)),
            }
        )
    return out
