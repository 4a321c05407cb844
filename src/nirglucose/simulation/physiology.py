"""Physiology layer: subject traits (fixed per subject) and state (per measurement).

Traits: age, BMI, Fitzpatrick type and melanin, skin thickness, baseline blood
pressure, heart and respiratory rate, baseline perfusion and hydration, subcutaneous
fat. State: hydration, dermal blood volume (perfusion) and saturation, skin
temperature, the cardiac and respiratory phase, blood pressure and heart rate.

Correlations (each an assumption of plausible sign and size, documented here):
skin thickness grows with BMI and thins with age (about 6 % per decade after 40,
Shuster et al., Br. J. Dermatol. 93, 639 (1975)); systolic pressure rises about
0.5 mmHg/yr with age (Framingham); subcutaneous fat share grows with BMI; perfusion
rises with skin temperature (about 3 %/degC, vasodilation) and falls with contact
pressure (blanching).
"""

from __future__ import annotations

import numpy as np

from .. import portable as pm
from ..config import ScenarioConfig
from ..constants import FITZPATRICK_MELANIN_FRACTION_RANGES
from ._random import RandomStreams, categorical, truncated_normal

__all__ = [
    "melanin_fraction_from_fitzpatrick",
    "subcutis_fat_fraction",
    "skin_temperature_c",
    "skin_thickness_mean_mm",
    "sample_traits",
    "sample_state",
    "apply_physiology",
]

# Every number of this layer is a field of :class:`~nirglucose.config.PhysiologyConfig`
# (the source of each in its description), so a sweep can vary it and every output
# records it.


def melanin_fraction_from_fitzpatrick(fitzpatrick_type: np.ndarray, u: np.ndarray) -> np.ndarray:
    """Melanosome volume fraction within a Fitzpatrick type's range.

    Parameters
    ----------
    fitzpatrick_type : array_like of int
        Fitzpatrick skin type, 1-6. [-]
    u : array_like
        Position within the type's range, 0-1 (uniform draws). [-]

    Returns
    -------
    numpy.ndarray
        Melanosome volume fraction (``constants.FITZPATRICK_MELANIN_FRACTION_RANGES``,
        after Jacques 1998). [-]

    Examples
    --------
    >>> melanin_fraction_from_fitzpatrick(np.array([1, 6]), np.array([0.0, 1.0]))
    array([0.01, 0.15])
    """
    lo = np.array([FITZPATRICK_MELANIN_FRACTION_RANGES[k][0] for k in range(1, 7)])
    hi = np.array([FITZPATRICK_MELANIN_FRACTION_RANGES[k][1] for k in range(1, 7)])
    idx = np.asarray(fitzpatrick_type, dtype=int) - 1
    return lo[idx] + np.asarray(u) * (hi[idx] - lo[idx])


def subcutis_fat_fraction(
    bmi_kgm2: np.ndarray,
    fat_min: float,
    fat_rise: float,
    bmi_range_kgm2: tuple[float, float],
) -> np.ndarray:
    """Fat volume fraction of the subcutis, rising linearly with BMI.

    f = fat_min + fat_rise clip((BMI - BMI_lo) / (BMI_hi - BMI_lo), 0, 1): 0.7 at BMI 18
    to 0.9 at BMI 40 with the scenario defaults. SOURCES.md layer table gives 0.7-0.9;
    the linear rise with BMI is an assumption (``physiology.subcutis_fat_*``).

    Examples
    --------
    >>> round(float(subcutis_fat_fraction(29.0, 0.7, 0.2, (18.0, 40.0))), 12)
    0.8
    """
    lo, hi = bmi_range_kgm2
    return fat_min + fat_rise * np.clip((np.asarray(bmi_kgm2) - lo) / (hi - lo), 0.0, 1.0)


