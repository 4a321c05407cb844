"""Scenario configuration: one pydantic model per simulator layer, presets, overrides.

A scenario is fully described by a :class:`ScenarioConfig`. It is built from a named
preset (:data:`PRESETS`) plus dotted overrides such as ``{"hardware.adc_bits": 14}``
and recorded, resolved, in every dataset and result the package writes.

Every numeric default names its source in the field description; a value that is an
assumption of this package (there is no published number for it) says so. The
``noise`` section has one switch and one scale per noise source (:data:`NOISE_SOURCES`);
the global ``noise_scale`` multiplies them all, for sweeps. The ``device`` section
holds the hardware capabilities a wearable team chooses (:data:`DEVICE_CAPABILITIES`);
:data:`PRESET_DESCRIPTIONS` and :data:`PRESET_CAPABILITIES` describe each preset.
"""

from __future__ import annotations

import json
import re
from typing import Annotated, Any, Literal

from pydantic import BaseModel, ConfigDict, Field, ValidationError, field_validator, model_validator

from .constants import (
    DARK_CURRENT_DOUBLING_COEFF_PER_C,
    DEFAULT_LED_WAVELENGTHS_NM,
    LED_AGEING_PER_1000H,
    LED_THERMAL_COEFF_PER_C,
    MGDL_PER_MMOLL_GLUCOSE,
    WATER_FRACTION_DERMIS_NOMINAL,
)
from .exceptions import ConfigError, unknown_name

__all__ = [
    "ScenarioConfig",
    "LED",
    "LEDConfig",
    "DEFAULT_LEDS",
    "LEGACY_LED_KEYS",
    "ContactConfig",
    "ReferenceTissue",
    "PhysiologyConfig",
    "GlucoseConfig",
    "EnvironmentConfig",
    "OpticsConfig",
    "HardwareConfig",
    "MeasurementConfig",
    "DeviceConfig",
    "DEVICE_CAPABILITIES",
    "device_capabilities",
    "NoiseSource",
    "NoiseConfig",
    "NOISE_SOURCES",
    "PRESETS",
    "PRESET_DESCRIPTIONS",
    "PRESET_CAPABILITIES",
    "PAPER_SIGNAL_GAIN",
    "WEARABLE_SIGNAL_GAIN",
    "FORWARD_MODELS",
    "resolve_config",
    "apply_overrides",
    "parse_override",
    "valid_keys",
    "is_valid_key",
]

#: Forward optical models selectable by name (``optics.model``).
FORWARD_MODELS = ("beer-lambert", "diffusion", "rte-lut")

#: Noise sources, each with an on/off switch and a scale in ``noise.<name>``.
NOISE_SOURCES = (
    "led_thermal_drift",
    "led_ageing",
    "led_flicker",
    "led_wavelength_shift",
    "dark_current",
    "shot",
    "johnson",
    "adc_inl",
    "adc_offset_drift",
    "ambient_light",
    "humidity_coupling",
    "contact_pressure",
    "pulsation",
    "pmf_measurement",
)


#: Magnitude no setting may exceed, whatever its own bounds: the largest default is
#: 1e5 (ambient lux, TIA gain in ohm); beyond 1e9 a value can only overflow the
#: simulation (exp, squares) into garbage codes (issue 20). [-]
MAX_ABS_VALUE = 1e9


class _Model(BaseModel):
    # every value finite: NaN or infinity would reach the ADC as garbage codes (issue 20)
    model_config = ConfigDict(
        extra="forbid", frozen=True, validate_default=True, allow_inf_nan=False
    )

    @field_validator("*")
    @classmethod
    def _bounded(cls, v: Any) -> Any:
        items = v.values() if isinstance(v, dict) else v if isinstance(v, tuple) else (v,)
        for x in items:
            if isinstance(x, int | float) and not isinstance(x, bool) and abs(x) > MAX_ABS_VALUE:
                raise ValueError(f"must lie within +-{MAX_ABS_VALUE:.0e}")
        return v


def _num(lo: float, hi: float, *, gt: bool = False) -> Any:
    """A float type within ``[lo, hi]`` (``(lo, hi]`` with ``gt``), as pydantic constraints."""
    return Annotated[float, Field(gt=lo, le=hi) if gt else Field(ge=lo, le=hi)]


def _pair(lo: float, hi: float, *, gt: bool = False) -> Any:
    """A ``(low, high)`` range type whose two values lie within ``[lo, hi]`` (see :func:`_num`)."""
    item = _num(lo, hi, gt=gt)
    return tuple[item, item]


def _check_range(value: tuple[float, float], name: str) -> tuple[float, float]:
    low, high = value
    if not low < high:
        raise ValueError(f"{name} range must have low < high, got ({low}, {high})")
    return value


class LED(_Model):
    """One LED of the set: where it emits, how wide, how strong, how well it is detected."""

    wavelength_nm: float = Field(
        ...,
        ge=700,
        le=1300,
        description="Centre wavelength, within the optics tables' 700-1300 nm grid "
        "(data/optics/SOURCES.md). [nm]",
    )
    fwhm_nm: float = Field(
        ...,
        gt=0,
        le=150,
        description="Emission full width at half maximum, typical of IR LEDs "
        "(e.g. Vishay VSLY5850 30 nm, TSAL6200 40 nm at 940 nm; longer wavelengths wider); "
        "at most 150 nm, a quarter of the optics tables' span. [nm]",
    )
    power_mw: float = Field(
        ...,
        gt=0,
        le=1000,
        description="Optical power at 25 degC as driven (IR LEDs give 5-40 mW at 20-100 mA; "
        "chosen per channel so tissue codes sit mid-scale); at most 1 W, the class of "
        "high-power IR emitters. [mW]",
    )
    responsivity_a_per_w: float = Field(
        ...,
        gt=0,
        le=1.05,
        description="Photodiode responsivity at this LED (the study's set: Hamamatsu S1336 "
        "typical spectral response read at 850/940/1050/1150 nm); at most 1.05, quantum "
        "efficiency 1 at 1300 nm (lambda / 1239.8 nm A/W). [A/W]",
    )


#: The study's four LEDs: FWHM typical of IR LEDs, power per channel for mid-scale
#: tissue codes, S1336 responsivity at each wavelength (:class:`LED` field sources).
DEFAULT_LEDS: tuple[LED, ...] = tuple(
    LED(wavelength_nm=wl, fwhm_nm=fwhm, power_mw=p, responsivity_a_per_w=r)
    for wl, fwhm, p, r in zip(
        DEFAULT_LED_WAVELENGTHS_NM,
        (40.0, 45.0, 50.0, 60.0),
        (2.0, 2.0, 2.7, 10.0),
        (0.58, 0.62, 0.40, 0.15),
        strict=True,
    )
)

#: Per-LED keys of the former layout (before issue 22) -> the :class:`LED` field they set.
LEGACY_LED_KEYS = {
    "leds.wavelengths_nm": "wavelength_nm",
    "leds.fwhm_nm": "fwhm_nm",
    "hardware.led_power_mw": "power_mw",
    "hardware.responsivity_a_per_w": "responsivity_a_per_w",
}


