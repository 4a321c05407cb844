"""Reference learners: no skill, a Gaussian process and gradient boosting.

What a user would pick instead of a physics-informed network, so that every benchmark
table says how much of a model's skill is more than the training mean (``mean``) and
more than an off-the-shelf learner on the same inputs (``gp``, ``gbr``).

All three read their input through the package's one schema boundary
(:func:`~nirglucose.models._base.fit_input`, :func:`~nirglucose.models._base.predict_input`,
:class:`~nirglucose.dataset.schema.DeviceSchema`), as PLS does: the device's absorbances
``log10(I0 / I)``, one per LED, then whichever physiological columns it records, so
they fit, predict, save and load on any LED set, ADC resolution and physiology (the
study's device: 4 + 12 = 16 inputs). The fitted device is saved with the model
(``schema_``) and restored on load.

References
----------
.. [1] C. E. Rasmussen, C. K. I. Williams, *Gaussian Processes for Machine Learning*,
   MIT Press (2006), ch. 2 (posterior mean, Eq. 2.25) and ch. 5.1 (automatic relevance
   determination: one length scale per input), ISBN 0-262-18253-X.
.. [2] J. H. Friedman, "Greedy function approximation: a gradient boosting machine",
   Ann. Statist. 29, 1189-1232 (2001), doi:10.1214/aos/1013203451.
.. [3] F. Pedregosa et al., "Scikit-learn: machine learning in Python", JMLR 12,
   2825-2830 (2011) (``GaussianProcessRegressor``, ``GradientBoostingRegressor``).
.. [4] G. C. Cawley, N. L. C. Talbot, "On over-fitting in model selection and subsequent
   selection bias in performance evaluation", JMLR 11, 2079-2107 (2010) (the marginal
   likelihood over-fits when it tunes many hyper-parameters, e.g. one length scale per
   input, on few rows).
.. [5] ISO 15197:2013, *In vitro diagnostic test systems - Requirements for
   blood-glucose monitoring systems for self-testing in managing diabetes mellitus*,
   sec. 6.3.3: 95 % of readings within +-15 mg/dL below 100 mg/dL and +-15 % above.
"""

from __future__ import annotations

from typing import Any, ClassVar

import numpy as np
from sklearn.base import BaseEstimator, RegressorMixin
from threadpoolctl import threadpool_limits

from ..exceptions import DataError
from ..fitted import require_fitted
from ._base import SchemaJsonMixin, fit_input, predict_input
from ._params import Integral, Interval, Real, StrOptions, ValidatedParamsMixin
from ._whitening import scale_of, zca_whitening
from .registry import register

__all__ = ["MeanReference", "GPReference", "GBRReference", "GP_RANDOM_STATE", "GP_NOISE_FLOOR",
           "GP_KERNELS"]

#: Seeds :func:`numpy.random.default_rng` takes: None, an integer >= 0 or a Generator
#: (the GP's row subset and restarts).
GP_RANDOM_STATE: list[Any] = [None, Interval(Integral, 0, None, closed="left"), np.random.Generator]


#: Lower bound of the GP's white-noise variance, in units of the training glucose
#: variance (``normalize_y``): a noise SD of at least 10 % of the glucose SD, about
#: 5-6 mg/dL on the presets (glucose SD 50-57 mg/dL). Below the label error of any
#: device study's reference: a self-test meter may err by +-15 mg/dL or +-15 % in 5 % of
#: readings (ISO 15197:2013, sec. 6.3.3; an SD of about 7.5 mg/dL, 0.017 of a 57 mg/dL
#: glucose variance), so a
#: GP should not believe its labels more precise. Measured (``mismatch`` study data,
#: ``rte-lut`` and ``diffusion``, seed 0, 40 subjects, grouped 3-fold): with a floor of
#: 1e-5 or 1e-3 a 1e-9 relative perturbation of six physiological columns moved the
#: CV RMSE from 38 to 14 mg/dL (the optimiser ended in another basin); with 1e-2 by
#: under 1 %.
GP_NOISE_FLOOR = 1e-2
#: The GP's kernels (``kernel``): one length scale per input (``"ard"``), one shared by
#: all inputs (``"isotropic"``), or whichever of the two has the higher Bayesian
#: information criterion of its maximised marginal likelihood (``"bic"``).
GP_KERNELS = ("ard", "isotropic", "bic")


