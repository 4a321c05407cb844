"""Readings averaged per estimate: what averaging buys (white noise) and what it costs (lag).

A device may average N readings into one estimate. Model (assumptions stated):

Timing
    One reading of one LED integrates over tau = 1 / (2 B), B the hardware's equivalent
    noise bandwidth (``hardware.bandwidth_hz``): an average over tau has a noise
    bandwidth of 1 / (2 tau) [1]_. A reading cycle lights each of the n_led LEDs once
    and takes one LED-off frame for the ambient subtraction, so it lasts
    (n_led + 1) tau (:func:`cycle_s`); a window of T seconds holds
    N = max(1, floor(T / cycle)) readings (:func:`readings_in`).
White noise
    Averaging N readings divides the variance of every per-reading noise term of the
    bound's noise model by N (:func:`~nirglucose.design.bound.noise_covariance`): shot
    and Johnson noise (independent per reading), quantisation (which averages only with
    a dither of about 1 LSB or more at the converter, standard practice: oversampling
    by 4^k adds k bits [2]_), LED flicker and the junction-temperature jitter between
    readings (taken as independent per reading; a correlated part would average less,
    so the bound stays a lower bound). The terms common to every channel (LED drift
    with ambient temperature and ageing between reference and reading) change over
    hours, not seconds, and are not divided.
The physiology's own change
    The nuisances' change inside the window is absorbed, to first order, into their
    mean over the window (the state the averaged reading sees); glucose's is not: the
    estimate is reported at the window's end (a real-time display) and compared with
    the reference glucose then, so it lags by the window. Its error is
    g(t) - mean of g over [t - T, t], whose RMS over the worn simulator's glucose
    trajectories (UVA/Padova, :mod:`~nirglucose.simulation.wear`; meals, and insulin
    for type 1, at the scenario's diabetes mix) is :func:`glucose_lag_rmse_mgdl`;
    it adds in quadrature to the bound (the lag is independent of the optical noise).
    Between the one-minute samples the trajectory is taken as linear (the mean is then
    exact).
In the simulator
    :func:`averaging_overrides` emulates an average of N readings with one reading of a
    quieter device: bandwidth B / N, flicker / sqrt(N), and floor(log4 N) more ADC bits
    (at most the config's 24): every term as in the bound but quantisation, which drops
    by 4^floor(log4 N) <= N (so the simulated device is never quieter than the bound's).

References
----------
.. [1] P. Horowitz, W. Hill, "The Art of Electronics", 3rd ed., Cambridge University
   Press (2015), ch. 8 (noise bandwidth of an averaging filter).
.. [2] Atmel, "AVR121: Enhancing ADC resolution by oversampling", application note
   8003A (2005): each factor 4 of oversampling and averaging adds one bit, given noise
   of at least 1 LSB.
"""

from __future__ import annotations

import json
import math
from functools import lru_cache

import numpy as np

from ..config import ScenarioConfig, resolve_config
from ..exceptions import ConfigError, check_positive_int
from ..simulation.wear import glucose_trajectories, subject_profiles

__all__ = [
    "LAG_SUBJECTS",
    "LAG_WEAR_DAYS",
    "MAX_ADC_BITS",
    "averaging_overrides",
    "cycle_s",
    "glucose_lag_rmse_mgdl",
    "readings_in",
    "window_error_rmse_mgdl",
]

#: Worn subjects and days of the lag's glucose trajectories (a fixed sample, seed 0, so
#: the lag is a deterministic function of the scenario; about 3 s to simulate). [-], [d]
LAG_SUBJECTS, LAG_WEAR_DAYS = 32, 2
#: Highest ADC resolution the config takes (``hardware.adc_bits``). [bit]
MAX_ADC_BITS = 24


def cycle_s(n_led: int, bandwidth_hz: float) -> float:
    """Duration of one reading cycle: n_led + 1 frames of 1 / (2 B) each. [s]

    Parameters
    ----------
    n_led : int
        LEDs lit in turn. [-]
    bandwidth_hz : float
        Equivalent noise bandwidth of one reading. [Hz]

    Examples
    --------
    >>> cycle_s(4, 10.0)
    0.25
    """
    n_led = check_positive_int("n_led", n_led)
    if not (math.isfinite(bandwidth_hz) and bandwidth_hz > 0):
        raise ConfigError(f"bandwidth_hz must be a positive number of Hz, got {bandwidth_hz!r}")
    return (n_led + 1) / (2.0 * bandwidth_hz)


def readings_in(window_s: float, n_led: int, bandwidth_hz: float) -> int:
    """Readings that fit in an averaging window (at least one). [-]

    Examples
    --------
    >>> readings_in(60.0, 4, 10.0), readings_in(0.0, 4, 10.0)
    (240, 1)
    """
    if not (math.isfinite(window_s) and window_s >= 0):
        raise ConfigError(f"the averaging window must be >= 0 s, got {window_s!r}")
    return max(1, int(math.floor(window_s / cycle_s(n_led, bandwidth_hz) + 1e-9)))