class LEDConfig(_Model):
    """The LED set, one record per LED (``leds.emitters``), and its band integration.

    One override replaces the set: ``leds=[{"wavelength_nm": 850, "fwhm_nm": 40,
    "power_mw": 2.0, "responsivity_a_per_w": 0.58}, ...]`` (or ``leds.emitters=[...]``);
    one LED's value is ``leds.emitters.<i>.<field>``. The per-LED tuples the layers use
    are read-only properties (:attr:`wavelengths_nm`, :attr:`fwhm_nm`, :attr:`power_mw`,
    :attr:`responsivity_a_per_w`).
    """

    emitters: tuple[LED, ...] = Field(
        DEFAULT_LEDS,
        min_length=1,
        description="The LED set, one record per LED with wavelength_nm [nm], fwhm_nm [nm], "
        "power_mw [mW] and responsivity_a_per_w [A/W] (the study's four by default). "
        "[nm, nm, mW, A/W]",
    )
    band_points: int = Field(
        3,
        ge=1,
        le=31,
        description="Gauss-Hermite points integrating each LED band. 3 points are within "
        "0.1-6 % of a 21-point integral, a near-constant factor per LED (spread across "
        "subjects <= 0.2 %) that the reference reading absorbs; raise it for accuracy. [-]",
    )

    @model_validator(mode="before")
    @classmethod
    def _from_list(cls, data: Any) -> Any:
        # ``leds=[...]``: the LED records alone; the former {wavelengths_nm, fwhm_nm} layout
        if isinstance(data, list | tuple):
            return {"emitters": data}
        return data

    @model_validator(mode="after")
    def _unique(self) -> LEDConfig:
        if len(set(self.wavelengths_nm)) != len(self.wavelengths_nm):
            raise ValueError("the LED set must not repeat a wavelength")
        return self

    wavelengths_nm = property(lambda self: tuple(e.wavelength_nm for e in self.emitters))
    fwhm_nm = property(lambda self: tuple(e.fwhm_nm for e in self.emitters))
    power_mw = property(lambda self: tuple(e.power_mw for e in self.emitters))
    responsivity_a_per_w = property(
        lambda self: tuple(e.responsivity_a_per_w for e in self.emitters)
    )


