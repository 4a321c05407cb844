"""Linear estimators: Enhanced Beer–Lambert ridge and the PLS chemometrics baseline.

Both follow the scikit-learn contract (``__init__`` stores keyword arguments, ``fit``
validates and returns self, learned state ends in ``_``), read the measured columns
only, choose their one hyperparameter by subject-grouped inner cross-validation
(:class:`~sklearn.model_selection.GroupKFold` when subject ids are known, else
:class:`~sklearn.model_selection.KFold`), fold their standardisation into the
coefficients, and save to JSON.

Cross-validation needs one pass over the data: each inner fold is standardised exactly
by its own training rows from sums (z, z z^T, z y) over all rows minus those over the
fold, and every candidate (all ridge penalties from one eigen-decomposition; all PLS
component counts from one kernel-PLS run) is scored at once. The results equal
``cross_val_predict`` with ``StandardScaler`` + ``Ridge`` / ``PLSRegression`` (tested).

References
----------
.. [1] R. Gani, "Physics-Informed Neural Networks vs. Physics Models for Non-Invasive
   Glucose Monitoring: A Comparative Study Under Noise-Stressed Synthetic Conditions",
   University College London (the Enhanced Beer–Lambert model, 56 features, ridge).
.. [2] A. E. Hoerl, R. W. Kennard, "Ridge regression: biased estimation for
   nonorthogonal problems", Technometrics 12, 55-67 (1970),
   doi:10.1080/00401706.1970.10488634
.. [3] S. de Jong, "SIMPLS: an alternative approach to partial least squares
   regression", Chemom. Intell. Lab. Syst. 18, 251-263 (1993),
   doi:10.1016/0169-7439(93)85002-X; scikit-learn's
   :class:`~sklearn.cross_decomposition.PLSRegression` (NIPALS, same predictions for a
   single response).
.. [4] B. S. Dayal, J. F. MacGregor, "Improved PLS algorithms", J. Chemometrics 11,
   73-85 (1997), doi:10.1002/(SICI)1099-128X(199701)11:1<73::AID-CEM435>3.0.CO;2-#
"""

from __future__ import annotations

import math
from typing import Any, ClassVar

import numpy as np
from sklearn.base import BaseEstimator, RegressorMixin
from sklearn.model_selection import GroupKFold, KFold
from threadpoolctl import threadpool_limits

from ..exceptions import DataError
from ..features import (
    compute_features,
    ebl_feature_matrix,
    feature_table,
)
from ..fitted import EstimatorNotFittedError, require_fitted
from ._base import SchemaJsonMixin, fit_input, predict_input
from ._ebl_folded import FoldedKernel, fold_ebl, folded_predict_one, predict_one_row
from ._linear_solvers import fit_standardized_cv, pls1_coefs, ridge_coefs
from ._params import Integral, Interval, IntervalArray, Real, ValidatedParamsMixin
from .registry import register

__all__ = ["EnhancedBeerLambert", "PLSBaseline", "DEFAULT_ALPHAS"]

#: Ridge penalties tried by the inner CV (sum-of-squares scale, as scikit-learn's Ridge).
DEFAULT_ALPHAS = tuple(float(a) for a in np.logspace(-6, 6, 25))
#: Inputs of the PLS baseline: the 4 log absorbances and the 12 measured PMF entries.


def _group_kfold_ids(groups: np.ndarray, n_splits: int) -> np.ndarray:
    """Fold of each row, exactly as :class:`sklearn.model_selection.GroupKFold` assigns.

    GroupKFold gives groups, largest first, to the currently lightest fold. With groups
    of equal size that is a round robin, computed here without its per-group Python
    loop (which dominates a fit with tens of thousands of subjects); other cases call
    GroupKFold itself.
    """
    _, group_idx = np.unique(groups, return_inverse=True)
    sizes = np.bincount(group_idx)
    if sizes.min() != sizes.max():
        fold = np.empty(len(groups), dtype=np.intp)
        splitter = GroupKFold(n_splits=n_splits)
        for f, (_, test) in enumerate(splitter.split(np.zeros((len(groups), 1)), groups=groups)):
            fold[test] = f
        return fold
    indices = np.argsort(sizes, kind="stable")[::-1]
    group_to_fold = np.empty(len(sizes), dtype=np.intp)
    group_to_fold[indices] = np.arange(len(sizes)) % n_splits
    return group_to_fold[group_idx]


