"""The schema's column registry: names of the sensor and physiological columns, their
units, and the ranges a meter and an ADC report (a leaf: the dataset container, the file
reader and the ADC policy read it; :mod:`nirglucose.dataset` re-exports every name)."""

from __future__ import annotations

import re
from collections.abc import Iterable
from typing import Any

from ..constants import DEFAULT_LED_WAVELENGTHS_NM
from ..exceptions import DataError

__all__ = [
    "PMF_COLUMNS",
    "ID_COLUMNS",
    "PPG_COLUMNS",
    "KNOWN_PHYSIOLOGY",
    "DEFAULT_ADC_BITS",
    "GLUCOSE_REPORTING_RANGE_MGDL",
    "WEAR_COLUMNS",
    "COLUMN_UNITS",
    "adc_columns",
    "ref_columns",
    "measured_columns",
    "ADC_COLUMN_RE",
    "CODE_COLUMN_RE",
    "led_wavelengths_in",
    "has_reference_columns",
]

#: The measured physiological vector, in the study's order (the simulator's
#: :func:`~nirglucose.simulation.measurement.measure_physiology` fills it).
PMF_COLUMNS = (
    "age_yr",
    "bmi_kgm2",
    "fitzpatrick_type",
    "melanin_fraction",
    "skin_thickness_mm",
    "hydration_pct",
    "systolic_bp_mmhg",
    "heart_rate_bpm",
    "resp_rate_bpm",
    "skin_temp_c",
    "humidity_pct",
    "pressure_mbar",
)
#: Identity columns, in the order outputs give them: read as written, kept whole, never
#: empty (:func:`nirglucose.dataset.files.validate_frame`).
ID_COLUMNS = ("measurement_id", "subject_id")

#: Columns of the PPG perfusion and saturation estimates (``device.ppg_perfusion_spo2``),
#: present only when that capability is on.
PPG_COLUMNS = ("blood_volume_pct", "spo2_pct")


def _wl_label(wavelength_nm: float) -> str:
    return f"{wavelength_nm:g}"


def adc_columns(wavelengths_nm: Iterable[float] = DEFAULT_LED_WAVELENGTHS_NM) -> list[str]:
    """``adc_<nm>`` column names.

    Examples
    --------
    >>> adc_columns()
    ['adc_850', 'adc_940', 'adc_1050', 'adc_1150']
    """
    return [f"adc_{_wl_label(w)}" for w in wavelengths_nm]


def ref_columns(wavelengths_nm: Iterable[float] = DEFAULT_LED_WAVELENGTHS_NM) -> list[str]:
    """``adc_ref_<nm>`` column names."""
    return [f"adc_ref_{_wl_label(w)}" for w in wavelengths_nm]


#: An LED's ADC column, ``adc_<nm>`` (``adc_850``, ``adc_1550.5``); group 1 is the
#: wavelength. ``adc_ref_<nm>`` does not match.
ADC_COLUMN_RE = re.compile(r"^adc_(\d+(?:\.\d+)?)$")
#: Any column of ADC codes, an LED's or its reference's: group 1 is ``ref_`` or None,
#: group 2 the wavelength.
CODE_COLUMN_RE = re.compile(r"^adc_(ref_)?(\d+(?:\.\d+)?)$")


def led_wavelengths_in(columns: Iterable[Any]) -> tuple[float, ...]:
    """The LEDs named by ``adc_<nm>`` columns, ascending: the one rule by which the
    schema, the dataset and the estimators read a device's channels. [nm]

    Raises
    ------
    DataError
        If a column spells its wavelength otherwise than :func:`adc_columns` does
        (``adc_850.0``, ``adc_0850``: a file's are renamed when it is read), or two
        columns name the same wavelength.

    Examples
    --------
    >>> led_wavelengths_in(["adc_940", "adc_ref_940", "adc_850.5", "age_yr"])
    (850.5, 940.0)
    """
    found: dict[float, str] = {}
    for c in columns:
        if isinstance(c, str) and (m := ADC_COLUMN_RE.match(c)):
            w = float(m.group(1))
            if c != f"adc_{_wl_label(w)}":  # read from a file, it would have been renamed
                raise DataError(f"column {c!r} names the {w:g} nm LED; spell it "
                                f"'adc_{_wl_label(w)}' (and its reference "
                                f"'adc_ref_{_wl_label(w)}')")
            if w in found:
                raise DataError(f"columns {found[w]!r} and {c!r} name the same LED "
                                f"({w:g} nm); keep one of them")
            found[w] = c
    return tuple(sorted(found))


