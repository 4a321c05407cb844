"""Configuration: presets, dotted overrides, validation."""

from __future__ import annotations

import pytest

from nirglucose.config import (
    DEFAULT_OFF_NOISE_SOURCES,
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
from nirglucose.config.keys import key_info
from nirglucose.exceptions import ConfigError


@pytest.mark.parametrize("preset", list(PRESETS))
def test_presets_resolve(preset):
    cfg = resolve_config(preset)
    assert cfg.preset == preset
    assert isinstance(cfg, ScenarioConfig)


def test_every_noise_source_has_switch_and_scale():
    cfg = resolve_config("paper")
    for src in NOISE_SOURCES:
        # confounders added after calibration are off by default (issue 40)
        assert cfg.noise_factor(src) == (0.0 if src in DEFAULT_OFF_NOISE_SOURCES else 1.0)
        on = resolve_config("paper", {f"noise.{src}.enabled": True})
        assert on.noise_factor(src) == 1.0
        off = resolve_config("paper", {f"noise.{src}.enabled": False})
        assert off.noise_factor(src) == 0.0
        scaled = resolve_config("paper", {f"noise.{src}.enabled": True,
                                          f"noise.{src}.scale": 2.0, "noise_scale": 3.0})
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


# --- issue 22: one record per LED; every scenario number in the config ---------------

THREE = [
    {"wavelength_nm": w, "fwhm_nm": 40.0, "power_mw": 3.0, "responsivity_a_per_w": 0.5}
    for w in (850.0, 940.0, 1150.0)
]


def test_one_override_changes_the_led_set():
    cfg = resolve_config("paper", {"leds": THREE})
    assert cfg.leds.wavelengths_nm == (850.0, 940.0, 1150.0)
    assert cfg.leds.power_mw == (3.0,) * 3 and cfg.leds.responsivity_a_per_w == (0.5,) * 3
    assert resolve_config("paper", {"leds.emitters": THREE}) == cfg
    # recorded: the records are in the config's JSON and come back from it
    assert ScenarioConfig.model_validate_json(cfg.to_json()) == cfg
    assert '"power_mw": 3.0' in cfg.to_json()


def test_led_records_must_be_json_and_part_names_may_go_unquoted():
    with pytest.raises(ConfigError, match="is not valid JSON .*no nan"):
        parse_override('leds.emitters=[{"wavelength_nm": nan}]')
    assert parse_override("leds=[L8957, G17190-005K]") == ("leds", ["L8957", "G17190-005K"])


@pytest.mark.parametrize("overrides, says", [
    ({"leds": {"wavelength_nm": 850}}, "leds must be a list of LED records or part names"),
    (["hardware.adc_bits"], "overrides must be a dict of dotted keys.*got a list"),
    ({1: 2}, "overrides must be a dict of dotted keys"),
])
def test_malformed_overrides_are_one_config_error(overrides, says):
    with pytest.raises(ConfigError, match=says) as err:
        resolve_config("paper", overrides)
    assert "\n" not in str(err.value)


def test_former_per_led_keys_map_onto_the_records():
    old = {
        "leds.wavelengths_nm": [850, 940, 1150],
        "leds.fwhm_nm": [40, 40, 40],
        "hardware.led_power_mw": [3, 3, 3],
        "hardware.responsivity_a_per_w": [0.5, 0.5, 0.5],
    }
    assert resolve_config("paper", old) == resolve_config("paper", {"leds": THREE})
    # same count: one former list changes that field only
    cfg = resolve_config("paper", {"hardware.led_power_mw": [1, 2, 3, 4]})
    assert cfg.leds.power_mw == (1, 2, 3, 4)
    assert cfg.leds.fwhm_nm == resolve_config("paper").leds.fwhm_nm
    # a new count needs every field: the error names the one key that does it
    with pytest.raises(ConfigError, match=r"gives 3 LEDs but the scenario has 4; .*leds=\["):
        resolve_config("paper", {"leds.wavelengths_nm": [850, 940, 1150]})


def test_config_recorded_in_the_former_layout_still_loads():
    data = resolve_config("wearable").model_dump(mode="json")
    data["leds"] = {"band_points": 3, "wavelengths_nm": [850, 940, 1150], "fwhm_nm": [40] * 3}
    data["hardware"]["led_power_mw"] = [3, 3, 3]
    data["hardware"]["responsivity_a_per_w"] = [0.5] * 3
    assert ScenarioConfig.model_validate(data) == resolve_config("wearable", {"leds": THREE})


def test_config_recorded_with_a_dropped_key_still_loads():
    # hardware.calibration_temperature_sd_c was read nowhere: recorded configs keep loading,
    # but it is no longer a key anyone can set
    data = resolve_config("wearable").model_dump(mode="json")
    data["hardware"]["calibration_temperature_sd_c"] = 2.0
    assert ScenarioConfig.model_validate(data) == resolve_config("wearable")
    with pytest.raises(ConfigError, match="unknown config key"):
        resolve_config("paper", {"hardware.calibration_temperature_sd_c": 2.0})


def test_one_led_value_is_a_key():
    cfg = resolve_config("paper", {"leds.emitters.3.power_mw": 8.0})
    assert cfg.leds.power_mw == (2.0, 2.0, 2.7, 8.0)
    with pytest.raises(ConfigError, match="has 4 LEDs"):
        resolve_config("paper", {"leds.emitters.4.power_mw": 8.0})
    with pytest.raises(ConfigError, match="unknown config key"):
        resolve_config("paper", {"leds.emitters.0.colour": "red"})
    with pytest.raises(ConfigError, match=r"leds\.emitters\.0\.power_mw.*\[mW\]"):
        resolve_config("paper", {"leds.emitters.0.power_mw": -1})
    with pytest.raises(ConfigError, match="repeat"):
        resolve_config("paper", {"leds": THREE + THREE[:1]})


#: Numbers that were module constants or inline literals of simulation/ before issue 22,
#: each with a value that must change the data when swept.
MOVED = {
    "physiology.heart_rate_bpm_mean": 90.0,
    "physiology.systolic_bp_mmhg_per_yr": 1.0,
    "physiology.skin_temp_c_neutral": 34.0,
    "physiology.perfusion_per_c": 0.05,
    "physiology.pulse_depth": 0.05,
    "physiology.skin_thickness_loss_per_decade": 0.1,
    "physiology.subcutis_fat_fraction_rise": 0.1,
    "glucose.dawn_peak_hour": 4.0,
    "glucose.meal_size_log_sd": 0.5,
    "contact.pressure_beta": (3.0, 2.0),
    "hardware.hours_since_reference_h": (0.0, 24.0),
    "hardware.board_skin_weight": 0.3,
    "hardware.led_thermal_coeff_per_c": 0.004,
    "optics.reference_tissue.blood_fraction": 0.03,
    "environment.perfusion_reference_mbar": 1000.0,
}


@pytest.mark.parametrize(("key", "value"), list(MOVED.items()))
def test_moved_numbers_are_sweepable_recorded_and_described(key, value):
    import nirglucose as ng

    info = key_info(key)
    assert info.unit and info.description, key
    base = ng.simulate("wearable", 6, 2, 3)
    moved = ng.simulate("wearable", 6, 2, 3, overrides={key: value})
    node = moved.config
    for part in key.split("."):
        node = getattr(node, part)
    assert node == value  # recorded in the dataset's config
    measured = [c for c in base.frame.columns if c.startswith(("adc_", "true_"))]
    assert not base.frame[measured].equals(moved.frame[measured]), key


def test_simulate_modules_hold_no_scenario_constants():
    from nirglucose import constants
    from nirglucose.simulation import contact, glucose, hardware, physiology

    # physical constants and datasheet defaults live in nirglucose.constants, with sources
    for module in (physiology, contact, glucose, hardware):
        numbers = [
            n
            for n, v in vars(module).items()
            if n.isupper()
            and not hasattr(constants, n)
            and not isinstance(v, bool)
            and (
                isinstance(v, int | float)
                or (isinstance(v, tuple) and any(isinstance(x, int | float) for x in v))
            )
        ]
        assert numbers == [], (module.__name__, numbers)


# --- issue 20: every numeric value has a physical range ----------------------------------


def test_every_numeric_value_has_an_explicit_physical_bound():
    """Each number of the config (fields, tuple items, dict values) has both bounds,
    narrower than the generic +-MAX_ABS_VALUE rule: a new unbounded field fails here."""
    from nirglucose.config import MAX_ABS_VALUE
    from nirglucose.config.keys import numeric_leaves

    leaves = numeric_leaves()
    assert len(leaves) > 150  # the walk sees the whole model (tuples, dicts, LED records)
    loose = [
        (path, str(b))
        for path, b in leaves
        if b.lo is None or b.hi is None or b.lo < -MAX_ABS_VALUE or b.hi > MAX_ABS_VALUE
        or b.hi - b.lo >= 2 * MAX_ABS_VALUE
    ]
    assert loose == []


def test_bound_walk_sees_an_unbounded_field():
    from typing import Annotated

    from pydantic import BaseModel, Field

    from nirglucose.config.keys import numeric_leaves

    class Probe(BaseModel):
        free: float = 1.0
        half: float = Field(1.0, ge=0)
        pair: tuple[Annotated[float, Field(ge=0, le=1)], float] = (0.0, 1.0)

    got = {p: (b.lo, b.hi) for p, b in numeric_leaves(Probe)}
    assert got == {
        "free": (None, None), "half": (0, None), "pair.0": (0, 1), "pair.1": (None, None)
    }


@pytest.mark.parametrize("preset", list(PRESETS))
def test_presets_lie_within_the_bounds(preset):
    from nirglucose.config.keys import bounds_of, numeric_leaves

    data = resolve_config(preset).model_dump(mode="json")
    checked = 0

    def walk(node, path):
        nonlocal checked
        if isinstance(node, dict):
            for k, v in node.items():
                walk(v, f"{path}.{k}" if path else k)
        elif isinstance(node, list):
            for i, v in enumerate(node):
                walk(v, f"{path}.{i}")
        elif isinstance(node, int | float) and not isinstance(node, bool):
            b = bounds_of(path)
            assert b is not None, path
            assert b.lo <= node <= b.hi, (path, node, str(b))
            checked += 1

    walk(data, "")
    assert checked >= len(numeric_leaves()) - 10  # variable-length items counted per item


@pytest.mark.parametrize(
    ("key", "value", "words"),
    [
        ("hardware.adc_bits", 40, ["hardware.adc_bits=40", "between 8 and 24", "[bit]"]),
        ("environment.temperature_c", (-40.0, 30.0),
         ["environment.temperature_c[0]=-40.0", "between -20 and 50", "[degC]"]),
        ("optics.source_detector_mm", 0.2, ["> 0.5 and <= 20", "[mm]"]),
        ("leds.emitters.1.wavelength_nm", 1800, ["between 700 and 1700", "[nm]"]),
        ("glucose.meal_peak_mgdl", {"normal": 35.0, "prediabetes": 60.0, "type1": 900.0,
                                    "type2": 95.0},
         ["glucose.meal_peak_mgdl[type1]=900.0", "between 0 and 500", "[mg/dL]"]),
    ],
)
def test_out_of_range_message_names_key_value_range_and_unit(key, value, words):
    with pytest.raises(ConfigError) as err:
        resolve_config("paper", {key: value})
    msg = str(err.value)
    assert "is out of range: must be" in msg and "\n" not in msg
    for w in words:
        assert w in msg, msg


def test_bounds_text():
    from nirglucose.config.keys import Bounds, key_range

    assert str(Bounds(8, 24)) == "between 8 and 24"
    assert str(Bounds(0, 1, lo_open=True)) == "> 0 and <= 1"
    assert str(Bounds(100, 1e9)) == "between 100 and 1e9"
    assert key_range("hardware.adc_bits") == "between 8 and 24"
    assert key_range("glucose.fasting_mgdl") == "0: between 20 and 600; 1: between 0 and 200"
    assert "wavelength_nm: between 700 and 1700" in key_range("leds")
    assert key_range("device.physiology") == ""
