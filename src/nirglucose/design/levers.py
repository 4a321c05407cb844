"""The levers a device team controls, as data: what each sets in the config, and its levels.

Every lever maps to config keys (``nirglucose keys``) and has ordered levels, index 0
being the study's basic wearable (preset ``physical`` as it is) and the last the most
capable. The requirements study (:mod:`~nirglucose.design.requirements`) searches these
levels; a :class:`Design` is one level per lever plus an LED set, and
:meth:`Design.overrides` turns it into the dotted overrides that make it.

Levers
------
Knowledge of each quantity (:data:`KNOWLEDGE`)
    The standard deviation of the instrument that tells the device one tissue or
    environment quantity, as a fraction of today's (:data:`KNOWLEDGE_FRACTIONS`, from
    today's ``measured`` value to exact): skin thickness, hydration, melanin, skin
    temperature (``measurement.*``), blood volume and saturation from the PPG
    (``device.blood_volume_error_rel``, ``device.spo2_error_pct``; read only with
    ``device.ppg_perfusion_spo2``) and ambient humidity (``measurement.humidity_pct``;
    used by ``device.humidity_compensation``). The other entries of the physiological
    vector (age, BMI, skin type, blood pressure, heart and respiration rate, air
    pressure) keep today's errors. A design always has ``device.physiology =
    "measured"``: the preset ``paper``'s "exact physiology" is what no device has.
Capabilities (:data:`CAPABILITIES`)
    ``device.monitor_photodiode``, ``device.constant_force_probe``,
    ``device.ppg_perfusion_spo2``, ``device.humidity_compensation``: off, on.
ADC resolution (:data:`ADC_BITS`)
    ``hardware.adc_bits``, 12 (the study's) to 24 bits. Read it as the converter's
    effective resolution: the bound's noise model has quantisation but no converter
    thermal noise.
LED power (:data:`POWER_FACTORS`)
    Every LED's power times k, capped at the exposure limit
    (:func:`~nirglucose.design.exposure.max_led_power_mw`) and, for a catalogue part, at
    its datasheet power; ``hardware.tia_gain_ohm`` divided by k so the codes stay where
    the drive rule put them. More photocurrent, less relative shot and Johnson noise.
Averaging window (:data:`WINDOW_S`)
    Readings averaged per estimate, as the window they take (one reading, then 1 s to
    the 5 min at which continuous glucose monitors report); see
    :mod:`~nirglucose.design.averaging`.
LED set
    Any subset of the detector's usable candidates
    (:func:`~nirglucose.design.requirements.candidate_records`): the
    study's four LEDs, six SWIR LEDs of one vendor given by value
    (:data:`SWIR_LED_RECORDS`, datasheet centre, FWHM and power) and a generic grid
    800-1,700 nm (FWHM by :mod:`~nirglucose.design.search`'s rule).

References
----------
.. [1] Marktech Optoelectronics datasheets MTSM5010-843-IR, MTSM0012-844-IR,
   MTSM0013-844-IR, MTSM6014-844-IR, MTSM5015-194-IR, MTSM5016-843-IR (typical values at
   50 mA, 25 degC); copies and the table read from them in the shared optics data
   (optics_ext/leds_swir.csv, with addresses).
.. [2] Maxim Integrated, MAX30208 datasheet 19-100550 rev. 1 (2020): +-0.1 degC from
   +30 to +50 degC.
.. [3] Sensirion, SHT3x-DIS datasheet v5 (2018) and SHT4x datasheet v1 (2020): SHT35
   and SHT45 +-1.5 %RH typical.
.. [4] FDA, "Pulse Oximeters - Premarket Notification Submissions" (2013): A_rms <= 3 %
   SpO2 (transmittance); ISO 80601-2-61:2017 <= 4 %.
.. [5] M. Berson et al., "High frequency (20 MHz) ultrasonic devices: advantages and
   applications", Eur. J. Ultrasound 10, 53-63 (1999).
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from ..config import ScenarioConfig
from ..config.presets import DEVICE_CAPABILITIES
from ..exceptions import ConfigError
from .averaging import MAX_ADC_BITS

__all__ = [
    "ADC_BITS",
    "CAPABILITIES",
    "KNOWLEDGE",
    "KNOWLEDGE_FRACTIONS",
    "LEVERS",
    "POWER_FACTORS",
    "SWIR_LED_RECORDS",
    "WINDOW_S",
    "Design",
    "Knowledge",
    "Lever",
    "lever_table",
]


@dataclass(frozen=True)
class Knowledge:
    """One quantity the device must know, and the instruments that could tell it.

    Attributes
    ----------
    name : str
        Short name (the lever is ``knowledge:<name>``).
    key : str
        Dotted config key of its measurement error (SD).
    unit : str
        Unit of that SD.
    today : str
        Today's instrument (the config default's source).
    instruments : tuple of (float, str)
        (fraction of today's SD, instrument that delivers it, with its source) where
        published; an empty tuple: none found.
    """

    name: str
    key: str
    unit: str
    today: str
    instruments: tuple[tuple[float, str], ...] = ()


#: The quantities whose precision is a lever (module docstring).
KNOWLEDGE: tuple[Knowledge, ...] = (
    Knowledge("skin_thickness", "measurement.skin_thickness_mm", "mm",
              "ultrasound estimate",
              ((1.0, "20-75 MHz high-frequency ultrasound images the dermis [5]; no "
                "per-reading precision below today's published in our sources"),)),
    Knowledge("hydration", "measurement.hydration_pct", "%", "Corneometer-type estimate"),
    Knowledge("melanin", "measurement.melanin_fraction", "-", "reflectance melanin meter"),
    Knowledge("skin_temperature", "measurement.skin_temp_c", "degC", "thermistor",
              ((0.5, "MAX30208 skin-temperature sensor, +-0.1 degC at 30-50 degC [2]"),)),
    Knowledge("blood_volume", "device.blood_volume_error_rel", "relative",
              "PPG estimate (no standard governs it)"),
    Knowledge("spo2", "device.spo2_error_pct", "% SpO2", "pulse oximeter at FDA's A_rms [4]"),
    Knowledge("humidity", "measurement.humidity_pct", "%RH", "SHT3x-class RH sensor, +-2 %RH",
              ((0.75, "SHT35 / SHT45 RH sensors, +-1.5 %RH typical [3]"),)),
)
#: Levels of every knowledge lever: fraction of today's SD, from today's (1) to exact (0).
KNOWLEDGE_FRACTIONS: tuple[float, ...] = (1.0, 0.75, 0.5, 0.25, 0.1, 0.0)
#: Capability switches that are levers (``exact_physiology`` is replaced by KNOWLEDGE).
CAPABILITIES: tuple[str, ...] = ("monitor_photodiode", "constant_force_probe",
                                 "ppg_perfusion_spo2", "humidity_compensation")
#: ADC resolutions: the study's 12 bits to the config's 24. [bit]
ADC_BITS: tuple[int, ...] = (12, 14, 16, 18, 20, 22, MAX_ADC_BITS)
#: LED power multipliers (each LED capped at its exposure limit). [-]
POWER_FACTORS: tuple[float, ...] = (1.0, 2.0, 4.0, 8.0)
#: Averaging windows: one reading (0), then 1 s to 5 min, a CGM's reporting interval. [s]
WINDOW_S: tuple[float, ...] = (0.0, 1.0, 5.0, 20.0, 60.0, 300.0)

#: SWIR LEDs given by value [1]_: (part, centre [nm], FWHM [nm], power at 50 mA [mW]).
SWIR_LED_RECORDS: tuple[tuple[str, float, float, float], ...] = (
    ("MTSM5010-843-IR", 1050.0, 59.0, 11.0),
    ("MTSM0012-844-IR", 1200.0, 70.0, 12.0),
    ("MTSM0013-844-IR", 1300.0, 78.0, 11.0),
    ("MTSM6014-844-IR", 1460.0, 118.0, 6.0),
    ("MTSM5015-194-IR", 1550.0, 120.0, 6.0),
    ("MTSM5016-843-IR", 1650.0, 130.0, 3.0),
)


@dataclass(frozen=True)
class Lever:
    """One lever: its name, group, levels (index 0 = today's basic wearable) and labels."""

    name: str
    group: str
    values: tuple[Any, ...]
    unit: str = "-"

    def label(self, level: int, cfg: ScenarioConfig | None = None) -> str:
        """The level as text (a knowledge level in its unit when ``cfg`` is given)."""
        v = self.values[level]
        if self.group == "knowledge":
            if v == 0:
                return "exact"
            if cfg is None:
                return f"x{v:g} of today's SD"
            key = _knowledge(self.name.split(":", 1)[1]).key
            return f"+-{v * _get(cfg, key):.3g} {self.unit}"
        if self.group == "capability":
            return "yes" if v else "no"
        if self.name == "window_s":
            return "one reading" if v == 0 else f"{v:g} s"
        if self.name == "power_factor":
            return f"x{v:g}"
        return f"{v:g}"


def _knowledge(name: str) -> Knowledge:
    return next(k for k in KNOWLEDGE if k.name == name)


def _get(cfg: ScenarioConfig, key: str) -> Any:
    node: Any = cfg
    for part in key.split("."):
        node = getattr(node, part)
    return node


#: Every lever but the LED set, in a fixed order (a design's ``levels`` follow it).
LEVERS: tuple[Lever, ...] = (
    *(Lever(f"knowledge:{k.name}", "knowledge", KNOWLEDGE_FRACTIONS, k.unit) for k in KNOWLEDGE),
    *(Lever(f"capability:{c}", "capability", (False, True)) for c in CAPABILITIES),
    Lever("power_factor", "power", POWER_FACTORS),
    Lever("window_s", "averaging", WINDOW_S, "s"),
    Lever("adc_bits", "adc", ADC_BITS, "bit"),
)
_INDEX = {lv.name: i for i, lv in enumerate(LEVERS)}


def lever_table() -> list[dict[str, Any]]:
    """The levers as rows: name, group, config keys, levels, unit (for the study's files)."""
    rows = []
    for lv in LEVERS:
        if lv.group == "knowledge":
            k = _knowledge(lv.name.split(":", 1)[1])
            keys, note = k.key, f"today: {k.today}; " + "; ".join(
                f"x{f:g}: {txt}" for f, txt in k.instruments)
        elif lv.group == "capability":
            keys, note = DEVICE_CAPABILITIES[lv.name.split(":", 1)[1]][0], ""
        elif lv.name == "power_factor":
            keys, note = "leds[*].power_mw, hardware.tia_gain_ohm", "capped at exposure limits"
        elif lv.name == "window_s":
            keys = "(readings averaged)"
            note = "simulated as bandwidth / N, flicker / sqrt(N), ADC bits + log4 N"
        else:
            keys, note = "hardware.adc_bits", "effective resolution"
        rows.append({"lever": lv.name, "group": lv.group, "config_keys": keys,
                     "levels": ",".join(f"{v:g}" if not isinstance(v, bool) else str(v)
                                        for v in lv.values),
                     "unit": lv.unit, "note": note.rstrip("; ")})
    return rows


@dataclass(frozen=True)
class Design:
    """A point of the lever space: the LED set and one level per lever of :data:`LEVERS`.

    Attributes
    ----------
    leds : tuple of int
        Indices into the detector's candidate records (sorted).
    levels : tuple of int
        One level index per lever of :data:`LEVERS`, in its order.
    """

    leds: tuple[int, ...]
    levels: tuple[int, ...] = field(default_factory=lambda: (0,) * len(LEVERS))

    def __post_init__(self) -> None:
        if len(self.levels) != len(LEVERS):
            raise ConfigError(f"a design needs {len(LEVERS)} lever levels, got {len(self.levels)}")
        for lv, i in zip(LEVERS, self.levels, strict=True):
            if not 0 <= i < len(lv.values):
                raise ConfigError(f"lever {lv.name}: level {i} outside 0-{len(lv.values) - 1}")
        leds = tuple(sorted(int(i) for i in self.leds))
        if not leds or leds[0] < 0 or len(set(leds)) != len(leds):
            raise ConfigError(f"a design needs one or more distinct LED indices, got {leds}")
        object.__setattr__(self, "leds", leds)

    def level(self, name: str) -> int:
        """The level index of lever ``name``."""
        return self.levels[_INDEX[name]]

    def value(self, name: str) -> Any:
        """The value of lever ``name`` at this design's level."""
        return LEVERS[_INDEX[name]].values[self.level(name)]

    def with_level(self, name: str, level: int) -> Design:
        """The same design with lever ``name`` at ``level``."""
        levels = list(self.levels)
        levels[_INDEX[name]] = level
        return replace(self, levels=tuple(levels))

    def with_group(self, group: str, top: bool) -> Design:
        """The same design with every lever of ``group`` at its last (``top``) or first
        level."""
        levels = [(len(lv.values) - 1 if top else 0) if lv.group == group else i
                  for lv, i in zip(LEVERS, self.levels, strict=True)]
        return replace(self, levels=tuple(levels))

    def capabilities(self) -> tuple[str, ...]:
        """The capability switches this design has on."""
        return tuple(c for c in CAPABILITIES if self.value(f"capability:{c}"))

    def knowledge_fractions(self) -> tuple[float, ...]:
        """Each :data:`KNOWLEDGE` quantity's SD as a fraction of today's."""
        return tuple(self.value(f"knowledge:{k.name}") for k in KNOWLEDGE)

    def overrides(self, base: ScenarioConfig, records: list[dict[str, Any]],
                  caps_mw: np.ndarray) -> dict[str, Any]:
        """Dotted overrides that make this design (one reading; averaging aside).

        Parameters
        ----------
        base : ScenarioConfig
            The preset the design starts from (today's errors and TIA gain).
        records : list of dict
            The detector's candidate LED records at their drive-rule power.
        caps_mw : numpy.ndarray
            Each candidate's power cap (exposure limit, datasheet power). [mW]
        """
        k = float(self.value("power_factor"))
        leds = [{**records[i], "power_mw": float(min(records[i]["power_mw"] * k, caps_mw[i]))}
                for i in self.leds]
        out: dict[str, Any] = {"leds": leds, "device.physiology": "measured",
                               "hardware.adc_bits": int(self.value("adc_bits")),
                               "hardware.tia_gain_ohm": base.hardware.tia_gain_ohm / k}
        for name, (key, on, off) in DEVICE_CAPABILITIES.items():
            if name in CAPABILITIES:
                out[key] = on if self.value(f"capability:{name}") else off
        for q, frac in zip(KNOWLEDGE, self.knowledge_fractions(), strict=True):
            out[q.key] = frac * _get(base, q.key)
        return out

    def describe(self, wavelengths_nm: list[float], base: ScenarioConfig) -> dict[str, str]:
        """Lever -> its level as text (and ``leds``: the centres), for tables."""
        out = {"leds": ",".join(f"{wavelengths_nm[i]:g}" for i in self.leds)}
        for lv, i in zip(LEVERS, self.levels, strict=True):
            out[lv.name] = lv.label(i, base)
        return out