class PhysiologyConfig(_Model):
    """Cohort traits (fixed per subject) and state (varying per measurement)."""

    age_yr: _pair(0, 122) = Field(
        (18.0, 80.0),
        description="Age range. Bound: 0-122 yr, the longest documented human life. [yr]",
    )
    bmi_kgm2_mean: float = Field(
        28.0,
        ge=10,
        le=100,
        description="Mean BMI, near the NHANES 2017-2020 adult mean (29.6). Bound: 10-100 "
        "kg/m^2, the span of living adults (an assumption). [kg/m^2]",
    )
    bmi_kgm2_sd: float = Field(
        5.0,
        ge=0,
        le=20,
        description="BMI standard deviation. At most 20 (an assumption: beyond, the 10-100 span "
        "clips). [kg/m^2]",
    )
    bmi_kgm2: _pair(10, 100) = Field(
        (18.0, 40.0),
        description="BMI range. Bound: 10-100 kg/m^2, the span of living adults (an "
        "assumption). [kg/m^2]",
    )
    fitzpatrick_probs: tuple[_num(0, 1), ...] = Field(
        (1 / 6,) * 6,
        description="Probability of Fitzpatrick types I-VI. Each a probability in 0-1. [-]",
    )
    skin_thickness_mm: _pair(0.5, 4) = Field(
        (0.5, 4.0),
        description="Epidermis + dermis thickness range. [mm]",
    )
    skin_thickness_mm_mean: float = Field(
        1.8,
        ge=0.5,
        le=4,
        description="Mean skin thickness (dermis about 1-2 mm, Meglinski 2002). Bound: 0.5-4 "
        "mm, the simulator's skin-layer range. [mm]",
    )
    skin_thickness_mm_sd: float = Field(
        0.6,
        ge=0,
        le=2,
        description="Between-subject SD. At most 2 mm, half the 0.5-4 mm range. [mm]",
    )
    hydration_pct_sd_subject: float = Field(
        4.0,
        ge=0,
        le=50,
        description="Between-subject SD of dermal water, % of nominal. At most 50 %, so dermal "
        "water (nominal 0.65) stays below 1. [%]",
    )
    hydration_pct_sd_state: float = Field(
        3.0,
        ge=0,
        le=50,
        description="Within-subject SD of dermal water, % of nominal. At most 50 %, so dermal "
        "water (nominal 0.65) stays below 1. [%]",
    )
    hydration_pct_limit: float = Field(
        10.0,
        gt=0,
        le=50,
        description="Hydration stays within +/- this of nominal (issue spec). At most 50 %, so "
        "dermal water (nominal 0.65) stays below 1. [%]",
    )
    blood_fraction_median: float = Field(
        0.02,
        gt=0,
        lt=0.2,
        description="Median dermal blood volume fraction (0.002-0.05, Meglinski 2002). [-]",
    )
    blood_fraction_log_sd_subject: float = Field(
        0.35,
        ge=0,
        le=2,
        description="Between-subject SD of ln(blood fraction). At most 2: a factor e^2 = 7.4 "
        "per SD already spans Meglinski's 0.002-0.05. [-]",
    )
    blood_fraction_log_sd_state: float = Field(
        0.15,
        ge=0,
        le=2,
        description="Within-subject SD of ln(blood fraction). At most 2: a factor e^2 = 7.4 per "
        "SD already spans Meglinski's 0.002-0.05. [-]",
    )
    saturation_mean: float = Field(
        0.7, gt=0, lt=1, description="Dermal mixed SO2, 0.6-0.8 (SOURCES.md layer table). [-]"
    )
    saturation_sd: float = Field(
        0.05,
        ge=0,
        le=0.5,
        description="SD of dermal SO2. At most 0.5, half of SO2's 0-1 span. [-]",
    )
    systolic_bp_mmhg: _pair(50, 250) = Field(
        (90.0, 180.0),
        description="Range. Bound: 50-250 mmHg, shock to hypertensive crisis. [mmHg]",
    )
    heart_rate_bpm: _pair(20, 250) = Field(
        (50.0, 120.0),
        description="Range. Bound: 20-250 /min, the span of human heart rates. [1/min]",
    )
    resp_rate_bpm: _pair(4, 60) = Field(
        (12.0, 20.0),
        description="Range. Bound: 4-60 /min, the span of human breathing rates. [1/min]",
    )
    # --- vital signs: cohort (mean, between-subject SD) and within-subject SD ---------
    heart_rate_bpm_mean: float = Field(
        72.0,
        ge=20,
        le=250,
        description="Resting adult heart rate, 72 +/- 9 /min (normal 60-100; Fleming et al., "
        "Lancet 377, 1011 (2011)). Bound: 20-250 /min, the span of human heart rates. [1/min]",
    )
    heart_rate_bpm_sd: float = Field(
        9.0,
        ge=0,
        le=50,
        description="Between-subject SD. At most 50 (an assumption). [1/min]",
    )
    heart_rate_bpm_sd_state: float = Field(
        4.0,
        ge=0,
        le=50,
        description="Within-subject SD between snapshots (an assumption). At most 50. [1/min]",
    )
    resp_rate_bpm_mean: float = Field(
        16.0,
        ge=4,
        le=60,
        description="Adult respiratory rate, 16 +/- 1.5 /min (normal 12-20; Fleming et al. "
        "2011). Bound: 4-60 /min, the span of human breathing rates. [1/min]",
    )
    resp_rate_bpm_sd: float = Field(
        1.5,
        ge=0,
        le=20,
        description="Between-subject SD. At most 20 (an assumption). [1/min]",
    )
    resp_rate_bpm_sd_state: float = Field(
        1.0,
        ge=0,
        le=20,
        description="Within-subject SD between snapshots (an assumption). At most 20. [1/min]",
    )
    systolic_bp_mmhg_at_18: float = Field(
        110.0,
        ge=50,
        le=250,
        description="Mean systolic pressure at 18 yr (Framingham). Bound: 50-250 mmHg, shock to "
        "hypertensive crisis. [mmHg]",
    )
    systolic_bp_mmhg_per_yr: float = Field(
        0.5,
        ge=-2,
        le=2,
        description="Rise of systolic pressure per year of age (Framingham). At most +-2: a "
        "century then spans 50-250 mmHg. [mmHg/yr]",
    )
    systolic_bp_mmhg_sd: float = Field(
        12.0,
        ge=0,
        le=50,
        description="Between-subject SD. At most 50 (an assumption). [mmHg]",
    )
    systolic_bp_mmhg_sd_state: float = Field(
        5.0,
        ge=0,
        le=50,
        description="Within-subject SD between snapshots (an assumption). At most 50. [mmHg]",
    )
    stress_systolic_mmhg: float = Field(
        8.0,
        ge=0,
        le=60,
        description="Systolic rise under acute mental stress (order of the laboratory responses "
        "reviewed by Kario et al., Hypertens. Res. 26, 355 (2003)). At most 60, above Kario's "
        "largest responses. [mmHg]",
    )
    stress_heart_rate_bpm: float = Field(
        10.0,
        ge=0,
        le=60,
        description="Heart-rate rise under acute mental stress (Kario et al. 2003). At most 60 "
        "(an assumption). [1/min]",
    )
    # --- skin thickness and subcutaneous fat -------------------------------------------
    skin_thickness_mm_per_bmi: float = Field(
        0.03,
        ge=-0.1,
        le=0.1,
        description="Skin-thickness growth per kg/m^2 of BMI (an assumption of size). At most "
        "+-0.1: 6 mm across BMI 10-70, beyond the 0.5-4 mm range. [mm/(kg/m^2)]",
    )
    skin_thickness_bmi_ref_kgm2: float = Field(
        25.0,
        ge=10,
        le=100,
        description="BMI at which skin_thickness_mm_mean applies. Bound: 10-100 kg/m^2, the "
        "span of living adults (an assumption). [kg/m^2]",
    )
    skin_thickness_loss_per_decade: float = Field(
        0.06, ge=0, le=1, description="Relative thinning per decade of age (Shuster et al., "
        "Br. J. Dermatol. 93, 639 (1975)). [1/decade]"
    )
    skin_thickness_loss_onset_yr: float = Field(
        40.0,
        ge=0,
        le=122,
        description="Age at which thinning starts (Shuster et al. 1975). Bound: 0-122 yr, the "
        "longest documented human life. [yr]",
    )
    subcutis_fat_fraction_min: float = Field(
        0.7, gt=0, lt=1, description="Subcutis fat volume fraction at the lowest BMI of "
        "subcutis_fat_bmi_kgm2 (SOURCES.md layer table: 0.7-0.9). [-]"
    )
    subcutis_fat_fraction_rise: float = Field(
        0.2, ge=0, lt=1, description="Rise of the fat fraction across subcutis_fat_bmi_kgm2, "
        "linear in BMI (an assumption; SOURCES.md: 0.7-0.9). [-]"
    )
    subcutis_fat_bmi_kgm2: _pair(10, 100) = Field(
        (18.0, 40.0),
        description="BMI range over which the fat fraction rises. Bound: 10-100 kg/m^2, the "
        "span of living adults (an assumption). [kg/m^2]",
    )
    water_fraction_nominal: float = Field(
        WATER_FRACTION_DERMIS_NOMINAL,
        gt=0,
        lt=1,
        description="Nominal dermal water volume fraction, 0.6-0.7 (Meglinski & Matcher, "
        "Physiol. Meas. 23, 741 (2002)). [-]",
    )
    nominal_fitzpatrick_type: int = Field(
        3, ge=1, le=6, description="Fitzpatrick type of every subject at variation_scale 0. [-]"
    )
    # --- skin temperature and perfusion ------------------------------------------------
    skin_temp_c_neutral: float = Field(
        33.0,
        ge=10,
        le=42,
        description="Skin temperature under the probe at skin_temp_ambient_ref_c (thermoneutral "
        "skin about 33 degC). Bound: 10-42 degC, cold-exposed skin to fever. [degC]",
    )
    skin_temp_ambient_ref_c: float = Field(
        25.0,
        ge=-20,
        le=50,
        description="Ambient temperature at which skin sits at skin_temp_c_neutral. Bound: -20 "
        "to 50 degC, as environment.temperature_c. [degC]",
    )
    skin_temp_per_ambient: float = Field(
        0.3, ge=0, le=1, description="Skin-temperature change per degC of ambient (an "
        "assumption of the wrist's coupling). [-]"
    )
    skin_temp_c_sd_state: float = Field(
        0.7,
        ge=0,
        le=5,
        description="Within-subject SD of skin temperature (an assumption). At most 5 degC (an "
        "assumption). [degC]",
    )
    perfusion_per_c: float = Field(
        0.03,
        ge=-0.5,
        le=0.5,
        description="Relative perfusion change per degC of skin above skin_temp_c_neutral "
        "(vasodilation; sign from Charkoudian, Mayo Clin. Proc. 78, 603 (2003), size an "
        "assumption). At most +-0.5 (an assumption). [1/degC]",
    )
    perfusion_per_mmhg: float = Field(
        0.002,
        ge=-0.05,
        le=0.05,
        description="Relative perfusion change per mmHg of systolic pressure above "
        "perfusion_ref_systolic_mmhg (an assumption). At most +-0.05 (an assumption). [1/mmHg]",
    )
    perfusion_ref_systolic_mmhg: float = Field(
        120.0,
        ge=50,
        le=250,
        description="Systolic pressure of nominal perfusion. Bound: 50-250 mmHg, shock to "
        "hypertensive crisis. [mmHg]",
    )
    pulse_depth: float = Field(
        0.02, ge=0, lt=1, description="Cardiac blood-volume modulation depth: PPG perfusion "
        "index about 1-2 % in the NIR (Lima & Bakker, Crit. Care Med. 30, 1210 (2002)). [-]"
    )
    resp_depth: float = Field(
        0.005, ge=0, lt=1, description="Respiratory blood-volume modulation depth, smaller "
        "than the cardiac one (an assumption). [-]"
    )
    saturation_limits: _pair(0, 1) = Field(
        (0.3, 0.98),
        description="Dermal SO2 is clipped to this range. Each a fraction in 0-1. [-]",
    )
    blood_fraction_limits: _pair(0, 1, gt=True) = Field(
        (1e-4, 0.2),
        description="Dermal blood volume fraction is clipped to this range (above Meglinski "
        "2002's 0.002-0.05 either side). Each a fraction in 0-1, above 0 (its log is drawn). "
        "[-]",
    )
    variation_scale: float = Field(
        1.0,
        ge=0,
        le=10,
        description="Multiplies every between- and within-subject spread (0: all subjects "
        "nominal, a cuvette-like phantom). At most 10 (an assumption: wider spreads clip). [-]",
    )

    _ranges = field_validator(
        "age_yr",
        "bmi_kgm2",
        "skin_thickness_mm",
        "systolic_bp_mmhg",
        "heart_rate_bpm",
        "resp_rate_bpm",
        "subcutis_fat_bmi_kgm2",
        "saturation_limits",
        "blood_fraction_limits",
    )(lambda v, info: _check_range(v, info.field_name))

    @field_validator("fitzpatrick_probs")
    @classmethod
    def _probs(cls, v: tuple[float, ...]) -> tuple[float, ...]:
        if len(v) != 6 or any(p < 0 for p in v) or abs(sum(v) - 1.0) > 1e-6:
            raise ValueError("fitzpatrick_probs needs 6 non-negative probabilities summing to 1")
        return v


