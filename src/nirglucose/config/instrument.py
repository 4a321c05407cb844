"""The instrument's sections: forward optics, hardware chain and measured physiology."""

from __future__ import annotations

from typing import Literal

from pydantic import Field

from ..constants import (
    DARK_CURRENT_DOUBLING_COEFF_PER_C,
    LED_AGEING_PER_1000H,
    LED_THERMAL_COEFF_PER_C,
    MGDL_PER_MMOLL_GLUCOSE,
    WATER_FRACTION_DERMIS_NOMINAL,
)
from ._base import _Model, _pair

#: Forward optical models selectable by name (``optics.model``).
FORWARD_MODELS = ("beer-lambert", "diffusion", "rte-lut")


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
    water_source: Literal[
        "kou1993", "segelstein1981", "hale_querry1973", "palmer_williams1974"
    ] = "kou1993"
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
    lut_grid: Literal["auto", "default", "swir"] = Field(
        "auto",
        description=(
            "Box of the rte-lut model's table: 'default' covers LED bands in 700-1320 nm, "
            "'swir' those in 1160-1700 nm (its own table, about 1.5 CPU-hours to build); 'auto' "
            "takes $NIRGLUCOSE_LUT_GRID where set, else for each LED the grid that covers "
            "its band."
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
