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
from numbers import Integral
from typing import NamedTuple

import numpy as np
from sklearn.base import BaseEstimator, RegressorMixin
from sklearn.model_selection import GroupKFold, KFold
from threadpoolctl import threadpool_limits

from ..dataset import PMF_COLUMNS
from ..exceptions import ConfigError, DataError
from ..features import (
    ALPHA_MEL,
    ALPHA_PERF,
    ALPHA_SKIN_PER_MM,
    CONTRAST_PAIRS,
    CURVATURE_WEIGHTS,
    DIFFERENCE_PAIRS,
    HYDRATION_CENTER_PCT,
    PERFUSION_COEFFS,
    PRESSURE_CENTER_MBAR,
    PRODUCT_PAIRS,
    SKIN_TEMP_CENTER_C,
    compute_features,
    ebl_feature_matrix,
    feature_table,
    log10_absorbance,
    perfusion_index,
)
from ._base import SchemaJsonMixin, fit_input, predict_input
from ._checks import EstimatorNotFittedError, require_fitted
from .registry import register

__all__ = ["EnhancedBeerLambert", "PLSBaseline", "DEFAULT_ALPHAS", "PLS_INPUT_NAMES"]

#: Ridge penalties tried by the inner CV (sum-of-squares scale, as scikit-learn's Ridge).
DEFAULT_ALPHAS = tuple(float(a) for a in np.logspace(-6, 6, 25))
#: Inputs of the PLS baseline: the 4 log absorbances and the 12 measured PMF entries.
PLS_INPUT_NAMES = ("A_850", "A_940", "A_1050", "A_1150", *PMF_COLUMNS)
_N_CH = 4


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


def _check_cv(cv) -> int:
    if isinstance(cv, bool) or not isinstance(cv, Integral) or cv < 2:
        raise ConfigError(f"cv must be an integer >= 2 (number of inner folds), got {cv!r}")
    return int(cv)