def has_reference_columns(columns: Iterable[Any], wavelengths_nm: Iterable[float]) -> bool:
    """Whether ``columns`` hold the reference codes ``adc_ref_<nm>`` of every LED (True)
    or of none (False).

    Raises
    ------
    DataError
        If some LEDs have reference codes and others not (one line naming the missing).

    Examples
    --------
    >>> has_reference_columns(["adc_850", "adc_ref_850"], [850.0])
    True
    """
    present = set(columns)
    refs = ref_columns(wavelengths_nm)
    have = [c in present for c in refs]
    if any(have) and not all(have):
        missing = [c for c, h in zip(refs, have, strict=True) if not h]
        raise DataError(f"reference codes for some LEDs only: missing {missing}; give "
                        "adc_ref_<nm> for every LED or for none")
    return bool(have) and all(have)


def measured_columns(wavelengths_nm: Iterable[float] = DEFAULT_LED_WAVELENGTHS_NM) -> list[str]:
    """Every column an estimator may read: ADC codes, references, physiological vector."""
    wl = list(wavelengths_nm)
    return adc_columns(wl) + ref_columns(wl) + list(PMF_COLUMNS)


#: Every physiological column a model knows: the study's 12 (:data:`PMF_COLUMNS`) plus
#: dermal blood volume and pulse-oximetry saturation, where a device records them.
KNOWN_PHYSIOLOGY: tuple[str, ...] = tuple(
    dict.fromkeys((*PMF_COLUMNS, "blood_volume_pct", "spo2_pct"))
)

#: ADC resolution assumed when neither the caller nor the file declares one (the
#: study's 12-bit ADC). [bit]
DEFAULT_ADC_BITS = 12

#: Range a blood-glucose meter reports; below it shows "LO", above it "HI" (e.g. Roche
#: Accu-Chek Guide and Abbott FreeStyle Lite user manuals: measuring range
#: 20-600 mg/dL). Reference glucose outside it is refused. [mg/dL]
GLUCOSE_REPORTING_RANGE_MGDL = (20.0, 600.0)

#: Time columns of a wear simulation (:mod:`nirglucose.simulation.wear`): minutes since
#: 00:00 of the wear's first day, the day of the wear (0 first) and the device's
#: placement (0 first, +1 at each re-seating).
WEAR_COLUMNS = ("time_min", "wear_day", "seating_id")

#: Units of the schema's named columns (``true_*`` columns carry theirs in the name).
COLUMN_UNITS = {
    "subject_id": "-",
    "measurement_id": "-",
    "time_min": "min since 00:00 of the wear's first day",
    "wear_day": "day of the wear, 0 first",
    "seating_id": "placement of the device, 0 first",
    "glucose_mgdl": "mg/dL",
    "diabetes_status": "-",
    "age_yr": "yr",
    "bmi_kgm2": "kg/m^2",
    "fitzpatrick_type": "I-VI as 1-6",
    "melanin_fraction": "volume fraction",
    "skin_thickness_mm": "mm",
    "hydration_pct": "% of nominal dermal water",
    "systolic_bp_mmhg": "mmHg",
    "heart_rate_bpm": "1/min",
    "resp_rate_bpm": "1/min",
    "skin_temp_c": "degC",
    "humidity_pct": "% RH",
    "pressure_mbar": "mbar",
    # PPG estimates, present only with device.ppg_perfusion_spo2 (config.DeviceConfig)
    "blood_volume_pct": "% detected dermal blood volume fraction",
    "spo2_pct": "% dermal oxygen saturation",
    "ambient_lux": "lx",
    **{c: "ADC code" for c in adc_columns() + ref_columns()},
}
