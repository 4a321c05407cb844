"""Accuracy standards for a worn (continuous) glucose monitor.

Paired readings of a device worn for days are judged differently from snapshots: the
readings cluster by subject, accuracy is reported per glucose range and per day of wear,
the rate of change and its direction matter, the sensor lags the blood, and the
clinical summary of a wear period is its time in ranges. This module holds those
standards, each as a function over plain arrays (glucose in mg/dL, subject ids, time in
minutes, day of wear), so they work on any data:

* :func:`mard_by_range`, :func:`mard_by_day` -- MARD overall, per reference range and
  per day of wear;
* :func:`agreement_rates`, :func:`icgm_criteria` -- agreement rates (within 15/20/40
  mg/dL or %) per range with a one-sided 95 % lower confidence bound that accounts for
  clustering by subject, next to the integrated-CGM (iCGM) accuracy criteria of the FDA
  special controls, 21 CFR 862.1355;
* :func:`rate_of_change`, :func:`trend_agreement` -- rates of change from consecutive
  readings and the agreement of their categories (a confusion matrix);
* :func:`estimated_lag` -- the time shift that best aligns the sensor to the reference,
  per subject;
* :func:`time_in_ranges`, :func:`time_in_range_agreement` -- TIR / TBR / TAR of the
  international consensus (Battelino et al. 2019) from reference and from prediction.

The DTS error grid sits with the other grids in
:mod:`nirglucose.metrics.error_grids` (:func:`~nirglucose.metrics.error_grids.dts_zones`).
"""

from __future__ import annotations

from types import MappingProxyType
from typing import Final, NamedTuple

import numpy as np
import pandas as pd
from numpy.typing import ArrayLike, NDArray
from scipy import stats

from nirglucose.exceptions import DataError
from nirglucose.metrics._validation import _as_1d_float, _describe_bad, _validate_pairs

__all__ = [
    "GLUCOSE_RANGE_LABELS",
    "AGREEMENT_LIMITS",
    "ICGM_CRITERIA",
    "TREND_EDGES_MGDL_PER_MIN",
    "TIME_IN_RANGE_TARGETS_PCT",
    "CI_METHODS",
    "TrendAgreement",
    "LagEstimate",
    "mard_by_range",
    "mard_by_day",
    "agreement_rates",
    "icgm_criteria",
    "rate_of_change",
    "trend_agreement",
    "estimated_lag",
    "time_in_ranges",
    "time_in_range_agreement",
]

# --- glucose ranges -----------------------------------------------------------------

#: Lower edge of the euglycaemic range (iCGM special controls; Battelino et al. 2019,
#: Table 1). [mg/dL]
_LOW_MGDL: Final[float] = 70.0
#: Upper edge of the euglycaemic range (same sources). [mg/dL]
_HIGH_MGDL: Final[float] = 180.0

#: Labels of the three glucose ranges: < 70, 70-180 (both edges included), > 180 mg/dL.
GLUCOSE_RANGE_LABELS: Final[tuple[str, ...]] = ("<70", "70-180", ">180")
_OVERALL: Final[str] = "overall"

#: Agreement limits: within N mg/dL in the < 70 mg/dL range, within N % above it. [mg/dL or %]
AGREEMENT_LIMITS: Final[tuple[int, ...]] = (15, 20, 40)

#: Methods for the lower confidence bound of an agreement rate.
CI_METHODS: Final[tuple[str, ...]] = ("bootstrap", "wilson")


def _range_codes(glucose_mgdl: NDArray[np.float64]) -> NDArray[np.intp]:
    """0 for < 70, 1 for 70-180 (inclusive), 2 for > 180 mg/dL."""
    return (glucose_mgdl >= _LOW_MGDL).astype(np.intp) + (glucose_mgdl > _HIGH_MGDL)


# --- validation helpers ---------------------------------------------------------------


def _labels(values: ArrayLike, n: int, name: str) -> NDArray:
    """Validate a 1-D label array (subject ids, days) of length ``n``."""
    arr = np.asarray(values)
    if arr.ndim != 1:
        raise DataError(f"{name} must be one-dimensional, got shape {arr.shape}")
    if arr.shape[0] != n:
        raise DataError(f"{name} has {arr.shape[0]} values but there are {n} readings")
    if arr.dtype.kind == "f":
        bad = ~np.isfinite(arr)
        if bad.any():
            raise DataError(f"{name} contains NaN or infinite values: {_describe_bad(bad)}")
    elif arr.dtype.kind == "O":
        bad = pd.isna(arr)
        if bad.any():
            raise DataError(f"{name} contains missing values: {_describe_bad(bad)}")
    return arr


def _times(time_min: ArrayLike, n: int) -> NDArray[np.float64]:
    t = _as_1d_float(time_min, "time_min")
    if t.shape[0] != n:
        raise DataError(f"time_min has {t.shape[0]} values but there are {n} readings")
    bad = ~np.isfinite(t)
    if bad.any():
        raise DataError(f"time_min contains NaN or infinite values: {_describe_bad(bad)}")
    return t


def _subject_codes(subject_id: ArrayLike, n: int) -> tuple[NDArray[np.intp], NDArray]:
    ids = _labels(subject_id, n, "subject_id")
    try:
        uniq, codes = np.unique(ids, return_inverse=True)
    except TypeError as exc:  # e.g. ints mixed with strings in an object array
        raise DataError(f"subject_id values must be of one sortable type: {exc}") from exc
    return codes.astype(np.intp), uniq


# --- MARD -------------------------------------------------------------------------------


def _mard_rows(ref, pred, groups: NDArray[np.intp], labels) -> list[tuple]:
    rel = np.abs(pred - ref) / ref
    k = len(labels)
    n = np.bincount(groups, minlength=k)
    total = np.bincount(groups, weights=rel, minlength=k)
    with np.errstate(invalid="ignore", divide="ignore"):
        mard = 100.0 * total / n
    return [(label, int(n[i]), float(mard[i]) if n[i] else float("nan"))
            for i, label in enumerate(labels)]


