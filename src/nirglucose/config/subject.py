"""The subject's sections: cohort physiology and glucose (traits, state and signal)."""

from __future__ import annotations

from pydantic import Field, field_validator, model_validator

from ..constants import WATER_FRACTION_DERMIS_NOMINAL
from ._base import _check_range, _Model, _num, _pair


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
    first_overtone_relative_peak: float = Field(
        10.0,
        ge=0,
        le=100,
        description="Peak of glucose's 1st C-H overtone band (1670 nm) relative to its 2nd "
        "(absorptivity_per_cm_per_mm at 1150 nm): an assumption, a factor of 10 per overtone "
        "order; no published absorptivity of the band was found (data/optics/SOURCES.md). At "
        "most 100. [-]",
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
