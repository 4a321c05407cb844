"""Fitted-state checks shared by the estimators (defined in :mod:`nirglucose.fitted`).

Input checks live at the schema boundary (:mod:`nirglucose.schema`, through
:func:`~nirglucose.models._base.fit_input` and
:func:`~nirglucose.models._base.predict_input`). The fitted-state helpers moved to the
leaf module :mod:`nirglucose.fitted` so that :mod:`nirglucose.features` and
:mod:`nirglucose.schema` need not import this package; they are re-exported here.
"""

from __future__ import annotations

from ..fitted import EstimatorNotFittedError, require_fitted

__all__ = ["EstimatorNotFittedError", "require_fitted"]