def mard_by_range(reference_mgdl: ArrayLike, predicted_mgdl: ArrayLike) -> pd.DataFrame:
    """MARD overall and per glucose range of the reference.

    MARD = mean over pairs of ``|predicted - reference| / reference`` x 100. The ranges
    are those of the iCGM special controls and of the consensus on time in ranges,
    by the *reference* value: < 70, 70-180 (both edges included) and > 180 mg/dL.

    Parameters
    ----------
    reference_mgdl : array_like
        Reference glucose, strictly positive. [mg/dL]
    predicted_mgdl : array_like
        Device / predicted glucose, same length. [mg/dL]

    Returns
    -------
    pandas.DataFrame
        One row per range plus ``"overall"`` (last), columns ``range``, ``n_readings``
        [-] and ``mard_pct`` [%]; an empty range has ``n_readings`` 0 and NaN MARD.

    Raises
    ------
    DataError
        On a length mismatch, empty input, NaN or infinite values or a reference <= 0.

    References
    ----------
    .. [1] Freckmann G, Pleus S, Grady M, Setford S, Levy B. Measures of accuracy for
       continuous glucose monitoring and blood glucose monitoring devices. J Diabetes
       Sci Technol 13(3):575-583, 2019. doi:10.1177/1932296818812062 (MARD definition).
    .. [2] Battelino T, Danne T, Bergenstal RM, et al. Clinical targets for continuous
       glucose monitoring data interpretation: recommendations from the international
       consensus on time in range. Diabetes Care 42(8):1593-1603, 2019.
       doi:10.2337/dci19-0028 (the 70 and 180 mg/dL range edges).

    Examples
    --------
    >>> mard_by_range([50, 100, 200], [55, 110, 180])["mard_pct"].round(3).tolist()
    [10.0, 10.0, 10.0, 10.0]
    """
    ref, pred = _validate_pairs(reference_mgdl, predicted_mgdl)
    rows = _mard_rows(ref, pred, _range_codes(ref), GLUCOSE_RANGE_LABELS)
    rows += _mard_rows(ref, pred, np.zeros(ref.shape[0], np.intp), (_OVERALL,))
    return pd.DataFrame(rows, columns=["range", "n_readings", "mard_pct"])


def mard_by_day(
    reference_mgdl: ArrayLike, predicted_mgdl: ArrayLike, day: ArrayLike
) -> pd.DataFrame:
    """MARD per day of wear.

    Parameters
    ----------
    reference_mgdl : array_like
        Reference glucose, strictly positive. [mg/dL]
    predicted_mgdl : array_like
        Device / predicted glucose, same length. [mg/dL]
    day : array_like
        Day of wear of each reading (any sortable label, e.g. 1, 2, ...). [d]

    Returns
    -------
    pandas.DataFrame
        One row per day in sorted order, columns ``day``, ``n_readings`` [-] and
        ``mard_pct`` [%].

    Raises
    ------
    DataError
        As :func:`mard_by_range`, and on a ``day`` array of the wrong length or with
        missing values.

    References
    ----------
    .. [1] Freckmann G, Pleus S, Grady M, Setford S, Levy B. Measures of accuracy for
       continuous glucose monitoring and blood glucose monitoring devices. J Diabetes
       Sci Technol 13(3):575-583, 2019. doi:10.1177/1932296818812062

    Examples
    --------
    >>> mard_by_day([100, 100, 100], [110, 120, 95], [1, 1, 2])["mard_pct"].round(6).tolist()
    [15.0, 5.0]
    """
    ref, pred = _validate_pairs(reference_mgdl, predicted_mgdl)
    days = _labels(day, ref.shape[0], "day")
    uniq, codes = np.unique(days, return_inverse=True)
    rows = _mard_rows(ref, pred, codes.astype(np.intp), uniq.tolist())
    return pd.DataFrame(rows, columns=["day", "n_readings", "mard_pct"])


# --- agreement rates and the iCGM criteria -----------------------------------------------


def _within(ref, pred, codes, limit: float, absolute_low: bool) -> NDArray[np.bool_]:
    absdiff = np.abs(pred - ref)
    # |d| <= L % of the reference, written 100 |d| <= L ref so integers compare exactly.
    rel = 100.0 * absdiff <= limit * ref
    if not absolute_low:
        return rel
    return np.where(codes == 0, absdiff <= limit, rel)


def _wilson_cc_lower(hits: NDArray, n: NDArray, alpha: float, rho_degenerate: float = 1.0
                     ) -> float:
    """Clustered, continuity-corrected Wilson lower bound (Short et al. 2020).

    The intraclass correlation is undefined at a rate of 0 or 1; ``rho_degenerate`` is
    used there (1, the most conservative, as the reference implementation of Stephan et
    al. 2022 does).
    """
    keep = n > 0
    x, m = hits[keep].astype(np.float64), n[keep].astype(np.float64)
    k = x.shape[0]
    big_m = m.sum()
    p = x.sum() / big_m
    m2 = float(np.sum(m * m))
    if k < 2 or p in (0.0, 1.0):
        rho = rho_degenerate if p in (0.0, 1.0) else 0.0
    else:
        bms = (np.sum(x * x / m) - x.sum() ** 2 / big_m) / (k - 1)
        dof_w = np.sum(m - 1.0)
        wms = (x.sum() - np.sum(x * x / m)) / dof_w if dof_w > 0 else 0.0
        n_star = (big_m**2 - m2) / ((k - 1) * big_m)
        denom = bms + (n_star - 1.0) * wms
        rho = max(0.0, (bms - wms) / denom) if denom > 0 else 0.0
    xi = 1.0 + rho * (m2 - big_m) / big_m  # variance inflation (design effect)
    z = stats.norm.ppf(1.0 - alpha)
    if p == 0.0:
        return 0.0
    root = np.sqrt(xi * z * z - 2.0 - 1.0 / big_m + 4.0 * p * (big_m * (1.0 - p) + 1.0))
    lower = (2 * big_m * p + xi * z * z - 1.0 - np.sqrt(xi) * z * root) / (
        2.0 * (big_m + xi * z * z))
    return float(max(lower, 0.0))


