"""Contact layer: probe pressure and humidity change the optical coupling and the path.

A hand-placed probe presses with a pressure drawn per reading (a share of full scale,
``contact.pressure_beta``); a constant-force probe holds it at
``contact.constant_force_pressure``. Pressure blanches the dermis (less blood under the
probe) and compresses the skin (a shorter path), and with relative humidity changes the
optical coupling between probe and skin:

* coupling C = exp(s z - L w), z ~ N(0, 1) per placement, s = ``contact.coupling_sd``,
  w the humidity's position in its range and L = ``environment.humidity_coupling_loss``
  (the issue's "up to 3 %" at the top of the RH range);
* blood f_b' = f_b exp(-b p), b = ``contact.blanching``;
* thickness d' = d exp(-c p), c = ``contact.compression``.

The exponential forms keep every factor positive; their sizes are assumptions of this
package (no published wrist-probe values). Pressure-induced blanching of the dermis is
well documented in reflectance PPG (e.g. Teng & Zhang, Physiol. Meas. 25, 1241 (2004):
the PPG amplitude depends strongly on contact pressure).
"""

from __future__ import annotations

import numpy as np

from .. import portable as pm
from ..config import ScenarioConfig
from ._random import RandomStreams

__all__ = [
    "sample_contact",
    "humidity_wetness",
    "coupling_factor",
    "blanched_blood_fraction",
    "compressed_thickness_mm",
    "apply_contact",
]


def sample_contact(cfg: ScenarioConfig, n: int, streams: RandomStreams):
    """Contact pressure (share of full scale) and the coupling's standard-normal draw.

    Both are drawn even with ``device.constant_force_probe`` (pressure then held at
    ``contact.constant_force_pressure``, no coupling variation), so no stream changes.
    """
    rng = streams("contact_pressure")
    pressure = rng.beta(*cfg.contact.pressure_beta, size=n)
    coupling_z = rng.normal(size=n)
    if cfg.device.constant_force_probe:
        pressure = np.full(n, cfg.contact.constant_force_pressure)
        coupling_z = np.zeros(n)
    return pressure, coupling_z


def humidity_wetness(humidity_pct, humidity_range_pct: tuple[float, float]) -> np.ndarray:
    """Position of a relative humidity in the scenario's RH range, 0 at its low end. [-]

    Examples
    --------
    >>> float(humidity_wetness(60.0, (30.0, 90.0)))
    0.5
    """
    lo, hi = humidity_range_pct
    return (np.asarray(humidity_pct) - lo) / (hi - lo)


def coupling_factor(
    coupling_z,
    wetness,
    coupling_sd: float,
    humidity_loss: float,
    f_contact: float,
    f_humidity: float,
) -> np.ndarray:
    """Optical coupling C = exp(f_c s z - f_h L w) (module docstring; assumptions). [-]

    Examples
    --------
    >>> float(coupling_factor(0.0, 1.0, 0.03, 0.03, 1.0, 1.0))  # doctest: +ELLIPSIS
    0.970445...
    """
    return pm.exp(
        f_contact * coupling_sd * np.asarray(coupling_z) - f_humidity * humidity_loss * wetness
    )


def blanched_blood_fraction(blood_fraction, pressure, blanching: float, f_contact: float):
    """Dermal blood under the probe, f_b exp(-f_c b p) (pressure blanching). [-]

    Examples
    --------
    >>> round(float(blanched_blood_fraction(0.02, 1.0, 0.3, 1.0)), 5)
    0.01482
    """
    return np.asarray(blood_fraction) * pm.exp(-f_contact * blanching * np.asarray(pressure))


def compressed_thickness_mm(thickness_mm, pressure, compression: float, f_contact: float):
    """Skin thickness under the probe, d exp(-f_c c p) (compression). [mm]

    Examples
    --------
    >>> round(float(compressed_thickness_mm(1.8, 1.0, 0.1, 1.0)), 4)
    1.6287
    """
    return np.asarray(thickness_mm) * pm.exp(-f_contact * compression * np.asarray(pressure))


