"""The bound of a design: the Cramér–Rao lower bound on glucose RMSE for a device.

A device (its LED set, detector, ADC, noise budget and the signals it measures) turns
glucose g and the per-reading nuisances theta into y = ln(adc / adc_ref) per LED. Near
the noise-free forward model m(g, theta) (:class:`~nirglucose.simulation.forward_model.
ForwardModel`, the simulator's optics) the reading is y ~ N(m(g, theta), S) with S the
hardware noise covariance (:func:`noise_covariance`). Its Fisher information is

    F(g, theta) = J^T S^-1 J,    J = d m / d(g, theta)   (forward differences),

and the variance of any unbiased estimate of glucose is at least [F^-1]_gg [1]_.
Two conditionings, :data:`CONDITIONS`:

``"device"`` (default) -- the Bayesian (van Trees) bound [2]_ of a device that knows
    none of the nuisances besides what it measures: with a Gaussian prior on glucose
    (variance of simulated glucose) and on the nuisances (their simulated spread given
    the device's measured physiological columns, a linear regression on a pilot
    simulation), ``MSE >= [(E F + P)^-1]_gg``, E the average over simulated states, P
    the prior precisions. Nuisances: :data:`~nirglucose.simulation.forward_model.
    NUISANCES` (blood volume under the probe, saturation, water, fat, melanin, skin
    thickness under the probe, one common LED peak shift, the optical coupling); each
    LED's own junction-temperature shift beyond the common one is taken as known, which
    can only lower the bound. Where ``noise.water_temperature`` is on (water absorbs at
    the skin temperature, Röttgers et al. 2014), the skin temperature is one more
    nuisance (:data:`~nirglucose.simulation.forward_model.TEMPERATURE_NUISANCE`) with the
    same prior: its simulated spread given the measured columns, which include the
    skin thermometer's reading ``skin_temp_c``, so its prior width is the thermometer's
    error (``measurement.skin_temp_c``, 0.2 degC; none with ``device.physiology =
    exact``) -- a known covariate with its error as prior width.
``"oracle"`` -- the information of the :class:`~nirglucose.models.oracle.Oracle`: it
    knows each reading's true nuisance state (the ``true_*`` columns, per-LED shifts
    included) but not the noise, and it shrinks to a Gaussian glucose prior, so per
    state ``MSE_i >= 1 / (F_gg,i + 1 / var g)`` and the bound is the root of their mean
    over states. This is the one to compare with the oracle's RMSE: a bound that
    marginalised nuisances the oracle knows would not bound the oracle.

The noise covariance is analytic, from the scenario's hardware section and noise
switches (each term scaled like the simulator's): shot noise of the photocurrent and
dark current, Johnson noise of the feedback resistor (and detector shunt), the 1/12
LSB^2 of quantisation, the same three for the start-up reference or the monitor
photodiode's reading, LED flicker at reading and reference and LED thermal power drift
(independent per LED, and common through ambient temperature), LED ageing (common) --
the last three only without a monitor photodiode, which cancels them. Omitted, which
can only lower the bound: ambient-light residuals and their shot noise, the
dark-current residual, ADC offset drift and INL, and the variance from the reference
thermal wavelength shift the oracle knows. A channel whose code saturates (at 0 or
full scale) carries no information. The Gaussian form makes this a bound for
estimators that use the first two moments of the noise and priors -- as the oracle's
generalised least squares and the physics inversion do; it is the exact CRLB where
noise and priors are Gaussian.

References
----------
.. [1] S. M. Kay, "Fundamentals of Statistical Signal Processing, Vol. I: Estimation
   Theory", Prentice Hall (1993), ch. 3 (CRLB, Eq. 3.31 for Gaussian data).
.. [2] H. L. Van Trees, K. L. Bell, "Bayesian Bounds for Parameter Estimation and
   Nonlinear Filtering/Tracking", Wiley-IEEE (2007), ch. 1 (the Bayesian CRB).
.. [3] Hamamatsu Photonics, "Si photodiodes" technical information; P. Horowitz,
   W. Hill, "The Art of Electronics", 3rd ed., 8.1 (shot and Johnson noise).
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from functools import lru_cache
from typing import Any

import numpy as np

from ..config import DEFAULT_LEDS, ScenarioConfig, resolve_config
from ..config.scenario import DETECTOR_KEYS, detector_key_default
from ..constants import (
    BOLTZMANN_J_PER_K,
    ELEMENTARY_CHARGE_C,
    PHYSIOLOGICAL_RANGES,
    ZERO_CELSIUS_K,
)
from ..exceptions import ConfigError, check_positive_int, unknown_name
from ..simulation.forward_model import ForwardModel
from ..simulation.hardware import dark_current_a, johnson_resistance_ohm
from ..simulation.simulator import simulate_frame

__all__ = ["CONDITIONS", "DesignBound", "DesignTerms", "design_bound", "design_terms",
           "noise_covariance"]

#: What the bound conditions on: ``"device"`` (nuisances unknown, with priors) or
#: ``"oracle"`` (the oracle's knowledge: true nuisances).
CONDITIONS = ("device", "oracle")
#: Pilot simulation of the nuisance states: subjects x readings, seed (a fixed sample,
#: so a design's bound is a deterministic function of its config). [-]
PILOT_SUBJECTS, PILOT_PER_SUBJECT, PILOT_SEED = 200, 3, 0
#: Forward-difference steps: glucose as the oracle's Jacobian [mg/dL], then each
#: nuisance of NUISANCES in its unit (about 1e-3 of its population spread), then the
#: skin temperature [degC] where ``noise.water_temperature`` is on (the model is linear
#: in it, so any step is exact).
_STEPS = np.array([0.5, 1e-3, 1e-4, 1e-4, 1e-4, 1e-5, 1e-3, 1e-3, 1e-4, 1e-3])


@dataclass(frozen=True)
class DesignBound:
    """The bound of one design.

    Attributes
    ----------
    rmse_mgdl : float
        Lower bound on glucose RMSE. [mg/dL]
    condition : str
        One of :data:`CONDITIONS`.
    wavelengths_nm : tuple of float
        The LED set. [nm]
    detector : str or None
        The detector's part name (None: the study's photodiode).
    glucose_sd_mgdl : float
        SD of the glucose prior (simulated glucose); 0 when ``prior=False``. [mg/dL]
    saturated_fraction : float
        Share of (state, LED) readings whose code saturates (no information). [-]
    n_states : int
        Simulated states averaged. [-]
    """

    rmse_mgdl: float
    condition: str
    wavelengths_nm: tuple[float, ...]
    detector: str | None
    glucose_sd_mgdl: float
    saturated_fraction: float
    n_states: int

    def as_dict(self) -> dict[str, Any]:
        """The fields as a JSON-ready dict."""
        return {
            "rmse_mgdl": self.rmse_mgdl,
            "condition": self.condition,
            "wavelengths_nm": list(self.wavelengths_nm),
            "detector": self.detector,
            "glucose_sd_mgdl": self.glucose_sd_mgdl,
            "saturated_fraction": self.saturated_fraction,
            "n_states": self.n_states,
        }


@dataclass(frozen=True)
class _Pilot:
    glucose_mgdl: np.ndarray  # (n,)
    theta: np.ndarray  # (n, 8) NUISANCES, (n, 9) with the skin temperature last
    board_c: np.ndarray  # (n,)
    ambient_step_var_c2: float  # E[(T_ambient - T_ambient at the subject's reference)^2]
    nuisance_cov: np.ndarray  # (k, k), theta's columns, given the measured physiology


@dataclass(frozen=True)
class DesignTerms:
    """Per-state Jacobians and noise of a set of LEDs, for bounds of any subset.

    Built by :func:`design_terms`; :meth:`bound` evaluates one subset of the LEDs in
    about a millisecond, so every k-subset of a candidate set can be ranked.

    Attributes
    ----------
    config : ScenarioConfig
        The resolved scenario with every candidate LED.
    jacobian : numpy.ndarray
        (n_states, n_led, 1 + n_nuisances) d ln(adc/adc_ref) / d(g [mg/dL], nuisances).
    noise_var : numpy.ndarray
        (n_states, n_led) independent noise variance of each channel. [-]
    common_var : float
        Variance common to every channel (LED power drift through ambient temperature
        and ageing). [-]
    saturated : numpy.ndarray
        (n_states, n_led) bool, the code at 0 or full scale.
    """

    config: ScenarioConfig
    jacobian: np.ndarray
    noise_var: np.ndarray
    common_var: float
    saturated: np.ndarray
    glucose_var: float
    nuisance_cov: np.ndarray = field(repr=False)

    def bound(self, leds=None, *, condition: str = "device", prior: bool = True) -> DesignBound:
        """The bound of the LEDs ``leds`` (indices into the set; all when None).

        Parameters
        ----------
        leds : sequence of int, optional
            Which LEDs of :attr:`config` the device has.
        condition : {'device', 'oracle'}
            See the module docstring.
        prior : bool
            Include the Gaussian prior of glucose (as the oracle's default).
        """
        if condition not in CONDITIONS:
            raise ConfigError(unknown_name("condition", condition, CONDITIONS))
        n_led = self.jacobian.shape[1]
        idx = np.arange(n_led) if leds is None else np.asarray(list(leds), dtype=int)
        if idx.size == 0 or idx.min() < 0 or idx.max() >= n_led:
            raise ConfigError(f"leds must index the {n_led} LEDs of the set, got {list(idx)}")
        J = self.jacobian[:, idx, :]
        var = self.noise_var[:, idx]
        sat = self.saturated[:, idx]
        # a saturated channel: no information (its Jacobian row removed)
        J = np.where(sat[:, :, None], 0.0, J)
        if condition == "oracle":
            J = J[:, :, :1]  # the oracle knows the nuisances: glucose's information only
        F = _fisher(J, var, self.common_var)
        lam = 1.0 / self.glucose_var if prior else 0.0
        if condition == "oracle":
            with np.errstate(divide="ignore"):
                var_g = 1.0 / (F[:, 0, 0] + lam)
            rmse = float(np.sqrt(np.mean(var_g)))
        else:
            info = F.mean(axis=0)
            info[0, 0] += lam
            info[1:, 1:] += np.linalg.inv(self.nuisance_cov)
            try:
                rmse = float(np.sqrt(np.linalg.inv(info)[0, 0]))
            except np.linalg.LinAlgError:
                rmse = float("inf")
        det = self.config.detector
        return DesignBound(
            rmse_mgdl=rmse,
            condition=condition,
            wavelengths_nm=tuple(self.config.leds.wavelengths_nm[i] for i in idx),
            detector=None if det is None else det.part,
            glucose_sd_mgdl=float(np.sqrt(self.glucose_var)) if prior else 0.0,
            saturated_fraction=float(sat.mean()),
            n_states=int(J.shape[0]),
        )


def _fisher(J: np.ndarray, var: np.ndarray, common_var: float) -> np.ndarray:
    """Per-state Fisher information J^T S^-1 J, (n, p, p), for S = diag(var) + c 1 1^T.

    By the Sherman-Morrison identity (G. H. Golub, C. F. Van Loan, "Matrix
    Computations", 4th ed. (2013), 2.1.4): J^T D^-1 J - c u u^T / (1 + c sum 1/var),
    u = J^T D^-1 1 -- the inverse of S without a solve per state.
    """
    w = 1.0 / var  # (n, k)
    wj = w[:, :, None] * J
    F = np.einsum("nki,nkj->nij", J, wj)
    if common_var > 0:
        u = wj.sum(axis=1)  # (n, p)
        scale = common_var / (1.0 + common_var * w.sum(axis=1))
        F -= scale[:, None, None] * u[:, :, None] * u[:, None, :]
    return F


def _resolve(config, leds, detector, overrides) -> ScenarioConfig:
    extra = dict(overrides or {})
    if leds is not None:
        extra["leds"] = list(leds)
    if detector is not None:
        extra["detector"] = detector
    if isinstance(config, ScenarioConfig):
        return resolve_config(config, extra) if extra else config
    if not isinstance(config, str):
        raise ConfigError(
            f"config must be a preset name or a ScenarioConfig, got {type(config).__name__}"
        )
    return resolve_config(config, extra)


def _population_key(cfg: ScenarioConfig) -> str:
    """The config less what a design changes (LEDs, detector): the pilot's cache key."""
    data = cfg.model_dump(mode="json")
    data["leds"] = {"emitters": [e.model_dump(mode="json") for e in DEFAULT_LEDS],
                    "band_points": data["leds"]["band_points"]}
    data["detector"] = None
    for section, key, _ in DETECTOR_KEYS:
        data[section][key] = detector_key_default(section, key)
    return json.dumps(data, sort_keys=True)


@lru_cache(maxsize=16)
def _pilot(population_json: str) -> _Pilot:
    """Nuisance states, temperatures and the nuisance prior from a pilot simulation."""
    cfg = ScenarioConfig.model_validate(json.loads(population_json))
    f = simulate_frame(cfg, PILOT_SUBJECTS, PILOT_PER_SUBJECT, PILOT_SEED)
    shift = f[[c for c in f.columns if c.startswith("true_led_shift_nm_")]].to_numpy(float)
    theta = np.column_stack([
        np.log(f["true_blood_fraction_detected"].to_numpy(float)),
        f["true_saturation"].to_numpy(float),
        f["true_water_fraction"].to_numpy(float),
        f["true_subcutis_fat_fraction"].to_numpy(float),
        f["true_melanin_fraction"].to_numpy(float),
        f["true_skin_thickness_probe_mm"].to_numpy(float),
        shift.mean(axis=1),
        np.log(f["true_coupling"].to_numpy(float)),
    ])
    if cfg.noise_factor("water_temperature") != 0.0:  # the water's (skin) temperature
        theta = np.column_stack([theta, f["true_skin_temp_c"].to_numpy(float)])
    amb = f["true_ambient_temperature_c"].to_numpy(float)
    first = f.groupby("subject_id")["true_ambient_temperature_c"].transform("first").to_numpy()
    measured = [c for c in PHYSIOLOGICAL_RANGES if c in f.columns]
    return _Pilot(
        glucose_mgdl=f["glucose_mgdl"].to_numpy(float),
        theta=theta,
        board_c=f["true_board_temperature_c"].to_numpy(float),
        ambient_step_var_c2=float(np.mean((amb - first) ** 2)),
        nuisance_cov=_conditional_cov(theta, f[measured].to_numpy(float)),
    )


def _conditional_cov(theta: np.ndarray, x: np.ndarray) -> np.ndarray:
    """Residual covariance of ``theta`` given ``x`` by least squares (unbiased: n - p - 1),
    with a floor of 1e-6 of each nuisance's variance so the prior stays invertible."""
    n = len(theta)
    X = np.column_stack([np.ones(n), x]) if x.size else np.ones((n, 1))
    coef, *_ = np.linalg.lstsq(X, theta, rcond=None)
    resid = theta - X @ coef
    cov = resid.T @ resid / max(n - X.shape[1], 1)
    floor = 1e-6 * np.maximum(theta.var(axis=0), 1e-12)
    return cov + np.diag(floor)


def noise_covariance(cfg: ScenarioConfig, log_ratio: np.ndarray, board_c) -> tuple:
    """Noise of ln(adc / adc_ref) per channel at given noise-free log ratios.

    Parameters
    ----------
    cfg : ScenarioConfig
        The device (LEDs, detector, hardware, noise switches).
    log_ratio : numpy.ndarray
        (n, n_led) noise-free ln(fraction / T_ref). [-]
    board_c : numpy.ndarray
        (n,) board temperature. [degC]

    Returns
    -------
    noise_var : numpy.ndarray
        (n, n_led) independent variance per channel. [-]
    common_var : float
        Variance shared by every channel (without a monitor photodiode). [-]
    saturated : numpy.ndarray
        (n, n_led) bool: the reading's code is at 0 or full scale (no information).

    Notes
    -----
    I = R P0 T_ref e^m, codes c = I R_f / V_ref (2^bits - 1); per reading and per
    reference (start-up or monitor, at I_ref = R P0 T_ref) the relative variance
    (2 e (I + I_dark) BW + 4 k T BW / R_J) / I^2 + 1 / (12 c^2) (Horowitz & Hill;
    Hamamatsu [3]_), plus each channel's own white conversion noise (read_noise_lsb / c)^2
    on the tissue reading (EMVA 1288), the reference's zero where it saturates; without a
    monitor photodiode 2 flicker^2 (each LED's own flicker where it has one) and the LED
    thermal drift a^2 (2 sd_junction^2) per channel, and a^2 E[dT_ambient^2] + b^2 var(dt)
    / 10^6 common (the coefficients of :func:`nirglucose.simulation.hardware.led_power_w`).
    """
    hw = cfg.hardware
    full = 2**hw.adc_bits - 1
    p0_w = np.asarray(cfg.leds.power_mw)[None, :] * 1e-3
    resp = np.asarray(cfg.leds.responsivity_a_per_w)[None, :]
    board_c = np.asarray(board_c, dtype=float)[:, None]
    i_ref = resp * p0_w * hw.reference_transmission
    i_sig = i_ref * np.exp(log_ratio)
    i_dark = dark_current_a(hw.dark_current_25c_na * 1e-9, board_c, hw.dark_current_per_c)
    f_shot, f_johnson = cfg.noise_factor("shot"), cfg.noise_factor("johnson")
    johnson_a2 = (
        4.0 * BOLTZMANN_J_PER_K * (board_c + ZERO_CELSIUS_K) * hw.bandwidth_hz
        / johnson_resistance_ohm(cfg)
    )

    def reading_var(i_a):
        code = i_a * hw.tia_gain_ohm / hw.adc_vref_v * full
        current_var = (
            f_shot**2 * 2.0 * ELEMENTARY_CHARGE_C * (i_a + i_dark) * hw.bandwidth_hz
            + f_johnson**2 * johnson_a2
        )
        return current_var / i_a**2 + 1.0 / (12.0 * code**2), code

    var_sig, code = reading_var(i_sig)
    # each channel's own white conversion noise (leds.emitters.<i>.read_noise_lsb, EMVA
    # 1288 temporal dark noise) on the tissue reading, as the simulator adds it
    read_lsb = cfg.noise_scale * np.asarray([e.read_noise_lsb for e in cfg.leds.emitters])
    var_sig = var_sig + (read_lsb[None, :] / np.maximum(code, 0.5)) ** 2
    var_ref, code_ref = reading_var(i_ref)
    # a saturated reference reads full scale every time: it adds no noise (and no longer
    # cancels LED drift, a term left out, which can only lower the bound)
    var = var_sig + np.where(code_ref >= full, 0.0, var_ref)
    common = 0.0
    if not cfg.device.monitor_photodiode:
        f_thermal = cfg.noise_factor("led_thermal_drift")
        a = hw.led_thermal_coeff_per_c * f_thermal
        flicker = (np.asarray(cfg.leds.flicker_rels(hw.led_flicker_rel))[None, :]
                   * cfg.noise_factor("led_flicker"))
        var = var + 2.0 * flicker**2 + 2.0 * (a * hw.led_self_heating_sd_c * f_thermal) ** 2
        # LEDs ageing at their own rates: their mean rate is the shared part
        b = (float(np.mean(cfg.leds.ageings(hw.led_ageing_per_1000h)))
             * cfg.noise_factor("led_ageing") / 1000.0)
        lo, hi = hw.hours_since_reference_h
        step_var_c2 = _pilot(_population_key(cfg)).ambient_step_var_c2
        common = a**2 * step_var_c2 + b**2 * (hi - lo) ** 2 / 12
    saturated = (code >= full) | (code < 0.5)
    return var, float(common), saturated


def design_terms(config="paper", leds=None, detector=None, *, overrides=None,
                 n_states: int = 256) -> DesignTerms:
    """Jacobians and noise of a device's LEDs over simulated states (see :class:`DesignTerms`).

    Parameters are as :func:`design_bound`'s.
    """
    n_states = check_positive_int("n_states", n_states)
    cfg = _resolve(config, leds, detector, overrides)
    pilot = _pilot(_population_key(cfg))
    n = min(n_states, len(pilot.glucose_mgdl))
    # an evenly spaced subsample of the pilot: deterministic, spread over subjects
    rows = np.linspace(0, len(pilot.glucose_mgdl) - 1, n).round().astype(int)
    g, theta, board_c = pilot.glucose_mgdl[rows], pilot.theta[rows], pilot.board_c[rows]
    fm = ForwardModel(cfg, cfg.optics.model)
    p = 1 + theta.shape[1]
    # one batched call: the state, then each parameter stepped
    gg = np.tile(g, p + 1)
    tt = np.tile(theta, (p + 1, 1))
    for j in range(p):
        block = slice((j + 1) * n, (j + 2) * n)
        if j == 0:
            gg[block] += _STEPS[0]
        else:
            tt[block, j - 1] += _STEPS[j]
    m_all = fm.log_ratio(gg, tt).reshape(p + 1, n, -1)
    m0 = m_all[0]
    jac = np.stack([(m_all[j + 1] - m0) / _STEPS[j] for j in range(p)], axis=-1)
    var, common, sat = noise_covariance(cfg, m0, board_c)
    return DesignTerms(
        config=cfg,
        jacobian=jac,
        noise_var=var,
        common_var=common,
        saturated=sat,
        glucose_var=float(pilot.glucose_mgdl.var(ddof=1)),
        nuisance_cov=pilot.nuisance_cov,
    )


def design_bound(config="paper", leds=None, detector=None, *, condition: str = "device",
                 prior: bool = True, overrides=None, n_states: int = 256) -> DesignBound:
    """The Cramér–Rao lower bound on glucose RMSE of a device design.

    Parameters
    ----------
    config : str or ScenarioConfig
        A preset name or a resolved scenario: the population, noise budget, ADC and
        the signals the device measures (``device.*``).
    leds : list, optional
        The LED set, replacing the scenario's: LED records (dicts with wavelength_nm,
        fwhm_nm, power_mw and optionally responsivity_a_per_w) or catalogue part names
        (``nirglucose parts``).
    detector : str or dict, optional
        A catalogue photodiode (``"G17190-005K"``) or a detector record; None keeps the
        scenario's.
    condition : {'device', 'oracle'}
        What the bound knows: see the module docstring.
    prior : bool
        Include the Gaussian prior of glucose (the oracle's default).
    overrides : dict, optional
        Further dotted config overrides.
    n_states : int
        Simulated states averaged (at most the pilot's 600). [-]

    Returns
    -------
    DesignBound

    Examples
    --------
    >>> b = design_bound("paper", condition="oracle")
    >>> bool(0 < b.rmse_mgdl < b.glucose_sd_mgdl)
    True
    >>> design_bound("paper").rmse_mgdl >= b.rmse_mgdl
    True
    """
    if condition not in CONDITIONS:
        raise ConfigError(unknown_name("condition", condition, CONDITIONS))
    terms = design_terms(config, leds, detector, overrides=overrides, n_states=n_states)
    return terms.bound(condition=condition, prior=prior)
