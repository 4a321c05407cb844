"""The oracle bound: invert the simulator's noise-free forward model for glucose.

For each snapshot the oracle knows what no device knows: the true nuisance state of
the tissue and the probe (the ``true_*`` columns: blood volume under the probe,
saturation, water and fat fractions, melanin, compressed skin thickness, LED peak
shifts, optical coupling) and the scenario (``Dataset.config``: optics tables, forward
model, geometry, the reference path's transmission). It does *not* know the noise
realisations (shot, Johnson, flicker, thermal drift, dark current, ADC INL and offset,
ambient light, quantisation).

From the training snapshots it learns three things, the way a calibration would:

* a per-channel offset ``o`` of the measured log ratio y = ln(adc / adc_ref) from the
  noise-free model m(g) = ln(fraction(g) / T_ref) at the reference glucose (the
  systematic part of the hardware terms);
* the 4 x 4 covariance ``S`` of the residual y - o - m(g_ref) across channels (the
  noise that remains, correlated across channels through temperature drift);
* with ``prior=True`` (default), the mean and variance of training glucose.

Prediction minimises, per snapshot, the generalised least-squares misfit

    (y - o - m(g))^T S^-1 (y - o - m(g)) + (g - mu)^2 / sigma^2   [second term: prior]

over glucose g by Gauss-Newton on all rows at once (a forward-difference Jacobian of
the forward model, a few iterations: m is nearly linear in g). Without the prior this
is the maximum-likelihood (least-squares) estimate; with it, the posterior mode, which
is never worse than predicting the training mean and so bounds a shrinking estimator
such as ridge as well. The oracle is the reference for what the data allow: benchmarks
report every model's RMSE as a ratio to it.

References
----------
.. [1] R. Gani, "Physics-Informed Neural Networks vs. Physics Models for Non-Invasive
   Glucose Monitoring", University College London (the study this package extends).
.. [2] Å. Björck, "Numerical Methods for Least Squares Problems", SIAM (1996), ch. 9
   (Gauss-Newton).
"""

from __future__ import annotations

from typing import Any, ClassVar

import numpy as np
import pandas as pd
from sklearn.base import BaseEstimator, RegressorMixin

from ..config import ScenarioConfig
from ..dataset import Dataset
from ..dataset.schema import DeviceSchema, check_fit_size, check_reference_glucose
from ..exceptions import DataError
from ..fitted import require_fitted
from ..simulation.simulator import detected_fraction_given_glucose, scenario_tables
from ._inversion_solver import residual_var_floor
from ._json_io import JsonModelMixin
from ._params import Integral, Interval, Real, ValidatedParamsMixin
from .registry import register

__all__ = ["Oracle", "ORACLE_TRUE_COLUMNS", "GLUCOSE_SEARCH_RANGE_MGDL"]

#: Truth columns the forward model needs besides the per-LED ``true_led_shift_nm_<nm>``.
ORACLE_TRUE_COLUMNS = (
    "true_blood_fraction_detected",
    "true_saturation",
    "true_water_fraction",
    "true_subcutis_fat_fraction",
    "true_melanin_fraction",
    "true_skin_thickness_probe_mm",
    "true_coupling",
)
#: Glucose is searched within this range. [mg/dL]
GLUCOSE_SEARCH_RANGE_MGDL = (1.0, 1500.0)
#: Forward-difference step of the Jacobian. [mg/dL]
_STEP_MGDL = 0.5


def _config_and_frame(X, fitted: ScenarioConfig | None) -> tuple[ScenarioConfig, pd.DataFrame]:
    if isinstance(X, Dataset):
        cfg = X.config if X.config is not None else fitted
        frame = X.frame
    elif isinstance(X, pd.DataFrame):
        cfg, frame = fitted, X
    else:
        raise DataError(
            "the oracle needs a Dataset (it reads the true_* columns and the scenario "
            f"config), got {type(X).__name__}"
        )
    if cfg is None:
        raise DataError(
            "the oracle needs the scenario config: pass the Dataset returned by "
            "nirglucose.simulate or load_dataset (a plain DataFrame carries no config)"
        )
    return cfg, frame


