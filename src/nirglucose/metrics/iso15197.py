"""ISO 15197:2013 system-accuracy criteria for blood-glucose monitoring systems.

ISO 15197:2013, clause 6.3.3, sets two minimum acceptable criteria for system accuracy:

a) at least 95 % of the measured values fall within ±15 mg/dL of the reference at
   reference concentrations < 100 mg/dL, and within ±15 % at >= 100 mg/dL;
b) at least 99 % of the measured values fall within zones A and B of the consensus
   (Parkes) error grid for type 1 diabetes.

A value exactly on a limit (e.g. reference 80, prediction 95) counts as within; a
reference of exactly 100 mg/dL uses the ±15 % rule (which there equals ±15 mg/dL).
"""

from __future__ import annotations

from typing import Final

import numpy as np
from numpy.typing import ArrayLike, NDArray

from nirglucose.metrics._validation import _to_mgdl, _unit_factor, _validate_pairs
from nirglucose.metrics.error_grids import _parkes_codes

#: Results of an ISO 15197:2013 system-accuracy evaluation: 100 subjects x 3 reagent lots
#: x 2 measurements (clause 6.3). [-]
ISO_MIN_RESULTS: Final[int] = 600

__all__ = [
    "ISO15197_2013_THRESHOLD_MGDL",
    "ISO15197_2013_LIMIT_MGDL",
    "ISO15197_2013_LIMIT_PCT",
    "ISO15197_2013_REQUIRED_WITHIN_PCT",
    "ISO15197_2013_REQUIRED_ZONE_AB_PCT",
    "iso15197_2013",
    "iso15197_2013_zone_ab",
    "iso15197_2013_passes",
]

#: Reference concentration below which the absolute limit applies. [mg/dL]
ISO15197_2013_THRESHOLD_MGDL: Final[float] = 100.0
#: Absolute limit below the threshold. [mg/dL]
ISO15197_2013_LIMIT_MGDL: Final[float] = 15.0
#: Relative limit at and above the threshold. [%]
ISO15197_2013_LIMIT_PCT: Final[float] = 15.0
#: Criterion a): minimum share of values within the limits. [%]
ISO15197_2013_REQUIRED_WITHIN_PCT: Final[float] = 95.0
#: Criterion b): minimum share of values in consensus-grid zones A + B. [%]
ISO15197_2013_REQUIRED_ZONE_AB_PCT: Final[float] = 99.0


def _iso_within_count(absdiff: NDArray[np.float64], ref: NDArray[np.float64]) -> int:
    # Below 100 mg/dL: |d| <= 15 mg/dL; at and above: |d| <= 15 % of the reference.
    # 15 % of the reference is < 15 mg/dL exactly when the reference is < 100 mg/dL, so
    # the limit is max(15 mg/dL, 15 % ref) and "within" is the OR of the two tests
    # (written 100 |d| <= 15 ref to compare integer inputs exactly).
    mask = (absdiff <= ISO15197_2013_LIMIT_MGDL) | (
        100.0 * absdiff <= ISO15197_2013_LIMIT_PCT * ref
    )
    return int(np.count_nonzero(mask))


def _zone_ab_count(ref: NDArray[np.float64], pred: NDArray[np.float64]) -> int:
    return int(np.count_nonzero(_parkes_codes(ref, pred, 1) <= 1))