def _bca_lower(boot: NDArray, theta: float, jack: NDArray, alpha: float) -> float:
    """BCa lower bound (DiCiccio & Efron 1996); percentile bound where BCa is undefined."""
    boot = boot[np.isfinite(boot)]
    jack = jack[np.isfinite(jack)]
    if boot.shape[0] == 0:
        return float("nan")
    if np.ptp(boot) == 0.0:
        return float("nan")  # no spread (e.g. a rate of 0 or 100 %): no bootstrap bound
    z_a = stats.norm.ppf(alpha)
    z0 = stats.norm.ppf(np.mean(boot < theta))
    u = jack.mean() - jack if jack.shape[0] else jack
    den = 6.0 * np.sum(u * u) ** 1.5
    a = np.sum(u**3) / den if den > 0 else 0.0
    level = alpha
    if np.isfinite(z0):
        shifted = z0 + (z0 + z_a) / (1.0 - a * (z0 + z_a))
        if np.isfinite(shifted):
            level = float(stats.norm.cdf(shifted))
    return float(np.quantile(boot, level))


def _rate_table(ref, pred, subj, n_subjects, range_codes, *, method, n_boot, seed,
                confidence) -> pd.DataFrame:
    alpha = 1.0 - confidence
    labels = (*GLUCOSE_RANGE_LABELS, _OVERALL)
    rows: list[dict] = []
    tasks = []  # (range label, limit, within mask, member mask)
    for limit in AGREEMENT_LIMITS:
        within_ranged = _within(ref, pred, range_codes, limit, absolute_low=True)
        within_rel = _within(ref, pred, range_codes, limit, absolute_low=False)
        for r, label in enumerate(labels):
            member = range_codes == r if label != _OVERALL else np.ones_like(ref, bool)
            within = within_ranged if label != _OVERALL else within_rel
            tasks.append((label, limit, within, member))
    # Per-subject counts, one column per task: hits[s, t], n[s, t].
    member_mat = np.stack([t[3] for t in tasks], axis=1)
    hit_mat = member_mat & np.stack([t[2] for t in tasks], axis=1)
    n_sub = np.zeros((n_subjects, len(tasks)))
    h_sub = np.zeros((n_subjects, len(tasks)))
    np.add.at(n_sub, subj, member_mat)
    np.add.at(h_sub, subj, hit_mat)
    n_tot, h_tot = n_sub.sum(axis=0), h_sub.sum(axis=0)
    with np.errstate(invalid="ignore", divide="ignore"):
        est = 100.0 * h_tot / n_tot
    if method == "bootstrap":
        rng = np.random.default_rng(seed)
        draws = rng.integers(0, n_subjects, size=(n_boot, n_subjects))
        flat = (np.arange(n_boot)[:, None] * n_subjects + draws).ravel()
        weights = np.bincount(flat, minlength=n_boot * n_subjects).reshape(
            n_boot, n_subjects).astype(np.float64)  # times each subject was drawn
        with np.errstate(invalid="ignore", divide="ignore"):
            boot = 100.0 * (weights @ h_sub) / (weights @ n_sub)
            jack = 100.0 * (h_tot - h_sub) / (n_tot - n_sub)  # leave one subject out
    for t, (label, limit, _, _) in enumerate(tasks):
        n_t = int(n_tot[t])
        if n_t == 0:
            lower = float("nan")
        elif method == "bootstrap":
            present = n_sub[:, t] > 0
            lower = _bca_lower(boot[:, t], float(est[t]), jack[present, t], alpha)
            if not np.isfinite(lower):
                lower = 100.0 * _wilson_cc_lower(h_sub[:, t], n_sub[:, t], alpha, 0.0)
        else:
            lower = 100.0 * _wilson_cc_lower(h_sub[:, t], n_sub[:, t], alpha)
        unit = "mg/dL" if label == "<70" else "%"
        rows.append({
            "range": label,
            "limit": f"{limit} {unit}",
            "estimate_pct": float(est[t]) if n_t else float("nan"),
            "lower_bound_pct": lower,
            "n_readings": n_t,
            "n_subjects": int(np.count_nonzero(n_sub[:, t])),
        })
    return pd.DataFrame(rows)


def _prepare_agreement(reference_mgdl, predicted_mgdl, subject_id, range_by, method, n_boot,
                       confidence):
    ref, pred = _validate_pairs(reference_mgdl, predicted_mgdl)
    subj, uniq = _subject_codes(subject_id, ref.shape[0])
    if range_by not in ("device", "reference"):
        raise DataError(f"range_by must be 'device' or 'reference', got {range_by!r}")
    if method not in CI_METHODS:
        raise DataError(f"method must be one of {list(CI_METHODS)}, got {method!r}")
    if isinstance(n_boot, bool) or not isinstance(n_boot, (int, np.integer)) or n_boot < 100:
        raise DataError(f"n_boot must be an integer >= 100, got {n_boot!r}")
    if not 0.5 < float(confidence) < 1.0:
        raise DataError(f"confidence must lie in (0.5, 1), got {confidence!r}")
    codes = _range_codes(pred if range_by == "device" else ref)
    return ref, pred, subj, uniq.shape[0], codes


