"""Detectors and LEDs as parts (config.detector, config.parts, data/parts)."""

from __future__ import annotations

import math

import numpy as np
import pytest

import nirglucose as ng
from nirglucose.config import resolve_config
from nirglucose.config.detector import band_responsivity_a_per_w, responsivity_curve
from nirglucose.config.parts import DETECTOR_PARTS, LED_PARTS, detector_part, led_part
from nirglucose.exceptions import ConfigError
from nirglucose.simulation.hardware import dark_current_a, johnson_resistance_ohm


def test_catalogue_rows_load_with_their_tables():
    assert set(DETECTOR_PARTS) == {"G17190-003K", "G17190-005K", "G17190-010K", "FGA01", "BPW34"}
    for det in DETECTOR_PARTS.values():
        wl, r = responsivity_curve(det)
        assert np.all(np.diff(wl) > 0) and np.all(r >= 0) and r.max() <= 1.05
    assert all(850 <= p.wavelength_nm <= 940 for p in LED_PARTS.values())
    assert LED_PARTS["L1909"].uncertain and not LED_PARTS["L8957"].uncertain


def test_datasheet_values_survive_the_conversions():
    # G17190: "1.09 times/degC" -> k = ln 1.09: one degree up multiplies the dark current by 1.09
    g = detector_part("G17190-005K")
    assert float(dark_current_a(1.0, 26.0, g.dark_current_per_c)) == pytest.approx(1.09)
    # BPW34 (Si): doubling per 10 degC
    b = detector_part("BPW34")
    assert float(dark_current_a(1.0, 35.0, b.dark_current_per_c)) == pytest.approx(2.0, rel=1e-5)
    # phi 0.5 mm -> pi 0.25^2 mm^2
    assert g.active_area_mm2 == pytest.approx(math.pi * 0.25**2, rel=1e-3)
    # BPW34 0.627 A/W at 950 nm (47 uA at 1 mW/cm^2 over 7.5 mm^2, data/parts/SOURCES.md)
    wl, r = responsivity_curve(b)
    assert float(np.interp(950.0, wl, r)) == pytest.approx(0.047 / 0.075, rel=0.01)


def test_unknown_names_are_one_error_listing_the_known():
    with pytest.raises(ConfigError, match="valid: G17190-003K, G17190-005K, G17190-010K, FGA01"):
        resolve_config("paper", {"detector": "G17190"})
    with pytest.raises(ConfigError, match="did you mean 'L8957'"):
        resolve_config("paper", {"leds": ["L8975"]})
    with pytest.raises(ConfigError):
        led_part("nope")


def test_band_responsivity_is_the_band_average():
    ramp = (np.array([700.0, 1300.0]), np.array([0.0, 0.6]))
    # linear curve: the symmetric band's mean is the centre value
    assert band_responsivity_a_per_w(1000.0, 60.0, ramp) == pytest.approx(0.3, rel=1e-9)
    # a narrow band reads the curve at its centre
    curve = responsivity_curve(detector_part("G17190-005K"))
    narrow = band_responsivity_a_per_w(1100.0, 0.5, curve)
    assert narrow == pytest.approx(float(np.interp(1100.0, *curve)), rel=1e-4)
    # a band past silicon's cut-off loses the part beyond it
    wl, r = responsivity_curve(detector_part("BPW34"))
    wide = band_responsivity_a_per_w(1080.0, 60.0, (wl, r))
    extended = (np.append(wl, 1300.0), np.append(r, r[-1]))
    assert 0 < wide < band_responsivity_a_per_w(1080.0, 60.0, extended)


def test_naming_a_detector_sets_its_values():
    cfg = resolve_config("paper", {"detector": "G17190-005K"})
    det = cfg.detector
    assert cfg.hardware.dark_current_25c_na == det.dark_current_25c_na
    assert cfg.hardware.dark_current_per_c == det.dark_current_per_c
    assert cfg.optics.detector_area_mm2 == det.active_area_mm2
    curve = responsivity_curve(det)
    for led in cfg.leds.emitters:
        assert led.responsivity_a_per_w == band_responsivity_a_per_w(
            led.wavelength_nm, led.fwhm_nm, curve)
    # a recorded config validates to itself
    assert ng.ScenarioConfig.model_validate(cfg.model_dump(mode="json")) == cfg