class GlucoseConfig(_Model):
    """Glucose snapshots by diabetes status, and the glucose signal's optical magnitudes."""

    status_probs: dict[str, _num(0, 1)] = Field(
        {"normal": 0.35, "prediabetes": 0.2, "type1": 0.15, "type2": 0.3},
        description="Cohort share of each diabetes status (an assumption; a clinic-like mix). "
        "[-]",
    )
    fasting_mgdl: dict[str, tuple[_num(20, 600), _num(0, 200)]] = Field(
        {
            "normal": (88.0, 8.0),
            "prediabetes": (112.0, 8.0),
            "type1": (150.0, 40.0),
            "type2": (145.0, 30.0),
        },
        description="(mean, SD) of fasting glucose per status; ADA thresholds: normal < 100, "
        "prediabetes 100-125, diabetes >= 126 mg/dL (ADA Standards of Care 2024, 2.1). Means "
        "within 20-600 mg/dL (range_mgdl's bound), SDs 0-200. [mg/dL]",
    )
    meal_peak_mgdl: dict[str, _num(0, 500)] = Field(
        {"normal": 35.0, "prediabetes": 60.0, "type1": 130.0, "type2": 95.0},
        description="Mean postprandial excursion at its peak, about 1 h after a meal (normal < "
        "140 mg/dL at 2 h, ADA; diabetic excursions larger). Each 0-500 (an assumption). "
        "[mg/dL]",
    )
    meal_peak_h: float = Field(
        1.0,
        gt=0,
        le=12,
        description="Time of the postprandial peak. At most 12 h (an assumption). [h]",
    )
    stress_prob: float = Field(0.15, ge=0, le=1, description="Share of stressed snapshots. [-]")
    stress_mgdl: _pair(0, 200) = Field(
        (10.0, 35.0),
        description="Stress (cortisol) rise range (an assumption). Each 0-200 (an assumption). "
        "[mg/dL]",
    )
    dawn_mgdl: dict[str, _num(0, 200)] = Field(
        {"normal": 5.0, "prediabetes": 10.0, "type1": 25.0, "type2": 20.0},
        description="Dawn-phenomenon rise, peaking about 06:00 (an assumption of size). Each "
        "0-200 (an assumption). [mg/dL]",
    )
    range_mgdl: _pair(20, 600) = Field(
        (60.0, 400.0),
        description="Snapshots are reflected into this range. Within 20-600 mg/dL, the span "
        "glucose meters report. [mg/dL]",
    )
    hours_since_meal_h: _pair(0, 24) = Field(
        (0.0, 6.0),
        description="Range of the time since the last meal, drawn uniformly (an excursion has "
        "decayed 6 h after a meal). Within 0-24 h. [h]",
    )
    meal_size_log_sd: float = Field(
        0.3,
        ge=0,
        le=2,
        description="SD of ln(meal size), a log-normal factor on the excursion (an assumption). "
        "At most 2 (a factor 7.4 per SD). [-]",
    )
    dawn_peak_hour: float = Field(
        6.0, ge=0, le=24, description="Hour of day of the dawn-phenomenon peak (Rizza et al., "
        "N. Engl. J. Med. 310, 746 (1984): early morning). [h]"
    )
    dawn_width_h: float = Field(
        2.0,
        gt=0,
        le=12,
        description="Width of the Gaussian dawn rise (an assumption). At most 12 h. [h]",
    )
    # --- optical magnitudes (SOURCES.md, Glucose section: weakly sourced) -------------
    water_displacement_per_mm: float = Field(
        1.1e-4,
        ge=0,
        le=1e-3,
        description="Fraction of water displaced per mM glucose (partial molar volume 112 "
        "mL/mol). At most 1e-3, ten times the literature. [1/mM]",
    )
    absorptivity_per_cm_per_mm: float = Field(
        1.0e-4,
        ge=0,
        le=1e-3,
        description="Glucose's own absorption at the 2nd C-H overtone peak (about 1150 nm), "
        "order-of-magnitude estimate (SOURCES.md: <= 1e-4 of water's mua per mM). At most 1e-3, "
        "ten times the estimate. [1/(cm mM)]",
    )
    scattering_rel_per_mm: float = Field(
        -1.25e-3,
        ge=-1e-2,
        le=0,
        description="Relative change of mus' per mM from refractive-index matching: -2 "
        "(dn/dC)/(n_s - n_ecf) with dn/dC = 2.5e-5/mM and n_s - n_ecf = 0.04 (Maier et al. "
        "1994). At least -1e-2, eight times Maier's. [1/mM]",
    )
    signal_gain: float = Field(
        1.0,
        gt=0,
        le=100,
        description="Multiplies all three glucose optical effects. 1 keeps literature "
        "magnitudes; the presets raise it to reach the study's correlation (PAPER_SIGNAL_GAIN, "
        "WEARABLE_SIGNAL_GAIN). At most 100, eight times the presets' gains. [-]",
    )

    @model_validator(mode="after")
    def _statuses(self) -> GlucoseConfig:
        names = set(self.status_probs)
        valid = {"normal", "prediabetes", "type1", "type2"}
        if not names <= valid:
            raise ValueError(
                f"unknown diabetes status {sorted(names - valid)}; valid: {sorted(valid)}"
            )
        for table in ("fasting_mgdl", "meal_peak_mgdl", "dawn_mgdl"):
            missing = names - set(getattr(self, table))
            if missing:
                raise ValueError(f"glucose.{table} lacks statuses {sorted(missing)}")
        if (
            any(p < 0 for p in self.status_probs.values())
            or abs(sum(self.status_probs.values()) - 1) > 1e-6
        ):
            raise ValueError("glucose.status_probs must be non-negative and sum to 1")
        # the bounds of each value are the fields' own (issue 20); here only low < high
        _check_range(self.range_mgdl, "glucose.range_mgdl")
        _check_range(self.hours_since_meal_h, "glucose.hours_since_meal_h")
        return self


class EnvironmentConfig(_Model):
    """Ambient temperature, humidity, pressure and light."""

    temperature_c: _pair(-20, 50) = Field(
        (18.0, 30.0),
        description="Range of a session's ambient temperature. Within -20 to 50 degC, where "
        "wearables are specified to work (an assumption). [degC]",
    )
    temperature_within_sd_c: float = Field(
        1.0,
        ge=0,
        le=20,
        description="SD of ambient temperature within a subject's session. At most 20 degC (an "
        "assumption). [degC]",
    )
    humidity_within_sd_pct: float = Field(
        5.0,
        ge=0,
        le=50,
        description="SD of relative humidity within a session. At most 50 %, half the RH scale. "
        "[%]",
    )
    pressure_within_sd_mbar: float = Field(
        1.0,
        ge=0,
        le=50,
        description="SD of pressure within a session (weather over hours). At most 50 mbar (an "
        "assumption). [mbar]",
    )
    humidity_pct: _pair(0, 100) = Field((30.0, 90.0), description="RH range. Within 0-100 %. [%]")
    humidity_coupling_loss: float = Field(
        0.03,
        ge=0,
        le=0.5,
        description="Coupling-efficiency loss at the top of the RH range (issue: up to 3 %). [-]",
    )
    # 300-1100 mbar: Everest summit (~337 mbar, West 1983) to the Dead Sea shore (~1065 mbar)
    pressure_mbar_mean: float = Field(
        1013.25, ge=300, le=1100, description="Mean barometric pressure. [mbar]"
    )
    pressure_mbar_sd: float = Field(
        12.0,
        ge=0,
        le=100,
        description="SD of pressure. At most 100 mbar (an assumption). [mbar]",
    )
    pressure_mbar: _pair(300, 1100) = Field(
        (950.0, 1050.0),
        description="Range. Within 300-1100 mbar, as pressure_mbar_mean. [mbar]",
    )
    perfusion_per_mbar: float = Field(
        1.0e-3,
        ge=-0.01,
        le=0.01,
        description="Relative blood-volume change per mbar above perfusion_reference_mbar (an "
        "assumption). At most +-0.01 (an assumption). [1/mbar]",
    )
    perfusion_reference_mbar: float = Field(
        1013.25,
        ge=300,
        le=1100,
        description="Pressure of nominal perfusion: the standard atmosphere (ISO 2533). [mbar]",
    )
    ambient_lux: _pair(0.1, 100_000) = Field(
        (10.0, 1000.0),
        description="Illuminance range, drawn log-uniformly. Within 0.1 lx (night) to 100,000 "
        "lx (direct sun). [lx]",
    )
    light_source_probs: dict[str, _num(0, 1)] = Field(
        {"sun": 0.1, "fluorescent": 0.45, "led": 0.45},
        description="Ambient spectrum mix. [-]",
    )
    baffle_optical_density: float = Field(
        2.0,
        ge=0,
        le=10,
        description="Baffle OD (issue). At most OD 10 (1e-10 leaks). [-]",
    )

    _ranges = field_validator("temperature_c", "humidity_pct", "pressure_mbar", "ambient_lux")(
        lambda v, info: _check_range(v, info.field_name)
    )

    @model_validator(mode="after")
    def _limits(self) -> EnvironmentConfig:
        valid = {"sun", "fluorescent", "led"}
        if not set(self.light_source_probs) <= valid:
            raise ValueError(f"light_source_probs keys must be among {sorted(valid)}")
        if abs(sum(self.light_source_probs.values()) - 1) > 1e-6:
            raise ValueError("light_source_probs must sum to 1")
        return self