def agreement_rates(
    reference_mgdl: ArrayLike,
    predicted_mgdl: ArrayLike,
    subject_id: ArrayLike,
    *,
    range_by: str = "device",
    method: str = "bootstrap",
    n_boot: int = 10_000,
    seed: int = 0,
    confidence: float = 0.95,
) -> pd.DataFrame:
    """Agreement rates per glucose range with a one-sided lower confidence bound.

    An agreement rate is the share of readings within a limit of their reference:
    within ``L`` mg/dL in the < 70 mg/dL range and within ``L`` % of the reference in the
    70-180 and > 180 mg/dL ranges, for ``L`` in 15, 20 and 40 (limits inclusive); the
    ``"overall"`` row uses ``L`` % for every reading, as the iCGM overall criterion does.
    Ranges are assigned by the device (predicted) reading, as in the iCGM special
    controls and the reference implementation of Stephan et al. (2022), or by the
    reference with ``range_by="reference"``.

    Readings of one subject are correlated, so the lower bound accounts for the
    clustering by subject:

    * ``method="bootstrap"`` (default, recommended by Stephan et al. 2022): subjects
      are resampled with replacement ``n_boot`` times with a fixed ``seed`` (a cluster
      bootstrap) and the bound is the bias-corrected and accelerated (BCa) percentile
      (DiCiccio & Efron 1996, the acceleration from a leave-one-subject-out jackknife),
      falling back to the plain percentile where the BCa correction is undefined, and
      to the continuity-corrected Wilson bound of the readings taken as independent
      where the resamples do not vary at all (a rate of 0 or 100 %, where a bootstrap
      bound would equal the estimate whatever the number of readings);
    * ``method="wilson"``: the continuity-corrected Wilson bound with the variance
      inflated by the design effect ``1 + rho (sum m_i^2 - M) / M`` of the intraclass
      correlation ``rho`` (Short et al. 2020); deterministic. With ``rho = 0`` it is
      Newcombe's (1998) continuity-corrected Wilson bound. At a rate of 0 or 100 % the
      intraclass correlation is undefined and ``rho = 1`` is used (each subject counts
      once), as in the reference implementation of Stephan et al. (2022).

    Parameters
    ----------
    reference_mgdl : array_like
        Reference (comparator) glucose, strictly positive. [mg/dL]
    predicted_mgdl : array_like
        Device / predicted glucose, same length. [mg/dL]
    subject_id : array_like
        Subject (or sensor) of each reading: the cluster. [-]
    range_by : {"device", "reference"}, optional
        Which value assigns a reading to a range. [-]
    method : {"bootstrap", "wilson"}, optional
        Lower-bound method (see above). [-]
    n_boot : int, optional
        Bootstrap resamples (Stephan et al. recommend at least 10,000). [-]
    seed : int, optional
        Seed of the bootstrap's generator (same seed, same bound). [-]
    confidence : float, optional
        One-sided confidence level of the lower bound. [-]

    Returns
    -------
    pandas.DataFrame
        One row per (limit, range): columns ``range`` ('<70', '70-180', '>180',
        'overall'), ``limit`` (e.g. '15 mg/dL', '15 %'), ``estimate_pct`` [%],
        ``lower_bound_pct`` [%], ``n_readings`` and ``n_subjects`` [-]. A range without
        readings has NaN estimate and bound.

    Raises
    ------
    DataError
        On bad glucose pairs (as :func:`~nirglucose.metrics.mard`), a ``subject_id`` of
        the wrong length or with missing values, or an unknown ``range_by`` /
        ``method``, ``n_boot`` < 100 or ``confidence`` outside (0.5, 1).

    References
    ----------
    .. [1] Stephan P, Eichenlaub M, Waldenmaier D, Pleus S, Rothenbühler M, Haug C,
       Freckmann G. A statistical approach for assessing the compliance of integrated
       continuous glucose monitoring systems with FDA accuracy requirements. Diabetes
       Technol Ther, 2023 (epub 28 Oct 2022). doi:10.1089/dia.2022.0331
    .. [2] Short MI, Cabral HJ, Weinberg JM, LaValley MP, Massaro JM. A novel confidence
       interval for a single proportion in the presence of clustered binary outcome
       data. Stat Methods Med Res 29(1):111-121, 2020.
    .. [3] Newcombe RG. Two-sided confidence intervals for the single proportion:
       comparison of seven methods. Stat Med 17(8):857-872, 1998.
       doi:10.1002/(SICI)1097-0258(19980430)17:8<857::AID-SIM777>3.0.CO;2-E
    .. [4] DiCiccio TJ, Efron B. Bootstrap confidence intervals. Stat Sci
       11(3):189-228, 1996. doi:10.1214/ss/1032280214

    Examples
    --------
    >>> t = agreement_rates([100, 100, 200, 60], [110, 130, 210, 50], [1, 1, 2, 2],
    ...                     method="wilson")
    >>> t.loc[t["limit"] == "20 %", ["range", "estimate_pct", "n_readings"]].values.tolist()
    [['70-180', 50.0, 2], ['>180', 100.0, 1], ['overall', 75.0, 4]]
    """
    ref, pred, subj, n_subjects, codes = _prepare_agreement(
        reference_mgdl, predicted_mgdl, subject_id, range_by, method, n_boot, confidence)
    table = _rate_table(ref, pred, subj, n_subjects, codes, method=method, n_boot=int(n_boot),
                        seed=seed, confidence=float(confidence))
    return table


class _Criterion(NamedTuple):
    range: str
    limit: str
    required_pct: float


#: iCGM accuracy criteria (21 CFR 862.1355, special controls; Stephan et al. 2022,
#: Table 1): the lower one-sided 95 % confidence bound of each agreement rate must
#: exceed ``required_pct``. Keys A-G (and H, I for the two crossing criteria) follow the
#: order of the regulation's list. [%]
ICGM_CRITERIA: Final = MappingProxyType({
    "A": _Criterion("<70", "15 mg/dL", 85.0),
    "B": _Criterion("70-180", "15 %", 70.0),
    "C": _Criterion(">180", "15 %", 80.0),
    "D": _Criterion("<70", "40 mg/dL", 98.0),
    "E": _Criterion("70-180", "40 %", 99.0),
    "F": _Criterion(">180", "40 %", 99.0),
    "G": _Criterion("overall", "20 %", 87.0),
})