def skin_temperature_c(
    ambient_c: np.ndarray,
    neutral_c: float,
    per_ambient: float,
    ambient_ref_c: float,
) -> np.ndarray:
    """Mean skin temperature under a probe at a given ambient temperature.

    T_skin = T_neutral + k (T_ambient - T_ref): 33 + 0.3 (T_ambient - 25) degC with the
    scenario defaults (thermoneutral skin about 33 degC; the coupling k is an assumption,
    ``physiology.skin_temp_*``). [degC]

    Examples
    --------
    >>> float(skin_temperature_c(35.0, 33.0, 0.3, 25.0))
    36.0
    """
    return neutral_c + per_ambient * (np.asarray(ambient_c) - ambient_ref_c)


def skin_thickness_mean_mm(cfg: ScenarioConfig, bmi_kgm2: np.ndarray, age_yr: np.ndarray):
    """Subject's expected skin thickness from BMI and age, within the configured range.

    T = T0 + a (BMI - BMI_ref) - l T0 max(age - onset, 0) / 10: thicker with BMI (an
    assumption of size) and about 6 % thinner per decade after 40 (Shuster et al., Br.
    J. Dermatol. 93, 639 (1975)). [mm]
    """
    p = cfg.physiology
    mean = (
        p.skin_thickness_mm_mean
        + p.skin_thickness_mm_per_bmi * (bmi_kgm2 - p.skin_thickness_bmi_ref_kgm2)
        - p.skin_thickness_loss_per_decade
        * p.skin_thickness_mm_mean
        * np.maximum(age_yr - p.skin_thickness_loss_onset_yr, 0.0)
        / 10.0
    )
    return np.clip(mean, *p.skin_thickness_mm)


def sample_traits(cfg: ScenarioConfig, n: int, streams: RandomStreams) -> dict:
    """Draw the traits of ``n`` subjects."""
    p = cfg.physiology
    v = p.variation_scale
    rng = streams("physiology.traits")
    age_mid = float(np.mean(p.age_yr))
    age = age_mid + v * (rng.uniform(*p.age_yr, size=n) - age_mid)
    bmi = truncated_normal(rng, p.bmi_kgm2_mean, v * p.bmi_kgm2_sd, *p.bmi_kgm2, size=n)
    if v > 0:
        fitz = 1 + categorical(rng, p.fitzpatrick_probs, n)
    else:
        fitz = np.full(n, p.nominal_fitzpatrick_type)
        rng.random(size=n)  # keep the stream's consumption independent of the scale
    melanin = melanin_fraction_from_fitzpatrick(fitz, 0.5 + v * (rng.random(size=n) - 0.5))
    thickness_mean = skin_thickness_mean_mm(cfg, bmi, age)
    thickness = truncated_normal(
        rng, thickness_mean, v * p.skin_thickness_mm_sd, *p.skin_thickness_mm, size=n
    )
    # Framingham: systolic pressure about 0.5 mmHg/yr higher with age
    sbp_mid = p.systolic_bp_mmhg_at_18 + p.systolic_bp_mmhg_per_yr * (age - 18.0)
    sbp = truncated_normal(rng, sbp_mid, v * p.systolic_bp_mmhg_sd, *p.systolic_bp_mmhg, size=n)
    hr = truncated_normal(
        rng, p.heart_rate_bpm_mean, v * p.heart_rate_bpm_sd, *p.heart_rate_bpm, size=n
    )
    rr = truncated_normal(
        rng, p.resp_rate_bpm_mean, v * p.resp_rate_bpm_sd, *p.resp_rate_bpm, size=n
    )
    log_blood = pm.log(p.blood_fraction_median) + v * p.blood_fraction_log_sd_subject * rng.normal(
        size=n
    )
    hydration = v * p.hydration_pct_sd_subject * rng.normal(size=n)
    return {
        "true_age_yr": age,
        "true_bmi_kgm2": bmi,
        "true_fitzpatrick_type": fitz.astype(np.int64),
        "true_melanin_fraction": melanin,
        "true_skin_thickness_mm": thickness,
        "true_subcutis_fat_fraction": subcutis_fat_fraction(
            bmi, p.subcutis_fat_fraction_min, p.subcutis_fat_fraction_rise, p.subcutis_fat_bmi_kgm2
        ),
        "_sbp_base": sbp,
        "_hr_base": hr,
        "_rr_base": rr,
        "_log_blood_base": log_blood,
        "_hydration_base": hydration,
    }


