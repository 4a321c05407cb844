"""Forward-model inversion: per reading, the posterior mode of glucose and the nuisances.

Where the oracle (:mod:`nirglucose.models.oracle`) inverts the forward model with the
true tissue and probe state, these estimators know a forward model but not the state.
Per reading they estimate glucose *and* the nuisances the device does not measure --
detected blood fraction, saturation, water and fat fractions, melanin, the skin
thickness under the probe, the LEDs' thermal peak shift and the optical coupling
(:data:`~nirglucose.models._inversion_solver.NUISANCES`) -- as the mode of

    p(theta, g | y) ~ N(y; a + b m(g, theta), S) N(theta; mu(x), diag(s^2)) N(g; mu_g, s_g^2)

with y = ln(adc / adc_ref) per LED, m a noise-free forward model, x the reading's
measured physiological columns, (a, b) a per-channel calibration and S the residual
covariance. Everything is solved for all rows at once by Levenberg-Marquardt.

What they learn from the training rows' measured columns and reference glucose (never
a ``true_*`` column), by empirical Bayes [1]_ (an EM iteration with a Laplace posterior):

* the prior means mu(x): a physical start from the measured columns, plus a ridge
  correction linear in the standardised physiology, refitted to the training rows'
  posterior modes at their known glucose;
* the prior widths s, from the spread of those modes plus their posterior variance;
* the calibration (a, b) per channel and S, from the residuals at the modes;
* the glucose prior: the training mean and variance.

:class:`ForwardModelInversion` is that machinery. The two registered estimators differ
only in what they read besides the measured columns (``privileged``):

* :class:`PhysicsInversion` (``physics-inversion``, privileged, a reference): the
  generating scenario (``Dataset.config``) -- the simulator's own forward model with
  glucose's optical signal at the scenario's ``glucose.signal_gain``, its LED bands,
  geometry and tables, and the simulator's relations as prior starts
  (:func:`prior_start`). It refuses data without a scenario (:func:`require_scenario`).
* :class:`~nirglucose.models.device_inversion.DeviceInversion` (``device-inversion``,
  deployable): the device's declared parts and published tables only; glucose's
  response per channel is learned.

References
----------
.. [1] A. P. Dempster, N. M. Laird, D. B. Rubin, "Maximum likelihood from incomplete
   data via the EM algorithm", J. R. Stat. Soc. B 39, 1-38 (1977).
.. [2] C. M. Bishop, "Pattern Recognition and Machine Learning", Springer (2006), 4.4
   (the Laplace approximation).
"""

from __future__ import annotations

from typing import Any, ClassVar

import numpy as np
import pandas as pd
from sklearn.base import BaseEstimator, RegressorMixin

from ..config import ScenarioConfig
from ..constants import LED_REFERENCE_TEMPERATURE_C
from ..dataset import Dataset
from ..exceptions import DataError
from ..fitted import require_fitted
from ..optics.forward import FORWARD_MODELS
from ..simulation.physiology import melanin_fraction_from_fitzpatrick, subcutis_fat_fraction
from ._base import SchemaJsonMixin, fit_input, predict_input
from ._inversion_solver import (
    NUISANCES,
    ForwardModel,
    map_estimate,
    model_jacobian,
    posterior_variance,
    residual_var_floor,
)
from ._params import Integral, Interval, Real, StrOptions, ValidatedParamsMixin
from .registry import register

__all__ = [
    "ForwardModelInversion",
    "PhysicsInversion",
    "PRIVILEGED_SCENARIO",
    "DEPLOYABLE_INVERSION",
    "START_SD",
    "prior_start",
    "require_scenario",
]

#: What the estimators that read the generating scenario know beyond the measured
#: columns: their ``privileged`` declaration
#: (:func:`~nirglucose.models.registry.privileged_knowledge`).
PRIVILEGED_SCENARIO = "the generating scenario and the simulator's forward model (Dataset.config)"
#: The registered forward-model estimator that reads no scenario: what a refusal names.
DEPLOYABLE_INVERSION = "device-inversion"

