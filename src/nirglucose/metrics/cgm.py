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
* rates of change, trend agreement and the sensor's lag in :mod:`nirglucose.metrics.trend`;
* TIR / TBR / TAR of the international consensus (Battelino et al. 2019) in
  :mod:`nirglucose.metrics.time_in_range`.

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
from nirglucose.metrics._validation import (
    label_array,
    subject_codes,
    validate_pairs,
)

__all__ = [
    "GLUCOSE_RANGE_LABELS",
    "AGREEMENT_LIMITS",
    "ICGM_CRITERIA",
    "CI_METHODS",
    "mard_by_range",
    "mard_by_day",
    "agreement_rates",
    "icgm_criteria",
]

# --- glucose ranges -----------------------------------------------------------------

#: Lower edge of the euglycaemic range (iCGM special controls; Battelino et al. 2019,
#: Table 1). [mg/dL]
EUGLYCAEMIC_LOW_MGDL: Final[float] = 70.0
#: Upper edge of the euglycaemic range (same sources). [mg/dL]
EUGLYCAEMIC_HIGH_MGDL: Final[float] = 180.0

#: Labels of the three glucose ranges: < 70, 70-180 (both edges included), > 180 mg/dL.
GLUCOSE_RANGE_LABELS: Final[tuple[str, ...]] = ("<70", "70-180", ">180")
_OVERALL: Final[str] = "overall"

#: Agreement limits: within N mg/dL in the < 70 mg/dL range, within N % above it. [mg/dL or %]
AGREEMENT_LIMITS: Final[tuple[int, ...]] = (15, 20, 40)

#: Methods for the lower confidence bound of an agreement rate.
CI_METHODS: Final[tuple[str, ...]] = ("bootstrap", "wilson", "clopper-pearson")


def _range_codes(glucose_mgdl: NDArray[np.float64]) -> NDArray[np.intp]:
    """0 for < 70, 1 for 70-180 (inclusive), 2 for > 180 mg/dL."""
    low, high = EUGLYCAEMIC_LOW_MGDL, EUGLYCAEMIC_HIGH_MGDL
    return (glucose_mgdl >= low).astype(np.intp) + (glucose_mgdl > high)


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
    ref, pred = validate_pairs(reference_mgdl, predicted_mgdl)
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
    ref, pred = validate_pairs(reference_mgdl, predicted_mgdl)
    days = label_array(day, ref.shape[0], "day")
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


def _icc(hits: NDArray, n: NDArray, rho_degenerate: float = 1.0) -> float:
    """ANOVA intraclass correlation of a within-limit indicator by subject (Short et al.
    2020, Eq. 2), 0 where the estimate is negative. At a rate of 0 or 1 it is undefined
    and ``rho_degenerate`` is returned (1, the most conservative, as the reference
    implementation of Stephan et al. 2022 does)."""
    keep = n > 0
    x, m = hits[keep].astype(np.float64), n[keep].astype(np.float64)
    k, big_m = x.shape[0], m.sum()
    p = x.sum() / big_m
    if p in (0.0, 1.0):
        return rho_degenerate
    if k < 2:
        return 0.0
    bms = (np.sum(x * x / m) - x.sum() ** 2 / big_m) / (k - 1)
    dof_w = np.sum(m - 1.0)
    wms = (x.sum() - np.sum(x * x / m)) / dof_w if dof_w > 0 else 0.0
    n_star = (big_m**2 - float(np.sum(m * m))) / ((k - 1) * big_m)
    denom = bms + (n_star - 1.0) * wms
    return float(max(0.0, (bms - wms) / denom)) if denom > 0 else 0.0


def _wilson_cc_lower(hits: NDArray, n: NDArray, alpha: float, rho: float) -> float:
    """Clustered, continuity-corrected Wilson lower bound (Short et al. 2020, Eq. 6) for
    the intraclass correlation ``rho``; Newcombe's (1998) bound at ``rho = 0``."""
    m = n[n > 0].astype(np.float64)
    big_m = m.sum()
    p = float(hits.sum()) / big_m
    if p == 0.0:
        return 0.0
    xi = 1.0 + rho * (float(np.sum(m * m)) - big_m) / big_m  # design effect
    z = stats.norm.ppf(1.0 - alpha)
    root = np.sqrt(xi * z * z - 2.0 - 1.0 / big_m + 4.0 * p * (big_m * (1.0 - p) + 1.0))
    lower = (2 * big_m * p + xi * z * z - 1.0 - np.sqrt(xi) * z * root) / (
        2.0 * (big_m + xi * z * z))
    return float(max(lower, 0.0))


def _clopper_pearson_lower(hits: float, n: float, alpha: float) -> float:
    """Exact binomial (Clopper & Pearson 1934) one-sided lower bound: the ``alpha``
    quantile of Beta(x, n - x + 1); 0 at x = 0."""
    if hits <= 0:
        return 0.0
    return float(stats.beta.ppf(alpha, hits, n - hits + 1.0))


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


def _subject_counts(ref, pred, subj, n_subjects, range_codes):
    """The (range, limit) tasks and per-subject readings ``n[s, t]`` and hits ``h[s, t]``."""
    labels = (*GLUCOSE_RANGE_LABELS, _OVERALL)
    tasks, members, hits = [], [], []
    for limit in AGREEMENT_LIMITS:
        within_ranged = _within(ref, pred, range_codes, limit, absolute_low=True)
        within_rel = _within(ref, pred, range_codes, limit, absolute_low=False)
        for r, label in enumerate(labels):
            member = range_codes == r if label != _OVERALL else np.ones_like(ref, bool)
            within = within_ranged if label != _OVERALL else within_rel
            tasks.append((label, limit))
            members.append(member)
            hits.append(member & within)
    n_sub = np.zeros((n_subjects, len(tasks)))
    h_sub = np.zeros((n_subjects, len(tasks)))
    np.add.at(n_sub, subj, np.stack(members, axis=1))
    np.add.at(h_sub, subj, np.stack(hits, axis=1))
    return tasks, n_sub, h_sub


