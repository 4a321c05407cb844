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

from ..config import ScenarioConfig
from ..constants import FITZPATRICK_MELANIN_FRACTION_RANGES, WATER_FRACTION_DERMIS_NOMINAL
from ._random import RandomStreams, truncated_normal

__all__ = [
    "melanin_fraction_from_fitzpatrick",
    "subcutis_fat_fraction",
    "skin_temperature_c",
    "sample_traits",
    "sample_state",
    "apply_physiology",
]

#: Relative perfusion change per degC of skin temperature (vasodilation; assumption
#: of size, sign from e.g. Charkoudian, Mayo Clin. Proc. 78, 603 (2003)). [1/degC]
PERFUSION_PER_C = 0.03
#: Cardiac and respiratory blood-volume modulation depths: a PPG perfusion index of
#: about 1-2 % at the wrist/finger in the NIR (Lima & Bakker, Crit. Care Med. 30, 1210
#: (2002)) and a smaller respiratory-induced variation. [-]
PULSE_DEPTH = 0.02
RESP_DEPTH = 0.005
#: Skin temperature: about 33 degC at thermoneutral ambient, rising about 0.3 degC per
#: degC of ambient (an assumption of the wrist's coupling). [degC], [-]
SKIN_TEMP_NEUTRAL_C = 33.0
#: Cohort vital signs, (mean, between-subject SD): resting heart rate of adults about
#: 72 +/- 9 /min and respiratory rate 16 +/- 1.5 /min (normal ranges 60-100 and 12-20;
#: e.g. Fleming et al., Lancet 377, 1011 (2011)). [1/min]
HEART_RATE_BPM = (72.0, 9.0)
RESP_RATE_BPM = (16.0, 1.5)
#: Systolic pressure at 18 yr, its rise per year of age (Framingham, about 0.5 mmHg/yr)
#: and between-subject SD. [mmHg], [mmHg/yr], [mmHg]
SBP_AT_18_MMHG, SBP_PER_YR_MMHG, SBP_SD_MMHG = 110.0, 0.5, 12.0
#: Within-subject SD between snapshots of systolic pressure, heart rate, respiratory rate
#: and skin temperature (assumptions of plausible size). [mmHg], [1/min], [1/min], [degC]
SBP_STATE_SD_MMHG, HR_STATE_SD_BPM, RR_STATE_SD_BPM, SKIN_TEMP_STATE_SD_C = 5.0, 4.0, 1.0, 0.7
#: Acute mental stress raises systolic pressure about 8 mmHg and heart rate about
#: 10 /min (order of the laboratory stress responses reviewed by Kario et al., Hypertens.
#: Res. 26, 355 (2003)). [mmHg], [1/min]
STRESS_SBP_MMHG, STRESS_HR_BPM = 8.0, 10.0
#: Skin thickness grows about 0.03 mm per kg/m^2 of BMI (an assumption of size) and thins
#: about 6 % per decade after 40 (Shuster et al. 1975). [mm/(kg/m^2)], [1/decade]
THICKNESS_PER_BMI_MM, THICKNESS_LOSS_PER_DECADE = 0.03, 0.06
SKIN_TEMP_PER_AMBIENT = 0.3


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


def subcutis_fat_fraction(bmi_kgm2: np.ndarray) -> np.ndarray:
    """Fat volume fraction of the subcutis, 0.7 at BMI 18 to 0.9 at BMI 40.

    SOURCES.md layer table gives 0.7-0.9; the linear rise with BMI is an assumption.

    Examples
    --------
    >>> float(subcutis_fat_fraction(29.0))
    0.8
    """
    return 0.7 + 0.2 * np.clip((np.asarray(bmi_kgm2) - 18.0) / 22.0, 0.0, 1.0)


def skin_temperature_c(ambient_c: np.ndarray) -> np.ndarray:
    """Mean skin temperature under a probe at a given ambient temperature.

    T_skin = 33 + 0.3 (T_ambient - 25) degC (assumption; see module constants).
    """
    return SKIN_TEMP_NEUTRAL_C + SKIN_TEMP_PER_AMBIENT * (np.asarray(ambient_c) - 25.0)