def icgm_criteria(
    reference_mgdl: ArrayLike,
    predicted_mgdl: ArrayLike,
    subject_id: ArrayLike,
    *,
    method: str = "bootstrap",
    n_boot: int = 10_000,
    seed: int = 0,
    confidence: float = 0.95,
) -> pd.DataFrame:
    """The iCGM accuracy criteria of the FDA special controls, pass or fail.

    The special controls for an integrated continuous glucose monitoring system
    (21 CFR 862.1355) set, on the *lower one-sided 95 % confidence bound* of each
    agreement rate, with ranges by the iCGM reading:

    * A: < 70 mg/dL, within 15 mg/dL: > 85 %;
    * B: 70-180 mg/dL, within 15 %: > 70 %;
    * C: > 180 mg/dL, within 15 %: > 80 %;
    * D: < 70 mg/dL, within 40 mg/dL: > 98 %;
    * E: 70-180 mg/dL, within 40 %: > 99 %;
    * F: > 180 mg/dL, within 40 %: > 99 %;
    * G: over the whole range, within 20 %: > 87 %;
    * H: no iCGM reading < 70 mg/dL with a reference > 180 mg/dL;
    * I: no iCGM reading > 180 mg/dL with a reference < 70 mg/dL.

    The agreement rates and bounds are those of :func:`agreement_rates` (ranges by the
    device reading). H and I are counts, judged without a bound. The limits and the
    range assignment follow the reference implementation of Stephan et al. (2022); the
    thresholds are those of the classification order. Check them against the current
    eCFR text before any regulatory use: this is a research metric, not a submission.

    Parameters
    ----------
    reference_mgdl : array_like
        Reference (comparator) glucose, strictly positive. [mg/dL]
    predicted_mgdl : array_like
        Device / predicted glucose, same length. [mg/dL]
    subject_id : array_like
        Subject (or sensor) of each reading. [-]
    method, n_boot, seed, confidence
        As :func:`agreement_rates`.

    Returns
    -------
    pandas.DataFrame
        One row per criterion A-I: ``criterion``, ``range``, ``limit``,
        ``estimate_pct`` [%] (for H and I the number of offending readings [-]),
        ``lower_bound_pct`` [%] (NaN for H and I), ``n_readings``, ``n_subjects`` [-],
        ``required`` (e.g. '> 85 %', '0 readings') and ``passes`` (bool; False where
        the range has no readings: a criterion without data is not met).

    Raises
    ------
    DataError
        As :func:`agreement_rates`.

    References
    ----------
    .. [1] 21 CFR 862.1355, Integrated continuous glucose monitoring system, special
       controls; classification order 87 FR 9237-9239, 18 Feb 2022 (FDA-2021-N-1343).
    .. [2] Stephan P, Eichenlaub M, Waldenmaier D, Pleus S, Rothenbühler M, Haug C,
       Freckmann G. A statistical approach for assessing the compliance of integrated
       continuous glucose monitoring systems with FDA accuracy requirements. Diabetes
       Technol Ther, 2023 (epub 28 Oct 2022). doi:10.1089/dia.2022.0331 (Table 1).

    Examples
    --------
    >>> ref = [60, 65, 100, 150, 200, 250]
    >>> t = icgm_criteria(ref, ref, [1, 1, 2, 2, 3, 3], method="wilson")
    >>> t[["criterion", "passes"]].values.tolist()[-2:]
    [['H', True], ['I', True]]
    """
    ref, pred, subj, n_subjects, codes = _prepare_agreement(
        reference_mgdl, predicted_mgdl, subject_id, "device", method, n_boot, confidence)
    rates = _rate_table(ref, pred, subj, n_subjects, codes, method=method,
                        n_boot=int(n_boot), seed=seed, confidence=float(confidence))
    rows = []
    for letter, crit in ICGM_CRITERIA.items():
        row = rates[(rates["range"] == crit.range) & (rates["limit"] == crit.limit)].iloc[0]
        lower = row["lower_bound_pct"]
        rows.append({
            "criterion": letter, "range": crit.range, "limit": crit.limit,
            "estimate_pct": row["estimate_pct"], "lower_bound_pct": lower,
            "n_readings": int(row["n_readings"]), "n_subjects": int(row["n_subjects"]),
            "required": f"> {crit.required_pct:g} %",
            "passes": bool(np.isfinite(lower) and lower > crit.required_pct),
        })
    for letter, device_mask, ref_mask, rng_label, ref_label in (
        ("H", codes == 0, ref > _HIGH_MGDL, "<70", "reference >180"),
        ("I", codes == 2, ref < _LOW_MGDL, ">180", "reference <70"),
    ):
        bad = device_mask & ref_mask
        rows.append({
            "criterion": letter, "range": rng_label, "limit": ref_label,
            "estimate_pct": float(np.count_nonzero(bad)), "lower_bound_pct": float("nan"),
            "n_readings": int(np.count_nonzero(device_mask)),
            "n_subjects": int(np.unique(subj[device_mask]).shape[0]),
            "required": "0 readings", "passes": not bool(bad.any()),
        })
    return pd.DataFrame(rows)


# --- rate of change and trend accuracy --------------------------------------------------

#: Edges of the rate-of-change categories < -2, -2..-1, -1..1, 1..2, >= 2 mg/dL/min: the
#: bands of the usual CGM trend arrows (steady within 1 mg/dL/min, single arrow 1-2,
#: double arrow beyond 2). A default, not a standard: the DTS Trend Accuracy Matrix
#: (Klonoff et al. 2024) defines its own categories, not reproduced here. [mg/dL/min]
TREND_EDGES_MGDL_PER_MIN: Final[tuple[float, ...]] = (-2.0, -1.0, 1.0, 2.0)


def _order(subj: NDArray[np.intp], t: NDArray[np.float64]) -> NDArray[np.intp]:
    order = np.lexsort((t, subj))
    s, tt = subj[order], t[order]
    dup = (s[1:] == s[:-1]) & (tt[1:] == tt[:-1])
    if dup.any():
        i = int(order[1:][np.argmax(dup)])
        raise DataError(f"time_min repeats within a subject (first at index {i}); "
                        "each subject needs one reading per time")
    return order


def _check_gap(max_gap_min: float | None) -> float:
    if max_gap_min is None:
        return np.inf
    if isinstance(max_gap_min, bool) or not (
            isinstance(max_gap_min, (int, float, np.number)) and max_gap_min > 0):
        raise DataError(f"max_gap_min must be a positive number or None, got {max_gap_min!r}")
    return float(max_gap_min)


def _rates(glucose, subj, t, order, max_gap_min: float = np.inf) -> NDArray[np.float64]:
    g, s, tt = glucose[order], subj[order], t[order]
    out_sorted = np.full(g.shape[0], np.nan)
    same = (s[1:] == s[:-1]) & (tt[1:] - tt[:-1] <= max_gap_min)
    out_sorted[1:][same] = (g[1:] - g[:-1])[same] / (tt[1:] - tt[:-1])[same]
    out = np.empty_like(out_sorted)
    out[order] = out_sorted
    return out