class ReferenceTissue(_Model):
    """The skin that fixes the Beer-Lambert geometry factor: the default cohort's centre."""

    blood_fraction: float = Field(
        0.02, gt=0, lt=0.2, description="As physiology.blood_fraction_median. [-]"
    )
    saturation: float = Field(0.7, gt=0, lt=1, description="As physiology.saturation_mean. [-]")
    water_fraction: float = Field(
        WATER_FRACTION_DERMIS_NOMINAL,
        gt=0,
        lt=1,
        description="Nominal dermal water, 0.6-0.7 (Meglinski & Matcher 2002). [-]",
    )
    subcutis_fat_fraction: float = Field(
        0.8, gt=0, lt=1, description="Subcutis fat at the cohort's mid BMI (0.7-0.9). [-]"
    )
    glucose_mgdl: float = Field(
        100.0,
        ge=20,
        le=600,
        description="A normal fasting glucose. Within glucose.range_mgdl's 20-600. [mg/dL]",
    )
    skin_thickness_mm: float = Field(
        1.8,
        ge=0.5,
        le=4,
        description="As physiology.skin_thickness_mm_mean. Bound: 0.5-4 mm, the simulator's "
        "skin-layer range. [mm]",
    )

    @property
    def glucose_mm(self) -> float:
        """Glucose in mmol/L. [mM]"""
        return self.glucose_mgdl / MGDL_PER_MMOLL_GLUCOSE


class OpticsConfig(_Model):
    """Forward optical model and probe geometry."""

    model: Literal["beer-lambert", "diffusion", "rte-lut"] = Field(
        "beer-lambert", description=f"Forward model, one of {FORWARD_MODELS}."
    )
    source_detector_mm: float = Field(
        3.0, gt=0.5, le=20, description="Source-detector separation (a wrist-probe value). [mm]"
    )
    detector_area_mm2: float = Field(
        6.6,
        gt=0,
        le=100,
        description="Photodiode active area (Hamamatsu S1223: 2.4 x 2.8 mm). At most 100 mm^2 "
        "(10 x 10 mm, e.g. Hamamatsu S1337-1010BR). [mm^2]",
    )
    water_source: Literal["kou1993", "segelstein1981", "hale_querry1973"] = "kou1993"
    epidermis_thickness_mm: float = Field(
        0.08, gt=0, le=0.3, description="Living epidermis 50-100 um (SOURCES.md). [mm]"
    )
    tissue_refractive_index: float = Field(1.4, ge=1.3, le=1.6, description="Dermis n. [-]")
    reference_tissue: ReferenceTissue = ReferenceTissue()
    lut_solver: Literal["monte-carlo", "diffusion"] = Field(
        "monte-carlo",
        description=(
            "What fills the rte-lut model's table: Monte Carlo of the RTE (about 2 CPU-hours "
            "per probe geometry, cached) or three-layer diffusion (about 40 s, smooth)."
        ),
    )


class HardwareConfig(_Model):
    """LEDs, photodiode, transimpedance amplifier and ADC."""

    led_self_heating_c: float = Field(
        8.0,
        ge=0,
        le=75,
        description="Junction temperature above ambient while pulsed. At most 75 degC: a "
        "junction max of 100 degC (TSAL6200) at 25 degC. [degC]",
    )
    led_self_heating_sd_c: float = Field(
        0.5,
        ge=0,
        le=10,
        description="SD of the junction temperature between readings at the same drive (an "
        "assumption). At most 10 degC (an assumption). [degC]",
    )
    led_age_h: _pair(0, 100_000) = Field(
        (0.0, 5000.0),
        description="Device age range. Within 0-100,000 h, beyond IR LEDs' rated lifetimes. [h]",
    )
    hours_since_reference_h: _pair(0, 8760) = Field(
        (0.0, 72.0),
        description="Range of the time between a subject's start-up reference and each "
        "measurement (snapshots over up to three days). Within a year, 0-8760 h. [h]",
    )
    led_thermal_coeff_per_c: float = Field(
        LED_THERMAL_COEFF_PER_C,
        ge=0,
        le=0.02,
        description="Relative LED power loss per degC above 25 (Vishay TSAL6200 datasheet, "
        "about -0.2 %/K). At most 2 %/K, ten times the datasheet. [1/degC]",
    )
    led_ageing_per_1000h: float = Field(
        LED_AGEING_PER_1000H,
        ge=0,
        le=1,
        description="Relative LED power loss per 1000 h of operation (DESIGN.md). At most 1: "
        "all the power lost per 1000 h. [1/(1000 h)]",
    )
    board_skin_weight: float = Field(
        0.5,
        ge=0,
        le=1,
        description="Board temperature = (1 - w) ambient + w skin: the board sits between "
        "air and skin (an assumption: halfway). [-]",
    )
    led_flicker_rel: float = Field(
        0.001,
        ge=0,
        le=0.1,
        description="Relative flicker SD, N(0, 0.1 %) (DESIGN.md). At most 10 % (an "
        "assumption). [-]",
    )
    led_wavelength_shift_nm_per_c: float = Field(
        0.25,
        ge=0,
        le=1,
        description="Peak shift with junction temperature, 0.2-0.3 nm/K (Vishay TSAL6200 / "
        "VSLY5850 datasheets). At most 1 nm/K, 4x the datasheets. [nm/degC]",
    )
    dark_current_25c_na: float = Field(
        0.1,
        ge=0,
        le=1000,
        description="Dark current at 25 degC (S1223: 0.1 nA typ at 10 V). At most 1 uA, "
        "large-area photodiodes' class. [nA]",
    )
    dark_current_per_c: float = Field(
        DARK_CURRENT_DOUBLING_COEFF_PER_C,
        ge=0,
        le=0.2,
        description="Dark current grows as exp(k (T - 25)), doubling about every 7 degC "
        "(Hamamatsu 'Si photodiodes' technical note). At most 0.2, doubling every 3.5 degC. "
        "[1/degC]",
    )
    bandwidth_hz: float = Field(
        10.0,
        gt=0,
        le=1e6,
        description="Equivalent noise bandwidth after in-device averaging. At most 1 MHz, a "
        "photodiode TIA's class. [Hz]",
    )
    tia_gain_ohm: float = Field(
        1.0e5,
        ge=100,
        le=1e9,
        description="Transimpedance (feedback resistor); also the Johnson-noise resistor. "
        "Within 100 Ohm-1 GOhm, feedback resistors' span. [Ohm]",
    )
    adc_bits: int = Field(12, ge=8, le=24, description="ADC resolution (the study's 12). [bit]")
    adc_vref_v: float = Field(
        3.3,
        gt=0,
        le=10,
        description="ADC full-scale voltage. At most 10 V, ADC references' span. [V]",
    )
    adc_inl_lsb: float = Field(
        2.0,
        ge=0,
        le=64,
        description="Peak integral non-linearity (ESP32 SAR ADC class: several LSB). At most 64 "
        "LSB (an assumption). [LSB]",
    )
    adc_offset_drift_lsb_per_c: float = Field(
        0.1,
        ge=0,
        le=10,
        description="Offset drift with board temperature. At most 10 LSB/degC (an assumption). "
        "[LSB/degC]",
    )
    reference_transmission: float = Field(
        0.02,
        gt=0,
        le=1,
        description="Transmission of the start-up reference path (a neutral attenuator), "
        "setting reference codes at 65-90 % of full scale. [-]",
    )
    ambient_rejection: float = Field(
        0.99,
        ge=0,
        le=1,
        description="Fraction of ambient photocurrent removed by the LED-off subtraction. [-]",
    )
    calibration_temperature_sd_c: float = Field(
        0.0,
        ge=0,
        le=10,
        description="Extra SD of the device temperature at start-up. At most 10 degC (an "
        "assumption). [degC]",
    )