def _fold_ids(n: int, groups, cv: int, random_state) -> np.ndarray | None:
    """Inner-CV fold of each row: subject-grouped when ``groups`` has >= 2 subjects
    (GroupKFold), else KFold (rows shuffled only when ``random_state`` is given); None
    when there are too few rows to split."""
    if groups is not None:
        groups = np.asarray(groups)
        n_groups = len(np.unique(groups))
        if n_groups >= 2:
            return _group_kfold_ids(groups, min(cv, n_groups))
    if n >= 2:
        fold = np.empty(n, dtype=np.intp)
        shuffle = random_state is not None  # None: row order, deterministic
        splitter = KFold(n_splits=min(cv, n), shuffle=shuffle, random_state=random_state)
        for f, (_, test) in enumerate(splitter.split(np.zeros((n, 1)))):
            fold[test] = f
        return fold
    return None


#: Constraints shared by both linear models: inner folds, the KFold seed, the ADC.
_COMMON_CONSTRAINTS: dict[str, Any] = {
    "cv": [Interval(Integral, 2, None, closed="left")],
    "random_state": ["random_state"],
    # checked where the resolution is resolved (check_adc_bits names the valid range)
    "adc_bits": "no_validation",
}


class _LinearBase(ValidatedParamsMixin, SchemaJsonMixin, RegressorMixin, BaseEstimator):
    """Shared plumbing: input handling, fitted checks, ``n_parameters``."""

    def _require_fitted(self) -> None:
        if "coef_" not in self.__dict__:  # cheap test first: this sits on the hot path
            require_fitted(self, "coef_")

    def _features(self, Xa: np.ndarray) -> np.ndarray:
        """Model inputs (n, p) from the fitted device's raw columns."""
        raise NotImplementedError

    @property
    def n_parameters(self) -> int:
        """Numbers the fitted predictor uses: the folded coefficients plus the intercept."""
        self._require_fitted()
        return int(np.size(self.coef_)) + 1

    def __sklearn_tags__(self):
        tags = super().__sklearn_tags__()
        tags.target_tags.single_output = True
        tags.target_tags.multi_output = False
        return tags