#: Rows per block of prediction: the GP's kernel rows and the trees' node indices are
#: (rows x training rows) and (rows x trees) arrays, so a large input is taken in
#: blocks of bounded memory (about 8192 x 1000 x 8 B = 66 MB for the GP).
PREDICT_ROWS = 8192


def _by_chunks(fn, U: np.ndarray) -> np.ndarray:
    """``fn`` applied to blocks of :data:`PREDICT_ROWS` rows of ``U``, concatenated."""
    if len(U) <= PREDICT_ROWS:
        return fn(U)
    return np.concatenate([fn(U[i : i + PREDICT_ROWS]) for i in range(0, len(U), PREDICT_ROWS)])


class _ReferenceBase(ValidatedParamsMixin, SchemaJsonMixin, RegressorMixin, BaseEstimator):
    """Input reading, fitted checks and the saved device, shared by the reference learners.

    Inputs: the fitted device's absorbances, then its physiological columns (n, p).
    """

    _FITTED = "n_features_in_"

    def _require_fitted(self) -> None:
        require_fitted(self, self._FITTED)

    def _fit_inputs(self, X, y, groups):
        """``(U (n, p), y)`` for ``fit``, parameters checked first; records the device
        as ``schema_``."""
        self._validate_params()
        self.schema_, Xa, y, _ = fit_input(self, X, y, groups)
        return self._inputs(Xa), y

    def _predict_inputs(self, X) -> np.ndarray:
        """``U (n, p)``: ``X`` read as the fitted device."""
        return self._inputs(predict_input(self, X))

    def _inputs(self, Xa: np.ndarray) -> np.ndarray:
        return self.schema_.stacked(Xa)

    @property
    def input_names_(self) -> tuple[str, ...]:
        """Names of the inputs: ``A_<nm>`` per LED, then the physiological columns."""
        return self.schema_.stacked_names

    def _check_width(self, name: str, width: int) -> None:
        """Refuse a state whose input width is not the saved device's (DataError)."""
        p = len(self.input_names_)
        if width != p:
            raise DataError(
                f"model state {name!r} is for {width} inputs but its device has {p}; "
                "refit the model"
            )

    def __sklearn_tags__(self):
        tags = super().__sklearn_tags__()
        tags.target_tags.single_output = True
        tags.target_tags.multi_output = False
        return tags


@register("mean")
class MeanReference(_ReferenceBase):
    """No skill: predicts the training mean of glucose for every row.

    Any model whose RMSE is not below this one's has learned nothing from the
    measurements.

    Attributes
    ----------
    schema_ : DeviceSchema
        The fitted device (its inputs are validated, then ignored).
    mean_ : float
        Training mean of glucose. [mg/dL]

    Examples
    --------
    >>> import nirglucose as ng
    >>> ds = ng.simulate("paper", n_subjects=10, per_subject=3, seed=0)
    >>> m = MeanReference().fit(ds)
    >>> bool(m.predict(ds)[0] == ds.frame["glucose_mgdl"].mean()), m.n_parameters
    (True, 1)
    """

    privileged: ClassVar[str | None] = None

    _STATE = {"schema_": "json", "mean_": None}
    _FITTED = "mean_"

    def fit(self, X, y=None, groups=None):
        """Store the mean of the target (the inputs are validated, then ignored)."""
        _, y = self._fit_inputs(X, y, groups)
        self.mean_ = float(np.mean(y))
        self._restore()
        return self

    def _restore(self) -> None:
        self._restore_schema()
        self.mean_ = float(self.mean_)

    def predict(self, X) -> np.ndarray:
        """The training mean for each row. [mg/dL]"""
        self._require_fitted()
        return np.full(len(self._predict_inputs(X)), self.mean_)

    @property
    def n_parameters(self) -> int:
        """One number: the mean."""
        self._require_fitted()
        return 1

    def __sklearn_tags__(self):
        tags = super().__sklearn_tags__()
        tags.regressor_tags.poor_score = True  # no skill by design: R^2 is 0 on its data
        return tags