def _check_truth(cfg: ScenarioConfig, frame: pd.DataFrame) -> None:
    wl = [f"{w:g}" for w in cfg.leds.wavelengths_nm]
    need = list(ORACLE_TRUE_COLUMNS) + [f"true_led_shift_nm_{w}" for w in wl]
    missing = [c for c in need if c not in frame.columns]
    if missing:
        raise DataError(
            f"the oracle needs the simulator's ground-truth columns; missing {missing} "
            "(a user's own measurements have none: use another model)"
        )
    bad = ~np.isfinite(frame[need].to_numpy(dtype=float)).all(axis=1)
    if bad.any():
        raise DataError(
            f"true_* columns have NaN or infinite values in rows {np.flatnonzero(bad)[:5].tolist()}"
        )


def _device_schema(cfg: ScenarioConfig) -> DeviceSchema:
    """The scenario's device as the schema boundary sees it: its LEDs (in the scenario's
    order), reference codes, its ADC resolution; the oracle reads no measured physiology."""
    return DeviceSchema(
        wavelengths_nm=tuple(float(w) for w in cfg.leds.wavelengths_nm),
        reference=True,
        adc_bits=int(cfg.hardware.adc_bits),
        physiology=(),
    )


def _log_ratio(cfg: ScenarioConfig, frame: pd.DataFrame) -> np.ndarray:
    """ln(adc / adc_ref) per LED, the codes read and checked by the schema (as every model's)."""
    schema = _device_schema(cfg)
    Xa = schema.raw(frame)
    k = schema.n_channels
    # column-major like a DataFrame block: the reductions downstream (mean, covariance)
    # then sum in the same order as before, so results stay byte-identical
    return np.asfortranarray(np.log(Xa[:, :k] / Xa[:, k : 2 * k]))


def _model_log_ratio(
    cfg: ScenarioConfig, frame: pd.DataFrame, glucose: np.ndarray, tables=None
) -> np.ndarray:
    """Noise-free ln(adc / adc_ref) = ln(fraction / T_ref) for each row at ``glucose``."""
    frac = detected_fraction_given_glucose(cfg, frame, glucose, tables)
    return np.log(frac / cfg.hardware.reference_transmission)