@register("ebl")
class EnhancedBeerLambert(_LinearBase):
    """Enhanced Beer–Lambert: physics features (56 on the study's device) -> ridge.

    The ridge penalty is chosen by subject-grouped inner cross-validation, with one
    eigen-decomposition per fold serving every penalty in closed form [2]_. The
    standardisation is folded into the coefficients, so prediction is one
    matrix-vector product on the raw features (:attr:`coef_`, :attr:`intercept_`).

    Parameters
    ----------
    alphas : sequence of float, optional
        Ridge penalties to try (sum-of-squares scale, as
        :class:`sklearn.linear_model.Ridge`); :data:`DEFAULT_ALPHAS` when None. One
        value skips the inner CV. [-]
    cv : int
        Number of inner folds (fewer when there are fewer subjects). [-]
    random_state : int, optional
        When subject ids are unknown the inner CV is a KFold over rows, in row order
        when None, shuffled with this seed otherwise.

    Attributes
    ----------
    alpha_ : float
        The chosen penalty.
    cv_mse_ : numpy.ndarray
        Inner-CV mean squared error for each penalty. [(mg/dL)^2]
    scaler_mean_, scaler_scale_ : numpy.ndarray
        Feature standardisation, (56,).
    coef_ : numpy.ndarray
        Coefficients on the raw features (standardisation folded in), (56,).
        [mg/dL per feature unit]
    intercept_ : float
        [mg/dL]
    n_features_in_ : int
        20: the measured columns.

    References
    ----------
    .. [1] R. Gani, UCL (the study's Enhanced Beer–Lambert model).
    .. [2] A. E. Hoerl, R. W. Kennard, Technometrics 12, 55-67 (1970).

    Examples
    --------
    >>> import nirglucose as ng
    >>> ds = ng.simulate("wearable", n_subjects=20, per_subject=3, seed=0)
    >>> m = EnhancedBeerLambert().fit(ds)
    >>> m.predict(ds).shape, m.n_parameters
    ((60,), 57)
    """

    privileged: ClassVar[str | None] = None

    _parameter_constraints: ClassVar[dict[str, Any]] = {
        "alphas": [
            None,
            Interval(Real, 0, None, closed="neither"),
            IntervalArray(Real, 0, None, closed="neither"),
        ],
        **_COMMON_CONSTRAINTS,
    }

    _STATE = {
        "schema_": "json",
        "alpha_": None,
        "cv_mse_": (-1,),
        "scaler_mean_": (-1,),
        "scaler_scale_": (-1,),
        "coef_": (-1,),
        "intercept_": None,
    }

    #: Batches up to this size are predicted row by row in plain Python (lower latency).
    SMALL_BATCH = 8

    def __init__(self, alphas=None, cv: int = 5, random_state=None, adc_bits=None):
        self.alphas = alphas
        self.cv = cv
        self.random_state = random_state
        self.adc_bits = adc_bits

    def _features(self, Xa: np.ndarray) -> np.ndarray:
        s = self.schema_
        if s.is_study:
            return ebl_feature_matrix(Xa)
        m = s.split(Xa)
        return compute_features(self.table_, s, m.absorbance, m.physiology)

    @classmethod
    def _params_from_json(cls, params):
        params = dict(params)
        if isinstance(params.get("alphas"), list):
            params["alphas"] = tuple(params["alphas"])
        return params

    def _alpha_grid(self) -> np.ndarray:
        alphas = DEFAULT_ALPHAS if self.alphas is None else self.alphas
        return np.atleast_1d(np.asarray(alphas, dtype=float))

    def fit(self, X, y=None, groups=None):
        """Fit on measurements.

        Parameters
        ----------
        X : Dataset, pandas.DataFrame or array_like (n, 20)
            Measurements; a frame's ``subject_id`` groups the inner CV.
        y : array_like, optional
            Reference glucose; ``glucose_mgdl`` of the frame when omitted. [mg/dL]
        groups : array_like, optional
            Subject ids for the inner CV (overrides ``subject_id``).

        Returns
        -------
        self
        """
        self._validate_params()
        alphas = self._alpha_grid()
        cv = int(self.cv)
        self.schema_, Xa, y, g = fit_input(self, X, y, groups, self.adc_bits)
        self.table_ = feature_table(self.schema_)
        folds = _fold_ids(len(Xa), g, cv, self.random_state) if len(alphas) > 1 else None
        fit = fit_standardized_cv(
            lambda rows: np.ascontiguousarray(self._features(Xa[rows]).T),
            len(Xa),
            y,
            folds,
            lambda R, xy: ridge_coefs(R, xy, alphas),
        )
        if fit.mse is not None:
            mse = fit.mse
            best = int(np.flatnonzero(mse <= mse.min() * (1 + 1e-12))[-1])  # ties: larger
        else:
            mse = np.zeros(len(alphas))
            best = len(alphas) - 1
        alpha = float(alphas[best])
        with threadpool_limits(limits=1, user_api="blas"):
            beta = ridge_coefs(fit.R, fit.xy, np.array([alpha]))[:, 0]
        self.alpha_ = alpha
        self.cv_mse_ = mse
        self.scaler_mean_ = fit.mean
        self.scaler_scale_ = fit.scale
        self.coef_ = beta / fit.scale
        self.intercept_ = float(fit.ybar - self.coef_ @ fit.mean)
        self._restore()
        return self

    def _restore(self) -> None:
        self._restore_schema()
        self.table_ = feature_table(self.schema_)
        if len(self.coef_) != len(self.table_):
            raise DataError(
                f"model has {len(self.coef_)} coefficients but its device has "
                f"{len(self.table_)} features; refit the model"
            )
        if self.schema_.is_study:  # the study's device: the folded fast paths
            self.folded_ = fold_ebl(self.coef_, self.intercept_)
            self._kernel = FoldedKernel(self.folded_)
        else:
            self.__dict__.pop("folded_", None)
            self._kernel = None

    def predict(self, X) -> np.ndarray:
        """Glucose for each row of measurements. [mg/dL]

        Evaluates the folded polynomial (:meth:`predict_one`'s, vectorised, in chunks),
        which equals ``ebl_feature_matrix(X) @ coef_ + intercept_`` to rounding. Up to
        :attr:`SMALL_BATCH` rows go through :meth:`predict_one` instead, where numpy's
        per-call overhead would exceed the arithmetic.
        """
        self._require_fitted()
        Xa = predict_input(self, X)
        if self._kernel is None:
            pred = self._features(Xa) @ self.coef_ + self.intercept_
            if not np.isfinite(pred).all():
                raise DataError("input gives non-finite predictions; check for extreme values")
            return pred
        if len(Xa) <= self.SMALL_BATCH:
            one = self.predict_one
            vals = [one(r[:4], r[4:8], r[8:]) for r in Xa.tolist()]
            pred = np.array(vals, dtype=float)
            finite = all(map(math.isfinite, vals))
        else:
            with np.errstate(invalid="ignore", over="ignore", divide="ignore"):
                pred = self._kernel(Xa)
            finite = bool(np.isfinite(pred).all())
        if not finite:
            raise DataError("input gives non-finite predictions; check for extreme values")
        return pred

    def predict_one(self, adc, adc_ref, pmf) -> float:
        """Glucose from one measurement's raw values, in plain Python (fast path).

        The fitted model is expanded into a polynomial in the absorbances and the
        physiological entries (the 56 coefficients and the scaler folded into 57
        numbers), so one call is a few dozen float operations and no numpy.

        Parameters
        ----------
        adc : sequence of 4 float
            ADC codes at 850, 940, 1050, 1150 nm. [ADC code]
        adc_ref : sequence of 4 float
            The device's reference codes, same order. [ADC code]
        pmf : sequence of 12 float
            Physiological entries in :data:`~nirglucose.dataset.PMF_COLUMNS` order.
            [column units]

        Returns
        -------
        float
            Glucose. [mg/dL]

        Other devices (not the study's four LEDs and 12-entry vector) take their own
        LEDs' codes (``adc_ref=None`` without reference codes) and physiological
        columns in ``schema_`` order, through :meth:`predict` on one row.
        """
        if self.__dict__.get("_kernel", 0) is None:
            return predict_one_row(self, adc, adc_ref, pmf)
        try:
            folded = self.folded_
        except AttributeError:
            raise EstimatorNotFittedError(
                "this EnhancedBeerLambert is not fitted yet; call fit before predict_one"
            ) from None
        return folded_predict_one(folded, adc, adc_ref, pmf)


