"""What every estimator shares: reading its input through the one schema boundary.

Estimators take a :class:`~nirglucose.dataset.Dataset` or a DataFrame of any device
(``adc_<nm>`` for any LEDs, optional ``adc_ref_<nm>``, any known physiological
columns; :class:`~nirglucose.dataset.schema.DeviceSchema` reads them), or a plain 2-D numeric
array. ``fit`` records the device as ``schema_``; ``predict`` requires the same columns
(an array: the schema's :attr:`~nirglucose.dataset.schema.DeviceSchema.raw_columns` in order).
They read measured columns only, never ``true_*`` ones (except
:class:`~nirglucose.models.oracle.Oracle`). Every model applies the same fitting-size
policy (:func:`~nirglucose.dataset.schema.check_fit_size`) and refuses reference glucose a meter
would not report (:func:`~nirglucose.dataset.schema.check_reference_glucose`).
"""

from __future__ import annotations

import numpy as np
import pandas as pd
from sklearn.utils import check_array
from sklearn.utils.validation import column_or_1d

from ..constants import DEFAULT_LED_WAVELENGTHS_NM
from ..dataset import Dataset, measured_columns
from ..dataset.schema import (
    DeviceSchema,
    _first_rows,
    check_fit_size,
    check_reference_glucose,
)
from ..exceptions import DataError
from ..fitted import as_raw_input, fit_schema
from ._json_io import JsonModelMixin

__all__ = [
    "MEASURED_COLUMNS",
    "N_MEASURED",
    "SchemaJsonMixin",
    "as_measurements",
    "fit_input",
    "predict_input",
    "target_of",
]

#: The study device's measured columns (4 ADC codes, 4 references, 12 physiological).
MEASURED_COLUMNS = tuple(measured_columns(DEFAULT_LED_WAVELENGTHS_NM))
N_MEASURED = len(MEASURED_COLUMNS)


def target_of(est, y, n: int) -> np.ndarray:
    """``y`` as a finite float64 (n,) array (a column vector warns, as scikit-learn does)."""
    try:
        y = check_array(y, ensure_2d=False, dtype=np.float64, input_name="y", estimator=est)
    except ValueError as exc:  # NaN, infinite or non-numeric reference glucose
        values = pd.to_numeric(pd.Series(np.ravel(np.asarray(y, dtype=object))), errors="coerce")
        bad = ~np.isfinite(values.to_numpy(dtype=float))
        where = f" at {_first_rows(bad)}" if bad.any() else ""
        raise DataError(f"{exc} (reference glucose, glucose_mgdl{where})") from None
    if y.ndim == 2 and y.shape[1] == 1:
        y = column_or_1d(y, warn=True)
    if y.ndim != 1 or len(y) != n:
        raise DataError(f"y must be one value per row of X ({n}), got shape {y.shape}")
    return y


def fit_input(est, X, y=None, groups=None, adc_bits: int | None = None):
    """``(schema, X raw (n, width), y, groups)`` for ``fit``, validated.

    Parameters
    ----------
    est : estimator
        Gets ``n_features_in_`` (and ``feature_names_in_`` for frames).
    X : Dataset, pandas.DataFrame or array_like
        Measurements.
    y : array_like, optional
        Reference glucose; ``glucose_mgdl`` of a frame when omitted. [mg/dL]
    groups : array_like, optional
        Subject ids (else the frame's ``subject_id``).
    adc_bits : int, optional
        Declared ADC resolution. [bit]

    Raises
    ------
    DataError
        Bad columns or values, no target, too few rows or subjects, reference glucose
        outside 20-600 mg/dL (device data).
    """
    schema: DeviceSchema = fit_schema(est, X, adc_bits)
    frame = X.frame if isinstance(X, Dataset) else X
    if isinstance(frame, pd.DataFrame):
        if y is None:
            if "glucose_mgdl" not in frame.columns:
                raise DataError("fitting needs reference glucose: a 'glucose_mgdl' column or y")
            y = pd.to_numeric(frame["glucose_mgdl"], errors="coerce")
        if groups is None and "subject_id" in frame.columns:
            groups = frame["subject_id"].to_numpy()
    elif y is None:
        raise DataError(
            f"{type(est).__name__} requires y to be passed, but the target y is None (give y, "
            "or a DataFrame/Dataset with a glucose_mgdl column)"
        )
    Xa = schema.raw(as_raw_input(est, X, schema))
    y = target_of(est, y, len(Xa))
    if groups is not None:
        groups = np.asarray(groups)
        if len(groups) != len(Xa):
            raise DataError(f"groups has {len(groups)} entries but X has {len(Xa)} rows")
    check_fit_size(len(Xa), groups)
    if not schema.is_plain:
        check_reference_glucose(y)
    return schema, Xa, y, groups