def _bootstrap_bounds(draws: NDArray[np.intp], n_sub, h_sub, est, alpha) -> NDArray:
    """BCa lower bound per task from cluster resamples ``draws[b, j]`` (subject codes)."""
    n_boot, n_subjects = draws.shape
    flat = (np.arange(n_boot)[:, None] * n_subjects + draws).ravel()
    weights = np.bincount(flat, minlength=n_boot * n_subjects).reshape(
        n_boot, n_subjects).astype(np.float64)  # times each subject was drawn
    n_tot, h_tot = n_sub.sum(axis=0), h_sub.sum(axis=0)
    with np.errstate(invalid="ignore", divide="ignore"):
        boot = 100.0 * (weights @ h_sub) / (weights @ n_sub)
        jack = 100.0 * (h_tot - h_sub) / (n_tot - n_sub)  # leave one subject out
    lower = np.full(n_sub.shape[1], np.nan)
    for t in range(n_sub.shape[1]):
        present = n_sub[:, t] > 0
        if n_tot[t] > 0:
            lower[t] = _bca_lower(boot[:, t], float(est[t]), jack[present, t], alpha)
    return lower


def _rate_table(ref, pred, subj, n_subjects, range_codes, *, method, n_boot, seed,
                confidence, draws=None) -> pd.DataFrame:
    """The table of :func:`agreement_rates`; ``draws`` (subject codes, one row per
    resample) replaces the seeded resamples, e.g. to replay another implementation's."""
    alpha = 1.0 - confidence
    tasks, n_sub, h_sub = _subject_counts(ref, pred, subj, n_subjects, range_codes)
    n_tot, h_tot = n_sub.sum(axis=0), h_sub.sum(axis=0)
    with np.errstate(invalid="ignore", divide="ignore"):
        est = 100.0 * h_tot / n_tot
    if method == "bootstrap":
        if draws is None:
            draws = np.random.default_rng(seed).integers(0, n_subjects, (n_boot, n_subjects))
        boot_lower = _bootstrap_bounds(np.asarray(draws), n_sub, h_sub, est, alpha)
    rows: list[dict] = []
    for t, (label, limit) in enumerate(tasks):
        n_t = int(n_tot[t])
        icc = _icc(h_sub[:, t], n_sub[:, t]) if n_t else float("nan")
        if n_t == 0:
            lower = float("nan")
        elif method == "clopper-pearson":
            lower = 100.0 * _clopper_pearson_lower(h_tot[t], n_tot[t], alpha)
        elif method == "wilson":
            lower = 100.0 * _wilson_cc_lower(h_sub[:, t], n_sub[:, t], alpha, icc)
        else:
            lower = float(boot_lower[t])
            if not np.isfinite(lower):  # no bootstrap spread: readings as independent
                lower = 100.0 * _wilson_cc_lower(h_sub[:, t], n_sub[:, t], alpha, 0.0)
        rows.append({
            "range": label,
            "limit": f"{limit} {'mg/dL' if label == '<70' else '%'}",
            "estimate_pct": float(est[t]) if n_t else float("nan"),
            "lower_bound_pct": lower,
            "n_readings": n_t,
            "n_subjects": int(np.count_nonzero(n_sub[:, t])),
            "icc": icc,
        })
    return pd.DataFrame(rows)


def _prepare_agreement(reference_mgdl, predicted_mgdl, subject_id, range_by, method, n_boot,
                       confidence):
    ref, pred = validate_pairs(reference_mgdl, predicted_mgdl)
    subj, uniq = subject_codes(subject_id, ref.shape[0])
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
      once), as in the reference implementation of Stephan et al. (2022);
    * ``method="clopper-pearson"``: the exact binomial bound (Clopper & Pearson 1934),
      the ``1 - confidence`` quantile of Beta(x, n - x + 1) for x of n readings within
      the limit (0 at x = 0). It takes the readings as *independent*, so on clustered
      data it is too optimistic; it is here for comparison, as the third column of
      Stephan et al. (2022).

    On the worked example of Stephan et al. (24 sensors, 3,600 paired readings; their
    repository's ``Test_Data.csv``), the rates, the Wilson and Clopper-Pearson bounds
    and the intraclass correlations equal the authors' published results, and the BCa
    bounds equal theirs when given their resamples (tests/metrics/
    test_metrics_cgm_worked.py).

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
    method : {"bootstrap", "wilson", "clopper-pearson"}, optional
        Lower-bound method (see above; the valid names are :data:`CI_METHODS`). [-]
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
        ``lower_bound_pct`` [%], ``n_readings``, ``n_subjects`` [-] and ``icc`` [-], the
        intraclass correlation by subject of being within the limit (Short et al.
        2020's ANOVA estimate, 0 where negative, 1 at a rate of 0 or 100 %: the value
        the Wilson bound uses; reported whatever the ``method``). A range without
        readings has NaN estimate, bound and ``icc``.

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
    .. [5] Clopper CJ, Pearson ES. The use of confidence or fiducial limits illustrated
       in the case of the binomial. Biometrika 26(4):404-413, 1934.
       doi:10.1093/biomet/26.4.404

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
        ("H", codes == 0, ref > EUGLYCAEMIC_HIGH_MGDL, "<70", "reference >180"),
        ("I", codes == 2, ref < EUGLYCAEMIC_LOW_MGDL, ">180", "reference <70"),
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