def rate_of_change(
    glucose_mgdl: ArrayLike,
    subject_id: ArrayLike,
    time_min: ArrayLike,
    *,
    max_gap_min: float | None = None,
) -> NDArray[np.float64]:
    """Rate of change of glucose from consecutive readings of each subject.

    The rate at a reading is ``(g_i - g_(i-1)) / (t_i - t_(i-1))`` with the previous
    reading of the same subject in time order (the readings need not be sorted); the
    first reading of each subject, and a reading more than ``max_gap_min`` after the
    previous one (a dropout), has no rate (NaN). This is the rate of the CG-EGA
    (Kovatchev et al. 2004) and of the trend categories of CGM accuracy studies.

    Parameters
    ----------
    glucose_mgdl : array_like
        Glucose readings, finite. [mg/dL]
    subject_id : array_like
        Subject of each reading. [-]
    time_min : array_like
        Time of each reading; distinct within a subject. [min]
    max_gap_min : float or None, optional
        Longest interval a rate may span; None for no limit. [min]

    Returns
    -------
    numpy.ndarray
        Rate at each reading, aligned with the input, NaN at each subject's first
        reading. [mg/dL/min]

    Raises
    ------
    DataError
        On non-finite glucose or time, arrays of different lengths, or a time repeated
        within a subject.

    References
    ----------
    .. [1] Kovatchev BP, Gonder-Frederick LA, Cox DJ, Clarke WL. Evaluating the accuracy
       of continuous glucose-monitoring sensors: continuous glucose-error grid analysis
       illustrated by TheraSense Freestyle Navigator data. Diabetes Care
       27(8):1922-1928, 2004. doi:10.2337/diacare.27.8.1922

    Examples
    --------
    >>> rate_of_change([100, 110, 90], [1, 1, 1], [0, 5, 15]).tolist()
    [nan, 2.0, -2.0]
    """
    g = _as_1d_float(glucose_mgdl, "glucose_mgdl")
    bad = ~np.isfinite(g)
    if bad.any():
        raise DataError(f"glucose_mgdl contains NaN or infinite values: {_describe_bad(bad)}")
    subj, _ = _subject_codes(subject_id, g.shape[0])
    t = _times(time_min, g.shape[0])
    return _rates(g, subj, t, _order(subj, t), _check_gap(max_gap_min))


class TrendAgreement(NamedTuple):
    """Result of :func:`trend_agreement`: ``(matrix, agreement_pct, n_pairs)``.

    ``matrix`` holds the counts, rows the reference category, columns the device
    category [-]; ``agreement_pct`` is the share of rate pairs in the same category [%];
    ``n_pairs`` the number of rate pairs compared [-].
    """

    matrix: pd.DataFrame
    agreement_pct: float
    n_pairs: int


def _category_labels(edges: tuple[float, ...]) -> list[str]:
    labels = [f"<{edges[0]:g}"]
    labels += [f"{lo:g}..{hi:g}" for lo, hi in zip(edges[:-1], edges[1:], strict=True)]
    return labels + [f">={edges[-1]:g}"]


def trend_agreement(
    reference_mgdl: ArrayLike,
    predicted_mgdl: ArrayLike,
    subject_id: ArrayLike,
    time_min: ArrayLike,
    *,
    edges_mgdl_per_min: tuple[float, ...] = TREND_EDGES_MGDL_PER_MIN,
    max_gap_min: float | None = None,
) -> TrendAgreement:
    """Agreement of rate-of-change categories between reference and device.

    Rates come from consecutive readings of each subject (:func:`rate_of_change`), for
    the reference and the device series at the same times; each rate falls in a
    category bounded by ``edges_mgdl_per_min`` (category ``lo..hi`` holds
    ``lo <= rate < hi``; by default < -2, -2..-1, -1..1, 1..2, >= 2 mg/dL/min). The
    result is the confusion matrix of the categories (rows: reference, columns:
    device) and the share on its diagonal.

    Parameters
    ----------
    reference_mgdl : array_like
        Reference glucose, strictly positive. [mg/dL]
    predicted_mgdl : array_like
        Device / predicted glucose, same length. [mg/dL]
    subject_id : array_like
        Subject of each reading. [-]
    time_min : array_like
        Time of each reading; distinct within a subject. [min]
    edges_mgdl_per_min : tuple of float, optional
        Strictly increasing category edges. [mg/dL/min]
    max_gap_min : float or None, optional
        Longest interval a rate may span (longer gaps give no rate pair); None for no
        limit. [min]

    Returns
    -------
    TrendAgreement
        ``(matrix, agreement_pct, n_pairs)``.

    Raises
    ------
    DataError
        On bad pairs, arrays of different lengths, a repeated time within a subject,
        edges that are not strictly increasing, or no subject with two readings.

    References
    ----------
    .. [1] Kovatchev BP, Gonder-Frederick LA, Cox DJ, Clarke WL. Evaluating the accuracy
       of continuous glucose-monitoring sensors: continuous glucose-error grid analysis
       illustrated by TheraSense Freestyle Navigator data. Diabetes Care
       27(8):1922-1928, 2004. doi:10.2337/diacare.27.8.1922
    .. [2] Klonoff DC, Freckmann G, Pleus S, et al. The Diabetes Technology Society Error
       Grid and Trend Accuracy Matrix for glucose monitors. J Diabetes Sci Technol
       18(6):1346-1361, 2024. doi:10.1177/19322968241275701

    Examples
    --------
    >>> r = trend_agreement([100, 110, 100], [100, 111, 100], [1, 1, 1], [0, 5, 10])
    >>> r.agreement_pct, r.n_pairs
    (50.0, 2)
    """
    ref, pred = _validate_pairs(reference_mgdl, predicted_mgdl)
    edges = np.asarray(edges_mgdl_per_min, dtype=np.float64)
    if edges.ndim != 1 or edges.shape[0] == 0 or np.any(np.diff(edges) <= 0) or not np.all(
            np.isfinite(edges)):
        raise DataError(f"edges_mgdl_per_min must be finite and strictly increasing, got "
                        f"{tuple(edges_mgdl_per_min)!r}")
    subj, _ = _subject_codes(subject_id, ref.shape[0])
    t = _times(time_min, ref.shape[0])
    order = _order(subj, t)
    gap = _check_gap(max_gap_min)
    rr, rp = _rates(ref, subj, t, order, gap), _rates(pred, subj, t, order, gap)
    keep = np.isfinite(rr)
    if not keep.any():
        raise DataError("no subject has two readings; a rate of change needs two")
    cr = np.searchsorted(edges, rr[keep], side="right")
    cp = np.searchsorted(edges, rp[keep], side="right")
    k = edges.shape[0] + 1
    counts = np.bincount(cr * k + cp, minlength=k * k).reshape(k, k)
    labels = _category_labels(tuple(edges.tolist()))
    matrix = pd.DataFrame(counts, index=pd.Index(labels, name="reference"),
                          columns=pd.Index(labels, name="device"))
    n = int(keep.sum())
    return TrendAgreement(matrix, float(100.0 * np.trace(counts) / n), n)


# --- lag --------------------------------------------------------------------------------