def apply_contact(
    cfg: ScenarioConfig, phys: dict, env: dict, measured: dict, streams: RandomStreams,
    placement: tuple[np.ndarray, np.ndarray] | None = None, *, compiled: bool = True,
) -> dict:
    """Contact layer entry: pressure, coupling, blood and thickness under the probe.

    ``measured`` is the device's physiological vector: with
    ``device.humidity_compensation`` the firmware divides out the coupling-vs-RH curve
    at the RH sensor's reading, so only the curve at the sensor's error remains.
    ``placement`` (optional): each reading's pressure and coupling draw, as
    :func:`sample_contact` returns them, where they persist over several readings (a
    worn device between re-seatings); drawn per reading when omitted. ``compiled``: the
    passes after the draws in one compiled pass (:mod:`.kernels.contact_kernel`, the
    same bits) where every input is a float64 vector; False: the NumPy form below, the
    reference.
    """
    n = len(phys["true_blood_fraction"])
    f_contact = cfg.noise_factor("contact_pressure")
    pressure, coupling_z = sample_contact(cfg, n, streams) if placement is None else placement
    rh_range = cfg.environment.humidity_pct
    c = cfg.contact
    f_humidity = cfg.noise_factor("humidity_coupling")
    inputs = (pressure, coupling_z, env["true_humidity_pct"], phys["true_blood_fraction"],
              phys["true_skin_thickness_mm"])
    if compiled and all(isinstance(x, np.ndarray) and x.dtype == np.float64 and x.ndim == 1
                        and len(x) == n for x in inputs):
        return _apply_contact_compiled(cfg, inputs, measured, f_contact, f_humidity)
    wet = humidity_wetness(env["true_humidity_pct"], rh_range)
    if cfg.device.humidity_compensation:
        wet = wet - humidity_wetness(measured["humidity_pct"], rh_range)
    coupling = coupling_factor(
        coupling_z,
        wet,
        c.coupling_sd,
        cfg.environment.humidity_coupling_loss,
        f_contact,
        f_humidity,
    )
    return {
        "true_contact_pressure": pressure,
        "true_coupling": coupling,
        "true_blood_fraction_detected": blanched_blood_fraction(
            phys["true_blood_fraction"], pressure, c.blanching, f_contact
        ),
        "true_skin_thickness_probe_mm": compressed_thickness_mm(
            phys["true_skin_thickness_mm"], pressure, c.compression, f_contact
        ),
    }


def _apply_contact_compiled(cfg, inputs, measured, f_contact, f_humidity) -> dict:
    """:func:`apply_contact` after its draws in one compiled pass: the scalar factors
    formed as the reference's expressions form them (left to right)."""
    from .kernels.contact_kernel import contact as kernel

    pressure, coupling_z, humidity, blood, thickness = inputs
    lo, hi = cfg.environment.humidity_pct
    c = cfg.contact
    compensate = bool(cfg.device.humidity_compensation)
    measured_h = (np.ascontiguousarray(measured["humidity_pct"], dtype=np.float64)
                  if compensate else humidity)
    k = np.array([lo, hi - lo, f_contact * c.coupling_sd,
                  f_humidity * cfg.environment.humidity_coupling_loss,
                  -f_contact * c.blanching, -f_contact * c.compression], dtype=np.float64)
    n = len(pressure)
    coupling, blood_out, thickness_out = np.empty(n), np.empty(n), np.empty(n)
    kernel(np.ascontiguousarray(pressure), np.ascontiguousarray(coupling_z),
           np.ascontiguousarray(humidity), measured_h, np.ascontiguousarray(blood),
           np.ascontiguousarray(thickness), k, compensate, coupling, blood_out,
           thickness_out)
    return {
        "true_contact_pressure": pressure,
        "true_coupling": coupling,
        "true_blood_fraction_detected": blood_out,
        "true_skin_thickness_probe_mm": thickness_out,
    }
