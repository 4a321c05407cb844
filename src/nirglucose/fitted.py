"""The estimators' side of the schema boundary: fitted-state checks and the input an
estimator records when it fits.

:mod:`nirglucose.dataset.schema` says what a device's measurements are
(:func:`~nirglucose.dataset.schema.schema_for_fit`) and writes onto nothing; this module
is the model plumbing shared by the estimators (:mod:`nirglucose.models`) and the feature
transformers (:mod:`nirglucose.features`): it records ``n_features_in_`` and
``feature_names_in_`` on an estimator as scikit-learn's contract asks, and checks the
input of ``predict``/``transform`` against them. It imports the data boundary and
scikit-learn, never the models package, whose models import it in turn.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pandas as pd
from sklearn.exceptions import NotFittedError as _SkNotFittedError
from sklearn.utils import check_array
from sklearn.utils.validation import check_is_fitted, validate_data

from .dataset.container import Dataset
from .dataset.schema import DeviceSchema, schema_for_fit
from .exceptions import DataError, NotFittedError

__all__ = ["EstimatorNotFittedError", "require_fitted", "fit_schema", "as_raw_input"]


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


def fit_schema(est: Any, X: Any, adc_bits: int | None = None) -> DeviceSchema:
    """The schema of fitting input ``X``, recording ``n_features_in_`` on ``est``.

    A device's measurements (:func:`~nirglucose.dataset.schema.schema_for_fit`) give
    their device schema, and ``est`` gets ``n_features_in_`` and ``feature_names_in_``
    (its raw columns); generic input (arrays, frames naming no schema column) a plain
    one, through :func:`sklearn.utils.validation.validate_data` (scikit-learn's
    standard messages and feature-name bookkeeping).
    """
    schema = schema_for_fit(X, adc_bits)
    if schema is not None:
        est.n_features_in_ = len(schema.raw_columns)
        est.feature_names_in_ = np.asarray(schema.raw_columns, dtype=object)
        return schema
    est.__dict__.pop("feature_names_in_", None)
    frame = X.frame if isinstance(X, Dataset) else X
    Xa = validate_data(est, frame, reset=True, dtype=np.float64)
    return DeviceSchema.plain(Xa.shape[1])


def as_raw_input(est: Any, X: Any, schema: DeviceSchema) -> Any:
    """X for :meth:`DeviceSchema.raw`: device frames as they are, arrays checked."""
    if schema.is_plain:
        frame = X.frame if isinstance(X, Dataset) else X
        return validate_data(est, frame, reset=False, dtype=np.float64)
    if isinstance(X, pd.DataFrame | Dataset):
        return X
    if type(X) is np.ndarray and X.dtype == np.float64 and X.ndim == 2 and X.size:
        Xa = X  # the common case, without check_array's overhead on one row
    else:
        want = (f"X must be a Dataset, a DataFrame or a 2-D array of the model's "
                f"{len(schema.raw_columns)} columns (its schema_.raw_columns)")
        if X is None or isinstance(X, str | bytes | dict):
            raise DataError(f"{want}, got {type(X).__name__}")
        try:
            Xa = check_array(X, dtype=np.float64, estimator=est, input_name="X")
        except ValueError as exc:
            raise DataError(f"{want}: {str(exc).splitlines()[0].rstrip(':')}") from None
    if Xa.shape[1] != len(schema.raw_columns):
        raise DataError(
            f"X has {Xa.shape[1]} features, but {type(est).__name__} is expecting "
            f"{len(schema.raw_columns)} features as input ({schema.describe()})"
        )
    return Xa