class LagEstimate(NamedTuple):
    """Result of :func:`estimated_lag`: ``(per_subject, median_min, q25_min, q75_min)``.

    ``per_subject`` has one row per subject with ``subject_id``, ``lag_min`` [min],
    ``correlation`` (at that lag) [-] and ``n_readings`` [-]; ``median_min``,
    ``q25_min`` and ``q75_min`` are the median and the 25th / 75th percentiles of the
    lag over subjects [min].
    """

    per_subject: pd.DataFrame
    median_min: float
    q25_min: float
    q75_min: float


def _best_shift(r: NDArray[np.float64], p: NDArray[np.float64], max_shift: int,
                min_overlap: int) -> tuple[float, float]:
    shifts = np.arange(-max_shift, max_shift + 1)
    corr = np.full(shifts.shape[0], -np.inf)
    for i, k in enumerate(shifts):
        # shift k > 0: the device at time t + k dt matches the reference at time t.
        a, b = (r[: r.shape[0] - k], p[k:]) if k >= 0 else (r[-k:], p[: p.shape[0] + k])
        if a.shape[0] < min_overlap or np.ptp(a) == 0 or np.ptp(b) == 0:
            continue
        corr[i] = float(np.corrcoef(a, b)[0, 1])
    i = int(np.argmax(corr))
    best, best_c = float(shifts[i]), float(corr[i])
    if 0 < i < shifts.shape[0] - 1 and np.isfinite(corr[i - 1]) and np.isfinite(corr[i + 1]):
        # Parabola through the peak and its two neighbours: sub-interval resolution.
        curv = corr[i - 1] - 2.0 * corr[i] + corr[i + 1]
        if curv < 0:
            best += 0.5 * (corr[i - 1] - corr[i + 1]) / curv
    return best, best_c


def estimated_lag(
    reference_mgdl: ArrayLike,
    predicted_mgdl: ArrayLike,
    subject_id: ArrayLike,
    time_min: ArrayLike,
    *,
    max_lag_min: float = 30.0,
) -> LagEstimate:
    """Time lag of the device behind the reference, per subject, by cross-correlation.

    For each subject the two series (uniformly sampled, interval ``dt``) are shifted
    against each other by ``k dt`` for ``|k dt| <= max_lag_min``; the lag is the shift
    that maximises the Pearson correlation of the overlapping parts (positive: the
    device follows the reference), refined below the sampling interval by the vertex
    of the parabola through the best shift and its two neighbours. This is the
    cross-correlation (time-shift) method of CGM time-delay studies
    (Schmelzeisen-Redeker et al. 2015). Subjects with fewer than three overlapping readings at
    every shift, or a constant series, get NaN and are left out of the median and IQR.

    Parameters
    ----------
    reference_mgdl : array_like
        Reference glucose, strictly positive. [mg/dL]
    predicted_mgdl : array_like
        Device / predicted glucose, same length. [mg/dL]
    subject_id : array_like
        Subject of each reading. [-]
    time_min : array_like
        Time of each reading; within a subject uniformly spaced (any order). [min]
    max_lag_min : float, optional
        Largest shift tried, each way. [min]

    Returns
    -------
    LagEstimate
        ``(per_subject, median_min, q25_min, q75_min)``.

    Raises
    ------
    DataError
        On bad pairs or times, a subject whose readings are not uniformly spaced, or a
        ``max_lag_min`` that is not positive.

    References
    ----------
    .. [1] Schmelzeisen-Redeker G, Schoemaker M, Kirchsteiger H, Freckmann G, Heinemann
       L, del Re L. Time delay of CGM sensors: relevance, causes, and countermeasures.
       J Diabetes Sci Technol 9(5):1006-1015, 2015. doi:10.1177/1932296815590154

    Examples
    --------
    >>> t = np.arange(0.0, 1440.0, 5.0)
    >>> ref = 120 + 40 * np.sin(t / 30)
    >>> dev = 120 + 40 * np.sin((t - 10) / 30)
    >>> round(estimated_lag(ref, dev, np.zeros(t.size), t).median_min, 1)
    10.0
    """
    ref, pred = _validate_pairs(reference_mgdl, predicted_mgdl)
    if not (np.isfinite(max_lag_min) and max_lag_min > 0):
        raise DataError(f"max_lag_min must be positive, got {max_lag_min!r}")
    subj, uniq = _subject_codes(subject_id, ref.shape[0])
    t = _times(time_min, ref.shape[0])
    order = _order(subj, t)
    s_sorted = subj[order]
    starts = np.flatnonzero(np.r_[True, s_sorted[1:] != s_sorted[:-1]])
    stops = np.r_[starts[1:], s_sorted.shape[0]]
    rows = []
    for a, b in zip(starts, stops, strict=True):  # one iteration per subject
        idx = order[a:b]
        tt = t[idx]
        lag, corr = float("nan"), float("nan")
        if idx.shape[0] >= 3:
            dts = np.diff(tt)
            if not np.allclose(dts, dts[0], rtol=1e-6, atol=1e-9):
                raise DataError(
                    f"subject {uniq[s_sorted[a]]!r}: readings are not uniformly spaced in "
                    "time (intervals from {:g} to {:g} min); resample first".format(
                        dts.min(), dts.max()))
            dt = float(dts[0])
            k, c = _best_shift(ref[idx], pred[idx], int(np.floor(max_lag_min / dt + 1e-9)), 3)
            if np.isfinite(c):
                lag, corr = k * dt, c
        rows.append((uniq[s_sorted[a]], lag, corr, int(b - a)))
    per = pd.DataFrame(rows, columns=["subject_id", "lag_min", "correlation", "n_readings"])
    lags = per["lag_min"].to_numpy(dtype=np.float64)
    lags = lags[np.isfinite(lags)]
    if lags.shape[0] == 0:
        return LagEstimate(per, float("nan"), float("nan"), float("nan"))
    q25, med, q75 = np.percentile(lags, [25, 50, 75])
    return LagEstimate(per, float(med), float(q25), float(q75))


# --- time in ranges ------------------------------------------------------------------

#: Consensus targets for most adults with type 1 or type 2 diabetes (Battelino et al.
#: 2019, Table 2 / Figure 2): ('>' or '<', value). [%]
TIME_IN_RANGE_TARGETS_PCT: Final = MappingProxyType({
    "tbr_lt54_pct": ("<", 1.0),
    "tbr_lt70_pct": ("<", 4.0),
    "tir_70_180_pct": (">", 70.0),
    "tar_gt180_pct": ("<", 25.0),
    "tar_gt250_pct": ("<", 5.0),
})