def averaging_overrides(cfg: ScenarioConfig, n_readings: int) -> dict[str, float | int]:
    """Overrides that make one simulated reading stand for the average of ``n_readings``.

    Bandwidth / N, flicker / sqrt(N), ADC bits + floor(log4 N) (at most
    :data:`MAX_ADC_BITS`); see the module docstring.

    Parameters
    ----------
    cfg : ScenarioConfig
        The design's scenario (one reading).
    n_readings : int
        Readings averaged. [-]

    Returns
    -------
    dict
        Dotted config keys -> values (empty for one reading).

    Examples
    --------
    >>> from nirglucose.config import resolve_config
    >>> averaging_overrides(resolve_config("physical"), 16)["hardware.adc_bits"]
    14
    """
    n = check_positive_int("n_readings", n_readings)
    if n == 1:
        return {}
    hw = cfg.hardware
    extra_bits = int(math.floor(math.log(n, 4) + 1e-9))
    return {
        "hardware.bandwidth_hz": hw.bandwidth_hz / n,
        "hardware.led_flicker_rel": hw.led_flicker_rel / math.sqrt(n),
        "hardware.adc_bits": min(MAX_ADC_BITS, hw.adc_bits + extra_bits),
    }


def window_error_rmse_mgdl(glucose_mgdl: np.ndarray, window_min) -> np.ndarray:
    """RMS of g(t) minus the mean of g over [t - T, t], g linear between samples.

    Parameters
    ----------
    glucose_mgdl : numpy.ndarray
        (n_subjects, n_minutes) glucose sampled every minute. [mg/dL]
    window_min : float or array_like
        Window lengths T >= 0. [min]

    Returns
    -------
    numpy.ndarray
        RMS error per window, over every subject and every minute with a full window
        behind it. [mg/dL]

    Notes
    -----
    With T = m + f (m whole minutes, 0 <= f < 1) the integral of g over [t - T, t] is
    the trapezoid sum over the last m minutes plus f (2 g[t-m] - f (g[t-m] - g[t-m-1]))
    / 2 over the fraction before them: exact for a piecewise-linear g.

    Examples
    --------
    >>> ramp = np.arange(100.0)[None, :] * 2.0  # 2 mg/dL per minute
    >>> window_error_rmse_mgdl(ramp, [0.5, 10.0]).round(6).tolist()
    [0.5, 10.0]
    """
    g = np.atleast_2d(np.asarray(glucose_mgdl, dtype=float))
    windows = np.atleast_1d(np.asarray(window_min, dtype=float))
    if not np.all(np.isfinite(g)):
        raise ConfigError("the glucose trajectories must be finite")
    if np.any(~np.isfinite(windows)) or np.any(windows < 0):
        raise ConfigError(f"windows must be >= 0 min, got {windows.tolist()}")
    n_min = g.shape[1]
    if np.any(windows > n_min - 2):
        raise ConfigError(f"windows must be shorter than the trajectories' {n_min - 2} min, "
                          f"got {windows.max():g}")
    cum = np.concatenate([np.zeros((g.shape[0], 1)),
                          np.cumsum((g[:, 1:] + g[:, :-1]) / 2.0, axis=1)], axis=1)
    out = np.zeros(windows.size)
    for i, w in enumerate(windows):
        if w == 0:
            continue
        m, f = int(math.floor(w)), w - math.floor(w)
        t = np.arange(m + 1, n_min)  # every end with the sample before the window
        full = cum[:, t] - cum[:, t - m]
        d = g[:, t - m] - g[:, t - m - 1]
        frac = f * (2.0 * g[:, t - m] - f * d) / 2.0
        err = g[:, t] - (full + frac) / w
        out[i] = float(np.sqrt(np.mean(err**2)))
    return out


@lru_cache(maxsize=4)
def _trajectories(config_json: str, n_subjects: int, wear_days: int, seed: int) -> np.ndarray:
    cfg = ScenarioConfig.model_validate(json.loads(config_json))
    codes, _ = subject_profiles(cfg, seed, 0, n_subjects, n_subjects)
    traj = glucose_trajectories(cfg, seed, np.arange(n_subjects), codes, wear_days)
    return traj["blood_mgdl"]


def glucose_lag_rmse_mgdl(window_s, config="physical", *, n_subjects: int = LAG_SUBJECTS,
                          wear_days: int = LAG_WEAR_DAYS, seed: int = 0) -> np.ndarray:
    """RMS error of a window-averaged estimate reported at the window's end. [mg/dL]

    Parameters
    ----------
    window_s : float or array_like
        Averaging windows. [s]
    config : str or ScenarioConfig
        Scenario whose diabetes mix and glucose model the worn trajectories follow.
    n_subjects, wear_days, seed : int
        The worn sample (default :data:`LAG_SUBJECTS` x :data:`LAG_WEAR_DAYS`, seed 0).

    Returns
    -------
    numpy.ndarray
        One RMS error per window. [mg/dL]
    """
    cfg = config if isinstance(config, ScenarioConfig) else resolve_config(config)
    n_subjects = check_positive_int("n_subjects", n_subjects)
    wear_days = check_positive_int("wear_days", wear_days)
    g = _trajectories(cfg.model_dump_json(), n_subjects, wear_days, int(seed))
    return window_error_rmse_mgdl(g, np.asarray(window_s, dtype=float) / 60.0)
