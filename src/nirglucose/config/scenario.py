"""The complete scenario: every section together, and configs of the former layout."""

from __future__ import annotations

import json
from typing import Any

from pydantic import Field, ValidationError, model_validator

from ..exceptions import ConfigError
from ._base import _Model
from .detector import Detector, band_responsivity_a_per_w, responsivity_curve
from .device import DeviceConfig
from .environment import ContactConfig, EnvironmentConfig
from .instrument import HardwareConfig, MeasurementConfig, OpticsConfig
from .leds import DEFAULT_LEDS, LEDConfig, _merge_legacy_leds, expand_led_part
from .noise import NOISE_SOURCES, NoiseConfig, NoiseSource
from .parts import detector_part
from .subject import GlucoseConfig, PhysiologyConfig

#: ``hardware`` keys of recorded configs that no longer exist: read nowhere when they
#: did, so a config recorded with them loads without them and simulates the same data.
_REMOVED_HARDWARE_KEYS = ("calibration_temperature_sd_c",)


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
    detector: Detector | None = Field(
        None,
        description="The photodiode as a part: a catalogue name (data/parts/detectors.csv, "
        "e.g. G17190-005K) or a record. It sets hardware.dark_current_25c_na, "
        "hardware.dark_current_per_c and optics.detector_area_mm2, the responsivity of "
        "each LED without its own (its curve over the LED's band) and adds its shunt "
        "resistance's Johnson noise; None: the study's photodiode (S1336 responsivities, "
        "hardware.* values). [-]",
    )

    @model_validator(mode="before")
    @classmethod
    def _former_layout(cls, data: Any) -> Any:
        if not isinstance(data, dict):
            return data
        hw = data.get("hardware")
        if isinstance(hw, dict) and any(k in hw for k in _REMOVED_HARDWARE_KEYS):
            # recorded before these keys were dropped; they never changed the data
            hw = {k: v for k, v in hw.items() if k not in _REMOVED_HARDWARE_KEYS}
            data = {**data, "hardware": hw}
        # configs recorded before issue 22 kept per-LED values in four parallel lists
        leds = data.get("leds")
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

    @model_validator(mode="before")
    @classmethod
    def _detector(cls, data: Any) -> Any:
        if not isinstance(data, dict):
            return data
        return _apply_detector(dict(data))

    def noise_factor(self, source: str) -> float:
        """Effective multiplier of a noise source: enabled x scale x ``noise_scale``."""
        if source not in NOISE_SOURCES:
            raise ConfigError(f"unknown noise source {source!r}; valid: {', '.join(NOISE_SOURCES)}")
        ns: NoiseSource = getattr(self.noise, source)
        return float(ns.enabled) * ns.scale * self.noise_scale

    def to_json(self) -> str:
        """The resolved configuration as canonical JSON (sorted keys)."""
        return json.dumps(self.model_dump(mode="json"), sort_keys=True)


#: Scenario keys a detector sets: (section, key, Detector field).
DETECTOR_KEYS = (
    ("hardware", "dark_current_25c_na", "dark_current_25c_na"),
    ("hardware", "dark_current_per_c", "dark_current_per_c"),
    ("optics", "detector_area_mm2", "active_area_mm2"),
)


def detector_key_default(section: str, key: str) -> Any:
    """The default of a key a detector sets (:data:`DETECTOR_KEYS`), read off its
    section's class: no default scenario is built (that deep-copies every default)."""
    sections: dict[str, type[_Model]] = {"hardware": HardwareConfig, "optics": OpticsConfig}
    return sections[section].model_fields[key].default


def _section_dict(value: Any) -> dict:
    if value is None:
        return {}
    return value.model_dump() if isinstance(value, _Model) else dict(value)


def _apply_detector(data: dict) -> dict:
    """Fill what a detector decides: its hardware and optics keys and LED responsivities.

    A key a detector sets must be at its default or already the detector's value (a
    recorded config); another value is a conflict, refused rather than overwritten.
    LEDs without ``responsivity_a_per_w`` get the detector's band-averaged curve; without
    a detector they are refused.
    """
    det = data.get("detector")
    if isinstance(det, str):
        det = detector_part(det)
    elif isinstance(det, dict):
        try:
            det = Detector.model_validate(det)
        except ValidationError as exc:
            err = exc.errors()[0]
            loc = ".".join(str(p) for p in err["loc"])
            raise ConfigError(
                f"invalid value for detector.{loc}: {err['msg']} (got {err.get('input')!r})"
            ) from None
    elif det is not None and not isinstance(det, Detector):
        return data  # pydantic reports the wrong type, with the key
    if det is not None:
        data["detector"] = det
        sections: dict[str, type[_Model]] = {"hardware": HardwareConfig, "optics": OpticsConfig}
        for section, key, field in DETECTOR_KEYS:
            values = _section_dict(data.get(section))
            want = getattr(det, field)
            default = sections[section].model_fields[key].default  # a class attribute
            have = values.get(key, default)
            if have != default and have != want:
                raise ConfigError(
                    f"{section}.{key}={have!r} conflicts with detector {det.part} "
                    f"({field} {want!r}); change the detector's record instead "
                    f'(detector={{..., "{field}": ...}}) or drop the detector'
                )
            values[key] = want
            data[section] = values
    return _fill_responsivities(data, det)


def _fill_responsivities(data: dict, det: Detector | None) -> dict:
    """LEDs without ``responsivity_a_per_w``: the detector's curve over their band."""
    leds = data.get("leds")
    if leds is None:
        return data
    if isinstance(leds, LEDConfig):
        leds = leds.model_dump()
    elif isinstance(leds, list | tuple):
        leds = {"emitters": leds}
    elif not isinstance(leds, dict) or "emitters" not in leds:
        return data
    leds = dict(leds)
    emitters = [
        e.model_dump() if isinstance(e, _Model) else expand_led_part(e) for e in leds["emitters"]
    ]
    missing = [i for i, e in enumerate(emitters)
               if isinstance(e, dict) and e.get("responsivity_a_per_w") is None]
    if missing and det is None:
        e = emitters[missing[0]]
        raise ConfigError(
            f"LED {missing[0]} ({e.get('wavelength_nm')} nm) has no responsivity_a_per_w: "
            'give one, or name a detector (detector="G17190-005K"; see `nirglucose parts`)'
        )
    if missing and det is not None:
        curve = responsivity_curve(det)
        for i in missing:
            e = dict(emitters[i])
            r = band_responsivity_a_per_w(e["wavelength_nm"], e["fwhm_nm"], curve)
            if not r > 0:
                raise ConfigError(
                    f"detector {det.part} ({det.material}) is blind at the LED at "
                    f"{e['wavelength_nm']:g} nm: its responsivity table ends at "
                    f"{curve[0][-1]:g} nm; choose another detector or LED"
                )
            e["responsivity_a_per_w"] = r
            emitters[i] = e
    leds["emitters"] = emitters
    data["leds"] = leds
    return data
