"""Shared input validation and unit conversion for the metrics subpackage.

Every public metric funnels its inputs through :func:`_validate_pairs`, so all of them
reject the same bad inputs with the same :class:`~nirglucose.exceptions.DataError`
messages (which name the problem, how many values are bad and the first bad index).
"""

from __future__ import annotations

from typing import Final

import numpy as np
import pandas as pd
from numpy.typing import ArrayLike, NDArray

from nirglucose.constants import MGDL_PER_MMOLL_GLUCOSE
from nirglucose.exceptions import DataError

__all__ = ["MGDL_PER_MMOLL", "VALID_UNITS"]

#: Below this median a mg/dL reference reads as mmol/L (as nirglucose.dataset.files). [mg/dL]
_MMOLL_SUSPECT_MEDIAN_MGDL = 35.0

#: Highest glucose a meter reports (Roche Accu-Chek Guide and Abbott FreeStyle Lite user
#: manuals: 20-600 mg/dL; as nirglucose.dataset.GLUCOSE_REPORTING_RANGE_MGDL). [mg/dL]
_METER_MAX_MGDL = 600.0

#: mg/dL per mmol/L of glucose (molar mass 180.16 g/mol / 10 dL/L). [mg/dL per mmol/L]
MGDL_PER_MMOLL: Final[float] = MGDL_PER_MMOLL_GLUCOSE

#: Glucose units accepted by the metrics, with the factor that converts them to mg/dL.
_UNIT_FACTORS: Final[dict[str, float]] = {"mg/dL": 1.0, "mmol/L": MGDL_PER_MMOLL}

#: The spellings accepted for ``units`` (matched case-insensitively).
VALID_UNITS: Final[tuple[str, ...]] = tuple(_UNIT_FACTORS)


def _unit_factor(units: str) -> float:
    """Return the factor converting ``units`` to mg/dL; raise on an unknown unit."""
    if isinstance(units, str):
        for name, factor in _UNIT_FACTORS.items():
            if units.strip().lower() == name.lower():
                return factor
    raise DataError(f"unknown glucose units {units!r}; valid units are {list(VALID_UNITS)}")


def _describe_bad(mask: NDArray[np.bool_]) -> str:
    """Return 'N value(s), first at index I' for a boolean mask with at least one True."""
    count = int(np.count_nonzero(mask))
    first = int(np.argmax(mask))
    noun = "value" if count == 1 else "values"
    return f"{count} {noun}, first at index {first}"


