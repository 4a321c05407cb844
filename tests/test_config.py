"""Configuration: presets, dotted overrides, validation."""

from __future__ import annotations

import pytest

from nirglucose.config import (
    DEVICE_CAPABILITIES,
    NOISE_SOURCES,
    PAPER_SIGNAL_GAIN,
    PRESET_CAPABILITIES,
    PRESET_DESCRIPTIONS,
    PRESETS,
    WEARABLE_SIGNAL_GAIN,
    ScenarioConfig,
    device_capabilities,
    parse_override,
    resolve_config,
    valid_keys,
)
from nirglucose.config_keys import key_info
from nirglucose.exceptions import ConfigError


@pytest.mark.parametrize("preset", list(PRESETS))
def test_presets_resolve(preset):
    cfg = resolve_config(preset)
    assert cfg.preset == preset
    assert isinstance(cfg, ScenarioConfig)


def test_every_noise_source_has_switch_and_scale():
    cfg = resolve_config("paper")
    for src in NOISE_SOURCES:
        assert cfg.noise_factor(src) == 1.0
        off = resolve_config("paper", {f"noise.{src}.enabled": False})
        assert off.noise_factor(src) == 0.0
        scaled = resolve_config("paper", {f"noise.{src}.scale": 2.0, "noise_scale": 3.0})
        assert scaled.noise_factor(src) == 6.0


def test_unknown_noise_source():
    with pytest.raises(ConfigError, match="valid"):
        resolve_config("paper").noise_factor("cosmic_rays")


def test_unknown_preset_lists_valid():
    with pytest.raises(ConfigError, match="valid: paper, wearable, physical, lab, field"):
        resolve_config("papr")


def test_unknown_key_suggests():
    with pytest.raises(ConfigError, match="did you mean hardware.adc_bits"):
        resolve_config("paper", {"adc_bits": 14})


@pytest.mark.parametrize(
    ("key", "value"),
    [
        ("hardware.adc_bits", 4),
        ("noise_scale", -1),
        ("physiology.age_yr", [80, 18]),
        ("environment.ambient_lux", [0.01, 10]),
        ("glucose.status_probs", {"normal": 0.5, "type3": 0.5}),
        ("leds.fwhm_nm", [40, 40]),
        ("hardware.led_power_mw", [1, 2]),
    ],
)
def test_invalid_values_raise_config_error(key, value):
    with pytest.raises(ConfigError):
        resolve_config("paper", {key: value})


def test_config_errors_are_value_errors():
    with pytest.raises(ValueError):
        resolve_config("nope")


def test_parse_override():
    assert parse_override("a.b=1.5") == ("a.b", 1.5)
    assert parse_override("a=false") == ("a", False)
    assert parse_override("optics.model=diffusion") == ("optics.model", "diffusion")
    with pytest.raises(ConfigError):
        parse_override("novalue")


def test_valid_keys_cover_nested():
    keys = valid_keys()
    assert "hardware.adc_bits" in keys and "noise.shot.scale" in keys


def test_config_json_round_trip():
    cfg = resolve_config("field", {"hardware.adc_bits": 14})
    again = ScenarioConfig.model_validate_json(cfg.to_json())
    assert again == cfg


@pytest.mark.parametrize("preset", list(PRESETS))
def test_every_preset_is_described_with_its_capabilities(preset):
    assert PRESET_DESCRIPTIONS[preset].strip()
    assert set(PRESET_CAPABILITIES[preset]) <= set(DEVICE_CAPABILITIES)
    # the capability list kept as data matches what the preset's config switches on
    assert device_capabilities(resolve_config(preset)) == PRESET_CAPABILITIES[preset]


def test_paper_and_wearable_differ_only_in_gain_and_capabilities():
    paper = resolve_config("paper").model_dump()
    wearable = resolve_config("wearable").model_dump()
    assert paper["glucose"].pop("signal_gain") == PAPER_SIGNAL_GAIN
    assert wearable["glucose"].pop("signal_gain") == WEARABLE_SIGNAL_GAIN
    for cfg in (paper, wearable):
        cfg.pop("preset")
        cfg.pop("device")
    assert paper == wearable
    assert PRESET_CAPABILITIES["wearable"] == ()
    assert set(PRESET_CAPABILITIES["paper"]) == set(DEVICE_CAPABILITIES)


def test_device_keys_are_sweepable_and_documented():
    cfg = resolve_config("wearable", {"device.monitor_photodiode": True})
    assert device_capabilities(cfg) == ("monitor_photodiode",)
    assert '"device"' in cfg.to_json()  # recorded in every output's config
    for key in [k for k in valid_keys() if k.startswith("device.")]:
        info = key_info(key)
        assert info.unit and info.description, key  # a description with a unit
    with pytest.raises(ConfigError):
        resolve_config("paper", {"device.physiology": "guessed"})
    assert key_info("device.nope").description == ""  # unknown: nothing to describe