@register("pls")
class PLSBaseline(_LinearBase):
    """PLS regression on the log absorbances and the physiology (4 + 12 on the study's).

    The classical chemometrics baseline [3]_: inputs standardised, the number of latent
    components chosen by subject-grouped inner CV, the fitted model folded to one
    linear map (:attr:`coef_`, :attr:`intercept_`) on the raw inputs.

    Parameters
    ----------
    n_components : int, optional
        Fixed number of components; chosen by inner CV when None. [-]
    max_components : int
        Largest number of components the CV tries (at most 16, the input width). [-]
    cv : int
        Number of inner folds. [-]
    random_state : int, optional
        When subject ids are unknown the inner CV is a KFold over rows, in row order
        when None, shuffled with this seed otherwise.

    Attributes
    ----------
    n_components_ : int
        Components used.
    cv_mse_ : numpy.ndarray
        Inner-CV mean squared error for 1 .. max components. [(mg/dL)^2]
    x_mean_ : numpy.ndarray
        (16,) training means of the inputs (the C export centres with them).
    coef_ : numpy.ndarray
        Coefficients on :attr:`input_names_` (log10 absorbances, then the
        physiological columns in their units; 16 at the study's device).
        [mg/dL per unit]
    intercept_ : float
        [mg/dL]

    References
    ----------
    .. [3] S. de Jong, Chemom. Intell. Lab. Syst. 18, 251-263 (1993); scikit-learn
       ``PLSRegression``.

    Examples
    --------
    >>> import nirglucose as ng
    >>> ds = ng.simulate("wearable", n_subjects=20, per_subject=3, seed=0)
    >>> m = PLSBaseline().fit(ds)
    >>> m.predict(ds).shape, m.n_parameters
    ((60,), 17)
    """

    privileged: ClassVar[str | None] = None

    _parameter_constraints: ClassVar[dict[str, Any]] = {
        "n_components": [None, Interval(Integral, 1, None, closed="left")],
        "max_components": [Interval(Integral, 1, None, closed="left")],
        **_COMMON_CONSTRAINTS,
    }

    _STATE = {
        "schema_": "json",
        "n_components_": None,
        "cv_mse_": (-1,),
        "x_mean_": (-1,),
        "coef_": (-1,),
        "intercept_": None,
    }

    def __init__(
        self,
        n_components=None,
        max_components: int = 16,
        cv: int = 5,
        random_state=None,
        adc_bits=None,
    ):
        self.n_components = n_components
        self.max_components = max_components
        self.cv = cv
        self.random_state = random_state
        self.adc_bits = adc_bits

    def _features(self, Xa: np.ndarray) -> np.ndarray:
        return self.schema_.stacked(Xa)

    @property
    def input_names_(self) -> tuple[str, ...]:
        """Names of the PLS inputs: ``A_<nm>`` per LED, then the physiological columns."""
        return self.schema_.stacked_names

    def fit(self, X, y=None, groups=None):
        """Fit on measurements (same inputs as :meth:`EnhancedBeerLambert.fit`)."""
        self._validate_params()
        cv = int(self.cv)
        mc = self.max_components
        nc = self.n_components
        self.schema_, Xa, y, g = fit_input(self, X, y, groups, self.adc_bits)
        U = self._features(Xa)
        n, p = U.shape
        # No more components than inputs, nor than the rows can support.
        limit = max(1, min(p, n - 1))
        k_max = min(int(nc), limit) if nc is not None else min(int(mc), limit)
        folds = _fold_ids(n, g, cv, self.random_state) if nc is None and k_max > 1 else None
        fit = fit_standardized_cv(
            lambda rows: np.ascontiguousarray(U[rows].T),
            n,
            y,
            folds,
            lambda R, xy: pls1_coefs(R, xy, k_max),
        )
        if fit.mse is not None:
            mse = fit.mse
            k = int(np.argmin(mse)) + 1
        else:
            mse = np.zeros(k_max)
            k = k_max
        with threadpool_limits(limits=1, user_api="blas"):
            beta = pls1_coefs(fit.R, fit.xy, k)[:, -1]
        self.n_components_ = k
        self.cv_mse_ = mse
        self.x_mean_ = fit.mean
        self.coef_ = beta / fit.scale
        self.intercept_ = float(fit.ybar - self.coef_ @ fit.mean)
        self._restore()
        return self

    def _restore(self) -> None:
        self._restore_schema()
        self.n_components_ = int(self.n_components_)
        if len(self.coef_) != len(self.input_names_) or len(self.x_mean_) != len(self.coef_):
            raise DataError("model's coefficients do not match its device; refit the model")

    def predict(self, X) -> np.ndarray:
        """Glucose for each row of measurements. [mg/dL]"""
        self._require_fitted()
        return self._features(predict_input(self, X)) @ self.coef_ + self.intercept_
