"""Physical constants and design values, with units in every name.

Physical constants are CODATA 2018 exact values. Design values (what a typical
four-LED wrist/finger prototype would use) carry the datasheet or paper they come
from; a value that is an assumption of this package says so.
"""

from __future__ import annotations

__all__ = [
    "MINUTES_PER_DAY",
    "ELEMENTARY_CHARGE_C",
    "BOLTZMANN_J_PER_K",
    "ZERO_CELSIUS_K",
    "MGDL_PER_MMOLL_GLUCOSE",
    "GLUCOSE_MOLAR_MASS_G_PER_MOL",
    "HEMOGLOBIN_MOLAR_MASS_G_PER_MOL",
    "DEFAULT_LED_WAVELENGTHS_NM",
    "PHYSIOLOGICAL_RANGES",
    "GLUCOSE_MIN_MGDL",
    "GLUCOSE_MAX_MGDL",
    "GLUCOSE_PARTIAL_MOLAR_VOLUME_L_PER_MOL",
    "GLUCOSE_DN_PER_MM",
    "LED_THERMAL_COEFF_PER_C",
    "LED_AGEING_PER_1000H",
    "LED_REFERENCE_TEMPERATURE_C",
    "DARK_CURRENT_DOUBLING_COEFF_PER_C",
    "WATER_FRACTION_DERMIS_NOMINAL",
    "FITZPATRICK_MELANIN_FRACTION_RANGES",
]

# --- CODATA 2018 (exact in the 2019 SI) --------------------------------------------
#: Minutes in a day. [min]
MINUTES_PER_DAY = 1440

ELEMENTARY_CHARGE_C = 1.602176634e-19
BOLTZMANN_J_PER_K = 1.380649e-23
ZERO_CELSIUS_K = 273.15

# --- Glucose -------------------------------------------------------------------------
#: Molar mass of D-glucose, C6H12O6 (IUPAC atomic weights). [g/mol]
GLUCOSE_MOLAR_MASS_G_PER_MOL = 180.156
#: mg/dL per mmol/L of glucose: 180.156 g/mol / 10 dL/L. [mg/dL per mmol/L]
MGDL_PER_MMOLL_GLUCOSE = 18.016
#: The clinically reported range the simulator draws from (the study's range). [mg/dL]
GLUCOSE_MIN_MGDL = 60.0
GLUCOSE_MAX_MGDL = 400.0
#: Partial molar volume of glucose in water, about 112 mL/mol (partial specific volume
#: 0.62 mL/g); 1 mM displaces about 1.1e-4 of the water (shared optics SOURCES.md,
#: "Glucose" section). [L/mol]
GLUCOSE_PARTIAL_MOLAR_VOLUME_L_PER_MOL = 0.112
#: Refractive-index increment of aqueous glucose, about 2.5e-5 per mM (CRC Handbook:
#: 10 % w/w glucose n = 1.3477 vs water 1.3330 at 0.576 M). [1/mM]
GLUCOSE_DN_PER_MM = 2.5e-5

# --- Haemoglobin ---------------------------------------------------------------------
#: Molar mass used by Prahl's OMLC compilation to convert eps to mua. [g/mol]
HEMOGLOBIN_MOLAR_MASS_G_PER_MOL = 64500.0

# --- LED (DESIGN.md physics notes: P = P0 [1 - 0.002 (T-25) - 0.001 t/1000h + N]) ---
#: Relative optical-power loss per degree above 25 degC, typical of GaAs/AlGaAs IR LEDs
#: (e.g. Vishay TSAL6200 datasheet, "relative radiant power vs ambient temperature"
#: about -0.2 %/K). [1/degC]
LED_THERMAL_COEFF_PER_C = 0.002
#: Relative optical-power loss per 1000 h of operation (DESIGN.md; typical IR-LED
#: lumen-maintenance order of magnitude). [1/(1000 h)]
LED_AGEING_PER_1000H = 0.001
LED_REFERENCE_TEMPERATURE_C = 25.0

# --- Photodiode ----------------------------------------------------------------------
#: Dark current grows about e^{0.1 (T-25)}, i.e. doubles every ~7 degC, typical of
#: silicon PIN photodiodes (Hamamatsu "Si photodiodes" technical note). [1/degC]
DARK_CURRENT_DOUBLING_COEFF_PER_C = 0.1