#: Range edges of the consensus (Battelino et al. 2019, Table 1). [mg/dL]
_VERY_LOW_MGDL: Final[float] = 54.0
_VERY_HIGH_MGDL: Final[float] = 250.0


def _tir_table(glucose, subj, uniq) -> pd.DataFrame:
    k = uniq.shape[0]
    n = np.bincount(subj, minlength=k).astype(np.float64)
    masks = {
        "tbr_lt54_pct": glucose < _VERY_LOW_MGDL,
        "tbr_lt70_pct": glucose < _LOW_MGDL,
        "tir_70_180_pct": (glucose >= _LOW_MGDL) & (glucose <= _HIGH_MGDL),
        "tar_gt180_pct": glucose > _HIGH_MGDL,
        "tar_gt250_pct": glucose > _VERY_HIGH_MGDL,
    }
    data = {"subject_id": uniq, "n_readings": n.astype(np.int64)}
    for key, mask in masks.items():
        data[key] = 100.0 * np.bincount(subj, weights=mask.astype(np.float64), minlength=k) / n
    return pd.DataFrame(data)


def time_in_ranges(glucose_mgdl: ArrayLike, subject_id: ArrayLike) -> pd.DataFrame:
    """Time below, in and above range per subject (international consensus, 2019).

    The share of each subject's readings in the consensus ranges: below 54 mg/dL
    (TBR level 2), below 70 mg/dL (TBR, level 1 and 2 together), 70-180 mg/dL (TIR,
    both edges included), above 180 mg/dL (TAR, level 1 and 2) and above 250 mg/dL
    (TAR level 2). With uniform sampling the share of readings is the share of time;
    resample unevenly spaced readings first. The targets for most adults with type 1
    or type 2 diabetes are in :data:`TIME_IN_RANGE_TARGETS_PCT` (TIR > 70 %, TBR < 4 %,
    < 54 mg/dL < 1 %, TAR < 25 %, > 250 mg/dL < 5 %).

    Parameters
    ----------
    glucose_mgdl : array_like
        Glucose readings, finite. [mg/dL]
    subject_id : array_like
        Subject of each reading. [-]

    Returns
    -------
    pandas.DataFrame
        One row per subject (sorted): ``subject_id``, ``n_readings`` [-],
        ``tbr_lt54_pct``, ``tbr_lt70_pct``, ``tir_70_180_pct``, ``tar_gt180_pct``,
        ``tar_gt250_pct`` [%].

    Raises
    ------
    DataError
        On non-finite glucose or a ``subject_id`` of the wrong length.

    References
    ----------
    .. [1] Battelino T, Danne T, Bergenstal RM, et al. Clinical targets for continuous
       glucose monitoring data interpretation: recommendations from the international
       consensus on time in range. Diabetes Care 42(8):1593-1603, 2019.
       doi:10.2337/dci19-0028

    Examples
    --------
    >>> time_in_ranges([50, 100, 150, 300], [1, 1, 1, 1])["tir_70_180_pct"].tolist()
    [50.0]
    """
    g = _as_1d_float(glucose_mgdl, "glucose_mgdl")
    if g.shape[0] == 0:
        raise DataError("glucose_mgdl is empty; at least one reading is needed")
    bad = ~np.isfinite(g)
    if bad.any():
        raise DataError(f"glucose_mgdl contains NaN or infinite values: {_describe_bad(bad)}")
    subj, uniq = _subject_codes(subject_id, g.shape[0])
    return _tir_table(g, subj, uniq)


def time_in_range_agreement(
    reference_mgdl: ArrayLike, predicted_mgdl: ArrayLike, subject_id: ArrayLike
) -> pd.DataFrame:
    """Time in ranges from the reference and from the device, per subject, and the gap.

    Each metric of :func:`time_in_ranges` is computed from the reference series and
    from the predicted series of each subject; the difference is predicted minus
    reference (a device that over-reads shows positive TAR differences). The consensus
    target of each metric (Battelino et al. 2019) is listed beside it, with whether the
    reference and the device each meet it -- a device that changes the verdict is
    clinically wrong even where its point accuracy looks fine.

    Parameters
    ----------
    reference_mgdl : array_like
        Reference glucose, strictly positive. [mg/dL]
    predicted_mgdl : array_like
        Device / predicted glucose, same length. [mg/dL]
    subject_id : array_like
        Subject of each reading. [-]

    Returns
    -------
    pandas.DataFrame
        Long format, one row per (subject, metric): ``subject_id``, ``metric``,
        ``reference_pct``, ``predicted_pct``, ``difference_pct`` [%], ``target`` (e.g.
        '> 70 %'), ``reference_meets``, ``predicted_meets`` (bool).

    Raises
    ------
    DataError
        As :func:`time_in_ranges`, and on bad pairs.

    References
    ----------
    .. [1] Battelino T, Danne T, Bergenstal RM, et al. Clinical targets for continuous
       glucose monitoring data interpretation: recommendations from the international
       consensus on time in range. Diabetes Care 42(8):1593-1603, 2019.
       doi:10.2337/dci19-0028

    Examples
    --------
    >>> t = time_in_range_agreement([100, 200], [100, 170], [1, 1])
    >>> t.loc[t["metric"] == "tir_70_180_pct", "difference_pct"].tolist()
    [50.0]
    """
    ref, pred = _validate_pairs(reference_mgdl, predicted_mgdl)
    subj, uniq = _subject_codes(subject_id, ref.shape[0])
    a, b = _tir_table(ref, subj, uniq), _tir_table(pred, subj, uniq)
    frames = []
    for metric, (sign, value) in TIME_IN_RANGE_TARGETS_PCT.items():
        r, p = a[metric].to_numpy(), b[metric].to_numpy()
        meets = np.greater if sign == ">" else np.less
        frames.append(pd.DataFrame({
            "subject_id": uniq, "metric": metric, "reference_pct": r, "predicted_pct": p,
            "difference_pct": p - r, "target": f"{sign} {value:g} %",
            "reference_meets": meets(r, value), "predicted_meets": meets(p, value),
        }))
    return pd.concat(frames, ignore_index=True)
