"""Point-accuracy statistics of a glucose estimate: RMSE, MARD, bias, agreement.

All functions follow the scikit-learn convention ``metric(y_true, y_pred, *, options)``
with the reference first. Errors are ``y_pred - y_true`` (positive = over-reading).
Negative predictions are accepted here (they are valid inputs to an error statistic);
reference values must be strictly positive.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from nirglucose.exceptions import DataError
from nirglucose.metrics._validation import _validate_pairs

__all__ = [
    "BlandAltmanResult",
    "rmse",
    "mard",
    "mean_bias",
    "within_percent",
    "bland_altman",
]

#: Quantile of the standard normal distribution for 95 % limits of agreement
#: (Bland & Altman 1986 use 1.96). [-]
_LOA_Z = 1.96


class BlandAltmanResult(NamedTuple):
    """Bias and 95 % limits of agreement; unpacks as ``(bias, lower_loa, upper_loa)``."""

    bias: float
    lower_loa: float
    upper_loa: float


# --- kernels on validated float arrays (shared with :mod:`summary`) -----------------


def _rmse(diff: NDArray[np.float64]) -> float:
    scale = float(np.max(np.abs(diff))) if diff.size else 0.0
    if not scale or scale < 1e150:  # the plain sum cannot overflow
        return float(np.sqrt(np.dot(diff, diff) / diff.shape[0]))
    d = diff / scale  # scaled first: values near 1e200 would square to inf
    return scale * float(np.sqrt(np.dot(d, d) / diff.shape[0]))


def _mard(absdiff: NDArray[np.float64], ref: NDArray[np.float64]) -> float:
    return float(100.0 * np.mean(absdiff / ref))


def _mean_bias(diff: NDArray[np.float64]) -> float:
    return float(np.mean(diff))


def _within_mask(
    absdiff: NDArray[np.float64], ref: NDArray[np.float64], pct: float
) -> NDArray[np.bool_]:
    # |pred - ref| <= pct/100 * ref, written as 100 |d| <= pct * ref so that integer
    # glucose values on the boundary compare exactly (0.15 * 200 is not 30 in binary).
    return 100.0 * absdiff <= pct * ref


def _bland_altman_from_diff(diff: NDArray[np.float64]) -> BlandAltmanResult:
    bias = float(np.mean(diff))
    sd = float(np.std(diff, ddof=1)) if diff.shape[0] > 1 else float("nan")
    return BlandAltmanResult(bias, bias - _LOA_Z * sd, bias + _LOA_Z * sd)


def _relative_diff(ref: NDArray[np.float64], pred: NDArray[np.float64]) -> NDArray[np.float64]:
    return 100.0 * (pred - ref) / (0.5 * (pred + ref))


# --- public API ------------------------------------------------------------------------


def rmse(y_true: ArrayLike, y_pred: ArrayLike) -> float:
    """Root-mean-square error of the prediction.

    ``RMSE = sqrt(mean((y_pred - y_true) ** 2))``, the usual root-mean-square deviation
    (e.g. Hyndman & Koehler 2006).

    Parameters
    ----------
    y_true : array_like
        Reference glucose, strictly positive. [mg/dL or mmol/L]
    y_pred : array_like
        Predicted glucose, same length and unit. [mg/dL or mmol/L]

    Returns
    -------
    float
        Root-mean-square error. [unit of the inputs]

    Raises
    ------
    DataError
        On a length mismatch, empty input, NaN or infinite values, or a reference
        value <= 0.

    References
    ----------
    .. [1] Hyndman RJ, Koehler AB. Another look at measures of forecast accuracy.
       Int J Forecast 22(4):679-688, 2006. doi:10.1016/j.ijforecast.2006.03.001

    Examples
    --------
    >>> rmse([100.0, 200.0], [110.0, 190.0])
    10.0
    """
    ref, pred = _validate_pairs(y_true, y_pred)
    return _rmse(pred - ref)


def mard(y_true: ArrayLike, y_pred: ArrayLike) -> float:
    """Mean absolute relative difference, in percent.

    ``MARD = 100 * mean(|y_pred - y_true| / y_true)``, relative to the reference value,
    as used for continuous glucose monitors (Reiterer et al. 2017).

    Parameters
    ----------
    y_true : array_like
        Reference glucose, strictly positive. [mg/dL or mmol/L]
    y_pred : array_like
        Predicted glucose, same length and unit. [mg/dL or mmol/L]

    Returns
    -------
    float
        MARD. [%]

    Raises
    ------
    DataError
        On a length mismatch, empty input, NaN or infinite values, or a reference
        value <= 0.

    References
    ----------
    .. [1] Reiterer F, Polterauer P, Schoemaker M, et al. Significance and reliability
       of MARD for the accuracy of CGM systems. J Diabetes Sci Technol 11(1):59-67,
       2017. doi:10.1177/1932296816662047

    Examples
    --------
    >>> mard([100.0, 200.0], [110.0, 180.0])
    10.0
    """
    ref, pred = _validate_pairs(y_true, y_pred)
    return _mard(np.abs(pred - ref), ref)


def mean_bias(y_true: ArrayLike, y_pred: ArrayLike) -> float:
    """Mean signed error ``mean(y_pred - y_true)`` (positive = over-reading).

    This is the "bias" of Bland & Altman (1986): the mean of the differences,
    prediction minus reference.

    Parameters
    ----------
    y_true : array_like
        Reference glucose, strictly positive. [mg/dL or mmol/L]
    y_pred : array_like
        Predicted glucose, same length and unit. [mg/dL or mmol/L]

    Returns
    -------
    float
        Mean bias. [unit of the inputs]

    Raises
    ------
    DataError
        On a length mismatch, empty input, NaN or infinite values, or a reference
        value <= 0.

    References
    ----------
    .. [1] Bland JM, Altman DG. Statistical methods for assessing agreement between two
       methods of clinical measurement. Lancet 327(8476):307-310, 1986.
       doi:10.1016/S0140-6736(86)90837-8

    Examples
    --------
    >>> mean_bias([100.0, 200.0], [110.0, 196.0])
    3.0
    """
    ref, pred = _validate_pairs(y_true, y_pred)
    return _mean_bias(pred - ref)


def within_percent(y_true: ArrayLike, y_pred: ArrayLike, pct: float) -> float:
    """Fraction of predictions within ``pct`` percent of the reference.

    A pair counts when ``|y_pred - y_true| <= pct / 100 * y_true``; a pair exactly on
    the limit counts as within (the "within ±20 %" / "%20/20" convention of CGM
    accuracy reports, e.g. Kovatchev et al. 2004).

    Parameters
    ----------
    y_true : array_like
        Reference glucose, strictly positive. [mg/dL or mmol/L]
    y_pred : array_like
        Predicted glucose, same length and unit. [mg/dL or mmol/L]
    pct : float
        Allowed relative deviation, non-negative and finite (15 means ±15 %). [%]

    Returns
    -------
    float
        Fraction of pairs within the limit, in [0, 1]. [-]

    Raises
    ------
    DataError
        On bad arrays (see :func:`rmse`) or a negative / non-finite ``pct``.

    References
    ----------
    .. [1] Kovatchev BP, Gonder-Frederick LA, Cox DJ, Clarke WL. Evaluating the
       accuracy of continuous glucose-monitoring sensors. Diabetes Care
       27(8):1922-1928, 2004. doi:10.2337/diacare.27.8.1922

    Examples
    --------
    >>> within_percent([100.0, 200.0, 300.0, 400.0], [120.0, 250.0, 300.0, 330.0], 20)
    0.75
    """
    pct_f = float(pct)
    if not np.isfinite(pct_f) or pct_f < 0.0:
        raise DataError(f"pct must be a finite, non-negative percentage, got {pct!r}")
    ref, pred = _validate_pairs(y_true, y_pred)
    return float(np.count_nonzero(_within_mask(np.abs(pred - ref), ref, pct_f)) / ref.shape[0])


def bland_altman(
    y_true: ArrayLike, y_pred: ArrayLike, *, relative: bool = False
) -> BlandAltmanResult:
    """Bland–Altman bias and 95 % limits of agreement.

    Differences are ``d = y_pred - y_true``; ``bias = mean(d)``, ``SD`` is the sample
    standard deviation of ``d`` (ddof = 1) and the limits of agreement are
    ``bias ± 1.96 SD`` (Bland & Altman 1986). With ``relative=True`` the differences
    are expressed relative to the mean of each pair,
    ``d = 100 (y_pred - y_true) / ((y_pred + y_true) / 2)``, the percentage-difference
    plot of Bland & Altman (1999), and all three results are in percent. Relative
    differences need non-negative predictions (so that every pair mean is positive).

    Parameters
    ----------
    y_true : array_like
        Reference glucose, strictly positive, at least two pairs. [mg/dL or mmol/L]
    y_pred : array_like
        Predicted glucose, same length and unit. [mg/dL or mmol/L]
    relative : bool, optional
        Use percentage differences relative to the pair mean. [-]

    Returns
    -------
    BlandAltmanResult
        Named tuple ``(bias, lower_loa, upper_loa)``. [unit of the inputs, or % when
        ``relative``]

    Raises
    ------
    DataError
        On bad arrays (see :func:`rmse`), fewer than two pairs, or a negative
        prediction with ``relative=True``.

    References
    ----------
    .. [1] Bland JM, Altman DG. Statistical methods for assessing agreement between two
       methods of clinical measurement. Lancet 327(8476):307-310, 1986.
       doi:10.1016/S0140-6736(86)90837-8
    .. [2] Bland JM, Altman DG. Measuring agreement in method comparison studies.
       Stat Methods Med Res 8(2):135-160, 1999. doi:10.1177/096228029900800204

    Examples
    --------
    >>> bias, low, high = bland_altman([100.0, 100.0], [98.0, 102.0])
    >>> bias, round(low, 4), round(high, 4)
    (0.0, -5.5437, 5.5437)
    """
    ref, pred = _validate_pairs(y_true, y_pred, allow_negative_pred=not relative, min_size=2)
    diff = _relative_diff(ref, pred) if relative else pred - ref
    return _bland_altman_from_diff(diff)