def predict_input(est, X) -> np.ndarray:
    """The fitted device's raw columns of ``X``, validated, (n, width)."""
    schema = est.schema_
    return schema.raw(as_raw_input(est, X, schema))


class SchemaJsonMixin(JsonModelMixin):
    """JSON save/load for estimators that read their input through the schema boundary.

    The one place a fitted ``schema_`` (:class:`~nirglucose.dataset.schema.DeviceSchema`) is
    written to and read back from a model file, and the input record scikit-learn
    expects rebuilt from it. Subclasses list ``"schema_": "json"`` in ``_STATE`` and
    call :meth:`_restore_schema` first thing in their ``_restore`` (run after ``fit``
    and after :meth:`~nirglucose.models._json_io.JsonModelMixin.load`).
    """

    def _state_dict(self):
        schema = self.schema_
        self.__dict__["schema_"] = schema.to_json()  # the JSON form, for saving only
        try:
            return super()._state_dict()
        finally:
            self.__dict__["schema_"] = schema

    def _restore_schema(self) -> None:
        """``schema_`` as a DeviceSchema (from its JSON form after load), and
        ``n_features_in_`` / ``feature_names_in_`` (a device's raw columns) from it."""
        if isinstance(self.schema_, dict):  # loaded from JSON
            self.schema_ = DeviceSchema.from_json(self.schema_)
        s = self.schema_
        self.n_features_in_ = len(s.raw_columns)
        if not s.is_plain:
            self.feature_names_in_ = np.asarray(s.raw_columns, dtype=object)


def as_measurements(X, y=None, *, require_target: bool = False):
    """``(X (n, 20), y, groups)``: the study device's measured columns (compatibility).

    For code written against the study's fixed layout (4 LEDs with references, the
    12-entry vector); estimators read any device through :func:`fit_input`.

    Raises
    ------
    DataError
        Missing columns, bad values, a wrong width, or no target when one is required.
    """
    schema = DeviceSchema()
    groups = None
    frame = X.frame if isinstance(X, Dataset) else X
    if isinstance(frame, pd.DataFrame):
        Xa = schema.raw(frame)
        if y is None and "glucose_mgdl" in frame.columns:
            y = frame["glucose_mgdl"]
        if "subject_id" in frame.columns:
            groups = frame["subject_id"].to_numpy()
    else:
        Xa = np.asarray(X, dtype=float)
        if Xa.ndim != 2 or Xa.shape[1] != N_MEASURED:
            raise DataError(
                f"expected a 2-D array with {N_MEASURED} measured columns "
                f"({', '.join(MEASURED_COLUMNS)}), got shape {Xa.shape}"
            )
        Xa = schema.raw(Xa)
    if y is not None:
        y = np.asarray(y, dtype=float).ravel()
        if len(y) != len(Xa) or not np.all(np.isfinite(y)):
            raise DataError(f"y must be {len(Xa)} finite values, got {len(y)}")
    elif require_target:
        raise DataError("fitting needs reference glucose: a 'glucose_mgdl' column or y")
    return Xa, y, groups