def sample_state(
    cfg: ScenarioConfig,
    traits: dict,
    env: dict,
    glucose: dict,
    n_rows: int,
    streams: RandomStreams,
    *,
    compiled: bool = True,
) -> dict:
    """Draw the per-measurement state, given repeated traits, environment and glucose.

    The ``physiology.state`` stream is drawn in a fixed order (hydration, systolic BP,
    heart rate, respiration, skin temperature, saturation, blood volume), then the
    ``pulsation`` stream; the helpers below keep that order. ``compiled``: the same
    draws, then one compiled pass with the same operations in the same order
    (:mod:`nirglucose.simulation.kernels.physiology_kernel`: the same bits); False: the
    NumPy form below, the reference.
    """
    if compiled:
        return _sample_state_compiled(cfg, traits, env, glucose, n_rows, streams)
    p = cfg.physiology
    v = p.variation_scale
    rng = streams("physiology.state")
    hydration = _hydration_pct(p, v, traits, rng, n_rows)
    sbp, hr, rr = _vitals(p, v, traits, glucose["true_stress"], rng, n_rows)
    skin_temp = skin_temperature_c(
        env["true_ambient_temperature_c"],
        p.skin_temp_c_neutral,
        p.skin_temp_per_ambient,
        p.skin_temp_ambient_ref_c,
    ) + v * p.skin_temp_c_sd_state * rng.normal(size=n_rows)
    saturation = np.clip(
        p.saturation_mean + v * p.saturation_sd * rng.normal(size=n_rows), *p.saturation_limits
    )
    blood = _blood_fraction(cfg, traits, env, skin_temp, sbp, rng, streams, n_rows)
    return {
        "true_hydration_pct": 100.0 + hydration,
        "true_water_fraction": p.water_fraction_nominal * (1.0 + hydration / 100.0),
        "true_systolic_bp_mmhg": sbp,
        "true_heart_rate_bpm": hr,
        "true_resp_rate_bpm": rr,
        "true_skin_temp_c": skin_temp,
        "true_saturation": saturation,
        "true_blood_fraction": np.clip(blood, *p.blood_fraction_limits),
    }


_STATE_COLUMNS = ("true_hydration_pct", "true_water_fraction", "true_systolic_bp_mmhg",
                  "true_heart_rate_bpm", "true_resp_rate_bpm", "true_skin_temp_c",
                  "true_saturation", "true_blood_fraction")


def _sample_state_compiled(cfg, traits: dict, env: dict, glucose: dict, n_rows: int,
                           streams: RandomStreams) -> dict:
    """:func:`sample_state` through the compiled pass: the reference's draws (the seven
    ``physiology.state`` normals of a reading row by row: one ``(7, n)`` draw is the same
    variates in the same order), then :func:`~nirglucose.simulation.kernels.
    physiology_kernel.state`."""
    from .kernels import physiology_kernel as pk

    z = streams("physiology.state").normal(size=(7, n_rows))
    phase = streams("pulsation").uniform(0.0, 2.0 * np.pi, size=(2, n_rows))
    base = np.empty((5, n_rows))
    for i, k in enumerate(("_hydration_base", "_sbp_base", "_hr_base", "_rr_base",
                           "_log_blood_base")):
        base[i] = traits[k]
    out = np.empty((len(_STATE_COLUMNS), n_rows))
    pk.state(base, np.ascontiguousarray(glucose["true_stress"], dtype=np.int64),
             np.ascontiguousarray(env["true_ambient_temperature_c"], dtype=np.float64),
             np.ascontiguousarray(env["true_pressure_mbar"], dtype=np.float64), z, phase,
             _state_constants(cfg), out)
    return dict(zip(_STATE_COLUMNS, out, strict=True))


