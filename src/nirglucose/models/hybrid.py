"""Hybrids: a physics backbone with a learned residual.

A backbone (the Enhanced Beer-Lambert ridge, or the forward-model inversion) predicts
glucose; a Gaussian process (:class:`~nirglucose.models.reference.GPReference`) then
learns what the backbone leaves, y - f_backbone(x), from the device's absorbances and
physiology together with the backbone's own prediction (stacking, Wolpert 1992 [1]_).
The residual learner is trained on the backbone's out-of-fold predictions over
subject-grouped folds (``cv``), so it learns the backbone's error on subjects it has
not seen, as at prediction; the backbone is then refitted on every training row. This
is the study's future work, "hybrid approaches that combine physics-based feature
engineering with selective neural network components" [2]_, with a GP as the learned part.

References
----------
.. [1] D. H. Wolpert, "Stacked generalization", Neural Networks 5, 241-259 (1992),
   doi:10.1016/S0893-6080(05)80023-1
.. [2] R. Gani, "Physics-Informed Neural Networks vs. Physics Models for Non-Invasive
   Glucose Monitoring", University College London (the study this package extends).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, ClassVar

import numpy as np
from sklearn.base import BaseEstimator, RegressorMixin
from sklearn.model_selection import GroupKFold

from ..dataset import Dataset
from ..exceptions import DataError
from ..fitted import require_fitted
from ._base import SchemaJsonMixin, fit_input, predict_input
from ._json_io import _state_value, _to_json
from ._params import Integral, Interval, ValidatedParamsMixin
from .reference import GP_RANDOM_STATE
from .registry import get_model_class, make_model, register

__all__ = ["EBLGP", "PhysicsInversionGP"]


def _rows(X, idx: np.ndarray):
    """Rows ``idx`` of a Dataset (keeping its config), a frame or an array."""
    if isinstance(X, Dataset):
        return X.rows(idx)
    if hasattr(X, "iloc"):
        return X.iloc[idx].reset_index(drop=True)
    return np.asarray(X)[idx]


def _nested_doc(model) -> dict:
    """A fitted component as ``{"params", "state"}`` (the model file's own parts)."""
    return {"params": _to_json(model.get_params(deep=False)), "state": model._state_dict()}


def _nested_model(name: str, doc) -> object:
    """A component rebuilt from :func:`_nested_doc` (checked as a model file's state)."""
    if not isinstance(doc, dict) or not isinstance(doc.get("state"), dict):
        raise DataError(f"the hybrid's saved {name!r} component is malformed")
    cls = get_model_class(name)
    try:
        model = cls(**doc.get("params", {}))
    except (TypeError, ValueError) as exc:
        msg = f"the hybrid's saved {name!r} component: invalid parameters: {exc}"
        raise DataError(msg) from None
    where = Path(f"<{name} inside a hybrid model file>")
    for key, shape in cls._STATE.items():
        if key not in doc["state"]:
            raise DataError(f"the hybrid's saved {name!r} component lacks state {key!r}")
        setattr(model, key, _state_value(where, key, doc["state"][key], shape))
    model._restore()
    return model


class _ResidualHybrid(ValidatedParamsMixin, SchemaJsonMixin, RegressorMixin, BaseEstimator):
    """Backbone, then a GP on its out-of-fold residual (see the module docstring).

    Parameters
    ----------
    backbone_params : dict, optional
        Keyword arguments of the backbone (its registered defaults when None).
    gp_params : dict, optional
        Keyword arguments of the residual GP (``random_state`` defaults to this
        model's).
    cv : int
        Subject-grouped folds of the out-of-fold backbone predictions the GP learns
        from; 0 or 1 learns from the backbone's in-sample residuals. [-]
    random_state : int, optional
        Seed of the GP's row subset and restarts.
    """

    backbone_name = ""
    _STATE = {"schema_": "json", "backbone_": "json", "residual_": "json"}
    _parameter_constraints: ClassVar[dict[str, Any]] = {
        "backbone_params": [None, dict],
        "gp_params": [None, dict],
        "cv": [Interval(Integral, 0, None, closed="left")],
        "random_state": GP_RANDOM_STATE,
    }

    def __init__(self, backbone_params=None, gp_params=None, cv: int = 3, random_state=None):
        self.backbone_params = backbone_params
        self.gp_params = gp_params
        self.cv = cv
        self.random_state = random_state

    def _require_fitted(self) -> None:
        require_fitted(self, "residual_")

    def _backbone(self):
        return make_model(self.backbone_name, **(self.backbone_params or {}))

    def _gp(self):
        params = {"random_state": self.random_state, **(self.gp_params or {})}
        return make_model("gp", **params)

    def _out_of_fold(self, X, y: np.ndarray, groups) -> np.ndarray:
        """The backbone's predictions of rows whose subjects it was not fitted on."""
        n_groups = 0 if groups is None else len(np.unique(groups))
        if self.cv < 2 or n_groups < self.cv:
            return None
        oof = np.empty(len(y))
        for tr, te in GroupKFold(n_splits=int(self.cv)).split(np.zeros(len(y)), y, groups):
            part = self._backbone().fit(_rows(X, tr), y[tr], groups[tr])
            oof[te] = part.predict(_rows(X, te))
        return oof

    def fit(self, X, y=None, groups=None):
        """Fit the backbone on every row and the GP on its out-of-fold residuals.

        Parameters
        ----------
        X : Dataset, pandas.DataFrame
            A device's readings (a Dataset keeps its scenario for the inversion).
        y : array_like, optional
            Reference glucose; ``glucose_mgdl`` when omitted. [mg/dL]
        groups : array_like, optional
            Subject ids (else the frame's ``subject_id``) for the grouped folds.

        Returns
        -------
        self
        """
        self._validate_params()
        self.schema_, Xa, y, groups = fit_input(self, X, y, groups)
        if self.schema_.is_plain:
            raise DataError(f"{self.registry_name} needs a device's ADC columns, not a plain array")
        oof = self._out_of_fold(X, y, groups)
        self.backbone_ = self._backbone().fit(X, y, groups)
        if oof is None:
            oof = self.backbone_.predict(X)
        U = np.column_stack([self.schema_.stacked(Xa), oof])
        self.residual_ = self._gp().fit(U, y - oof)
        self._restore_schema()
        return self

    def predict(self, X) -> np.ndarray:
        """The backbone's glucose plus the GP's residual. [mg/dL]"""
        self._require_fitted()
        Xa = predict_input(self, X)
        base = np.asarray(self.backbone_.predict(X), dtype=float).ravel()
        U = np.column_stack([self.schema_.stacked(Xa), base])
        return base + self.residual_.predict(U)

    @property
    def n_parameters(self) -> int:
        """The backbone's learned numbers plus the GP's."""
        self._require_fitted()
        return int(self.backbone_.n_parameters) + int(self.residual_.n_parameters)

    def _state_dict(self):
        parts = self.backbone_, self.residual_
        self.__dict__["backbone_"] = _nested_doc(parts[0])
        self.__dict__["residual_"] = _nested_doc(parts[1])
        try:
            return super()._state_dict()
        finally:
            self.__dict__["backbone_"], self.__dict__["residual_"] = parts

    def _restore(self) -> None:
        self._restore_schema()
        if isinstance(self.backbone_, dict):
            self.backbone_ = _nested_model(self.backbone_name, self.backbone_)
        if isinstance(self.residual_, dict):
            self.residual_ = _nested_model("gp", self.residual_)

    def __sklearn_tags__(self):
        tags = super().__sklearn_tags__()
        tags.non_deterministic = False
        return tags


@register("ebl+gp")
class EBLGP(_ResidualHybrid):
    """Enhanced Beer-Lambert, then a GP on its residual (:class:`_ResidualHybrid`).

    Examples
    --------
    >>> import nirglucose as ng
    >>> ds = ng.simulate("paper", 20, 3, seed=0)
    >>> EBLGP(random_state=0).fit(ds).predict(ds).shape
    (60,)
    """

    backbone_name = "ebl"


@register("physics-inversion+gp")
class PhysicsInversionGP(_ResidualHybrid):
    """The forward-model inversion, then a GP on its residual (:class:`_ResidualHybrid`).

    Examples
    --------
    >>> import nirglucose as ng
    >>> ds = ng.simulate("paper", 20, 3, seed=0)
    >>> PhysicsInversionGP(random_state=0, cv=0).fit(ds).predict(ds).shape
    (60,)
    """

    backbone_name = "physics-inversion"

    def estimate_state(self, X):
        """The backbone's tissue-state estimates, with this model's glucose (the
        residual GP corrects glucose only). See
        :meth:`~nirglucose.models.inversion.PhysicsInversion.estimate_state`."""
        self._require_fitted()
        state = self.backbone_.estimate_state(X)
        state["glucose_mgdl"] = self.predict(X)
        return state
