"""The complete scenario: every section together, and configs of the former layout."""

from __future__ import annotations

import json
from typing import Any

from pydantic import Field, model_validator

from ..exceptions import ConfigError
from ._base import _Model
from .device import DeviceConfig
from .environment import ContactConfig, EnvironmentConfig
from .instrument import HardwareConfig, MeasurementConfig, OpticsConfig
from .leds import DEFAULT_LEDS, LEDConfig, _merge_legacy_leds
from .noise import NOISE_SOURCES, NoiseConfig, NoiseSource
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

    def noise_factor(self, source: str) -> float:
        """Effective multiplier of a noise source: enabled x scale x ``noise_scale``."""
        if source not in NOISE_SOURCES:
            raise ConfigError(f"unknown noise source {source!r}; valid: {', '.join(NOISE_SOURCES)}")
        ns: NoiseSource = getattr(self.noise, source)
        return float(ns.enabled) * ns.scale * self.noise_scale

    def to_json(self) -> str:
        """The resolved configuration as canonical JSON (sorted keys)."""
        return json.dumps(self.model_dump(mode="json"), sort_keys=True)