class MeasurementConfig(_Model):
    """Standard deviations of the measured physiological vector (what a device knows)."""

    age_yr: float = Field(
        0.5,
        ge=0,
        le=10,
        description="Age recorded in whole years. At most 10 (an assumption). [yr]",
    )
    bmi_kgm2: float = Field(
        0.5,
        ge=0,
        le=10,
        description="Scale + tape measure. At most 10 (an assumption). [kg/m^2]",
    )
    fitzpatrick_misclass: float = Field(
        0.2, ge=0, le=1, description="Probability a self-reported type is off by one. [-]"
    )
    melanin_fraction: float = Field(
        0.01,
        ge=0,
        le=0.5,
        description="Reflectance melanin meter. At most 0.5 (an assumption). [-]",
    )
    skin_thickness_mm: float = Field(
        0.15,
        ge=0,
        le=2,
        description="Ultrasound estimate. At most 2 (an assumption). [mm]",
    )
    hydration_pct: float = Field(
        2.0,
        ge=0,
        le=50,
        description="Corneometer-type estimate. At most 50 (an assumption). [%]",
    )
    systolic_bp_mmhg: float = Field(
        5.0,
        ge=0,
        le=50,
        description="Cuff (AAMI: SD <= 8). At most 50 (an assumption). [mmHg]",
    )
    heart_rate_bpm: float = Field(
        2.0,
        ge=0,
        le=50,
        description="PPG estimate. At most 50 (an assumption). [1/min]",
    )
    resp_rate_bpm: float = Field(
        1.0,
        ge=0,
        le=20,
        description="Estimate. At most 20 (an assumption). [1/min]",
    )
    skin_temp_c: float = Field(
        0.2,
        ge=0,
        le=5,
        description="Thermistor. At most 5 (an assumption). [degC]",
    )
    humidity_pct: float = Field(
        2.0,
        ge=0,
        le=50,
        description="RH sensor (e.g. SHT3x +/- 2 %). At most 50 (an assumption). [%]",
    )
    pressure_mbar: float = Field(
        1.0,
        ge=0,
        le=100,
        description="Barometer (e.g. BMP280 +/- 1 hPa). At most 100 (an assumption). [mbar]",
    )


class NoiseSource(_Model):
    """One noise source's switch and scale."""

    enabled: bool = True
    scale: float = Field(1.0, ge=0, le=100)  # as noise_scale


class NoiseConfig(_Model):
    """A switch and a scale for every noise source in :data:`NOISE_SOURCES`."""

    led_thermal_drift: NoiseSource = NoiseSource()
    led_ageing: NoiseSource = NoiseSource()
    led_flicker: NoiseSource = NoiseSource()
    led_wavelength_shift: NoiseSource = NoiseSource()
    dark_current: NoiseSource = NoiseSource()
    shot: NoiseSource = NoiseSource()
    johnson: NoiseSource = NoiseSource()
    adc_inl: NoiseSource = NoiseSource()
    adc_offset_drift: NoiseSource = NoiseSource()
    ambient_light: NoiseSource = NoiseSource()
    humidity_coupling: NoiseSource = NoiseSource()
    contact_pressure: NoiseSource = NoiseSource()
    pulsation: NoiseSource = NoiseSource()
    pmf_measurement: NoiseSource = NoiseSource()


class ContactConfig(_Model):
    """Probe contact pressure: changes coupling, blood content and optical path."""

    coupling_sd: float = Field(
        0.03,
        ge=0,
        le=1,
        description="Relative SD of optical coupling between placements (at most 1: a "
        "relative SD beyond 100 % has no physical meaning for a coupling factor). [-]",
    )
    blanching: float = Field(
        0.3, ge=0, le=1, description="Blood-volume loss at full contact pressure (assumption). [-]"
    )
    compression: float = Field(
        0.1,
        ge=0,
        le=0.5,
        description="Skin-thickness loss at full contact pressure (assumption). [-]",
    )
    pressure_beta: _pair(0, 100, gt=True) = Field(
        (2.0, 2.0),
        description="Beta(a, b) shape of a hand-placed probe's contact pressure, a share of "
        "full scale (an assumption: unimodal, mean 0.5). Each above 0, at most 100. [-]",
    )
    constant_force_pressure: float = Field(
        0.5,
        ge=0,
        le=1,
        description="Contact pressure held by a constant-force probe (device.constant_force_probe"
        "), a share of full scale: the mean of Beta(2, 2), so the cohort's mean blanching and "
        "compression are unchanged. [-]",
    )

    @field_validator("pressure_beta")
    @classmethod
    def _positive(cls, v: tuple[float, float]) -> tuple[float, float]:
        if min(v) <= 0:
            raise ValueError(f"contact.pressure_beta needs positive shapes, got {v}")
        return v


#: Pulse-oximeter accuracy: FDA premarket guidance ("Pulse Oximeters - Premarket
#: Notification Submissions", 2013) asks for A_rms <= 3.0 % SpO2 over 70-100 % for
#: transmittance sensors (3.5 % for reflectance); ISO 80601-2-61:2017 requires <= 4 %. [%]
SPO2_ARMS_PCT = 3.0


class DeviceConfig(_Model):
    """Hardware capabilities a wearable team chooses; all off is a basic four-LED wearable.

    Each switch is a design choice with a cost (an extra photodiode, a spring-loaded
    probe, a clinical-grade physiological workup, a PPG front end); :data:`PRESETS`
    record which ones a preset assumes (:data:`PRESET_CAPABILITIES`).
    """

    monitor_photodiode: bool = Field(
        False,
        description="A monitor photodiode reads each LED's output at every reading (through "
        "the reference path's attenuation, hardware.reference_transmission), so adc_ref_<nm> "
        "is a per-reading monitor code instead of the start-up reference: cancels LED power "
        "drift, ageing and flicker, not the thermal wavelength shift; the monitor has its own "
        "shot and Johnson noise and its own ADC conversion. [-]",
    )
    constant_force_probe: bool = Field(
        False,
        description="A constant-force (spring-loaded) probe: contact pressure is held at the "
        "cohort's mean (0.5 of full scale), so readings carry no pressure-driven coupling, "
        "blanching or compression variation. [-]",
    )
    physiology: Literal["measured", "exact"] = Field(
        "measured",
        description="'measured': the physiological vector carries the instruments' errors "
        "(measurement.*); 'exact': it equals the truth (a clinical-grade workup; also makes "
        "blood_volume_pct and spo2_pct exact). [-]",
    )
    ppg_perfusion_spo2: bool = Field(
        False,
        description="Perfusion and oxygen saturation measured from the pulsatile PPG the "
        "wearable records: adds the columns blood_volume_pct (detected dermal blood volume "
        "fraction) and spo2_pct (the dermal saturation the optics see), with the errors "
        "device.blood_volume_error_rel and device.spo2_error_pct. [-]",
    )
    humidity_compensation: bool = Field(
        False,
        description="Firmware divides each reading by the coupling-loss-vs-humidity curve "
        "(environment.humidity_coupling_loss, factory-calibrated) at the RH sensor's reading "
        "(humidity_pct): only the curve at the sensor's error remains. [-]",
    )
    spo2_error_pct: float = Field(
        SPO2_ARMS_PCT,
        ge=0, le=50, description="SD of spo2_pct: pulse-oximeter A_rms (FDA 2013 guidance: <= 3 % "
        "transmittance, 3.5 % reflectance; ISO 80601-2-61: <= 4 %). "
        "At most 50 %, half of SpO2's scale. [%]",
    )
    blood_volume_error_rel: float = Field(
        0.1,
        ge=0,
        le=1,
        description="Relative SD of blood_volume_pct (an assumption of this package: no "
        "standard governs a PPG blood-volume estimate). [-]",
    )