@register("oracle")
class Oracle(ValidatedParamsMixin, JsonModelMixin, RegressorMixin, BaseEstimator):
    """Best-case estimator: the forward model inverted with the true nuisance state.

    Reads ``true_*`` columns (the only estimator allowed to). See the module docstring
    for exactly what it knows and learns.

    Parameters
    ----------
    prior : bool
        Add the Gaussian prior of training glucose (posterior mode); False gives the
        pure least-squares (maximum-likelihood) inversion.
    max_iter : int
        Gauss-Newton iterations at most. [-]
    tol : float
        Stop when no estimate moves more than this. [mg/dL]

    Attributes
    ----------
    offset_ : numpy.ndarray
        (n_led,) mean residual of ln(adc/adc_ref) from the noise-free model. [-]
    noise_cov_ : numpy.ndarray
        (n_led, n_led) residual covariance (with a small quantisation floor). [-]
    prior_mean_, prior_var_ : float
        Training glucose mean [mg/dL] and variance [(mg/dL)^2].
    config_ : ScenarioConfig
        The training scenario (used for a prediction frame that carries none).

    Examples
    --------
    >>> import nirglucose as ng
    >>> ds = ng.simulate("paper", 10, 3, seed=0, overrides={"noise_scale": 0.0})
    >>> o = Oracle().fit(ds)
    >>> bool(abs(o.predict(ds) - ds.frame["glucose_mgdl"]).max() < 3.0)
    True
    """

    privileged: ClassVar[str | None] = (
        "true nuisances (true_* columns) and the generating scenario (Dataset.config)"
    )

    _parameter_constraints: ClassVar[dict[str, Any]] = {
        "prior": ["boolean"],
        "max_iter": [Interval(Integral, 1, None, closed="left")],
        "tol": [Interval(Real, 0, None, closed="neither")],  # [mg/dL]
    }

    _STATE = {
        "offset_": (-1,),
        "noise_cov_": (-1, -1),
        "prior_mean_": None,
        "prior_var_": None,
        "config_": "json",
    }

    def __init__(self, prior: bool = True, max_iter: int = 20, tol: float = 1e-3):
        self.prior = prior
        self.max_iter = max_iter
        self.tol = tol

    def _require_fitted(self) -> None:
        require_fitted(self, "offset_")

    def _state_dict(self):
        out = {}
        for name in self._STATE:
            value = getattr(self, name)
            if name == "config_":
                out[name] = value.model_dump(mode="json")
            else:
                out[name] = np.asarray(value).tolist()
        return out

    def _restore(self) -> None:
        if isinstance(self.config_, dict):
            try:
                self.config_ = ScenarioConfig.model_validate(self.config_)
            except ValueError as exc:
                raise DataError(f"the saved oracle's config is invalid: {exc}") from None
        self.prior_mean_ = float(self.prior_mean_)
        self.prior_var_ = float(self.prior_var_)

    def fit(self, X, y=None):
        """Learn the channel offsets, the residual covariance and the glucose prior.

        Parameters
        ----------
        X : Dataset
            Simulated snapshots with their ``config`` and ``true_*`` columns.
        y : array_like, optional
            Reference glucose; ``glucose_mgdl`` when omitted. [mg/dL]

        Returns
        -------
        self
        """
        self._validate_params()
        cfg, frame = _config_and_frame(X, None)
        _check_truth(cfg, frame)
        if y is None:
            if "glucose_mgdl" not in frame.columns:
                raise DataError("fitting needs reference glucose: a 'glucose_mgdl' column or y")
            y = frame["glucose_mgdl"]
        y = np.asarray(y, dtype=float).ravel()
        if len(y) != len(frame) or not np.all(np.isfinite(y)):
            raise DataError("the target must be finite, one value per row")
        groups = frame["subject_id"].to_numpy() if "subject_id" in frame.columns else None
        check_fit_size(len(y), groups)  # the one policy of every model
        check_reference_glucose(y)
        resid = _log_ratio(cfg, frame) - _model_log_ratio(cfg, frame, y)
        n_led = resid.shape[1]
        self.offset_ = resid.mean(axis=0)
        cov = np.cov(resid, rowvar=False) if len(y) > 1 else np.zeros((n_led, n_led))
        # floor: the quantisation of the scenario's ADC (averaging raises its bits)
        floor = residual_var_floor(int(cfg.hardware.adc_bits))
        self.noise_cov_ = np.atleast_2d(cov) + floor * np.eye(n_led)
        self.prior_mean_ = float(y.mean())
        self.prior_var_ = float(max(y.var(ddof=1) if len(y) > 1 else 0.0, 1.0))
        self.config_ = cfg
        self.n_features_in_ = 2 * n_led + 12
        return self

    @property
    def n_parameters(self) -> int:
        """Numbers learned from training data: offsets, the covariance's unique entries,
        and the prior's mean and variance."""
        self._require_fitted()
        k = len(self.offset_)
        return k + k * (k + 1) // 2 + 2

    def predict(self, X) -> np.ndarray:
        """Glucose of each snapshot by inverting the forward model. [mg/dL]

        Parameters
        ----------
        X : Dataset or pandas.DataFrame
            Simulated snapshots; a DataFrame is read with the training scenario.
        """
        self._require_fitted()
        self._validate_params()
        cfg, frame = _config_and_frame(X, self.config_)
        _check_truth(cfg, frame)
        y_obs = _log_ratio(cfg, frame) - self.offset_
        n = len(frame)
        W = np.linalg.inv(self.noise_cov_)
        lam = 1.0 / self.prior_var_ if self.prior else 0.0
        lo, hi = GLUCOSE_SEARCH_RANGE_MGDL
        g = np.full(n, float(np.clip(self.prior_mean_, lo, hi)))

        tables = scenario_tables(cfg)  # once per call, not twice per Gauss-Newton step
        for _ in range(int(self.max_iter)):
            m = _model_log_ratio(cfg, frame, g, tables)
            J = (_model_log_ratio(cfg, frame, g + _STEP_MGDL, tables) - m) / _STEP_MGDL
            r = y_obs - m
            JW = J @ W
            num = np.einsum("ij,ij->i", JW, r) - lam * (g - self.prior_mean_)
            den = np.einsum("ij,ij->i", JW, J) + lam
            step = np.divide(num, den, out=np.zeros(n), where=den > 0)
            g_new = np.clip(g + step, lo, hi)
            moved = np.abs(g_new - g)
            g = g_new
            if moved.max(initial=0.0) < self.tol:
                break
        return g

    def __sklearn_tags__(self):
        tags = super().__sklearn_tags__()
        tags.non_deterministic = False
        tags.target_tags.single_output = True
        return tags