#: A positive count (rows, stages, depth).
_POSITIVE_INT = [Interval(Integral, 1, None, closed="left")]


@register("gp")
class GPReference(_ReferenceBase):
    """Gaussian process, RBF kernel with one length scale per input (ARD) + white noise.

    Inputs (the device's p absorbances and physiological columns) standardised, then
    scikit-learn's ``GaussianProcessRegressor`` [3]_ with kernel
    ``C * RBF(l_1..l_p) + White`` and ``normalize_y=True``; the kernel's
    hyper-parameters maximise the log marginal likelihood [1]_ inside every ``fit``:
    that is this model's tuning (it has no grid in
    :func:`~nirglucose.models.tuning.search_space`). The white-noise variance is
    bounded below by ``noise_floor`` (:data:`GP_NOISE_FLOOR`): with few rows the
    marginal likelihood over-fits one length scale per input [4]_, and without the
    floor its optimum jumped between basins when the inputs moved by 1e-9. For the
    same reason ``kernel="bic"`` fits both one length scale per input and one shared
    by all, and keeps the one with the higher ``log ML - k/2 ln n`` (k hyper-parameters,
    n rows: Schwarz's criterion [6]_ with the kernel's hyper-parameters counted as
    fitted parameters). Prediction is the posterior mean, ``k(x*, X) @ alpha``
    rescaled (Rasmussen & Williams Eq. 2.25), computed from the stored state, so a
    loaded model predicts the same numbers.

    Parameters
    ----------
    max_fit_rows : int
        At most this many training rows (a random subset, seeded by ``random_state``)
        enter the GP: its cost grows as rows cubed. [-]
    n_restarts_optimizer : int
        Extra random starts of the hyper-parameter search (scikit-learn's, drawn
        log-uniformly within the bounds). [-]
    random_state : int, optional
        Seed of the row subset and of the restarts. The fit runs on one BLAS thread,
        so the same seed gives the same state whatever the machine's core count.
    noise_floor : float
        Lower bound of the white-noise variance, a fraction of the training glucose
        variance (:data:`GP_NOISE_FLOOR`: below a self-test reference's label error
        [5]_). [-]
    kernel : {'ard', 'isotropic', 'bic'}
        One length scale per input, one for all, or the one of the two the
        information criterion prefers (:data:`GP_KERNELS`).

    Attributes
    ----------
    schema_ : DeviceSchema
        The fitted device.
    x_mean_, x_scale_ : numpy.ndarray
        (p,) input standardisation.
    X_train_ : numpy.ndarray
        (m, p) standardised training inputs kept by the GP.
    alpha_ : numpy.ndarray
        (m,) weights of the posterior mean (normalised-target units).
    length_scales_ : numpy.ndarray
        (p,) fitted length scales (standardised-input units; all equal for an
        isotropic kernel). [-]
    kernel_choice_ : str
        The kernel fitted, ``"ard"`` or ``"isotropic"``.
    signal_variance_, noise_variance_ : float
        Fitted constant and white-noise variances (normalised-target units). [-]
    y_mean_, y_std_ : float
        Target normalisation. [mg/dL]

    References
    ----------
    .. [1] Rasmussen & Williams (2006), Eq. 2.25, ch. 5.1.
    .. [3] Pedregosa et al., JMLR 12, 2825-2830 (2011).
    .. [4] Cawley & Talbot, JMLR 11, 2079-2107 (2010).
    .. [5] ISO 15197:2013, sec. 6.3.3.
    .. [6] G. Schwarz, "Estimating the dimension of a model", Ann. Statist. 6, 461-464
       (1978), doi:10.1214/aos/1176344136.

    Examples
    --------
    >>> import nirglucose as ng
    >>> ds = ng.simulate("paper", n_subjects=10, per_subject=3, seed=0)
    >>> GPReference(random_state=0).fit(ds).predict(ds).shape
    (30,)
    """

    privileged: ClassVar[str | None] = None

    _parameter_constraints: ClassVar[dict[str, Any]] = {
        "max_fit_rows": _POSITIVE_INT,
        "n_restarts_optimizer": [Interval(Integral, 0, None, closed="left")],
        "random_state": GP_RANDOM_STATE,
        "noise_floor": [Interval(Real, 0, 1, closed="neither")],
        "kernel": [StrOptions(set(GP_KERNELS))],
    }

    _STATE = {
        "schema_": "json",
        "kernel_choice_": "json",
        "x_mean_": (-1,),
        "x_scale_": (-1,),
        "X_train_": (-1, -1),
        "alpha_": (-1,),
        "length_scales_": (-1,),
        "signal_variance_": None,
        "noise_variance_": None,
        "y_mean_": None,
        "y_std_": None,
    }
    _FITTED = "alpha_"

    def __init__(self, max_fit_rows: int = 1000, n_restarts_optimizer: int = 0, random_state=None,
                 noise_floor: float = GP_NOISE_FLOOR, kernel: str = "ard"):
        self.max_fit_rows = max_fit_rows
        self.n_restarts_optimizer = n_restarts_optimizer
        self.random_state = random_state
        self.noise_floor = noise_floor
        self.kernel = kernel

    def _fit_kernel(self, Z: np.ndarray, y: np.ndarray, kind: str, seed: int | None):
        """scikit-learn's GP with kernel ``kind`` (``"ard"`` or ``"isotropic"``), fitted."""
        import warnings

        from sklearn.exceptions import ConvergenceWarning
        from sklearn.gaussian_process import GaussianProcessRegressor
        from sklearn.gaussian_process.kernels import RBF, WhiteKernel
        from sklearn.gaussian_process.kernels import ConstantKernel as C

        # Starting point: a smooth, nearly linear fit (length scales of 10 on inputs
        # standardised to unit variance, i.e. several times their spread) with all the
        # target's variance as noise; starting from unit length scales the search stops
        # in an over-fitted optimum (measured: test RMSE at the no-skill level on the
        # paper preset). Bounds wide enough that an input can be switched off (length
        # scale 1e5) or the fit become pure noise; the noise no lower than the floor.
        ls = np.full(Z.shape[1], 10.0) if kind == "ard" else 10.0
        kernel = C(1.0, (1e-3, 1e5)) * RBF(ls, (1e-2, 1e5)) + WhiteKernel(
            1.0, (float(self.noise_floor), 1e1)
        )
        gp = GaussianProcessRegressor(
            kernel=kernel,
            normalize_y=True,
            n_restarts_optimizer=int(self.n_restarts_optimizer),
            random_state=seed,
        )
        # One BLAS thread: the fitted kernel depends on the thread count (1 against 2
        # threads: predictions 0.5 mg/dL apart on 1,002 rows), and on a shared 2-core
        # machine one thread was faster (40 rows 0.16 against 7.6 s; 1,002 rows 43
        # against 89 s), as for the linear models.
        with warnings.catch_warnings(), threadpool_limits(limits=1, user_api="blas"):
            # a length scale at its bound is an input the GP switched off: expected
            warnings.simplefilter("ignore", ConvergenceWarning)
            gp.fit(Z, y)
        return gp

    def fit(self, X, y=None, groups=None):
        """Fit the kernel's hyper-parameters and the posterior on the training rows."""
        U, y = self._fit_inputs(X, y, groups)
        max_rows = int(self.max_fit_rows)
        rng = np.random.default_rng(self.random_state)
        if len(U) > max_rows:
            keep = np.sort(rng.choice(len(U), size=max_rows, replace=False))
            U, y = U[keep], y[keep]
        mean = U.mean(axis=0)
        scale = U.std(axis=0)
        scale[scale == 0] = 1.0  # a constant input carries nothing; keep it finite
        Z = (U - mean) / scale
        seed = None if self.random_state is None else int(rng.integers(2**31 - 1))
        kinds = ("ard", "isotropic") if self.kernel == "bic" else (str(self.kernel),)
        best, best_score = None, -np.inf
        for kind in kinds:
            gp = self._fit_kernel(Z, y, kind, seed)
            # [6]: log ML - k/2 ln n, k the kernel's fitted hyper-parameters
            score = gp.log_marginal_likelihood_value_ - 0.5 * len(gp.kernel_.theta) * np.log(
                len(Z))
            if best is None or score > best_score:
                best, best_score, self.kernel_choice_ = gp, score, kind
        gp = best
        k = gp.kernel_
        self.x_mean_, self.x_scale_ = mean, scale
        self.X_train_ = np.asarray(gp.X_train_, dtype=float)
        self.alpha_ = np.asarray(gp.alpha_, dtype=float).ravel()
        ls = np.atleast_1d(np.asarray(k.k1.k2.length_scale, dtype=float))
        self.length_scales_ = np.broadcast_to(ls, (U.shape[1],)).copy()
        self.signal_variance_ = float(k.k1.k1.constant_value)
        self.noise_variance_ = float(k.k2.noise_level)
        self.y_mean_ = float(np.ravel(gp._y_train_mean)[0])
        self.y_std_ = float(np.ravel(gp._y_train_std)[0])
        self._restore()
        return self

    def _restore(self) -> None:
        self._restore_schema()
        if self.kernel_choice_ not in GP_KERNELS[:2]:
            raise DataError(f"model state 'kernel_choice_' is {self.kernel_choice_!r}, not one "
                            f"of {', '.join(GP_KERNELS[:2])}; refit the model")
        for name in ("x_mean_", "x_scale_", "length_scales_"):
            self._check_width(name, len(getattr(self, name)))
        self._check_width("X_train_", self.X_train_.shape[1])
        if len(self.alpha_) != len(self.X_train_):
            raise DataError(
                f"model state 'alpha_' has {len(self.alpha_)} weights for "
                f"{len(self.X_train_)} training rows; refit the model"
            )

    def predict(self, X) -> np.ndarray:
        """Posterior mean of glucose for each row. [mg/dL]"""
        self._require_fitted()
        Z = (self._predict_inputs(X) - self.x_mean_) / self.x_scale_ / self.length_scales_
        T = self.X_train_ / self.length_scales_
        t2 = (T * T).sum(1)[None, :]

        def chunk(z: np.ndarray) -> np.ndarray:
            d2 = (z * z).sum(1)[:, None] + t2 - 2.0 * z @ T.T
            return self.signal_variance_ * np.exp(-0.5 * np.maximum(d2, 0.0)) @ self.alpha_

        return _by_chunks(chunk, Z) * self.y_std_ + self.y_mean_

    @property
    def n_parameters(self) -> int:
        """Numbers the predictor uses: kept inputs, weights, kernel and scaling."""
        self._require_fitted()
        p = len(self.length_scales_)
        return int(self.X_train_.size + self.alpha_.size + 2 * p + p + 4)


