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

The package is split by concept; every name is importable from here as before:
:mod:`._base` (the shared bounded model), :mod:`.leds`, :mod:`.subject` (physiology,
glucose), :mod:`.environment` (ambient conditions, probe contact), :mod:`.instrument`
(optics, hardware, measured physiology), :mod:`.noise`, :mod:`.device`,
:mod:`.scenario`, :mod:`.presets`, :mod:`.keys` (every key's unit, range and the
nearest valid keys) and :mod:`.overrides` (``--set`` parsing and :func:`resolve_config`).
"""

from __future__ import annotations

from ._base import MAX_ABS_VALUE
from .device import SPO2_ARMS_PCT, DeviceConfig
from .environment import ContactConfig, EnvironmentConfig
from .instrument import (
    FORWARD_MODELS,
    HardwareConfig,
    MeasurementConfig,
    OpticsConfig,
    ReferenceTissue,
)
from .keys import valid_keys
from .leds import DEFAULT_LEDS, LED, LEGACY_LED_KEYS, LEDConfig
from .noise import DEFAULT_OFF_NOISE_SOURCES, NOISE_SOURCES, NoiseConfig, NoiseSource
from .overrides import apply_overrides, is_valid_key, parse_override, resolve_config
from .presets import (
    DEVICE_CAPABILITIES,
    PAPER_SIGNAL_GAIN,
    PRESET_CAPABILITIES,
    PRESET_DESCRIPTIONS,
    PRESETS,
    WEARABLE_SIGNAL_GAIN,
    device_capabilities,
)
from .scenario import ScenarioConfig
from .subject import GlucoseConfig, PhysiologyConfig

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
    "DEFAULT_OFF_NOISE_SOURCES",
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
    "MAX_ABS_VALUE",
    "SPO2_ARMS_PCT",
]