class _LinearBase(SchemaJsonMixin, RegressorMixin, BaseEstimator):
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
    """Enhanced Beer–Lambert: 56 physics features -> standardisation -> ridge.

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
        try:
            grid = np.atleast_1d(np.asarray(alphas, dtype=float))
        except (TypeError, ValueError):
            raise ConfigError(f"alphas must be positive numbers, got {alphas!r}") from None
        if grid.ndim != 1 or grid.size == 0 or not np.all(np.isfinite(grid)) or np.any(grid <= 0):
            raise ConfigError(f"alphas must be positive finite numbers, got {alphas!r}")
        return grid

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
        alphas = self._alpha_grid()
        cv = _check_cv(self.cv)
        self.schema_, Xa, y, g = fit_input(self, X, y, groups, self.adc_bits)
        self.table_ = feature_table(self.schema_)
        folds = _fold_ids(len(Xa), g, cv, self.random_state) if len(alphas) > 1 else None
        fit = _fit_standardized_cv(
            lambda rows: np.ascontiguousarray(self._features(Xa[rows]).T),
            len(Xa),
            y,
            folds,
            lambda R, xy, n_tr: _ridge_coefs(R, xy, alphas),
        )
        if fit.mse is not None:
            mse = fit.mse
            best = int(np.flatnonzero(mse <= mse.min() * (1 + 1e-12))[-1])  # ties: larger
        else:
            mse = np.zeros(len(alphas))
            best = len(alphas) - 1
        alpha = float(alphas[best])
        with threadpool_limits(limits=1, user_api="blas"):
            beta = _ridge_coefs(fit.R, fit.xy, np.array([alpha]))[:, 0]
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
            self.folded_ = _fold_ebl(self.coef_, self.intercept_)
            self._kernel = _FoldedKernel(self.folded_)
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
            return _predict_one_row(self, adc, adc_ref, pmf)
        try:
            (
                b,
                l0,
                t0,
                P0,
                m0,
                T0,
                H0,
                D0,
                l1,
                t1,
                P1,
                m1,
                T1,
                H1,
                D1,
                l2,
                t2,
                P2,
                m2,
                T2,
                H2,
                D2,
                l3,
                t3,
                P3,
                m3,
                T3,
                H3,
                D3,
                q00,
                q01,
                q02,
                q03,
                q11,
                q12,
                q13,
                q22,
                q23,
                q33,
                e0,
                e1,
                e2,
                e3,
                e4,
                e5,
                e6,
                e7,
                e8,
                e9,
                e10,
                e11,
                vtt,
                vhh,
                vpp,
                vth,
                vtp,
                vhp,
            ) = self.folded_
        except AttributeError:
            raise EstimatorNotFittedError(
                "this EnhancedBeerLambert is not fitted yet; call fit before predict_one"
            ) from None
        if type(adc) is np.ndarray:  # numpy scalars are slow in scalar math
            adc = adc.tolist()
        if type(adc_ref) is np.ndarray:
            adc_ref = adc_ref.tolist()
        if type(pmf) is np.ndarray:
            pmf = pmf.tolist()
        try:
            i0, i1, i2, i3 = adc
            r0, r1, r2, r3 = adc_ref
            (x0, x1, x2, mel, t, hyd, sbp, x7, x8, temp, x10, pres) = pmf
            a0 = _log10(r0 / i0)
            a1 = _log10(r1 / i1)
            a2 = _log10(r2 / i2)
            a3 = _log10(r3 / i3)
        except (ValueError, TypeError, ZeroDivisionError):
            raise DataError(
                "predict_one needs 4 positive ADC codes, 4 positive reference codes and "
                f"{len(PMF_COLUMNS)} physiological values"
            ) from None
        dt = temp - _T0
        dh = (hyd - _H0) * _INV_H0
        dp = (pres - _P0) * _INV_P0
        p = _exp(_PC_T * dt + _PC_S * (sbp - _PC_S0) + _PC_P * (pres - _P0))
        return (
            b
            + a0
            * (
                l0
                + t0 * t
                + P0 * p
                + m0 * mel
                + T0 * dt
                + H0 * dh
                + D0 * dp
                + q00 * a0
                + q01 * a1
                + q02 * a2
                + q03 * a3
            )
            + a1
            * (
                l1
                + t1 * t
                + P1 * p
                + m1 * mel
                + T1 * dt
                + H1 * dh
                + D1 * dp
                + q11 * a1
                + q12 * a2
                + q13 * a3
            )
            + a2
            * (l2 + t2 * t + P2 * p + m2 * mel + T2 * dt + H2 * dh + D2 * dp + q22 * a2 + q23 * a3)
            + a3 * (l3 + t3 * t + P3 * p + m3 * mel + T3 * dt + H3 * dh + D3 * dp + q33 * a3)
            + e0 * x0
            + e1 * x1
            + e2 * x2
            + e3 * mel
            + e4 * t
            + e5 * hyd
            + e6 * sbp
            + e7 * x7
            + e8 * x8
            + e9 * temp
            + e10 * x10
            + e11 * pres
            + dt * (vtt * dt + vth * dh + vtp * dp)
            + dh * (vhh * dh + vhp * dp)
            + vpp * dp * dp
        )


_log10 = math.log10
_exp = math.exp
_T0 = SKIN_TEMP_CENTER_C
_H0 = HYDRATION_CENTER_PCT
_INV_H0 = 1.0 / HYDRATION_CENTER_PCT
_P0 = PRESSURE_CENTER_MBAR
_INV_P0 = 1.0 / PRESSURE_CENTER_MBAR
_PC_T = PERFUSION_COEFFS["temp"]
_PC_S = PERFUSION_COEFFS["sbp"]
_PC_S0 = PERFUSION_COEFFS["sbp_center"]
_PC_P = PERFUSION_COEFFS["pressure"]


def _predict_one_row(model, adc, adc_ref, pmf) -> float:
    """predict_one for any device: one raw row through :meth:`predict`."""
    s = model.schema_
    parts = [np.ravel(np.asarray(adc, dtype=float))]
    if s.reference:
        parts.append(np.ravel(np.asarray(adc_ref, dtype=float)))
    parts.append(np.ravel(np.asarray(pmf if pmf is not None else [], dtype=float)))
    row = np.concatenate(parts)
    if row.size != len(s.raw_columns):
        raise DataError(
            f"predict_one takes {len(s.raw_columns)} values for this device "
            f"({', '.join(s.raw_columns)}), got {row.size}"
        )
    return float(model.predict(row[None, :])[0])


class _StandardizedFit(NamedTuple):
    """Sufficient statistics of a standardised least-squares problem (all rows)."""

    R: np.ndarray  # X^T X of the standardised inputs, (p, p)
    xy: np.ndarray  # X^T (y - ybar), (p,)
    mean: np.ndarray  # input means, (p,)
    scale: np.ndarray  # input SDs (1 where constant), (p,)
    ybar: float
    mse: np.ndarray | None  # inner-CV MSE per hyperparameter value, or None


def _standardize_stats(G, zy, zsum, ysum, n):
    """From sums over n rows (z z^T, z y, z, y), the problem on rows standardised by
    their own mean and SD: returns ``(R, xy, mu, sd, ybar)``."""
    mu = zsum / n
    ybar = ysum / n
    cov = G - n * np.outer(mu, mu)
    sd = np.sqrt(np.clip(np.diag(cov) / n, 0.0, None))
    sd[sd <= 1e-12] = 1.0
    R = cov / np.outer(sd, sd)
    return (R + R.T) / 2.0, (zy - mu * ysum) / sd, mu, sd, ybar


def _fit_standardized_cv(inputs, n, y, folds, solve) -> _StandardizedFit:
    """Standardise, cross-validate a family of linear solutions, return the statistics.

    Parameters
    ----------
    inputs : callable
        ``inputs(rows)`` -> (p, len(rows)) inputs of those rows (one row per input).
    n : int
        Number of rows.
    y : numpy.ndarray
        Target, (n,).
    folds : numpy.ndarray or None
        Inner fold of each row, or None for no CV.
    solve : callable
        ``solve(R, xy, n_train)`` -> (p, h) standardised coefficients, one column per
        hyperparameter value.

    Each fold is standardised exactly by its own training rows, computed from sums over
    all rows minus sums over the fold (rows are sorted by fold, so a fold is one
    contiguous block): one pass over the data in all.
    """
    order = np.argsort(folds, kind="stable") if folds is not None else np.arange(n)
    with threadpool_limits(limits=1, user_api="blas"):  # tiny dense algebra
        Z = inputs(order)
        y = np.asarray(y, dtype=float)[order]
        # Global standardisation first, for conditioning of the sums.
        m0 = Z.mean(axis=1)
        Z = Z - m0[:, None]
        s0 = np.sqrt(np.einsum("ij,ij->i", Z, Z) / n)
        s0[s0 <= 1e-12 * np.maximum(np.abs(m0), 1.0)] = 1.0
        Z /= s0[:, None]
        G, zy, zs, ys = Z @ Z.T, Z @ y, Z.sum(axis=1), y.sum()
        mse = None
        if folds is not None:
            bounds = np.searchsorted(folds[order], np.arange(int(folds.max()) + 2))
            sse = 0.0
            for a, b in zip(bounds[:-1], bounds[1:], strict=True):
                Zv, yv = Z[:, a:b], y[a:b]
                R, xy, mu, sd, ybar = _standardize_stats(
                    G - Zv @ Zv.T, zy - Zv @ yv, zs - Zv.sum(axis=1), ys - yv.sum(), n - (b - a)
                )
                coef = solve(R, xy, n - (b - a))
                pred = coef.T @ ((Zv - mu[:, None]) / sd[:, None]) + ybar
                sse = sse + ((pred - yv) ** 2).sum(axis=1)
            mse = sse / n
        R, xy, mu, sd, ybar = _standardize_stats(G, zy, zs, ys, n)
    return _StandardizedFit(R, xy, m0 + s0 * mu, s0 * sd, float(ybar), mse)


def _ridge_coefs(R, xy, alphas) -> np.ndarray:
    """Ridge coefficients for every alpha from one eigen-decomposition, (p, n_alpha).

    coef = V diag(1 / (lambda + alpha)) V^T X^T y with X^T X = V diag(lambda) V^T
    (Hoerl & Kennard 1970).
    """
    lam, V = np.linalg.eigh(R)
    lam = np.clip(lam, 0.0, None)
    return V @ ((V.T @ xy)[:, None] / (lam[:, None] + np.asarray(alphas)[None, :]))


def _pls1_coefs(R, xy, n_components: int) -> np.ndarray:
    """PLS1 coefficients for 1..n_components latent variables, (p, n_components).

    The kernel algorithm of Dayal & MacGregor (1997) on X^T X and X^T y: the same
    components as NIPALS / SIMPLS (de Jong 1993) for a single response. When the
    cross-covariance is exhausted (a perfect fit), further columns repeat the last.
    """
    p = len(xy)
    B = np.zeros((p, n_components))
    Rs = np.zeros((p, n_components))
    Ps = np.zeros((p, n_components))
    s = xy.astype(float).copy()
    s_norm0 = np.linalg.norm(s)
    b = np.zeros(p)
    for a in range(n_components):
        norm = np.linalg.norm(s)
        if norm <= 1e-12 * max(s_norm0, 1e-300):
            B[:, a:] = b[:, None]
            break
        w = s / norm
        r = w - Rs[:, :a] @ (Ps[:, :a].T @ w)
        Rr = R @ r
        tt = r @ Rr
        if tt <= 0:
            B[:, a:] = b[:, None]
            break
        pa = Rr / tt
        q = (s @ r) / tt
        s = s - pa * (q * tt)
        Rs[:, a], Ps[:, a] = r, pa
        b = b + r * q
        B[:, a] = b
    return B


def _fold_ebl(coef: np.ndarray, intercept: float) -> tuple[float, ...]:
    """Fold the 56 raw-feature coefficients into the 57-number polynomial of the model.

    The model is b + sum_k A_k g_k + sum_m e_m pmf_m + (dT, dH, dP) quadratic, with
    g_k = l_k + t_k t + P_k P + M_k M + T_k dT + H_k dH + D_k dP + sum_{j>=k} q_kj A_j.
    Returns ``(b, [l_k, t_k, P_k, M_k, T_k, H_k, D_k] for k = 0..3, q_00, q_01, q_02,
    q_03, q_11, q_12, q_13, q_22, q_23, q_33, e_0..e_11, v_TT, v_HH, v_PP, v_TH, v_TP,
    v_HP)``: 1 + 28 + 10 + 12 + 6 = 57 floats.
    """
    c = np.asarray(coef, dtype=float)
    lin = c[0:4].copy()
    for m, (i, j) in enumerate(CONTRAST_PAIRS + DIFFERENCE_PAIRS):
        lin[i] += c[4 + m]
        lin[j] -= c[4 + m]
    lin += CURVATURE_WEIGHTS.T @ c[10:12]
    cw, ct, chy, cp = c[22:26], c[26:30], c[30:34], c[34:38]
    per_channel: list[float] = []
    for k in range(_N_CH):
        per_channel += [
            lin[k],
            cw[k] * ALPHA_SKIN_PER_MM[k],
            cw[k] * ALPHA_PERF[k],
            cw[k] * ALPHA_MEL[k],
            ct[k],
            chy[k],
            cp[k],
        ]
    assert PRODUCT_PAIRS == tuple((i, j) for i in range(4) for j in range(i, 4))
    return tuple(float(v) for v in [intercept, *per_channel, *c[12:22], *c[38:50], *c[50:56]])


class _FoldedKernel:
    """Vectorised evaluation of the folded polynomial, chunked over rows.

    Per chunk: A (4 rows), the basis u = (1, t, P, M, dT, dH, dP); one small matrix
    product gives g_k for all k at once (u and A stacked), then
    sum_k A_k g_k + e . pmf + the (dT, dH, dP) quadratic.
    """

    _CHUNK = 8192

    def __init__(self, folded: tuple[float, ...]):
        f = np.asarray(folded, dtype=float)
        self.b = float(f[0])
        per = f[1:29].reshape(4, 7)
        q = np.zeros((4, 4))
        q[np.triu_indices(4)] = f[29:39]
        self.C = np.hstack([q, per])  # (4, 11) acting on [A; u]
        self.E = np.ascontiguousarray(f[39:51])
        v = f[51:57]
        self.V = np.array([[v[0], v[3], v[4]], [0.0, v[1], v[5]], [0.0, 0.0, v[2]]])

    def __call__(self, X: np.ndarray) -> np.ndarray:
        n = len(X)
        out = np.empty(n)
        if n == 0:
            return out
        col_major = X.strides[0] == X.itemsize
        size = min(n, self._CHUNK)
        Z = np.empty((11, size))  # rows: A_0..A_3, 1, t, P, M, dT, dH, dP
        Z[4] = 1.0
        G = np.empty((4, size))
        for start in range(0, n, self._CHUNK):
            stop = min(start + self._CHUNK, n)
            m = stop - start
            T = X[start:stop].T
            if not col_major:
                T = np.ascontiguousarray(T)
            codes = T[: 2 * _N_CH]
            if not codes.min() > 0:
                bad = np.flatnonzero(~(codes > 0).all(axis=0))
                raise DataError(
                    "ADC and reference codes must be positive numbers; "
                    f"{len(bad)} rows are not, first row {start + int(bad[0])}"
                )
            z = Z[:, :m]
            A, u = z[:4], z[4:]
            log10_absorbance(T[:_N_CH], T[_N_CH : 2 * _N_CH], out=A)
            pmf = T[2 * _N_CH :]
            u[1] = pmf[4]
            u[3] = pmf[3]
            np.subtract(pmf[9], _T0, out=u[4])
            np.subtract(pmf[5], _H0, out=u[5])
            u[5] *= _INV_H0
            np.subtract(pmf[11], _P0, out=u[6])
            u[6] *= _INV_P0
            perfusion_index(pmf[9], pmf[6], pmf[11], out=u[2])
            g = np.matmul(self.C, z, out=G[:, :m])
            o = out[start:stop]
            np.einsum("km,km->m", A, g, out=o)
            o += self.E @ pmf
            d = u[4:7]
            o += np.einsum("km,km->m", d, self.V @ d)
        out += self.b
        return out


@register("pls")
class PLSBaseline(_LinearBase):
    """PLS regression on the 4 log absorbances and the 12 measured PMF entries.

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
        (16,) coefficients on :data:`PLS_INPUT_NAMES` (log10 absorbances, PMF in column
        units). [mg/dL per unit]
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
        cv = _check_cv(self.cv)
        mc = self.max_components
        if isinstance(mc, bool) or not isinstance(mc, Integral) or mc < 1:
            raise ConfigError(f"max_components must be a positive integer, got {mc!r}")
        nc = self.n_components
        if nc is not None and (isinstance(nc, bool) or not isinstance(nc, Integral) or nc < 1):
            raise ConfigError(f"n_components must be None or a positive integer, got {nc!r}")
        self.schema_, Xa, y, g = fit_input(self, X, y, groups, self.adc_bits)
        U = self._features(Xa)
        n, p = U.shape
        # No more components than inputs, nor than the rows can support.
        limit = max(1, min(p, n - 1))
        k_max = min(int(nc), limit) if nc is not None else min(int(mc), limit)
        folds = _fold_ids(n, g, cv, self.random_state) if nc is None and k_max > 1 else None
        fit = _fit_standardized_cv(
            lambda rows: np.ascontiguousarray(U[rows].T),
            n,
            y,
            folds,
            lambda R, xy, n_tr: _pls1_coefs(R, xy, k_max),
        )
        if fit.mse is not None:
            mse = fit.mse
            k = int(np.argmin(mse)) + 1
        else:
            mse = np.zeros(k_max)
            k = k_max
        with threadpool_limits(limits=1, user_api="blas"):
            beta = _pls1_coefs(fit.R, fit.xy, k)[:, -1]
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