class ScenarioConfig(_Model):
    """A complete, resolved simulation scenario."""

    preset: str = "paper"
    # at most 100: the harshest preset uses 2 and the noise-scale study 4 (issue 20)
    noise_scale: float = Field(
        1.0, ge=0, le=100, description="Multiplies every noise source. [-]"
    )
    leds: LEDConfig = LEDConfig()
    physiology: PhysiologyConfig = PhysiologyConfig()
    glucose: GlucoseConfig = GlucoseConfig()
    environment: EnvironmentConfig = EnvironmentConfig()
    optics: OpticsConfig = OpticsConfig()
    hardware: HardwareConfig = HardwareConfig()
    contact: ContactConfig = ContactConfig()
    measurement: MeasurementConfig = MeasurementConfig()
    device: DeviceConfig = DeviceConfig()
    noise: NoiseConfig = NoiseConfig()

    @model_validator(mode="before")
    @classmethod
    def _former_layout(cls, data: Any) -> Any:
        # configs recorded before issue 22 kept per-LED values in four parallel lists
        if not isinstance(data, dict):
            return data
        leds, hw = data.get("leds"), data.get("hardware")
        old = {}
        if isinstance(leds, dict):
            old.update({f"leds.{k}": leds[k] for k in ("wavelengths_nm", "fwhm_nm") if k in leds})
        if isinstance(hw, dict):
            per_led = ("led_power_mw", "responsivity_a_per_w")
            old.update({f"hardware.{k}": hw[k] for k in per_led if k in hw})
        if not old:
            return data
        data = dict(data)
        former = ("wavelengths_nm", "fwhm_nm", "led_power_mw", "responsivity_a_per_w")
        leds = leds if isinstance(leds, dict) else {}
        data["leds"] = {k: v for k, v in leds.items() if k not in former}
        data["hardware"] = {k: v for k, v in (hw or {}).items() if k not in former}
        base = [e.model_dump() for e in DEFAULT_LEDS]
        data["leds"]["emitters"] = _merge_legacy_leds(base, old)
        return data

    def noise_factor(self, source: str) -> float:
        """Effective multiplier of a noise source: enabled x scale x ``noise_scale``."""
        if source not in NOISE_SOURCES:
            raise ConfigError(f"unknown noise source {source!r}; valid: {', '.join(NOISE_SOURCES)}")
        ns: NoiseSource = getattr(self.noise, source)
        return float(ns.enabled) * ns.scale * self.noise_scale

    def to_json(self) -> str:
        """The resolved configuration as canonical JSON (sorted keys)."""
        return json.dumps(self.model_dump(mode="json"), sort_keys=True)


# --- presets -----------------------------------------------------------------------------

#: Device capability -> (config key, value when on, value when off). Every preset
#: sets each key to one of the two values; :func:`device_capabilities` reads them back.
DEVICE_CAPABILITIES: dict[str, tuple[str, Any, Any]] = {
    "monitor_photodiode": ("device.monitor_photodiode", True, False),
    "constant_force_probe": ("device.constant_force_probe", True, False),
    "exact_physiology": ("device.physiology", "exact", "measured"),
    "ppg_perfusion_spo2": ("device.ppg_perfusion_spo2", True, False),
    "humidity_compensation": ("device.humidity_compensation", True, False),
}

#: Glucose-signal gain of a basic wearable (``wearable``, ``lab``, ``field``): with
#: literature noise and physiology and none of the device capabilities, the raw
#: glucose-NIR correlation reaches the study's 0.21 only when glucose's optical effects
#: are 12.5 times the literature magnitudes (calibrated on 20,000 snapshots; README,
#: "Presets and calibration").
WEARABLE_SIGNAL_GAIN = 12.5
#: Glucose-signal gain of ``paper`` (the study's regime with the capabilities its
#: accuracy implies), chosen for the raw correlation alone: the gain whose raw
#: correlation (20,000 snapshots, mean over seeds 0-4) is closest to the study's 0.21,
#: on a grid of 0.5 (README, "Presets and calibration"; benchmarks/presets.py).
PAPER_SIGNAL_GAIN = 11.0


def _capabilities(*on: str) -> dict[str, Any]:
    """Overrides that switch the named device capabilities on and every other one off."""
    return {key: (v_on if name in on else v_off) for name, (key, v_on, v_off) in
            DEVICE_CAPABILITIES.items()}


#: The capabilities the study's accuracy implies (README, "Presets and calibration").
_PAPER_CAPABILITIES = (
    "monitor_photodiode",
    "constant_force_probe",
    "exact_physiology",
    "ppg_perfusion_spo2",
    "humidity_compensation",
)

#: Preset name -> overrides on the defaults.
PRESETS: dict[str, dict[str, Any]] = {
    # The study's regime with the capabilities its accuracy implies.
    "paper": {
        "glucose.signal_gain": PAPER_SIGNAL_GAIN,
        **_capabilities(*_PAPER_CAPABILITIES),
    },
    # A basic four-LED wearable with none of the capabilities (the former ``paper``).
    "wearable": {"glucose.signal_gain": WEARABLE_SIGNAL_GAIN, **_capabilities()},
    # Literature glucose magnitudes everywhere, whatever correlation they give.
    "physical": {"glucose.signal_gain": 1.0, **_capabilities()},
    # Cuvette-like: one nominal 'subject', no ambient light, a quiet instrument.
    "lab": {
        "glucose.signal_gain": WEARABLE_SIGNAL_GAIN,
        **_capabilities(),
        "physiology.variation_scale": 0.0,
        "environment.temperature_c": (24.5, 25.5),
        "environment.temperature_within_sd_c": 0.2,
        "environment.ambient_lux": (0.1, 0.2),
        "environment.pressure_mbar_sd": 0.0,
        "noise.contact_pressure.enabled": False,
        "noise.pulsation.enabled": False,
        "noise.humidity_coupling.enabled": False,
        "noise.led_thermal_drift.scale": 0.1,
    },
    # Harsher than wearable: outdoor light, wide temperatures, motion and contact.
    "field": {
        "glucose.signal_gain": WEARABLE_SIGNAL_GAIN,
        **_capabilities(),
        "environment.temperature_c": (5.0, 35.0),
        "environment.temperature_within_sd_c": 4.0,
        "environment.ambient_lux": (1.0, 100000.0),
        "environment.light_source_probs": {"sun": 0.5, "fluorescent": 0.25, "led": 0.25},
        "contact.coupling_sd": 0.08,
        "noise_scale": 2.0,
    },
}

#: Preset name -> one-line description (``nirglucose`` help, README table).
PRESET_DESCRIPTIONS: dict[str, str] = {
    "paper": "the study's regime (raw correlation 0.21) with the device capabilities its "
    "accuracy implies",
    "wearable": "a basic four-LED wearable, no device capabilities, raw correlation 0.21 "
    "(the former 'paper')",
    "physical": "literature glucose magnitudes throughout, basic wearable",
    "lab": "cuvette-like: one nominal subject, no ambient light, a quiet instrument",
    "field": "outdoor light, 5-35 degC, motion and contact, noise x 2, basic wearable",
}


def device_capabilities(cfg: ScenarioConfig) -> tuple[str, ...]:
    """Names of the :data:`DEVICE_CAPABILITIES` switched on in a scenario.

    Examples
    --------
    >>> device_capabilities(resolve_config("wearable"))
    ()
    """
    out = []
    for name, (key, v_on, _) in DEVICE_CAPABILITIES.items():
        node: Any = cfg
        for part in key.split("."):
            node = getattr(node, part)
        if node == v_on:
            out.append(name)
    return tuple(out)