def sample_traits(cfg: ScenarioConfig, n: int, streams: RandomStreams) -> dict:
    """Draw the traits of ``n`` subjects."""
    p = cfg.physiology
    v = p.variation_scale
    rng = streams("physiology.traits")
    age_mid = float(np.mean(p.age_yr))
    age = age_mid + v * (rng.uniform(*p.age_yr, size=n) - age_mid)
    bmi = truncated_normal(rng, p.bmi_kgm2_mean, v * p.bmi_kgm2_sd, *p.bmi_kgm2, size=n)
    if v > 0:
        fitz = 1 + rng.choice(6, p=np.asarray(p.fitzpatrick_probs), size=n)
    else:
        fitz = np.full(n, 3)
        rng.random(size=n)  # keep the stream's consumption independent of the scale
    melanin = melanin_fraction_from_fitzpatrick(fitz, 0.5 + v * (rng.random(size=n) - 0.5))
    thickness_mean = (
        p.skin_thickness_mm_mean
        + THICKNESS_PER_BMI_MM * (bmi - 25.0)
        - THICKNESS_LOSS_PER_DECADE * p.skin_thickness_mm_mean * np.maximum(age - 40.0, 0.0) / 10.0
    )
    thickness_mean = np.clip(thickness_mean, *p.skin_thickness_mm)
    thickness = truncated_normal(
        rng, thickness_mean, v * p.skin_thickness_mm_sd, *p.skin_thickness_mm, size=n
    )
    sbp_mid = SBP_AT_18_MMHG + SBP_PER_YR_MMHG * (age - 18.0)
    sbp = truncated_normal(rng, sbp_mid, v * SBP_SD_MMHG, *p.systolic_bp_mmhg, size=n)
    hr = truncated_normal(rng, HEART_RATE_BPM[0], v * HEART_RATE_BPM[1], *p.heart_rate_bpm, size=n)
    rr = truncated_normal(rng, RESP_RATE_BPM[0], v * RESP_RATE_BPM[1], *p.resp_rate_bpm, size=n)
    log_blood = np.log(p.blood_fraction_median) + v * p.blood_fraction_log_sd_subject * rng.normal(
        size=n
    )
    hydration = v * p.hydration_pct_sd_subject * rng.normal(size=n)
    return {
        "true_age_yr": age,
        "true_bmi_kgm2": bmi,
        "true_fitzpatrick_type": fitz.astype(np.int64),
        "true_melanin_fraction": melanin,
        "true_skin_thickness_mm": thickness,
        "true_subcutis_fat_fraction": subcutis_fat_fraction(bmi),
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
) -> dict:
    """Draw the per-measurement state, given repeated traits, environment and glucose."""
    p = cfg.physiology
    v = p.variation_scale
    rng = streams("physiology.state")
    stress = glucose["true_stress"]
    lim = p.hydration_pct_limit
    hydration = traits["_hydration_base"] + v * p.hydration_pct_sd_state * rng.normal(size=n_rows)
    hydration = lim * np.tanh(hydration / lim)  # stays inside +/- limit, smoothly
    sbp = np.clip(
        traits["_sbp_base"]
        + v * SBP_STATE_SD_MMHG * rng.normal(size=n_rows)
        + STRESS_SBP_MMHG * stress,
        *p.systolic_bp_mmhg,
    )
    hr = np.clip(
        traits["_hr_base"] + v * HR_STATE_SD_BPM * rng.normal(size=n_rows) + STRESS_HR_BPM * stress,
        *p.heart_rate_bpm,
    )
    rr = np.clip(
        traits["_rr_base"] + v * RR_STATE_SD_BPM * rng.normal(size=n_rows), *p.resp_rate_bpm
    )
    skin_temp = skin_temperature_c(
        env["true_ambient_temperature_c"]
    ) + v * SKIN_TEMP_STATE_SD_C * rng.normal(size=n_rows)
    saturation = np.clip(
        p.saturation_mean + v * p.saturation_sd * rng.normal(size=n_rows), 0.3, 0.98
    )
    log_blood = (
        traits["_log_blood_base"]
        + v * p.blood_fraction_log_sd_state * rng.normal(size=n_rows)
        + PERFUSION_PER_C * (skin_temp - SKIN_TEMP_NEUTRAL_C)
        + 0.002 * (sbp - 120.0)
        + cfg.environment.perfusion_per_mbar * (env["true_pressure_mbar"] - 1013.25)
    )
    pulse = cfg.noise_factor("pulsation")
    phase = streams("pulsation").uniform(0.0, 2.0 * np.pi, size=(2, n_rows))
    modulation = 1.0 + pulse * (PULSE_DEPTH * np.sin(phase[0]) + RESP_DEPTH * np.sin(phase[1]))
    blood = np.exp(log_blood) * modulation
    return {
        "true_hydration_pct": 100.0 + hydration,
        "true_water_fraction": WATER_FRACTION_DERMIS_NOMINAL * (1.0 + hydration / 100.0),
        "true_systolic_bp_mmhg": sbp,
        "true_heart_rate_bpm": hr,
        "true_resp_rate_bpm": rr,
        "true_skin_temp_c": skin_temp,
        "true_saturation": saturation,
        "true_blood_fraction": np.clip(blood, 1e-4, 0.2),
    }


def apply_physiology(cfg, traits_rows, env, glucose, n_rows, streams) -> dict:
    """Physiology layer entry: repeated traits plus the per-measurement state."""
    state = sample_state(cfg, traits_rows, env, glucose, n_rows, streams)
    public = {k: v for k, v in traits_rows.items() if not k.startswith("_")}
    return {**public, **state}