# --- Skin ----------------------------------------------------------------------------
#: Nominal dermal water volume fraction, 0.6-0.7 (Meglinski & Matcher 2002, Physiol.
#: Meas. 23, 741, doi:10.1088/0967-3334/23/4/312). [-]
WATER_FRACTION_DERMIS_NOMINAL = 0.65

#: Study LEDs. [nm]
DEFAULT_LED_WAVELENGTHS_NM = (850.0, 940.0, 1050.0, 1150.0)

#: Melanosome volume fraction of the epidermis for each Fitzpatrick type I-VI.
#: Jacques (1998, "Skin optics", OMLC News) gives 0.01-0.03 for light, 0.11-0.16 for
#: moderately pigmented and 0.18-0.43 for dark skin; the study's simulator restricts the
#: whole range to 0.01-0.15, so the six types partition that range monotonically
#: (an assumption of this package, documented in the README). [-]
FITZPATRICK_MELANIN_FRACTION_RANGES = {
    1: (0.010, 0.020),
    2: (0.020, 0.035),
    3: (0.035, 0.060),
    4: (0.060, 0.090),
    5: (0.090, 0.120),
    6: (0.120, 0.150),
}

#: Values a measuring device can produce for each physiological column:
#: (low, high, source). Values outside are refused as a device or transcription fault.
PHYSIOLOGICAL_RANGES: dict[str, tuple[float, float, str]] = {
    "age_yr": (
        0.0,
        125.0,
        "oldest verified human 122 yr (Robine & Allard, Science 279, 1834 (1998))",
    ),
    "bmi_kgm2": (
        10.0,
        100.0,
        "WHO BMI classes (severe thinness < 16, obesity III >= 40); "
        "recorded extremes lie within 10-100 kg/m^2",
    ),
    "fitzpatrick_type": (1.0, 6.0, "Fitzpatrick, Arch. Dermatol. 124, 869 (1988): types I-VI"),
    "melanin_fraction": (
        0.0,
        0.5,
        "epidermal melanosome volume fraction 1.3-43 % "
        "(Jacques, Oregon Med. Laser Center news (1998))",
    ),
    "skin_thickness_mm": (
        0.1,
        10.0,
        "skin (epidermis + dermis) 0.5-4 mm over the body "
        "(Laurent et al., Skin Res. Technol. 13, 163 (2007))",
    ),
    "hydration_pct": (
        0.0,
        200.0,
        "percent of nominal dermal water: positive, and no tissue holds twice its nominal water",
    ),
    "systolic_bp_mmhg": (
        50.0,
        300.0,
        "below 50 mmHg is circulatory collapse; highest "
        "recorded ~370 mmHg during exercise (MacDougall, J. Appl. Physiol. "
        "58, 785 (1985)); automated cuffs read up to 280-300 mmHg",
    ),
    "heart_rate_bpm": (
        20.0,
        300.0,
        "ISO 80601-2-61 / IEC 60601-2-27 heart-rate display ranges (about 30-300 /min)",
    ),
    "resp_rate_bpm": (
        2.0,
        80.0,
        "adult 12-20 /min, neonates up to 60 /min (WHO IMCI); capnograph ranges to 80-150 /min",
    ),
    "skin_temp_c": (
        15.0,
        45.0,
        "skin temperature 20-40 C in normal environments (Webb, "
        "J. Appl. Physiol. 1992); beyond 45 C burns",
    ),
    "humidity_pct": (0.0, 100.0, "relative humidity, by definition 0-100 %"),
    "pressure_mbar": (
        300.0,
        1100.0,
        "Everest summit ~337 mbar; record sea-level high 1084 mbar (WMO)",
    ),
    "blood_volume_pct": (
        0.0,
        100.0,
        "a volume fraction in percent (dermal blood ~0.2-10 %, Jacques 2013)",
    ),
    "spo2_pct": (
        0.0,
        100.0,
        "oxygen saturation in percent; ISO 80601-2-61 pulse-oximeter display range",
    ),
}
