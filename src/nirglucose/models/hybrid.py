"""Hybrids: a physics backbone with a learned residual.

A backbone (the Enhanced Beer-Lambert ridge, or the forward-model inversion) predicts
glucose; a Gaussian process (:class:`~nirglucose.models.reference.GPReference`) then
learns what the backbone leaves, y - f_backbone(x), from the device's absorbances and
physiology together with the backbone's own prediction (stacking, Wolpert 1992 [1]_).
The residual learner is trained on the backbone's out-of-fold predictions over
subject-grouped folds (``cv``), so it learns the backbone's error on subjects it has
not seen, as at prediction; the backbone is then refitted on every training row.

Where the residual holds no signal the GP only adds noise, and where the backbone holds
none it can be worse than the training mean, so the hybrid is a stack (Breiman 1996
[3]_)::

    y_mean + a * (f_backbone(x) - y_mean) + s * GP(x)

On the training rows only, the GP is cross-fitted over the same subject-grouped folds (on
the backbone's out-of-fold predictions: stacking, not nested),
giving out-of-fold residual predictions ``r_hat`` next to the backbone's out-of-fold
glucose; ``s`` in [0, 1] is the least-squares weight of ``r_hat`` in the backbone's
out-of-fold residual, and ``a`` is 1, or 0 (with ``s`` 0: the training mean) where the
training mean has the smaller out-of-fold error. ``s`` near 0: the backbone alone;
``s`` 1: the full hybrid.

This is the study's future work, "hybrid approaches that combine physics-based feature
engineering with selective neural network components" [2]_, with a GP as the learned part.

References
----------
.. [1] D. H. Wolpert, "Stacked generalization", Neural Networks 5, 241-259 (1992),
   doi:10.1016/S0893-6080(05)80023-1
.. [2] R. Gani, "Physics-Informed Neural Networks vs. Physics Models for Non-Invasive
   Glucose Monitoring", University College London (the study this package extends).
.. [3] L. Breiman, "Stacked regressions", Machine Learning 24, 49-64 (1996),
   doi:10.1007/BF00117832
"""

from __future__ import annotations

import math
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
from ._validate import check_loaded_params
from .inversion import PRIVILEGED_SCENARIO
from .reference import GP_RANDOM_STATE
from .registry import get_model_class, make_model, register

__all__ = ["EBLGP", "PhysicsInversionGP", "SHRINKAGE_FOLDS"]

#: Subject-grouped folds the stacking weight is learned over when ``cv`` is 0 or 1 (the
#: GP learns in-sample residuals, so there are no folds to reuse): the hybrids' default
#: ``cv`` and the tuning's grouped 3-fold CV (``tools/tune.py``).
SHRINKAGE_FOLDS = 3


def _rows(X, idx: np.ndarray):
    """Rows ``idx`` of a Dataset (keeping its config), a frame or an array."""
    if isinstance(X, Dataset):
        return X.rows(idx)
    if hasattr(X, "iloc"):
        return X.iloc[idx].reset_index(drop=True)
    return np.asarray(X)[idx]


