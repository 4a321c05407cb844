"""The parts catalogue: commercial photodiodes and NIR LEDs selectable by name.

``data/parts/detectors.csv`` and ``data/parts/leds.csv`` (sources in
``data/parts/SOURCES.md``) hold the datasheets' values. A scenario names a detector
(``detector="G17190-005K"``) or an LED (``leds=["L8957", {"part": "SMC870",
"power_mw": 3.0}]``); an unknown name is one :class:`~nirglucose.exceptions.ConfigError`
listing the known ones.

Examples
--------
>>> detector_part("G17190-005K").material
'InGaAs'
>>> sorted(LED_PARTS)[:2]
['IR-1W-850', 'L1909']
"""

from __future__ import annotations

import csv
import math
from dataclasses import dataclass
from functools import cache
from importlib import resources

from ..exceptions import ConfigError, unknown_name
from .detector import Detector

__all__ = ["LEDPart", "LED_PARTS", "DETECTOR_PARTS", "detector_part", "led_part"]


@dataclass(frozen=True)
class LEDPart:
    """One catalogue LED: typical centre, its bin, FWHM and power at the datasheet's drive.

    ``wavelength_min_nm`` / ``wavelength_max_nm`` are the datasheet's min-max peak
    wavelength (None where it states none); ``uncertain`` marks a row that
    data/parts/SOURCES.md says to verify. [nm, nm, nm, nm, mW, -]
    """

    part: str
    vendor: str
    wavelength_nm: float
    wavelength_min_nm: float | None
    wavelength_max_nm: float | None
    fwhm_nm: float
    power_mw: float
    uncertain: bool

    def led_record(self) -> dict:
        """The LED record of a scenario (``leds=[...]``), responsivity from the detector."""
        return {
            "part": self.part,
            "wavelength_nm": self.wavelength_nm,
            "fwhm_nm": self.fwhm_nm,
            "power_mw": self.power_mw,
        }


def _rows(filename: str) -> list[dict[str, str]]:
    text = resources.files("nirglucose.data").joinpath("parts", filename).read_text()
    return list(csv.DictReader(text.splitlines()))


def _opt(text: str) -> float | None:
    return float(text) if text.strip() else None


@cache
def _detectors() -> dict[str, Detector]:
    out = {}
    for row in _rows("detectors.csv"):
        out[row["part"]] = Detector(
            part=row["part"],
            vendor=row["vendor"],
            material=row["material"],
            responsivity_table=row["responsivity_table"],
            active_area_mm2=float(row["active_area_mm2"]),
            dark_current_25c_na=float(row["dark_current_25c_na"]),
            # the datasheets' "x times per degC" as the exponent of I25 exp(k (T - 25))
            dark_current_per_c=math.log(float(row["dark_current_factor_per_c"])),
            shunt_resistance_mohm=_opt(row["shunt_resistance_mohm"]),
            capacitance_pf=_opt(row["capacitance_pf"]),
        )
    return out


@cache
def _leds() -> dict[str, LEDPart]:
    return {
        row["part"]: LEDPart(
            part=row["part"],
            vendor=row["vendor"],
            wavelength_nm=float(row["wavelength_nm"]),
            wavelength_min_nm=_opt(row["wavelength_min_nm"]),
            wavelength_max_nm=_opt(row["wavelength_max_nm"]),
            fwhm_nm=float(row["fwhm_nm"]),
            power_mw=float(row["power_mw"]),
            uncertain=row["uncertain"].strip().lower() == "true",
        )
        for row in _rows("leds.csv")
    }


#: Catalogue photodiodes by part name (data/parts/detectors.csv).
DETECTOR_PARTS: dict[str, Detector] = _detectors()
#: Catalogue LEDs by part name (data/parts/leds.csv).
LED_PARTS: dict[str, LEDPart] = _leds()


def detector_part(name: str) -> Detector:
    """The catalogue photodiode called ``name``.

    Raises
    ------
    ConfigError
        Unknown name (the message lists the known ones).
    """
    if name not in DETECTOR_PARTS:
        raise ConfigError(unknown_name("detector", name, DETECTOR_PARTS))
    return DETECTOR_PARTS[name]


def led_part(name: str) -> LEDPart:
    """The catalogue LED called ``name``.

    Raises
    ------
    ConfigError
        Unknown name (the message lists the known ones).
    """
    if name not in LED_PARTS:
        raise ConfigError(unknown_name("LED part", name, LED_PARTS))
    return LED_PARTS[name]
