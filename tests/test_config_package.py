"""The config package (issue 22 split) keeps every name importable from ``nirglucose.config``."""

from __future__ import annotations

import importlib

import nirglucose.config as config


def test_every_public_name_is_importable_from_the_package():
    missing = [name for name in config.__all__ if not hasattr(config, name)]
    assert missing == []
    assert len(config.__all__) == len(set(config.__all__))


def test_each_name_is_the_object_of_its_concept_module():
    for module, names in {
        "leds": ("LED", "LEDConfig", "DEFAULT_LEDS", "LEGACY_LED_KEYS"),
        "scenario": ("ScenarioConfig",),
        "presets": ("PRESETS", "device_capabilities"),
        "overrides": ("resolve_config", "apply_overrides", "parse_override", "valid_keys"),
    }.items():
        mod = importlib.import_module(f"nirglucose.config.{module}")
        for name in names:
            assert getattr(config, name) is getattr(mod, name), (module, name)
