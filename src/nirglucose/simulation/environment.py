"""Environment layer: ambient temperature, humidity, barometric pressure, ambient light.

Ambient light reaches the photodiode through a baffle of optical density OD
(transmission 10^-OD). Its photocurrent per lux depends on the spectrum: the radiant
power per lux is the inverse of the source's luminous efficacy of radiation (LER).
A device subtracts an LED-off reading; what remains is the ambient change between the
two readings (the source's flicker) times (1 - rejection), plus its shot noise.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from .. import portable as pm
from ..config import EnvironmentConfig, ScenarioConfig
from ._random import RandomStreams, categorical, categories, truncated_normal

__all__ = [
    "LIGHT_SOURCES",
    "ambient_photocurrent_a",
    "ambient_at_probe",
    "sample_environment",
    "apply_environment",
]

#: Ambient spectra: (radiant power per lux [W/m^2/lx] = 1/LER, responsivity-weighted
#: share of that power a Si photodiode converts [A/W], residual flicker between the
#: LED-off and LED-on readings [-]).
#: LER: daylight about 105 lm/W (total solar radiation, Darula & Kittler 2012 place
#: daylight efficacy at 95-125 lm/W); tri-phosphor fluorescent about 330 lm/W and white
#: LED about 300 lm/W of radiation (Schubert, "Light-Emitting Diodes", 2nd ed., ch. 16).
#: Effective Si responsivity over each spectrum: sunlight about 0.45 A/W (half its power
#: in the NIR where Si peaks), visible-only lamps about 0.3 A/W (S1336 response,
#: 450-650 nm). Flicker: mains fluorescent ripple at 100/120 Hz, modulation depth about
#: 0.1-0.3 (IEEE Std 1789-2015 survey); LED drivers vary widely (0.05 typical of
#: constant-current drivers); daylight moves slowly (0.005 between readings).
#: These are order-of-magnitude values; the scenario scales the whole source.
LIGHT_SOURCES = {
    "sun": (1.0 / 105.0, 0.45, 0.005),
    "fluorescent": (1.0 / 330.0, 0.30, 0.2),
    "led": (1.0 / 300.0, 0.30, 0.05),
}


def ambient_photocurrent_a(
    illuminance_lux: np.ndarray,
    watts_per_m2_per_lux: np.ndarray,
    responsivity_a_per_w: np.ndarray,
    detector_area_m2: float,
    baffle_optical_density: float,
) -> np.ndarray:
    """Photocurrent of ambient light through a baffle.

    I = E_v / LER * A * R * 10^-OD.

    Parameters
    ----------
    illuminance_lux : array_like
        Illuminance at the probe. [lx]
    watts_per_m2_per_lux : array_like
        Radiant power per lux of the spectrum (1 / luminous efficacy). [W/m^2/lx]
    responsivity_a_per_w : array_like
        Photodiode responsivity averaged over the spectrum. [A/W]
    detector_area_m2 : float
        Active area. [m^2]
    baffle_optical_density : float
        Decadic optical density of the baffle. [-]

    Returns
    -------
    numpy.ndarray
        Photocurrent. [A]

    References
    ----------
    CIE S 017/E:2011 (luminous efficacy); IEEE Std 1789-2015 (flicker).

    Examples
    --------
    >>> round(float(ambient_photocurrent_a(1000.0, 1 / 330, 0.3, 6.6e-6, 2.0)) * 1e9, 1)
    60.0
    """
    return (
        np.asarray(illuminance_lux)
        * np.asarray(watts_per_m2_per_lux)
        * detector_area_m2
        * np.asarray(responsivity_a_per_w)
        * pm.power(10.0, -baffle_optical_density)
    )


def ambient_at_probe(cfg: ScenarioConfig, env: dict) -> tuple[np.ndarray, np.ndarray]:
    """Ambient photocurrent of each reading and its source's residual flicker.

    Looks up each reading's light source in :data:`LIGHT_SOURCES` and applies
    :func:`ambient_photocurrent_a` through the baffle (``environment.baffle_optical_density``)
    onto the photodiode (``optics.detector_area_mm2``).

    Returns
    -------
    tuple of numpy.ndarray
        Photocurrent (n,) [A] and relative flicker between LED-off and LED-on readings (n,) [-].
    """
    names = tuple(LIGHT_SOURCES)
    table = np.array([LIGHT_SOURCES[k] for k in names])
    light = env["true_light_source"]
    # each category's row, then each reading's by its code: one 1-D take a column (the
    # same values as table[idx, j] with idx each reading's row, a third of the time)
    rows = table[[names.index(c) for c in light.categories]]
    codes = light.codes
    w_per_lux, resp_amb, flicker = (rows[:, j].take(codes) for j in range(3))
    current_a = ambient_photocurrent_a(
        env["true_ambient_lux"],
        w_per_lux,
        resp_amb,
        cfg.optics.detector_area_mm2 * 1e-6,
        cfg.environment.baffle_optical_density,
    )
    return current_a, flicker


def sample_environment(
    cfg: EnvironmentConfig, n_sessions: int, per_session: int, streams: RandomStreams
) -> dict:
    """Draw ambient conditions for ``n_sessions`` x ``per_session`` measurements.

    Temperature, humidity and pressure are drawn per session (a subject's measurements
    happen in one place) and vary within it by ``*_within_sd`` (truncated to the
    configured ranges); illuminance and light source vary per measurement.
    """
    rng = streams("environment")
    n = n_sessions * per_session
    rep = np.repeat(np.arange(n_sessions), per_session)
    t_lo, t_hi = cfg.temperature_c
    # one session mean per subject; truncation probabilities computed per session
    temperature_c = truncated_normal(
        rng, rng.uniform(t_lo, t_hi, size=n_sessions), cfg.temperature_within_sd_c,
        t_lo, t_hi, size=n, group=rep,
    )
    h_lo, h_hi = cfg.humidity_pct
    humidity_pct = truncated_normal(
        rng, rng.uniform(h_lo, h_hi, size=n_sessions), cfg.humidity_within_sd_pct,
        h_lo, h_hi, size=n, group=rep,
    )
    session_p = truncated_normal(
        rng, cfg.pressure_mbar_mean, cfg.pressure_mbar_sd, *cfg.pressure_mbar, size=n_sessions
    )
    pressure_mbar = truncated_normal(
        rng, session_p, cfg.pressure_within_sd_mbar, *cfg.pressure_mbar, size=n, group=rep
    )
    log_lo, log_hi = pm.log10(cfg.ambient_lux)
    ambient_lux = pm.power(10.0, rng.uniform(log_lo, log_hi, size=n))
    names = list(cfg.light_source_probs)
    probs = np.array([cfg.light_source_probs[k] for k in names])
    source_idx = categorical(rng, probs, n)
    return {
        "temperature_c": temperature_c,
        "humidity_pct": humidity_pct,
        "pressure_mbar": pressure_mbar,
        "ambient_lux": ambient_lux,
        "light_source": pd.Categorical.from_codes(source_idx, dtype=categories(tuple(names))),
    }


def apply_environment(
    cfg: ScenarioConfig, n_sessions: int, per_session: int, streams: RandomStreams
) -> dict:
    """Environment layer entry: the columns of the ambient conditions (``true_*`` names)."""
    env = sample_environment(cfg.environment, n_sessions, per_session, streams)
    return {
        "true_ambient_temperature_c": env["temperature_c"],
        "true_humidity_pct": env["humidity_pct"],
        "true_pressure_mbar": env["pressure_mbar"],
        "true_ambient_lux": env["ambient_lux"],
        "true_light_source": env["light_source"],
    }