def _as_1d_float(values: ArrayLike, name: str) -> NDArray[np.float64]:
    """Convert ``values`` to a 1-D float64 array or raise :class:`DataError`."""
    try:
        arr = np.asarray(values, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise DataError(f"{name} must be numeric: {exc}") from exc
    if arr.ndim != 1:
        raise DataError(f"{name} must be one-dimensional, got shape {arr.shape}")
    return arr


def _validate_pairs(
    y_true: ArrayLike,
    y_pred: ArrayLike,
    *,
    allow_negative_pred: bool = True,
    min_size: int = 1,
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Validate paired reference / predicted glucose and return them as float arrays.

    Checks, in this order: numeric and one-dimensional, equal length, at least
    ``min_size`` pairs, no NaN, no infinity, reference strictly positive and (when
    ``allow_negative_pred`` is false) prediction non-negative.

    Parameters
    ----------
    y_true : array_like
        Reference glucose. [any glucose unit]
    y_pred : array_like
        Predicted glucose. [same unit as ``y_true``]
    allow_negative_pred : bool, optional
        Accept negative predictions (fine for error statistics, meaningless on an error
        grid). [-]
    min_size : int, optional
        Smallest number of pairs accepted. [-]

    Returns
    -------
    tuple of numpy.ndarray
        ``(y_true, y_pred)`` as 1-D float64 arrays. [same unit as the input]

    Raises
    ------
    DataError
        On any failed check; the message names the array, the problem, the number of
        bad values and the index of the first one.
    """
    ref = _as_1d_float(y_true, "y_true")
    pred = _as_1d_float(y_pred, "y_pred")
    if ref.shape[0] != pred.shape[0]:
        raise DataError(
            f"y_true and y_pred differ in length: {ref.shape[0]} reference values, "
            f"{pred.shape[0]} predictions"
        )
    if ref.shape[0] < min_size:
        if ref.shape[0] == 0:
            raise DataError("y_true and y_pred are empty; at least one pair is needed")
        raise DataError(f"at least {min_size} pairs are needed, got {ref.shape[0]}")
    for name, arr in (("y_true", ref), ("y_pred", pred)):
        if np.isfinite(arr).all():  # fast path: details only when something is wrong
            continue
        nan = np.isnan(arr)
        if nan.any():
            raise DataError(f"{name} contains NaN: {_describe_bad(nan)}")
        raise DataError(f"{name} contains infinite values: {_describe_bad(np.isinf(arr))}")
    if ref.min() <= 0.0:
        raise DataError(
            f"y_true must be strictly positive (a reference glucose of 0 or below is not "
            f"physical): {_describe_bad(ref <= 0.0)}"
        )
    if not allow_negative_pred and pred.min() < 0.0:
        raise DataError(
            f"y_pred must be non-negative for an error grid (a negative glucose is not "
            f"physical; clip explicitly with np.clip(y_pred, 0, None) if intended): "
            f"{_describe_bad(pred < 0.0)}"
        )
    return ref, pred


def _to_mgdl(
    ref: NDArray[np.float64], pred: NDArray[np.float64], units: str
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Convert already-validated arrays from ``units`` to mg/dL (no copy for mg/dL)."""
    factor = _unit_factor(units)
    if factor == 1.0:
        if ref.size and float(np.median(ref)) < _MMOLL_SUSPECT_MEDIAN_MGDL:
            import warnings

            warnings.warn(
                f"reference glucose (median {float(np.median(ref)):g}) looks like mmol/L, "
                "not mg/dL; pass units='mmol/L' or the zones are those of mg/dL values",
                UserWarning, stacklevel=3)
        return ref, pred
    top = float(np.max(ref)) if ref.size else 0.0
    if top * factor > _METER_MAX_MGDL:  # no meter reports it: mg/dL values, surely
        import warnings

        warnings.warn(
            f"reference glucose up to {top:g} {units} is above what a meter reports "
            f"({_METER_MAX_MGDL / factor:.1f} {units} = {_METER_MAX_MGDL:g} mg/dL): it looks "
            "like mg/dL; pass units='mg/dL' or the zones are those of impossible values",
            UserWarning, stacklevel=3)
    return ref * factor, pred * factor


# --- labelled series of a worn monitor (metrics.cgm, .trend, .time_in_range) ---------


def label_array(values: ArrayLike, n: int, name: str) -> NDArray:
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


def time_array(time_min: ArrayLike, n: int) -> NDArray[np.float64]:
    t = _as_1d_float(time_min, "time_min")
    if t.shape[0] != n:
        raise DataError(f"time_min has {t.shape[0]} values but there are {n} readings")
    bad = ~np.isfinite(t)
    if bad.any():
        raise DataError(f"time_min contains NaN or infinite values: {_describe_bad(bad)}")
    return t


def subject_codes(subject_id: ArrayLike, n: int) -> tuple[NDArray[np.intp], NDArray]:
    ids = label_array(subject_id, n, "subject_id")
    try:
        uniq, codes = np.unique(ids, return_inverse=True)
    except TypeError as exc:  # e.g. ints mixed with strings in an object array
        raise DataError(f"subject_id values must be of one sortable type: {exc}") from exc
    return codes.astype(np.intp), uniq


#: Public names of the shared checks, for the worn-monitor modules (cgm, trend,
#: time_in_range): the same functions as the underscored ones the older modules import.
as_1d_float = _as_1d_float
describe_bad = _describe_bad
validate_pairs = _validate_pairs
