"""Input and fitted-state checks shared by the linear models and the oracle.

Arrays go through :func:`sklearn.utils.check_array` first (the standard messages for
sparse, complex, empty, non-numeric and non-finite input), then must have exactly the
20 measured columns; DataFrames and Datasets go through
:func:`~nirglucose.models._base.as_measurements` (column names, ADC ranges).
"""

from __future__ import annotations

import numpy as np
import pandas as pd
from sklearn.exceptions import NotFittedError as _SkNotFittedError
from sklearn.utils import check_array
from sklearn.utils.validation import check_is_fitted

from ..dataset import Dataset
from ..exceptions import DataError, NotFittedError
from ._base import MEASURED_COLUMNS, N_MEASURED, as_measurements

__all__ = ["EstimatorNotFittedError", "require_fitted", "measured_input"]


class EstimatorNotFittedError(NotFittedError, _SkNotFittedError):
    """Used before ``fit``: both nirglucose's and scikit-learn's NotFittedError."""


def require_fitted(est, attr: str) -> None:
    """Raise :class:`EstimatorNotFittedError` unless ``est`` has the fitted ``attr``."""
    try:
        check_is_fitted(est, attr)
    except _SkNotFittedError:
        raise EstimatorNotFittedError(
            f"this {type(est).__name__} is not fitted yet; call fit before using it"
        ) from None


def measured_input(est, X, y=None, *, fit: bool, finite: bool = True):
    """``(X (n, 20) float64, y or None, groups or None)`` from any accepted input.

    Parameters
    ----------
    est : estimator
        For messages.
    X : Dataset, pandas.DataFrame or array_like
        Measurements.
    y : array_like, optional
        Target [mg/dL] (required for arrays when ``fit``).
    fit : bool
        Whether a target is required.
    finite : bool
        Check arrays for NaN/inf here (False: the caller checks its output instead).
    """
    if isinstance(X, pd.DataFrame | Dataset):
        return as_measurements(X, y, require_target=fit)
    name = type(est).__name__
    if type(X) is np.ndarray and X.dtype == np.float64 and X.ndim == 2 and X.size:
        # What check_array would return, without its overhead (it dominates the latency
        # of a one-row prediction); anything unusual still goes through check_array.
        Xa = X
        if finite and not np.isfinite(Xa).all():
            check_array(Xa, estimator=est, input_name="X")  # raises its standard message
    else:
        Xa = check_array(
            X, dtype=np.float64, ensure_all_finite=finite, estimator=est, input_name="X"
        )
    if fit and y is None:
        raise DataError(
            f"{name} requires y to be passed, but the target y is None (give y, or a "
            "DataFrame/Dataset with a glucose_mgdl column)"
        )
    if Xa.shape[1] != N_MEASURED:
        raise DataError(
            f"{name} takes the {N_MEASURED} measured columns ({', '.join(MEASURED_COLUMNS)}); "
            f"got an array with {Xa.shape[1]}"
        )
    if y is not None:
        y = check_array(y, ensure_2d=False, dtype=np.float64, input_name="y", estimator=est)
        if y.ndim != 1:
            y = y.ravel() if y.ndim == 2 and y.shape[1] == 1 else y
        if y.ndim != 1 or len(y) != len(Xa):
            raise DataError(f"y must be one value per row of X ({len(Xa)}), got shape {y.shape}")
    return Xa, y, None