#: Prior standard deviation of each nuisance before the empirical-Bayes updates (an
#: assumption: about a quarter of each one's population spread in SOURCES.md's layer
#: table -- blood 1-5 %, saturation 0.6-0.8, water 0.6-0.7, fat 0.7-0.9, melanin
#: 0.01-0.15, dermis 0.5-3 mm -- an LED shift of about 3 degC at 0.3 nm/degC, and a 3 %
#: coupling). The fit replaces them by what the training rows support.
START_SD = {
    "log_blood_fraction": 0.5,
    "saturation": 0.05,
    "water_fraction": 0.03,
    "subcutis_fat_fraction": 0.05,
    "melanin_fraction": 0.02,
    "skin_thickness_mm": 0.3,
    "led_shift_nm": 1.0,
    "log_coupling": 0.03,
}
#: Smallest prior width the updates may reach, as a share of :data:`START_SD` (keeps
#: the whitened problem well conditioned). [-]
_SD_FLOOR = 1e-3
#: Ridge penalty of the prior-mean correction, on standardised physiology. [-]
_PRIOR_RIDGE = 1.0
_LN10 = np.log(10.0)
#: Over-relaxation of the widths' EM update in log space (1: plain EM). [-]
_OVERRELAX = 2.0


def _column(schema, phys: np.ndarray, name: str):
    """A measured physiological column, or None where the device does not record it."""
    return phys[:, schema.physiology.index(name)] if name in schema.physiology else None


def _led_shift_start_nm(cfg: ScenarioConfig, skin_c) -> np.ndarray | float:
    """Expected LED peak shift from the skin temperature. [nm]

    Ambient from the skin's documented response to it (``physiology.skin_temp_*``,
    inverted), the junction ``hardware.led_self_heating_c`` above ambient, and the
    datasheet coefficient ``hardware.led_wavelength_shift_nm_per_c`` about the 25 degC
    reference (:func:`nirglucose.simulation.hardware.led_peak_shift_nm`), scaled by the
    scenario's ``led_wavelength_shift`` switch.
    """
    p, hw = cfg.physiology, cfg.hardware
    if skin_c is None:
        ambient_c = p.skin_temp_ambient_ref_c
    else:
        ambient_c = p.skin_temp_ambient_ref_c + (skin_c - p.skin_temp_c_neutral) / max(
            p.skin_temp_per_ambient, 1e-6
        )
    led_c = ambient_c + hw.led_self_heating_c
    factor = cfg.noise_factor("led_wavelength_shift")
    return factor * hw.led_wavelength_shift_nm_per_c * (led_c - LED_REFERENCE_TEMPERATURE_C)


def prior_start(cfg: ScenarioConfig, schema, phys: np.ndarray) -> np.ndarray:
    """The physical start of each nuisance's prior mean from the measured columns.

    Each from the scenario's documented relations (:mod:`nirglucose.simulation.physiology`,
    :mod:`nirglucose.simulation.measurement`) and population values where the device
    does not measure it: PPG ``blood_volume_pct`` (else ``physiology.blood_fraction_median``)
    and ``spo2_pct`` (else ``physiology.saturation_mean``); water =
    ``physiology.water_fraction_nominal`` x hydration / 100; fat from BMI
    (:func:`~nirglucose.simulation.physiology.subcutis_fat_fraction`); melanin as measured
    (else the middle of the Fitzpatrick type's range); skin thickness as measured (else
    ``physiology.skin_thickness_mm_mean``); LED shift from skin temperature; coupling 1.

    Returns
    -------
    numpy.ndarray
        (n, len(NUISANCES)) in the units of :data:`NUISANCES`.
    """
    p = cfg.physiology
    n = len(phys)

    def col(name, default):
        v = _column(schema, phys, name)
        return np.full(n, float(default)) if v is None else np.asarray(v, float)

    blood = col("blood_volume_pct", 100.0 * p.blood_fraction_median) / 100.0
    bmi = col("bmi_kgm2", p.bmi_kgm2_mean)
    fitz = col("fitzpatrick_type", p.nominal_fitzpatrick_type)
    melanin_default = melanin_fraction_from_fitzpatrick(np.clip(np.rint(fitz), 1, 6), 0.5)
    melanin = _column(schema, phys, "melanin_fraction")
    fat_args = (p.subcutis_fat_fraction_min, p.subcutis_fat_fraction_rise, p.subcutis_fat_bmi_kgm2)
    out = np.column_stack(
        [
            np.log(np.maximum(blood, 1e-4)),
            col("spo2_pct", 100.0 * p.saturation_mean) / 100.0,
            p.water_fraction_nominal * col("hydration_pct", 100.0) / 100.0,
            subcutis_fat_fraction(bmi, *fat_args),
            melanin_default if melanin is None else melanin,
            col("skin_thickness_mm", p.skin_thickness_mm_mean),
            np.broadcast_to(_led_shift_start_nm(cfg, _column(schema, phys, "skin_temp_c")), n),
            np.zeros(n),
        ]
    )
    return out