@register("gbr")
class GBRReference(_ReferenceBase):
    """Gradient-boosted regression trees (scikit-learn ``GradientBoostingRegressor``).

    Squared-error boosting [2]_ on the device's absorbances and physiological columns,
    ZCA-whitened by default (:func:`~nirglucose.models._whitening.zca_whitening`: glucose
    lies in low-variance directions of these correlated inputs, which axis-aligned splits
    cannot follow: on ``paper`` the raw inputs give no skill, 59 mg/dL against a no-skill
    56, the whitened ones 26-33 mg/dL, seeds 0-1, grouped 5-fold), with scikit-learn's
    default settings [3]_ (100 stages of depth-3 trees, shrinkage
    0.1, every row); tuned values (:func:`~nirglucose.models.tuning.search_space`:
    stages, shrinkage, depth, row fraction) come through the benchmark's per-preset
    parameters. The fitted trees are kept as padded node
    arrays and evaluated by this class (all trees at once), so the model saves to
    JSON and a loaded model predicts the same numbers as scikit-learn (tested).

    Parameters
    ----------
    n_estimators : int
        Boosting stages. [-]
    learning_rate : float
        Shrinkage per stage. [-]
    max_depth : int
        Depth of each tree. [-]
    subsample : float
        Fraction of rows per stage (stochastic gradient boosting). [-]
    whiten_inputs : bool
        Standardise and ZCA-whiten the inputs (with the training rows' statistics) before
        the trees; False boosts on the raw inputs as scikit-learn would.
    random_state : int, optional
        Seed of the subsampling.

    Attributes
    ----------
    schema_ : DeviceSchema
        The fitted device.
    init_ : float
        The boosting's starting value: the training mean. [mg/dL]
    left_, right_, feature_ : numpy.ndarray
        (trees, nodes) child indices (-1 at a leaf) and split input of every node.
    threshold_ : numpy.ndarray
        (trees, nodes) split thresholds (go left when ``input <= threshold``).
    value_ : numpy.ndarray
        (trees, nodes) leaf values, already multiplied by the learning rate. [mg/dL]
    n_nodes_ : numpy.ndarray
        (trees,) nodes of each tree (the rest of its row is padding). [-]
    depth_ : int
        Deepest leaf. [-]
    x_mean_ : numpy.ndarray
        (p,) training means of the inputs (zeros without whitening).
    whitening_ : numpy.ndarray
        (p, p) map of centred inputs to the trees' inputs, ``(U - x_mean_) @ whitening_``
        (the identity without whitening). [-]

    Examples
    --------
    >>> import nirglucose as ng
    >>> ds = ng.simulate("paper", n_subjects=10, per_subject=3, seed=0)
    >>> GBRReference(n_estimators=20, random_state=0).fit(ds).predict(ds).shape
    (30,)
    """

    privileged: ClassVar[str | None] = None

    _parameter_constraints: ClassVar[dict[str, Any]] = {
        "n_estimators": _POSITIVE_INT,
        "learning_rate": [Interval(Real, 0, 1, closed="right")],
        "max_depth": _POSITIVE_INT,
        "subsample": [Interval(Real, 0, 1, closed="right")],
        "whiten_inputs": ["boolean"],
        "random_state": ["random_state"],
    }

    _STATE = {
        "schema_": "json",
        "init_": None,
        "left_": (-1, -1),
        "right_": (-1, -1),
        "feature_": (-1, -1),
        "threshold_": (-1, -1),
        "value_": (-1, -1),
        "n_nodes_": (-1,),
        "depth_": None,
        "x_mean_": (-1,),
        "whitening_": (-1, -1),
    }
    _FITTED = "value_"

    def __init__(
        self,
        n_estimators: int = 100,
        learning_rate: float = 0.1,
        max_depth: int = 3,
        subsample: float = 1.0,
        whiten_inputs: bool = True,
        random_state=None,
    ):
        self.n_estimators = n_estimators
        self.learning_rate = learning_rate
        self.max_depth = max_depth
        self.subsample = subsample
        self.whiten_inputs = whiten_inputs
        self.random_state = random_state

    def fit(self, X, y=None, groups=None):
        """Fit the boosted trees on the training rows."""
        from sklearn.ensemble import GradientBoostingRegressor

        U, y = self._fit_inputs(X, y, groups)
        p = U.shape[1]
        if self.whiten_inputs:
            self.x_mean_ = U.mean(axis=0)
            scale = scale_of(U)
            self.whitening_ = zca_whitening((U - self.x_mean_) / scale) / scale[:, None]
        else:
            self.x_mean_, self.whitening_ = np.zeros(p), np.eye(p)
        U = (U - self.x_mean_) @ self.whitening_
        gbr = GradientBoostingRegressor(
            n_estimators=int(self.n_estimators),
            learning_rate=float(self.learning_rate),
            max_depth=int(self.max_depth),
            subsample=float(self.subsample),
            random_state=self.random_state,
        ).fit(U, y)
        trees = [t.tree_ for t in gbr.estimators_.ravel()]
        m = max(t.node_count for t in trees)

        def padded(get, fill):
            out = np.full((len(trees), m), fill, dtype=float)
            for k, t in enumerate(trees):
                out[k, : t.node_count] = get(t)
            return out

        self.init_ = float(np.ravel(gbr.init_.predict(U[:1]))[0])
        self.left_ = padded(lambda t: t.children_left, -1.0)
        self.right_ = padded(lambda t: t.children_right, -1.0)
        self.feature_ = padded(lambda t: np.maximum(t.feature, 0), 0.0)
        self.threshold_ = padded(lambda t: t.threshold, 0.0)
        self.value_ = padded(lambda t: t.value.reshape(t.node_count) * gbr.learning_rate, 0.0)
        self.n_nodes_ = np.array([t.node_count for t in trees], dtype=float)
        self.depth_ = int(max(t.max_depth for t in trees))
        self._restore()
        return self

    def _restore(self) -> None:
        self._restore_schema()
        self.depth_ = int(self.depth_)
        shape = self.value_.shape
        arrays = (self.left_, self.right_, self.feature_, self.threshold_)
        if any(a.shape != shape for a in arrays) or self.n_nodes_.shape != shape[:1]:
            raise DataError("model's tree arrays do not have one shape; refit the model")
        p_in = len(self.input_names_)
        if self.x_mean_.shape != (p_in,) or self.whitening_.shape != (p_in, p_in):
            raise DataError(
                f"model's whitening does not match its device's {p_in} inputs; refit the model"
            )
        self._left = self.left_.astype(np.intp)
        self._right = self.right_.astype(np.intp)
        self._feature = self.feature_.astype(np.intp)
        n_nodes = shape[1]
        p = len(self.input_names_)
        if (
            self._feature.min(initial=0) < 0
            or self._feature.max(initial=0) >= p
            or np.minimum(self._left, self._right).min(initial=0) < -1
            or np.maximum(self._left, self._right).max(initial=0) >= n_nodes
        ):
            raise DataError(
                f"model's trees name inputs or nodes outside its device's {p} inputs; "
                "refit the model"
            )

    def predict(self, X) -> np.ndarray:
        """Glucose for each row. [mg/dL]"""
        self._require_fitted()
        U = (self._predict_inputs(X) - self.x_mean_) @ self.whitening_
        # scikit-learn's trees compare float32 inputs with float64 thresholds
        Uf = U.astype(np.float32).astype(np.float64)
        tix = np.arange(self.value_.shape[0])

        def chunk(u: np.ndarray) -> np.ndarray:
            node = np.zeros((len(u), len(tix)), dtype=np.intp)
            for _ in range(self.depth_):
                left = self._left[tix, node]
                x = np.take_along_axis(u, self._feature[tix, node], axis=1)
                nxt = np.where(x <= self.threshold_[tix, node], left, self._right[tix, node])
                node = np.where(left < 0, node, nxt)
            return self.value_[tix, node].sum(axis=1)

        return self.init_ + _by_chunks(chunk, Uf)

    @property
    def n_parameters(self) -> int:
        """Tree nodes (a threshold or a leaf value each) plus the initial constant."""
        self._require_fitted()
        return int(self.n_nodes_.sum()) + 1
