"""Fitted-state checks shared by the estimators and the feature transformers.

A leaf module (it imports only :mod:`nirglucose.exceptions` and scikit-learn), so
:mod:`nirglucose.features` and :mod:`nirglucose.schema` can use it without importing
the :mod:`nirglucose.models` package, whose models import them in turn.
"""

from __future__ import annotations

from sklearn.exceptions import NotFittedError as _SkNotFittedError
from sklearn.utils.validation import check_is_fitted

from .exceptions import NotFittedError

__all__ = ["EstimatorNotFittedError", "require_fitted"]


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