def require_scenario(X, schema, who: str) -> ScenarioConfig:
    """The generating scenario of ``X``, which a privileged estimator reads.

    Parameters
    ----------
    X : Dataset
        Training data; a Dataset from :func:`nirglucose.simulate` (or its Parquet file)
        carries its scenario (``Dataset.config``).
    schema : DeviceSchema
        The fitted device (its LEDs must be the scenario's).
    who : str
        The estimator's registered name, for the message.

    Raises
    ------
    DataError
        In one line, where ``X`` carries no scenario (a DataFrame, a CSV file, a
        device's own file: never read as if it were a preset), naming the deployable
        estimator to use instead; or where its LEDs are not the scenario's.
    """
    cfg = X.config if isinstance(X, Dataset) else None
    if cfg is None:
        raise DataError(
            f"{who} reads the generating scenario (the simulator's forward model and "
            "glucose gain), which only a Dataset from `nirglucose simulate` or its "
            "Parquet file carries; this data has none (a CSV, a DataFrame or a "
            f"device's own file): use {DEPLOYABLE_INVERSION!r}, which needs only the "
            "device's parts"
        )
    leds = tuple(float(w) for w in cfg.leds.wavelengths_nm)
    if leds != tuple(schema.wavelengths_nm):
        raise DataError(
            f"{who} needs the device's optics: the data's LEDs {schema.labels} "
            f"are not the scenario's {leds}; pass the Dataset (with its config)"
        )
    return cfg