def _state_constants(cfg) -> tuple:
    """The scalars of the compiled state pass, each as the NumPy form computes it (the
    draws' factors v x SD as Python floats, as the reference's left-to-right products)."""
    p = cfg.physiology
    v = p.variation_scale
    e = cfg.environment
    return tuple(float(x) for x in (
        v * p.hydration_pct_sd_state, p.hydration_pct_limit, p.water_fraction_nominal,
        v * p.systolic_bp_mmhg_sd_state, p.stress_systolic_mmhg, *p.systolic_bp_mmhg,
        v * p.heart_rate_bpm_sd_state, p.stress_heart_rate_bpm, *p.heart_rate_bpm,
        v * p.resp_rate_bpm_sd_state, *p.resp_rate_bpm,
        p.skin_temp_c_neutral, p.skin_temp_per_ambient, p.skin_temp_ambient_ref_c,
        v * p.skin_temp_c_sd_state, p.saturation_mean, v * p.saturation_sd,
        *p.saturation_limits, v * p.blood_fraction_log_sd_state, p.perfusion_per_c,
        p.perfusion_per_mmhg, p.perfusion_ref_systolic_mmhg, e.perfusion_per_mbar,
        e.perfusion_reference_mbar, cfg.noise_factor("pulsation"), p.pulse_depth,
        p.resp_depth, *p.blood_fraction_limits))


def _hydration_pct(p, v: float, traits: dict, rng, n_rows: int) -> np.ndarray:
    """Hydration offset from nominal, squashed smoothly inside +/- its limit. [%]"""
    lim = p.hydration_pct_limit
    hydration = traits["_hydration_base"] + v * p.hydration_pct_sd_state * rng.normal(size=n_rows)
    return lim * pm.tanh(hydration / lim)  # stays inside +/- limit, smoothly


def _vitals(p, v: float, traits: dict, stress, rng, n_rows: int):
    """Systolic BP [mmHg], heart rate [1/min] and respiration rate [1/min] per reading.

    Each is the subject's base plus a per-reading variation; stress raises BP and heart
    rate. Drawn in this order from ``rng``.
    """
    sbp = np.clip(
        traits["_sbp_base"]
        + v * p.systolic_bp_mmhg_sd_state * rng.normal(size=n_rows)
        + p.stress_systolic_mmhg * stress,
        *p.systolic_bp_mmhg,
    )
    hr = np.clip(
        traits["_hr_base"]
        + v * p.heart_rate_bpm_sd_state * rng.normal(size=n_rows)
        + p.stress_heart_rate_bpm * stress,
        *p.heart_rate_bpm,
    )
    rr = np.clip(
        traits["_rr_base"] + v * p.resp_rate_bpm_sd_state * rng.normal(size=n_rows),
        *p.resp_rate_bpm,
    )
    return sbp, hr, rr


def _blood_fraction(cfg, traits: dict, env: dict, skin_temp, sbp, rng, streams, n_rows: int):
    """Dermal blood volume fraction of each reading, before its limits. [-]

    Log-normal around the subject's base, raised by skin temperature (vasodilation),
    systolic pressure and ambient pressure, and modulated by the cardiac and
    respiratory pulsation (``pulsation`` stream).
    """
    p = cfg.physiology
    v = p.variation_scale
    log_blood = (
        traits["_log_blood_base"]
        + v * p.blood_fraction_log_sd_state * rng.normal(size=n_rows)
        + p.perfusion_per_c * (skin_temp - p.skin_temp_c_neutral)
        + p.perfusion_per_mmhg * (sbp - p.perfusion_ref_systolic_mmhg)
        + cfg.environment.perfusion_per_mbar
        * (env["true_pressure_mbar"] - cfg.environment.perfusion_reference_mbar)
    )
    pulse = cfg.noise_factor("pulsation")
    phase = streams("pulsation").uniform(0.0, 2.0 * np.pi, size=(2, n_rows))
    modulation = 1.0 + pulse * (
        p.pulse_depth * pm.sin(phase[0]) + p.resp_depth * pm.sin(phase[1])
    )
    return pm.exp(log_blood) * modulation


def apply_physiology(cfg, traits_rows, env, glucose, n_rows, streams) -> dict:
    """Physiology layer entry: repeated traits plus the per-measurement state."""
    state = sample_state(cfg, traits_rows, env, glucose, n_rows, streams)
    public = {k: v for k, v in traits_rows.items() if not k.startswith("_")}
    return {**public, **state}
