"""What every estimator shares: reading a Dataset, a DataFrame or an array.

Estimators take a :class:`~nirglucose.dataset.Dataset`, a DataFrame with the schema's
measured columns, or a 2-D array whose columns are
:func:`~nirglucose.dataset.measured_columns` in order (ADC codes, reference codes,
physiological vector). They read the measured columns only, never ``true_*`` ones
(except :class:`~nirglucose.models.oracle.Oracle`).
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from ..constants import DEFAULT_LED_WAVELENGTHS_NM
from ..dataset import Dataset, measured_columns, validate_measurements
from ..exceptions import DataError

__all__ = ["MEASURED_COLUMNS", "N_MEASURED", "as_measurements"]

MEASURED_COLUMNS = tuple(measured_columns(DEFAULT_LED_WAVELENGTHS_NM))
N_MEASURED = len(MEASURED_COLUMNS)


def as_measurements(X, y=None, *, require_target: bool = False):
    """Return ``(X, y, groups)``: measured columns as float64 (n, 20), target, subject ids.

    Parameters
    ----------
    X : Dataset, pandas.DataFrame or array_like
        Measurements.
    y : array_like, optional
        Reference glucose [mg/dL]; taken from ``glucose_mgdl`` when X is a
        Dataset/DataFrame that has it and ``y`` is None.
    require_target : bool
        Raise if no target is found.

    Returns
    -------
    X : numpy.ndarray, (n, 20)
    y : numpy.ndarray or None
    groups : numpy.ndarray or None
        ``subject_id`` when present (for subject-grouped inner CV).
    """
    groups = None
    if isinstance(X, Dataset):
        X = X.frame
    if isinstance(X, pd.DataFrame):
        frame = X
        checked = validate_measurements(frame)
        Xa = checked[list(MEASURED_COLUMNS)].to_numpy(dtype=float)
        if y is None and "glucose_mgdl" in frame.columns:
            y = frame["glucose_mgdl"]
        if "subject_id" in frame.columns:
            groups = frame["subject_id"].to_numpy()
    else:
        Xa = np.asarray(X, dtype=float)
        if Xa.ndim != 2 or Xa.shape[1] != N_MEASURED:
            shape = Xa.shape
            raise DataError(
                f"expected a 2-D array with {N_MEASURED} measured columns "
                f"({', '.join(MEASURED_COLUMNS)}), got shape {shape}"
            )
        if not np.all(np.isfinite(Xa)):
            bad = np.flatnonzero(~np.isfinite(Xa).all(axis=1))
            raise DataError(
                f"input has NaN or infinite values in {len(bad)} rows, first row {bad[0]}"
            )
    if y is not None:
        y = np.asarray(y, dtype=float).ravel()
        if len(y) != len(Xa):
            raise DataError(f"X has {len(Xa)} rows but y has {len(y)}")
        if not np.all(np.isfinite(y)):
            raise DataError("target glucose_mgdl has NaN or infinite values")
    elif require_target:
        raise DataError("fitting needs reference glucose: a 'glucose_mgdl' column or y")
    return Xa, y, groups