def test_explicit_responsivity_still_wins_and_defaults_stay():
    cfg = resolve_config("paper", {"detector": "BPW34",
                                   "leds.emitters.0.responsivity_a_per_w": 0.3})
    assert cfg.leds.responsivity_a_per_w[0] == 0.3
    assert cfg.leds.responsivity_a_per_w[1] != 0.62
    base = resolve_config("paper")
    assert base.detector is None and base.leds.responsivity_a_per_w == (0.58, 0.62, 0.40, 0.15)
    assert johnson_resistance_ohm(base) == base.hardware.tia_gain_ohm


def test_conflicts_and_missing_values_are_refused():
    with pytest.raises(ConfigError, match="conflicts with detector BPW34"):
        resolve_config("paper", {"detector": "BPW34", "hardware.dark_current_25c_na": 5.0})
    with pytest.raises(ConfigError, match="has no responsivity_a_per_w"):
        resolve_config("paper", {"leds": [{"wavelength_nm": 900, "fwhm_nm": 30, "power_mw": 2}]})
    with pytest.raises(ConfigError, match="blind"):
        resolve_config("paper", {"detector": "BPW34", "leds": [
            {"wavelength_nm": 1250, "fwhm_nm": 30, "power_mw": 2}]})
    with pytest.raises(ConfigError, match="below 800 nm"):
        resolve_config("paper", {"detector": "G17190-005K", "leds": [
            {"wavelength_nm": 750, "fwhm_nm": 30, "power_mw": 2}]})


def test_led_parts_by_name_and_with_fields():
    cfg = resolve_config("wearable", {"detector": "BPW34",
                                      "leds": ["L8957", {"part": "L1909", "power_mw": 3.0}]})
    a, b = cfg.leds.emitters
    assert (a.part, a.wavelength_nm, a.fwhm_nm, a.power_mw) == ("L8957", 870.0, 45.0, 5.8)
    assert (b.part, b.power_mw) == ("L1909", 3.0)


def test_shunt_adds_johnson_noise_in_parallel():
    cfg = resolve_config("paper", {"detector": "G17190-010K"})
    # 100 kOhm || 125 MOhm
    assert johnson_resistance_ohm(cfg) == pytest.approx(1e5 * 125e6 / (1e5 + 125e6))
    assert johnson_resistance_ohm(resolve_config("paper", {"detector": "FGA01"})) == 1e5


def test_a_small_detector_collects_less_light():
    base = ng.simulate("paper", 4, 2, seed=0, overrides={"noise_scale": 0.0}).frame
    small = ng.simulate("paper", 4, 2, seed=0,
                        overrides={"noise_scale": 0.0, "detector": "G17190-005K"}).frame
    cols = [c for c in base.columns if c.startswith("true_signal_v_")]
    assert (small[cols].to_numpy() < base[cols].to_numpy()).all()


def test_parts_command_lists_the_catalogue():
    from typer.testing import CliRunner

    from nirglucose.cli import app

    out = CliRunner().invoke(app, ["parts"])
    assert out.exit_code == 0
    for name in (*DETECTOR_PARTS, *LED_PARTS):
        assert name in out.stdout
    assert out.stdout.count("UNCERTAIN") == sum(p.uncertain for p in LED_PARTS.values())


def test_a_detector_record_by_value():
    record = {"part": "my-pd", "material": "Si", "active_area_mm2": 5.0,
              "responsivity_table": "responsivity_si_vishay_bpw34.csv",
              "dark_current_25c_na": 1.0, "dark_current_per_c": 0.07}
    cfg = resolve_config("paper", {"detector": record})
    assert cfg.detector.part == "my-pd" and cfg.optics.detector_area_mm2 == 5.0
    with pytest.raises(ConfigError, match="detector.material"):
        resolve_config("paper", {"detector": {**record, "material": "Ge"}})