#: Preset name -> the device capabilities it assumes (kept as data; a test checks it
#: against the resolved presets).
PRESET_CAPABILITIES: dict[str, tuple[str, ...]] = {
    "paper": _PAPER_CAPABILITIES,
    "wearable": (),
    "physical": (),
    "lab": (),
    "field": (),
}


def valid_keys(model: type[BaseModel] = ScenarioConfig, prefix: str = "") -> list[str]:
    """Every dotted key accepted by :func:`apply_overrides`."""
    keys = []
    for name, field in model.model_fields.items():
        ann = field.annotation
        if not prefix and name == "preset":  # a label set by the preset, not a setting
            continue
        if isinstance(ann, type) and issubclass(ann, BaseModel):
            keys.extend(valid_keys(ann, f"{prefix}{name}."))
        else:
            keys.append(f"{prefix}{name}")
    return keys


def parse_override(text: str) -> tuple[str, Any]:
    """Parse ``"key=value"`` from the command line; the value is read as JSON if it can be.

    Examples
    --------
    >>> parse_override("hardware.adc_bits=14")
    ('hardware.adc_bits', 14)
    >>> parse_override("environment.temperature_c=[5, 35]")
    ('environment.temperature_c', [5, 35])
    """
    if "=" not in text:
        raise ConfigError(f"override {text!r} must look like key=value, e.g. hardware.adc_bits=14")
    key, raw = text.split("=", 1)
    key, raw = key.strip(), raw.strip()
    if not key:
        raise ConfigError(f"override {text!r} has an empty key")
    try:
        value = json.loads(raw)
    except json.JSONDecodeError:
        lowered = raw.lower()
        value = {"true": True, "false": False}.get(lowered, raw)
    return key, value


#: ``leds.emitters.<i>.<field>``: one value of one LED.
_PER_LED_KEY = re.compile(r"leds\.emitters\.(\d+)\.(\w+)")


def is_valid_key(dotted: str) -> bool:
    """Whether :func:`apply_overrides` accepts a dotted key.

    Besides :func:`valid_keys`: ``leds`` (the whole LED set, a list of records), one
    LED's value ``leds.emitters.<i>.<field>`` and the former per-LED list keys
    (:data:`LEGACY_LED_KEYS`).

    Examples
    --------
    >>> is_valid_key("leds.emitters.3.power_mw"), is_valid_key("leds.emitters.0.colour")
    (True, False)
    """
    if dotted in valid_keys() or dotted == "leds" or dotted in LEGACY_LED_KEYS:
        return True
    m = _PER_LED_KEY.fullmatch(dotted)
    return bool(m) and m.group(2) in LED.model_fields


def _merge_legacy_leds(emitters: list[dict], old: dict[str, Any]) -> list[dict]:
    """LED records with the former per-LED lists (:data:`LEGACY_LED_KEYS`) merged in."""
    for key, value in old.items():
        if not isinstance(value, list | tuple):
            raise ConfigError(f"{key} needs one value per LED (a list), got {value!r}")
    counts = {key: len(value) for key, value in old.items()}
    if len(set(counts.values())) > 1:
        lengths = ", ".join(f"{k}: {n}" for k, n in counts.items())
        raise ConfigError(f"the per-LED lists differ in length ({lengths}); give one per LED")
    n = next(iter(counts.values()))
    if n != len(emitters) and len(old) < len(LEGACY_LED_KEYS):
        key = next(iter(old))
        raise ConfigError(
            f"{key} gives {n} LEDs but the scenario has {len(emitters)}; set a new LED set with "
            'one key: leds=[{"wavelength_nm": ..., "fwhm_nm": ..., "power_mw": ..., '
            '"responsivity_a_per_w": ...}, ...]'
        )
    out = [dict(e) for e in emitters] if n == len(emitters) else [{} for _ in range(n)]
    for key, value in old.items():
        for record, v in zip(out, value, strict=True):
            record[LEGACY_LED_KEYS[key]] = v
    return out


def _plain(value: Any) -> Any:
    """A value with models dumped and tuples as lists (LED records given as :class:`LED`)."""
    if isinstance(value, BaseModel):
        return value.model_dump(mode="json")
    if isinstance(value, list | tuple):
        return [_plain(v) for v in value]
    return value


def _set_per_led(out: dict[str, Any], dotted: str, value: Any) -> None:
    m = _PER_LED_KEY.fullmatch(dotted)
    assert m is not None
    emitters = out["leds"]["emitters"]
    i = int(m.group(1))
    if i >= len(emitters):
        raise ConfigError(
            f"{dotted}: the scenario has {len(emitters)} LEDs (indices 0-{len(emitters) - 1})"
        )
    emitters[i][m.group(2)] = value


def apply_overrides(data: dict[str, Any], overrides: dict[str, Any]) -> dict[str, Any]:
    """Return a copy of a config dict with dotted overrides set; unknown keys raise.

    Whole values are set first (``leds`` is ``leds.emitters``), then the former per-LED
    lists (:data:`LEGACY_LED_KEYS`) are merged into the LED records, then single LED
    values (``leds.emitters.<i>.<field>``).
    """
    out = json.loads(json.dumps(data))
    keys = set(valid_keys())
    legacy: dict[str, Any] = {}
    per_led: dict[str, Any] = {}
    for dotted, value in overrides.items():
        if dotted == "leds" and isinstance(value, list | tuple):
            dotted = "leds.emitters"
        if dotted in LEGACY_LED_KEYS:
            legacy[dotted] = value
            continue
        if dotted not in keys:
            if is_valid_key(dotted):
                per_led[dotted] = value
                continue
            from .config_keys import suggest_keys

            close = suggest_keys(dotted, keys)
            hint = f"; did you mean {', '.join(close)}?" if close else ""
            raise ConfigError(
                f"unknown config key {dotted!r}{hint} (run `nirglucose keys` for the valid keys)"
            )
        node = out
        parts = dotted.split(".")
        for part in parts[:-1]:
            node = node.setdefault(part, {})
        node[parts[-1]] = _plain(value)
    if legacy:
        out["leds"]["emitters"] = _merge_legacy_leds(out["leds"]["emitters"], legacy)
    for dotted, value in per_led.items():
        _set_per_led(out, dotted, value)
    return out


#: pydantic error types of a number outside its ``ge/gt/le/lt`` bounds.
_RANGE_ERRORS = ("greater_than", "greater_than_equal", "less_than", "less_than_equal")


def resolve_config(
    preset: str | ScenarioConfig = "paper", overrides: dict[str, Any] | None = None
) -> ScenarioConfig:
    """Build the scenario of a preset with dotted overrides, validated.

    Parameters
    ----------
    preset : str or ScenarioConfig
        A name of :data:`PRESETS`, or a config to start from.
    overrides : dict, optional
        Dotted keys (``"hardware.adc_bits"``) to values.

    Raises
    ------
    ConfigError
        Unknown preset or key, or a value outside its valid range.

    Examples
    --------
    >>> resolve_config("paper", {"hardware.adc_bits": 14}).hardware.adc_bits
    14
    """
    if isinstance(preset, ScenarioConfig):
        base = preset.model_dump(mode="json")
        all_overrides = dict(overrides or {})
    else:
        if preset not in PRESETS:
            raise ConfigError(unknown_name("preset", preset, PRESETS))
        base = ScenarioConfig(preset=preset).model_dump(mode="json")
        all_overrides = {**PRESETS[preset], **(overrides or {})}
    data = apply_overrides(base, all_overrides)
    try:
        return ScenarioConfig.model_validate(data)
    except ValidationError as exc:
        err = exc.errors()[0]
        loc = ".".join(str(p) for p in err["loc"]) or "config"
        from .config_keys import out_of_range_message, unit_of

        if err["type"] in _RANGE_ERRORS:
            msg = out_of_range_message(loc, err.get("input"))
            if msg is not None:
                raise ConfigError(msg) from None
        unit = unit_of(loc)
        raise ConfigError(
            f"invalid value for {loc}: {err['msg']}{f' [{unit}]' if unit else ''} "
            f"(got {err.get('input')!r})"
        ) from None