def _stacking_weights(z: np.ndarray, b: np.ndarray, r_hat: np.ndarray) -> tuple[float, float]:
    """The stack's weights ``(a, s)`` from out-of-fold predictions: ``(1, s)`` with
    ``s = clip(<z - b, r_hat> / <r_hat, r_hat>, 0, 1)``, or ``(0, 0)`` (the training
    mean) where that has the larger squared error.

    ``z`` is glucose minus its training mean, ``b`` the backbone's out-of-fold glucose
    minus that mean, ``r_hat`` the residual GP's out-of-fold prediction of ``z - b``.
    ``s`` is the least-squares weight of ``r_hat`` under non-negativity, capped at 1 so
    the GP is never amplified (L. Breiman, "Stacked regressions", Machine Learning 24,
    49-64 (1996), doi:10.1007/BF00117832); the choice between that stack and the mean is
    by the same out-of-fold error. Sums are exactly rounded (:func:`math.fsum`).
    """
    den = math.fsum(r_hat * r_hat)
    s = 0.0 if den <= 0.0 else float(np.clip(math.fsum((z - b) * r_hat) / den, 0.0, 1.0))
    err = z - b - s * r_hat
    if math.fsum(err * err) <= math.fsum(z * z):
        return 1.0, s
    return 0.0, 0.0


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
    check_loaded_params(model, where)
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
        from, and of the cross-fit that learns the stacking weights; 0 or 1 learns
        from the backbone's in-sample residuals, as do fewer subjects than ``cv`` (the
        weights then from :data:`SHRINKAGE_FOLDS` folds of the whole fit). [-]
    random_state : int, optional
        Seed of the GP's row subset and restarts.

    Attributes
    ----------
    backbone_ : estimator
        The backbone fitted on every training row.
    residual_ : GPReference
        The GP on the backbone's residuals.
    y_mean_ : float
        Training mean of glucose, the stack's constant. [mg/dL]
    backbone_weight_ : float
        Weight of the backbone's glucose about ``y_mean_``: 1, or 0 where the training
        mean has a smaller out-of-fold error than backbone plus weighted GP. [-]
    shrinkage_ : float
        Stacking weight of the GP's residual, in [0, 1]: 0 where its cross-fitted
        predictions explain none of the residual. Both weights are 1 without subject
        ids or with fewer than :data:`SHRINKAGE_FOLDS` subjects (the plain hybrid, as
        before issue 29). [-]
    """

    backbone_name = ""
    _STATE = {"schema_": "json", "backbone_": "json", "residual_": "json",
              "y_mean_": None, "backbone_weight_": None, "shrinkage_": None}
    _parameter_constraints: ClassVar[dict[str, Any]] = {
        "backbone_params": [None, dict],
        "gp_params": [None, dict],
        "cv": [Interval(Integral, 0, None, closed="left")],
        "random_state": GP_RANDOM_STATE,
    }

    def __init__(self, backbone_params=None, gp_params=None, cv: int = SHRINKAGE_FOLDS,
                 random_state=None):
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

    def _folds(self, y: np.ndarray, groups, n_splits: int) -> list | None:
        """Subject-grouped ``(train, test)`` folds, or None without enough subjects."""
        n_groups = 0 if groups is None else len(np.unique(groups))
        if n_splits < 2 or n_groups < n_splits:
            return None
        return list(GroupKFold(n_splits=n_splits).split(np.zeros(len(y)), y, groups))

    def _out_of_fold(self, X, y: np.ndarray, groups, folds) -> np.ndarray:
        """The backbone's predictions of rows whose subjects it was not fitted on."""
        oof = np.empty(len(y))
        for tr, te in folds:
            part = self._backbone().fit(_rows(X, tr), y[tr], groups[tr])
            oof[te] = part.predict(_rows(X, te))
        return oof

    def _cross_fit_residual(self, X, A, y, groups, folds, oof) -> tuple:
        """``(base, r_hat)``: each row's backbone glucose and the residual GP's
        prediction of its residual, the GP fitted on the other folds' rows only.

        With ``oof`` (the backbone's out-of-fold predictions over ``folds``) only the GP
        is refitted per fold, on those rows' out-of-fold predictions: ordinary stacking,
        not nested, so a row's own label has entered the backbones behind the other
        rows' ``oof``. Without it (``cv`` < 2, or fewer subjects than ``cv``) the
        backbone and the GP on its in-sample residuals are refitted per fold, as
        :meth:`fit` does on every row.
        """
        base, r_hat = np.empty(len(y)), np.empty(len(y))
        for tr, te in folds:
            if oof is not None:
                base_tr, base_te = oof[tr], oof[te]
            else:
                part = self._backbone().fit(_rows(X, tr), y[tr], groups[tr])
                base_tr, base_te = part.predict(_rows(X, tr)), part.predict(_rows(X, te))
            gp = self._gp().fit(np.column_stack([A[tr], base_tr]), y[tr] - base_tr)
            base[te] = base_te
            r_hat[te] = gp.predict(np.column_stack([A[te], base_te]))
        return base, r_hat

    def fit(self, X, y=None, groups=None):
        """Fit the backbone on every row, the GP on its out-of-fold residuals and the
        stacking weights (``backbone_weight_``, ``shrinkage_``) on out-of-fold
        predictions of both.

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
        A = self.schema_.stacked(Xa)
        folds = self._folds(y, groups, int(self.cv))
        oof = None if folds is None else self._out_of_fold(X, y, groups, folds)
        self.backbone_ = self._backbone().fit(X, y, groups)
        base = self.backbone_.predict(X) if oof is None else oof
        self.residual_ = self._gp().fit(np.column_stack([A, base]), y - base)
        if folds is None:
            folds = self._folds(y, groups, SHRINKAGE_FOLDS)
        self.y_mean_ = float(np.mean(y))
        self.backbone_weight_, self.shrinkage_ = 1.0, 1.0  # no folds: the plain hybrid
        if folds is not None:
            base, r_hat = self._cross_fit_residual(X, A, y, groups, folds, oof)
            self.backbone_weight_, self.shrinkage_ = _stacking_weights(
                y - self.y_mean_, base - self.y_mean_, r_hat)
        self._restore_schema()
        return self

    def predict(self, X) -> np.ndarray:
        """The stacked glucose: ``y_mean_ + backbone_weight_ * (backbone - y_mean_) +
        shrinkage_ * GP residual``. [mg/dL]"""
        self._require_fitted()
        Xa = predict_input(self, X)
        base = np.asarray(self.backbone_.predict(X), dtype=float).ravel()
        U = np.column_stack([self.schema_.stacked(Xa), base])
        stacked = self.y_mean_ + self.backbone_weight_ * (base - self.y_mean_)
        if self.shrinkage_ == 0.0:  # the GP's weight is 0: no need to evaluate it
            return stacked
        return stacked + self.shrinkage_ * self.residual_.predict(U)

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
        for key in ("backbone_weight_", "shrinkage_"):
            if not 0.0 <= getattr(self, key) <= 1.0:
                raise DataError(f"the hybrid's saved {key} is {getattr(self, key)!r}, "
                                "outside [0, 1]; refit the model")
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
    """Enhanced Beer-Lambert ridge, then a GP on its residual, stacked.

    Parameters, the stack and its weights: :class:`_ResidualHybrid` and the module notes.

    Examples
    --------
    >>> import nirglucose as ng
    >>> ds = ng.simulate("paper", 20, 3, seed=0)
    >>> EBLGP(random_state=0).fit(ds).predict(ds).shape
    (60,)
    """

    privileged: ClassVar[str | None] = None

    backbone_name = "ebl"


@register("physics-inversion+gp")
class PhysicsInversionGP(_ResidualHybrid):
    """The forward-model inversion, then a GP on its residual, stacked.

    Parameters, the stack and its weights: :class:`_ResidualHybrid` and the module notes.

    Examples
    --------
    >>> import nirglucose as ng
    >>> ds = ng.simulate("paper", 20, 3, seed=0)
    >>> PhysicsInversionGP(random_state=0, cv=0).fit(ds).predict(ds).shape
    (60,)
    """

    privileged: ClassVar[str | None] = PRIVILEGED_SCENARIO  # its backbone's

    backbone_name = "physics-inversion"

    def estimate_state(self, X):
        """The backbone's tissue-state estimates, with this model's glucose (the
        residual GP corrects glucose only). See
        :meth:`~nirglucose.models.inversion.PhysicsInversion.estimate_state`."""
        self._require_fitted()
        state = self.backbone_.estimate_state(X)
        state["glucose_mgdl"] = self.predict(X)
        return state