def _prepare(
    y_true: ArrayLike, y_pred: ArrayLike, units: str, allow_negative_pred: bool
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    _unit_factor(units)
    ref, pred = _validate_pairs(y_true, y_pred, allow_negative_pred=allow_negative_pred)
    return _to_mgdl(ref, pred, units)


def iso15197_2013(y_true: ArrayLike, y_pred: ArrayLike, *, units: str = "mg/dL") -> float:
    """Fraction of values within the ISO 15197:2013 accuracy limits (criterion a).

    A pair is within when ``|y_pred - y_true| <= 15 mg/dL`` for ``y_true < 100 mg/dL``
    and ``|y_pred - y_true| <= 15 % of y_true`` for ``y_true >= 100 mg/dL``
    (ISO 15197:2013, 6.3.3 a); limits are inclusive. The standard requires >= 95 %.

    Parameters
    ----------
    y_true : array_like
        Reference glucose, strictly positive. [mg/dL, or ``units``]
    y_pred : array_like
        Measured / predicted glucose, same length. [mg/dL, or ``units``]
    units : {"mg/dL", "mmol/L"}, optional
        Unit of both inputs (converted with 18.016 mg/dL per mmol/L). [-]

    Returns
    -------
    float
        Fraction of pairs within the limits, in [0, 1]. [-]

    Raises
    ------
    DataError
        On a length mismatch, empty input, NaN or infinite values, a reference value
        <= 0, or unknown ``units``.

    References
    ----------
    .. [1] ISO 15197:2013. In vitro diagnostic test systems -- Requirements for
       blood-glucose monitoring systems for self-testing in managing diabetes mellitus,
       clause 6.3.3. International Organization for Standardization, Geneva, 2013.
    .. [2] Pfützner A, Klonoff DC, Pardo S, Parkes JL. Technical aspects of the Parkes
       error grid. J Diabetes Sci Technol 7(5):1275-1281, 2013.
       doi:10.1177/193229681300700517

    Examples
    --------
    >>> iso15197_2013([80, 80, 200, 200], [95, 96, 230, 231])
    0.5
    """
    ref, pred = _prepare(y_true, y_pred, units, allow_negative_pred=True)
    return _iso_within_count(np.abs(pred - ref), ref) / ref.shape[0]


def iso15197_2013_zone_ab(y_true: ArrayLike, y_pred: ArrayLike, *, units: str = "mg/dL") -> float:
    """Fraction of values in zones A + B of the type 1 consensus grid (criterion b).

    ISO 15197:2013, 6.3.3 b) requires >= 99 % of the values in zones A and B of the
    consensus (Parkes) error grid for type 1 diabetes; zones as in
    :func:`~nirglucose.metrics.error_grids.parkes_zones` with ``diabetes_type=1``.

    Parameters
    ----------
    y_true : array_like
        Reference glucose, strictly positive. [mg/dL, or ``units``]
    y_pred : array_like
        Measured / predicted glucose, non-negative, same length. [mg/dL, or ``units``]
    units : {"mg/dL", "mmol/L"}, optional
        Unit of both inputs (converted with 18.016 mg/dL per mmol/L). [-]

    Returns
    -------
    float
        Fraction of pairs in zones A or B, in [0, 1]. [-]

    Raises
    ------
    DataError
        As :func:`iso15197_2013`, and on a negative prediction.

    References
    ----------
    .. [1] ISO 15197:2013. In vitro diagnostic test systems -- Requirements for
       blood-glucose monitoring systems for self-testing in managing diabetes mellitus,
       clause 6.3.3. International Organization for Standardization, Geneva, 2013.
    .. [2] Pfützner A, Klonoff DC, Pardo S, Parkes JL. Technical aspects of the Parkes
       error grid. J Diabetes Sci Technol 7(5):1275-1281, 2013.
       doi:10.1177/193229681300700517

    Examples
    --------
    >>> iso15197_2013_zone_ab([100, 100, 100, 100], [110, 150, 200, 100])
    0.75
    """
    ref, pred = _prepare(y_true, y_pred, units, allow_negative_pred=False)
    return _zone_ab_count(ref, pred) / ref.shape[0]


def iso15197_2013_passes(y_true: ArrayLike, y_pred: ArrayLike, *, units: str = "mg/dL") -> bool:
    """Whether both ISO 15197:2013 system-accuracy criteria (6.3.3 a and b) are met.

    True when at least 95 % of the pairs are within the limits of
    :func:`iso15197_2013` *and* at least 99 % lie in consensus-grid (type 1) zones
    A + B (:func:`iso15197_2013_zone_ab`). The comparison is done on counts
    (``100 * count >= 95 * n``), so exactly 95 % / 99 % passes.

    Parameters
    ----------
    y_true : array_like
        Reference glucose, strictly positive. [mg/dL, or ``units``]
    y_pred : array_like
        Measured / predicted glucose, non-negative, same length. [mg/dL, or ``units``]
    units : {"mg/dL", "mmol/L"}, optional
        Unit of both inputs (converted with 18.016 mg/dL per mmol/L). [-]

    Returns
    -------
    bool
        True if both criteria pass. [-]

    Raises
    ------
    DataError
        As :func:`iso15197_2013_zone_ab`.

    References
    ----------
    .. [1] ISO 15197:2013. In vitro diagnostic test systems -- Requirements for
       blood-glucose monitoring systems for self-testing in managing diabetes mellitus,
       clause 6.3.3. International Organization for Standardization, Geneva, 2013.
    .. [2] Pfützner A, Klonoff DC, Pardo S, Parkes JL. Technical aspects of the Parkes
       error grid. J Diabetes Sci Technol 7(5):1275-1281, 2013.
       doi:10.1177/193229681300700517

    Examples
    --------
    >>> iso15197_2013_passes([80, 200], [90, 220])
    True
    >>> iso15197_2013_passes([80, 200], [90, 240])
    False
    """
    ref, pred = _prepare(y_true, y_pred, units, allow_negative_pred=False)
    n = ref.shape[0]
    if n < ISO_MIN_RESULTS:
        import warnings

        warnings.warn(
            f"ISO 15197:2013 system accuracy is evaluated on at least {ISO_MIN_RESULTS} "
            f"results (100 subjects, 3 reagent lots, clause 6.3); a verdict on {n} "
            "pairs is not the standard's", UserWarning, stacklevel=2)
    n_within = _iso_within_count(np.abs(pred - ref), ref)
    within_ok = 100 * n_within >= ISO15197_2013_REQUIRED_WITHIN_PCT * n
    zone_ok = 100 * _zone_ab_count(ref, pred) >= ISO15197_2013_REQUIRED_ZONE_AB_PCT * n
    return bool(within_ok and zone_ok)