class ForwardModelInversion(
    ValidatedParamsMixin, SchemaJsonMixin, RegressorMixin, BaseEstimator
):
    """Forward-model inversion for glucose and the unmeasured nuisances (MAP; not registered).

    The machinery the registered inversions share (see the module docstring for the
    model, what it learns and from what). A subclass says what it reads besides the
    measured columns, and nothing else:

    * :meth:`_assume`: what ``fit`` takes from the training data (a scenario, the
      device's declared parts);
    * :meth:`_build_forward`: the forward model from the fitted state;
    * :meth:`_prior_start`: the physical start of the nuisances' prior means;
    * optionally :meth:`_calibrate` (the per-channel calibration) and
      :meth:`_var_floor`.

    Parameters
    ----------
    forward_model : {'beer-lambert', 'diffusion', 'rte-lut'}
        The forward model assumed (need not be the one that made the data).
    prior_scale : float
        Multiplies every nuisance's learned prior width at prediction (1: as learned;
        larger trusts the measured columns less). [-]
    n_em : int
        Empirical-Bayes rounds in ``fit`` (0: the physical start and unit gains). [-]
    max_iter : int
        Levenberg-Marquardt iterations at most per solve. [-]

    Attributes
    ----------
    schema_ : DeviceSchema
        The fitted device.
    offset_, gain_ : numpy.ndarray
        (k,) per-channel calibration a, b of ln(adc / adc_ref). [-]
    noise_cov_ : numpy.ndarray
        (k, k) residual covariance S. [-]
    prior_coef_ : numpy.ndarray
        (len(NUISANCES), 1 + m) correction of each prior mean, linear in the
        standardised physiology. [nuisance units]
    prior_sd_ : numpy.ndarray
        (len(NUISANCES),) learned prior widths. [nuisance units]
    x_mean_, x_scale_ : numpy.ndarray
        (m,) standardisation of the physiology.
    glucose_mean_, glucose_var_ : float
        Prior of glucose: [mg/dL] and [(mg/dL)^2].
    """

    _parameter_constraints: ClassVar[dict[str, Any]] = {
        "forward_model": [StrOptions(set(FORWARD_MODELS))],
        "prior_scale": [Interval(Real, 0, None, closed="neither")],
        "n_em": [Interval(Integral, 0, None, closed="left")],
        "max_iter": [Interval(Integral, 1, None, closed="left")],
    }

    _STATE: ClassVar[dict[str, Any]] = {
        "schema_": "json",
        "offset_": (-1,),
        "gain_": (-1,),
        "noise_cov_": (-1, -1),
        "prior_coef_": (len(NUISANCES), -1),
        "prior_sd_": (len(NUISANCES),),
        "x_mean_": (-1,),
        "x_scale_": (-1,),
        "glucose_mean_": None,
        "glucose_var_": None,
    }

    def __init__(
        self,
        forward_model: str = "beer-lambert",
        prior_scale: float = 1.0,
        n_em: int = 30,
        max_iter: int = 30,
    ):
        self.forward_model = forward_model
        self.prior_scale = prior_scale
        self.n_em = n_em
        self.max_iter = max_iter

    # ------------------------------------------------------------------ plumbing

    def _require_fitted(self) -> None:
        require_fitted(self, "offset_")

    def _restore(self) -> None:
        self._restore_schema()
        self.glucose_mean_ = float(self.glucose_mean_)
        self.glucose_var_ = float(self.glucose_var_)
        self.forward_ = self._build_forward()

    # ------------------------------------------------------------------ what it reads

    def _assume(self, X) -> None:
        """Take what the forward model needs besides the measured columns from the
        training data ``X`` (fitted attributes); called once in ``fit``."""
        raise NotImplementedError

    def _build_forward(self):
        """The forward model (``log_ratio(glucose_mgdl, theta)``) from the fitted state."""
        raise NotImplementedError

    def _prior_start(self, phys: np.ndarray) -> np.ndarray:
        """(n, len(NUISANCES)) physical start of the prior means from the physiology."""
        raise NotImplementedError

    def _var_floor(self) -> float:
        """Variance added to the residual covariance's diagonal: the quantisation floor
        of the data's declared ADC bits (:func:`~nirglucose.models._inversion_solver.
        residual_var_floor`; 2e-8 at 12 bits). [-]"""
        return residual_var_floor(self.schema_.adc_bits)

    def _design(self, phys: np.ndarray) -> np.ndarray:
        """(n, 1 + m): a constant and the standardised physiology."""
        return np.column_stack([np.ones(len(phys)), (phys - self.x_mean_) / self.x_scale_])

    def _observed(self, Xa: np.ndarray):
        """ln(adc / adc_ref) per LED (-ln 10 x absorbance) and the physiology."""
        m = self.schema_.split(Xa)
        return -_LN10 * m.absorbance, m.physiology

    def _prior(self, phys: np.ndarray, glucose=None):
        """(mean, sd), each (n, 1 + len(NUISANCES)): glucose first (its reference value
        and any sd where given), then the nuisances."""
        n = len(phys)
        nuis = self._prior_start(phys)
        nuis += self._design(phys) @ self.prior_coef_.T
        g = np.full(n, self.glucose_mean_) if glucose is None else glucose
        mean = np.column_stack([g, nuis])
        sd = np.concatenate([[np.sqrt(self.glucose_var_)], self.prior_sd_])
        return mean, np.broadcast_to(sd, mean.shape).copy()

    def _root_w(self) -> np.ndarray:
        """R with R^T R = S^-1 (S the residual covariance): the whitening of the misfit.

        The Cholesky factor of S^-1 where it exists in floating point; where S is so
        ill-conditioned that it does not (residuals far above the quantisation floor
        along some directions and at it along others: a floor of many ADC bits), S's
        eigen-decomposition gives the same R^T R, its eigenvalues held at the floor.
        """
        try:
            return np.linalg.cholesky(np.linalg.inv(self.noise_cov_)).T
        except np.linalg.LinAlgError:
            lam, vec = np.linalg.eigh(self.noise_cov_)
            lam = np.maximum(lam, self._var_floor())
            return (vec / np.sqrt(lam)).T

    # ------------------------------------------------------------------ fit

    def fit(self, X, y=None, groups=None):
        """Learn the calibration, noise, priors and glucose prior from training rows.

        Parameters
        ----------
        X : Dataset or pandas.DataFrame
            Readings of a device with ADC (and reference) codes and physiology (what
            else is read: the subclass's ``privileged`` declaration).
        y : array_like, optional
            Reference glucose; ``glucose_mgdl`` when omitted. [mg/dL]
        groups : array_like, optional
            Subject ids (checked by the fitting-size policy only).

        Returns
        -------
        self
        """
        self._validate_params()
        self.schema_, Xa, y, groups = fit_input(self, X, y, groups)
        if self.schema_.is_plain:
            raise DataError(
                f"{self.registry_name} needs a device's ADC columns (adc_<nm>), not a plain "
                "array"
            )
        self._assume(X)
        obs, phys = self._observed(Xa)
        self.x_mean_ = phys.mean(axis=0)
        sc = phys.std(axis=0)
        self.x_scale_ = np.where(sc > 0, sc, 1.0)
        self.glucose_mean_ = float(y.mean())
        self.glucose_var_ = float(max(y.var(ddof=1), 1.0))
        self.forward_ = self._build_forward()
        self.prior_coef_ = np.zeros((len(NUISANCES), 1 + phys.shape[1]))
        self.prior_sd_ = np.array([START_SD[n] for n in NUISANCES])
        mean, _ = self._prior(phys, y)
        self._calibrate(obs, self.forward_.log_ratio(y, mean[:, 1:]), y)
        free = np.array([False] + [True] * len(NUISANCES))
        for _ in range(int(self.n_em)):
            self._em_round(obs, phys, y, free)
        self._restore_schema()
        self._after_fit(X, y, groups)
        return self

    def _after_fit(self, X, y: np.ndarray, groups) -> None:
        """What a subclass learns once the EM has run (nothing here)."""

    def _calibrate(self, obs: np.ndarray, model: np.ndarray, y: np.ndarray,
                   edf: float = 0.0) -> None:
        """Per channel, least squares obs = a + b model (``y``, the rows' reference
        glucose, is not needed here); then S (:meth:`_set_noise`)."""
        mc = model - model.mean(axis=0)
        var = (mc**2).mean(axis=0)
        cross = (mc * (obs - obs.mean(axis=0))).mean(axis=0)
        b = np.where(var > 0, cross / np.where(var > 0, var, 1.0), 1.0)
        a = obs.mean(axis=0) - b * model.mean(axis=0)
        self.offset_, self.gain_ = a, b
        self._set_noise(obs - a - b * model, edf, 2)

    def _set_noise(self, resid: np.ndarray, edf: float, per_channel: int) -> None:
        """S from the residuals, divided by the share of the n k residual degrees of
        freedom left free by the modes (``edf`` parameters fitted in all) and the
        calibration (``per_channel`` coefficients per channel; Hastie et al. 2009,
        Eq. 7.5), plus :meth:`_var_floor` on the diagonal."""
        k = resid.shape[1]
        cov = np.atleast_2d(np.cov(resid, rowvar=False)) if len(resid) > 1 else np.zeros((k, k))
        dof = resid.size / max(resid.size - edf - per_channel * k, 0.1 * resid.size)
        self.noise_cov_ = dof * cov + self._var_floor() * np.eye(k)

    def _em_round(self, obs, phys, y, free) -> None:
        """One empirical-Bayes round at the known glucose: modes, then priors and
        calibration refitted to them (Dempster et al. 1977, with the Laplace posterior)."""
        mean, sd = self._prior(phys, y)
        calib = (self.offset_, self.gain_)
        root_w = self._root_w()
        theta, m = map_estimate(
            self.forward_, obs, calib, root_w, mean, sd, free=free, max_iter=self.max_iter
        )
        post, edf = posterior_variance(
            self.forward_, obs, calib, root_w, mean, sd, theta, free=free
        )
        start = self._prior_start(phys)
        D = self._design(phys)
        target = theta[:, 1:] - start
        pen = _PRIOR_RIDGE * np.eye(D.shape[1])
        pen[0, 0] = 0.0  # the intercept is not shrunk
        coef = np.linalg.solve(D.T @ D + pen, D.T @ target)  # (1 + m, n_nuis)
        resid = target - D @ coef
        var = (resid**2).mean(axis=0) + post[:, 1:].mean(axis=0)
        start_sd = np.array([START_SD[n] for n in NUISANCES])
        self.prior_coef_ = coef.T
        # never wider than the population's spread, never narrower than the floor
        # over-relaxed in log sd (Salakhutdinov & Roweis 2003, ICML, "Adaptive
        # overrelaxed bound optimization methods"): EM shrinks a width slowly where
        # the data leave little to explain
        log_sd = np.log(self.prior_sd_) + _OVERRELAX * (0.5 * np.log(var) - np.log(self.prior_sd_))
        self.prior_sd_ = np.clip(np.exp(log_sd), _SD_FLOOR * start_sd, start_sd)
        self._calibrate(obs, m, y, float(edf.sum()))

    # ------------------------------------------------------------------ predict

    def estimate_state(self, X) -> pd.DataFrame:
        """Each reading's estimated glucose [mg/dL] and nuisances (:data:`NUISANCES`,
        blood fraction and coupling as values, not logs), as a DataFrame."""
        self._require_fitted()
        self._validate_params()
        obs, phys = self._observed(predict_input(self, X))
        mean, sd = self._prior(phys)
        sd[:, 1:] *= float(self.prior_scale)
        theta, _ = map_estimate(
            self.forward_, obs, (self.offset_, self.gain_), self._root_w(), mean, sd,
            free=np.ones(mean.shape[1], bool), max_iter=self.max_iter,
        )
        out = pd.DataFrame(theta[:, 1:], columns=list(NUISANCES))
        out.insert(0, "glucose_mgdl", theta[:, 0])
        out["blood_fraction"] = np.exp(out.pop("log_blood_fraction"))
        out["coupling"] = np.exp(out.pop("log_coupling"))
        return out

    def sample_log_ratios(self, X, glucose_mgdl, random_state=None) -> np.ndarray:
        r"""Readings the fitted forward model generates for the physiology of ``X``.

        Per row, the nuisances are drawn from their learned prior
        :math:`N(\mu(x), \mathrm{diag}(s^2))` (x the row's measured physiology),
        and :math:`y = a + b\,m(g, \theta) + \epsilon`,
        :math:`\epsilon \sim N(0, S)`: the model this estimator inverts, run forwards.

        Parameters
        ----------
        X : Dataset, pandas.DataFrame or array_like
            Readings of the fitted device; only their physiology is used.
        glucose_mgdl : array_like
            (n,) glucose of each generated reading. [mg/dL]
        random_state : int, numpy.random.Generator or None
            Seeds the draws.

        Returns
        -------
        numpy.ndarray
            (n, k) ln(adc / adc_ref) per LED (NaN where the drawn state is outside the
            optics' domain, e.g. volume fractions summing past 1). [-]
        """
        self._require_fitted()
        _, phys = self._observed(predict_input(self, X))
        g = np.asarray(glucose_mgdl, dtype=float).ravel()
        if len(g) != len(phys) or not np.all(np.isfinite(g)):
            raise DataError(f"glucose_mgdl must be {len(phys)} finite values, got {len(g)}")
        rng = np.random.default_rng(random_state)
        mean, sd = self._prior(phys, g)
        theta = mean[:, 1:] + sd[:, 1:] * rng.standard_normal(mean[:, 1:].shape)
        noise = rng.standard_normal((len(g), len(self.offset_))) @ np.linalg.cholesky(
            self.noise_cov_
        ).T
        with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
            m = self.forward_.log_ratio(g, theta)
        return self.offset_ + self.gain_ * m + noise

    def glucose_likelihood(self, X, glucose_mgdl) -> tuple[np.ndarray, np.ndarray]:
        r"""Each reading's likelihood of glucose, the nuisances marginalised (Laplace).

        The measured log ratios y of a reading, as a function of its glucose g alone:
        the forward model is linearised about ``glucose_mgdl`` and the nuisances' mode
        there, and the nuisances are integrated out under their prior (Bishop 2006,
        4.4 and 2.3.3 [2]_), which leaves a Gaussian in g.

        Parameters
        ----------
        X : Dataset, pandas.DataFrame or array_like
            Readings of the fitted device (measured columns only are read).
        glucose_mgdl : array_like
            (n,) where to linearise, e.g. the reference glucose of training rows
            (glucose's optical effect is linear, so the point matters little). [mg/dL]

        Returns
        -------
        glucose_mgdl : numpy.ndarray
            (n,) the likelihood's mode :math:`\hat g`. [mg/dL]
        information_per_mgdl2 : numpy.ndarray
            (n,) its curvature :math:`w = J_g^T\Sigma^{-1}J_g` (0 where the forward
            model cannot be evaluated). [1/(mg/dL)^2]

        Notes
        -----
        With :math:`\hat\theta` the nuisances' mode at :math:`g_0`, :math:`m` the
        forward model, :math:`(a, b)` the calibration, S the residual covariance and
        :math:`s` the prior widths (times ``prior_scale``):

        .. math::

            y \approx a + b\,[m(g_0, \hat\theta) + J_g (g - g_0)
                + J_\theta(\theta - \hat\theta)],\quad
            \theta \sim N(\mu(x), \mathrm{diag}(s^2))
            \Rightarrow y \sim N(a + b\,[m + J_\theta(\mu - \hat\theta)]
                + bJ_g(g - g_0),\ \Sigma),

        :math:`\Sigma = S + b J_\theta \mathrm{diag}(s^2) J_\theta^T b`. Then
        :math:`-2\ln p(y \mid g) = w (g - \hat g)^2 + \mathrm{const}` with
        :math:`w = (bJ_g)^T\Sigma^{-1}(bJ_g)` and :math:`\hat g = g_0 + (bJ_g)^T
        \Sigma^{-1} r_0 / w`, :math:`r_0` the residual at :math:`g_0`.
        """
        return self.likelihood_of(self.linearise(X, glucose_mgdl))

    def likelihood_of(self, lin: dict[str, np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`glucose_likelihood` from a :meth:`linearise` result (mode, information)."""
        theta, mean, sd, J = lin["theta"], lin["prior_mean"], lin["prior_sd"], lin["jacobian"]
        g0 = theta[:, 0]
        jg, jt = J[:, :, 0], J[:, :, 1:]
        cov = self.noise_cov_ + np.einsum("nki,ni,nli->nkl", jt, sd[:, 1:] ** 2, jt)
        r0 = lin["residual"] - np.einsum("nki,ni->nk", jt, mean[:, 1:] - theta[:, 1:])
        with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
            sol = np.linalg.solve(cov, np.stack([jg, r0], axis=-1))
            info = np.einsum("nk,nk->n", jg, sol[:, :, 0])
            g_hat = g0 + np.einsum("nk,nk->n", jg, sol[:, :, 1]) / info
        ok = np.isfinite(g_hat) & np.isfinite(info) & (info > 0)
        return np.where(ok, g_hat, g0), np.where(ok, info, 0.0)

    def linearise(self, X, glucose_mgdl) -> dict[str, np.ndarray]:
        """The forward model about each reading's nuisance mode at the given glucose.

        Parameters
        ----------
        X : Dataset, pandas.DataFrame or array_like
            Readings of the fitted device (measured columns only are read).
        glucose_mgdl : array_like
            (n,) glucose held fixed while the nuisances are solved for. [mg/dL]

        Returns
        -------
        dict of numpy.ndarray
            ``theta`` (n, 1 + len(NUISANCES)): the glucose given, then the nuisances'
            posterior mode (:data:`NUISANCES` units); ``residual`` (n, k): the measured
            ln(adc / adc_ref) minus the calibrated model there, y - a - b m;
            ``jacobian`` (n, k, 1 + len(NUISANCES)): b dm/dtheta there; ``prior_mean``
            and ``prior_sd`` (n, 1 + len(NUISANCES)): the prior (nuisance widths times
            ``prior_scale``; glucose's entries are the given value and the training
            spread).
        """
        self._require_fitted()
        self._validate_params()
        obs, phys = self._observed(predict_input(self, X))
        g0 = np.asarray(glucose_mgdl, dtype=float).ravel()
        if len(g0) != len(obs) or not np.all(np.isfinite(g0)):
            raise DataError(f"glucose_mgdl must be {len(obs)} finite values, got {len(g0)}")
        mean, sd = self._prior(phys, g0)
        sd[:, 1:] *= float(self.prior_scale)
        calib = (self.offset_, self.gain_)
        free = np.array([False] + [True] * len(NUISANCES))
        theta, m = map_estimate(
            self.forward_, obs, calib, self._root_w(), mean, sd, free=free, max_iter=self.max_iter
        )
        J = self.gain_[None, :, None] * model_jacobian(self.forward_, theta, sd)
        return {
            "theta": theta,
            "residual": obs - self.offset_ - self.gain_ * m,
            "jacobian": J,
            "prior_mean": mean,
            "prior_sd": sd,
        }

    def predict(self, X) -> np.ndarray:
        """Glucose of each reading: the posterior mode. [mg/dL]"""
        return self.estimate_state(X)["glucose_mgdl"].to_numpy()

    @property
    def n_parameters(self) -> int:
        """Numbers learned from the training rows: calibration, noise covariance, prior
        corrections and widths, standardisation and the glucose prior."""
        self._require_fitted()
        k = len(self.offset_)
        return 2 * k + k * (k + 1) // 2 + self.prior_coef_.size + self.prior_sd_.size + (
            2 * self.x_mean_.size + 2
        )

    def __sklearn_tags__(self):
        tags = super().__sklearn_tags__()
        tags.non_deterministic = False
        return tags


@register("physics-inversion")
class PhysicsInversion(ForwardModelInversion):
    """Forward-model inversion with the generating scenario's own model: a reference.

    :class:`ForwardModelInversion` over the simulator's forward model
    (:class:`~nirglucose.models._inversion_solver.ForwardModel`) as the data's scenario
    (``Dataset.config``) defines it: the LED bands, geometry and chromophore tables,
    glucose's optical signal at the scenario's ``glucose.signal_gain``, and the
    simulator's relations as the prior means' start (:func:`prior_start`). A reference
    of what inverting the generator's own model gives, never a deployable estimator: a
    file without a scenario is refused (:func:`require_scenario`); a device's file is
    fitted by ``device-inversion``
    (:class:`~nirglucose.models.device_inversion.DeviceInversion`).

    Parameters
    ----------
    forward_model : {'beer-lambert', 'diffusion', 'rte-lut'}
        The forward model assumed (need not be the one that made the data).
    prior_scale : float
        Multiplies every nuisance's learned prior width at prediction. [-]
    n_em : int
        Empirical-Bayes rounds in ``fit``. [-]
    max_iter : int
        Levenberg-Marquardt iterations at most per solve. [-]

    Attributes
    ----------
    config_ : ScenarioConfig
        The scenario whose optics are assumed (with the attributes of
        :class:`ForwardModelInversion`).

    Examples
    --------
    >>> import nirglucose as ng
    >>> ds = ng.simulate("paper", 20, 3, seed=0)
    >>> PhysicsInversion().fit(ds).predict(ds).shape
    (60,)
    """

    privileged: ClassVar[str | None] = PRIVILEGED_SCENARIO

    _STATE: ClassVar[dict[str, Any]] = {**ForwardModelInversion._STATE, "config_": "json"}

    def _assume(self, X) -> None:
        self.config_ = require_scenario(X, self.schema_, self.registry_name)

    def _build_forward(self) -> ForwardModel:
        return ForwardModel(self.config_, self.forward_model)

    def _prior_start(self, phys: np.ndarray) -> np.ndarray:
        return prior_start(self.config_, self.schema_, phys)

    def _state_dict(self):
        cfg = self.config_
        self.__dict__["config_"] = cfg.model_dump(mode="json")
        try:
            return super()._state_dict()
        finally:
            self.__dict__["config_"] = cfg

    def _restore(self) -> None:
        if isinstance(self.config_, dict):
            try:
                self.config_ = ScenarioConfig.model_validate(self.config_)
            except ValueError as exc:
                raise DataError(f"the saved model's scenario config is invalid: {exc}") from None
        super()._restore()
