"""Rates of change, trend agreement and the sensor's lag, for a worn monitor.

* :func:`rate_of_change`, :func:`rate_categories`, :func:`trend_agreement` -- rates of
  change from consecutive readings, their categories (trend-arrow bands) and the
  agreement of the categories (a confusion matrix);
* :func:`estimated_lag` -- the time shift that best aligns the sensor to the reference,
  per subject.

Split from :mod:`nirglucose.metrics.cgm` (the agreement standards), with which it shares
the validation of labelled series (:mod:`nirglucose.metrics._validation`).
"""

from __future__ import annotations

from typing import Final, NamedTuple

import numpy as np
import pandas as pd
from numpy.typing import ArrayLike, NDArray

from nirglucose.exceptions import DataError
from nirglucose.metrics._validation import (
    as_1d_float,
    describe_bad,
    subject_codes,
    time_array,
    validate_pairs,
)

__all__ = [
    "TREND_EDGES_MGDL_PER_MIN",
    "TrendAgreement",
    "LagEstimate",
    "rate_of_change",
    "rate_categories",
    "trend_agreement",
    "estimated_lag",
]

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
    g = as_1d_float(glucose_mgdl, "glucose_mgdl")
    bad = ~np.isfinite(g)
    if bad.any():
        raise DataError(f"glucose_mgdl contains NaN or infinite values: {describe_bad(bad)}")
    subj, _ = subject_codes(subject_id, g.shape[0])
    t = time_array(time_min, g.shape[0])
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
    # A rate on an edge belongs to the category nearer zero (see rate_categories).
    labels = [f"<{edges[0]:g}" if edges[0] <= 0 else f"<={edges[0]:g}"]
    labels += [f"{lo:g}..{hi:g}" for lo, hi in zip(edges[:-1], edges[1:], strict=True)]
    return labels + [f">{edges[-1]:g}" if edges[-1] > 0 else f">={edges[-1]:g}"]


def _check_edges(edges_mgdl_per_min) -> NDArray[np.float64]:
    edges = np.asarray(edges_mgdl_per_min, dtype=np.float64)
    if edges.ndim != 1 or edges.shape[0] == 0 or np.any(np.diff(edges) <= 0) or not np.all(
            np.isfinite(edges)):
        raise DataError(f"edges_mgdl_per_min must be finite and strictly increasing, got "
                        f"{tuple(edges_mgdl_per_min)!r}")
    return edges


def _categories(rate: NDArray[np.float64], edges: NDArray[np.float64]) -> NDArray[np.intp]:
    above = np.searchsorted(edges, rate, side="left")   # an edge joins the lower band
    below = np.searchsorted(edges, rate, side="right")  # an edge joins the upper band
    return np.where(rate > 0, above, below).astype(np.intp)


def rate_categories(
    rate_mgdl_per_min: ArrayLike,
    *,
    edges_mgdl_per_min: tuple[float, ...] = TREND_EDGES_MGDL_PER_MIN,
) -> NDArray[np.intp]:
    """Trend category of each rate of change: the band between consecutive edges.

    Category ``0`` lies below the first edge and category ``len(edges)`` above the
    last. A rate *on* an edge falls in the category nearer zero, as in the clinical
    trend concurrence analysis of Eichenlaub et al. (2024): with the default edges,
    ``-1 <= rate <= 1`` is steady, ``1 < rate <= 2`` rising, ``rate > 2`` rising fast, and
    the same mirrored below zero, so a fall and a rise of the same size get mirrored
    categories (integer readings 5 minutes apart give rates of exactly 1 or 2
    mg/dL/min often). A rate of exactly 0 on an edge of 0 goes to the category above.

    Parameters
    ----------
    rate_mgdl_per_min : array_like
        Rates of change, e.g. from :func:`rate_of_change`; NaN allowed. [mg/dL/min]
    edges_mgdl_per_min : tuple of float, optional
        Strictly increasing category edges. [mg/dL/min]

    Returns
    -------
    numpy.ndarray
        Category index of each rate, ``0 .. len(edges)``; ``-1`` where the rate is
        NaN. [-]

    Raises
    ------
    DataError
        On edges that are not finite and strictly increasing, or an infinite rate.

    References
    ----------
    .. [1] Eichenlaub M, Pleus S, Freckmann G. A proposal for the clinical
       characterization of continuous glucose monitoring trend arrow accuracy.
       J Diabetes Sci Technol, 2024. doi:10.1177/19322968241232679 (categories
       '<-3', '-3 to <-2', '-2 to <-1', '-1 to +1', '>+1 to +2', '>+2 to +3', '>+3').

    Examples
    --------
    >>> rate_categories([-2.0, -1.0, 0.0, 1.0, 1.5, 2.0, 2.5, np.nan]).tolist()
    [1, 2, 2, 2, 3, 3, 4, -1]
    """
    edges = _check_edges(edges_mgdl_per_min)
    rate = as_1d_float(rate_mgdl_per_min, "rate_mgdl_per_min")
    if np.isinf(rate).any():
        raise DataError("rate_mgdl_per_min contains infinite values: "
                        f"{describe_bad(np.isinf(rate))}")
    out = _categories(rate, edges)
    out[np.isnan(rate)] = -1
    return out


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
    category bounded by ``edges_mgdl_per_min`` (:func:`rate_categories`: a rate on an
    edge belongs to the category nearer zero; by default < -2, -2..-1, -1..1 (both
    included), 1..2, > 2 mg/dL/min). The result is the confusion matrix of the
    categories (rows: reference, columns: device) and the share on its diagonal.

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
    .. [3] Eichenlaub M, Pleus S, Freckmann G. A proposal for the clinical
       characterization of continuous glucose monitoring trend arrow accuracy.
       J Diabetes Sci Technol, 2024. doi:10.1177/19322968241232679 (edges joining the
       category nearer zero).

    Examples
    --------
    >>> r = trend_agreement([100, 110, 100], [100, 109, 95], [1, 1, 1], [0, 5, 10])
    >>> r.agreement_pct, r.n_pairs
    (50.0, 2)
    """
    ref, pred = validate_pairs(reference_mgdl, predicted_mgdl)
    edges = _check_edges(edges_mgdl_per_min)
    subj, _ = subject_codes(subject_id, ref.shape[0])
    t = time_array(time_min, ref.shape[0])
    order = _order(subj, t)
    gap = _check_gap(max_gap_min)
    rr, rp = _rates(ref, subj, t, order, gap), _rates(pred, subj, t, order, gap)
    keep = np.isfinite(rr)
    if not keep.any():
        raise DataError("no subject has two readings; a rate of change needs two")
    cr, cp = _categories(rr[keep], edges), _categories(rp[keep], edges)
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
    ref, pred = validate_pairs(reference_mgdl, predicted_mgdl)
    if not (np.isfinite(max_lag_min) and max_lag_min > 0):
        raise DataError(f"max_lag_min must be positive, got {max_lag_min!r}")
    subj, uniq = subject_codes(subject_id, ref.shape[0])
    t = time_array(time_min, ref.shape[0])
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
                who = uniq[s_sorted[a:a + 1]].tolist()[0]  # a Python value, not np.int64(3)
                raise DataError(
                    f"subject {who!r}: readings are not uniformly spaced in time (intervals "
                    f"from {dts.min():g} to {dts.max():g} min); resample first")
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

