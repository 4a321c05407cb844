"""design.levers: every lever level is a real config override; designs validate."""

from __future__ import annotations

import pytest

from nirglucose.config import resolve_config
from nirglucose.design.levers import (
    KNOWLEDGE,
    KNOWLEDGE_FRACTIONS,
    LEVERS,
    Design,
    lever_table,
)
from nirglucose.design.requirements import candidate_records
from nirglucose.exceptions import ConfigError


@pytest.fixture(scope="module")
def cands():
    return candidate_records("physical", "BPW34", (800.0, 1000.0))


def _get(cfg, key):
    node = cfg
    for part in key.split("."):
        node = getattr(node, part)
    return node


def test_every_level_of_every_lever_resolves_to_the_config_it_says(cands):
    base = resolve_config("physical")
    for i, lv in enumerate(LEVERS):
        for level in range(len(lv.values)):
            levels = [0] * len(LEVERS)
            levels[i] = level
            d = Design((0, 1), tuple(levels))
            cfg = resolve_config("physical", {**d.overrides(base, cands.records, cands.caps_mw),
                                              "detector": "BPW34"})
            if lv.group == "knowledge":
                k = next(k for k in KNOWLEDGE if lv.name.endswith(k.name))
                assert _get(cfg, k.key) == pytest.approx(lv.values[level] * _get(base, k.key))
            elif lv.name == "adc_bits":
                assert cfg.hardware.adc_bits == lv.values[level]
            elif lv.name == "power_factor":
                assert cfg.hardware.tia_gain_ohm == pytest.approx(
                    base.hardware.tia_gain_ohm / lv.values[level])
            assert cfg.device.physiology == "measured"  # never the paper's exact physiology


def test_today_is_the_presets_value_and_instruments_sit_on_the_grid():
    base = resolve_config("physical")
    assert KNOWLEDGE_FRACTIONS[0] == 1 and KNOWLEDGE_FRACTIONS[-1] == 0
    for k in KNOWLEDGE:
        assert _get(base, k.key) > 0, k.key
        for frac, _ in k.instruments:
            assert frac in KNOWLEDGE_FRACTIONS
    names = [row["lever"] for row in lever_table()]
    assert names == [lv.name for lv in LEVERS]
    # index 0 of every lever is the study's basic wearable
    d = Design((0,))
    assert d.capabilities() == () and d.value("adc_bits") == base.hardware.adc_bits
    assert d.value("window_s") == 0 and d.value("power_factor") == 1


def test_power_lever_respects_each_records_cap(cands):
    base = resolve_config("physical")
    top = Design(tuple(range(len(cands.records))), tuple(len(lv.values) - 1 for lv in LEVERS))
    leds = top.overrides(base, cands.records, cands.caps_mw)["leds"]
    for led, cap in zip(leds, cands.caps_mw, strict=True):
        assert led["power_mw"] <= cap + 1e-12


@pytest.mark.parametrize("kwargs", [dict(leds=()), dict(leds=(1, 1)), dict(leds=(-1,)),
                                    dict(leds=(0,), levels=(0,) * 3),
                                    dict(leds=(0,), levels=(99,) + (0,) * (len(LEVERS) - 1))])
def test_bad_designs_are_refused(kwargs):
    with pytest.raises(ConfigError):
        Design(**kwargs)
