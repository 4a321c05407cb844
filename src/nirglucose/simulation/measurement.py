"""What the device knows: the physiological vector as it would be measured.

Each entry of the 12-dimensional physiological vector (the study's PMF input) is the
true value plus the measurement error of the instrument that would provide it
(standard deviations in :class:`nirglucose.config.MeasurementConfig`), scaled by the
``pmf_measurement`` noise source.
"""

from __future__ import annotations

import numpy as np

from .. import portable as pm
from ..config import ScenarioConfig
from ..constants import PHYSIOLOGICAL_RANGES
from ..dataset import PMF_COLUMNS, PPG_COLUMNS  # the data schema owns the column names
from ._random import RandomStreams

__all__ = ["PMF_COLUMNS", "PPG_COLUMNS", "measure_physiology", "measure_ppg"]


#: Measured column -> the truth it measures.
_TRUTH = {
    "age_yr": "true_age_yr",
    "bmi_kgm2": "true_bmi_kgm2",
    "melanin_fraction": "true_melanin_fraction",
    "skin_thickness_mm": "true_skin_thickness_mm",
    "hydration_pct": "true_hydration_pct",
    "systolic_bp_mmhg": "true_systolic_bp_mmhg",
    "heart_rate_bpm": "true_heart_rate_bpm",
    "resp_rate_bpm": "true_resp_rate_bpm",
    "skin_temp_c": "true_skin_temp_c",
    "humidity_pct": "true_humidity_pct",
    "pressure_mbar": "true_pressure_mbar",
}


def measure_physiology(
    cfg: ScenarioConfig, truth: dict, streams: RandomStreams, *, compiled: bool = True
) -> dict:
    """Return the measured physiological vector (:data:`PMF_COLUMNS`) from the truth.

    With ``device.physiology = "exact"`` every column equals its truth (age not
    rounded, Fitzpatrick type not misclassified); the random draws are made either way,
    so no other stream changes. ``compiled``: each column in one compiled pass
    (:mod:`.kernels.measurement_kernel`, the same bits) where its truth is a float64
    vector; False: the NumPy form below, the reference.
    """
    from .kernels import measurement_kernel as mk  # numba, deferred until a block runs

    m = cfg.measurement
    exact = cfg.device.physiology == "exact"
    f = 0.0 if exact else cfg.noise_factor("pmf_measurement")
    rng = streams("pmf_measurement")
    n = len(truth["true_age_yr"])
    out = {}
    draws = rng.normal(size=(len(_TRUTH), n))
    for i, (col, true_col) in enumerate(_TRUTH.items()):
        # truth + f sd z, in place in the draw's row (+ and x commute exactly)
        value = draws[i]
        # An instrument reports within its display range (PHYSIOLOGICAL_RANGES); only
        # errors scaled far beyond the instruments' (noise_scale >> 1) reach its ends.
        lo, hi, _ = PHYSIOLOGICAL_RANGES[col]
        t = truth[true_col]
        if compiled and isinstance(t, np.ndarray) and t.dtype == np.float64 and t.ndim == 1:
            mk.measured_row(value, f * getattr(m, col), t, float(lo), float(hi))
            out[col] = value
            continue
        value *= f * getattr(m, col)
        value += t
        out[col] = np.clip(value, lo, hi, out=value)
    if not exact:
        out["age_yr"] = np.floor(out["age_yr"])  # recorded in whole years
    off = rng.random(size=n) < f * m.fitzpatrick_misclass
    step = np.where(rng.random(size=n) < 0.5, -1, 1)
    fitz = truth["true_fitzpatrick_type"] + np.where(off, step, 0)
    out["fitzpatrick_type"] = np.clip(fitz, 1, 6).astype(np.int64)
    return {col: out[col] for col in PMF_COLUMNS}


def measure_ppg(
    cfg: ScenarioConfig, blood_fraction: np.ndarray, saturation: np.ndarray,
    streams: RandomStreams, *, compiled: bool = True,
) -> dict:
    """Perfusion and oxygen saturation as a PPG front end would report them.

    ``blood_volume_pct`` = 100 f_b exp(s_b z1) and ``spo2_pct`` = 100 S + s_S z2, clipped
    to 0-100 %, with f_b the detected dermal blood volume fraction, S the dermal
    saturation the optics see, s_b = ``device.blood_volume_error_rel`` and s_S =
    ``device.spo2_error_pct`` (pulse-oximeter A_rms, FDA 2013 premarket guidance;
    ISO 80601-2-61:2017), both scaled by the ``pmf_measurement`` noise source and zero
    with ``device.physiology = "exact"``. The log-normal blood-volume error keeps the
    estimate positive.

    Parameters
    ----------
    cfg : ScenarioConfig
        Scenario.
    blood_fraction : numpy.ndarray
        Detected dermal blood volume fraction (after contact blanching), (n,). [-]
    saturation : numpy.ndarray
        Dermal oxygen saturation, (n,). [-]
    streams : RandomStreams
        Random generators of the block (stream ``ppg``).
    compiled : bool
        After the draws, one compiled pass (:mod:`.kernels.measurement_kernel`, the same
        bits) where both inputs are float64 vectors; False: the NumPy form, the reference.

    Returns
    -------
    dict
        ``blood_volume_pct`` and ``spo2_pct``, (n,) each. [%]
    """
    f = 0.0 if cfg.device.physiology == "exact" else cfg.noise_factor("pmf_measurement")
    z = streams("ppg").normal(size=(2, len(blood_fraction)))
    d = cfg.device
    from .kernels import measurement_kernel as mk  # numba, deferred until a block runs

    if compiled and all(isinstance(x, np.ndarray) and x.dtype == np.float64 and x.ndim == 1
                        for x in (blood_fraction, saturation)):
        blood_pct, spo2_pct = np.empty(len(blood_fraction)), np.empty(len(blood_fraction))
        mk.ppg(blood_fraction, saturation, z, f * d.blood_volume_error_rel,
               f * d.spo2_error_pct, blood_pct, spo2_pct)
        return {"blood_volume_pct": blood_pct, "spo2_pct": spo2_pct}
    blood_pct = np.minimum(
        100.0 * np.asarray(blood_fraction) * pm.exp(f * d.blood_volume_error_rel * z[0]), 100.0
    )
    spo2_pct = np.clip(100.0 * np.asarray(saturation) + f * d.spo2_error_pct * z[1], 0.0, 100.0)
    return {"blood_volume_pct": blood_pct, "spo2_pct": spo2_pct}
