"""Non-finite, overflowing or out-of-range settings: exit 2, one line, no file (issue 20)."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from cli_helpers import assert_one_line_error

import nirglucose as ng
from nirglucose.exceptions import ConfigError
from nirglucose.simulation.hardware import adc_convert

BAD_SETS = [
    ("noise_scale=Infinity", ["noise_scale", "finite"]),
    ("noise_scale=-Infinity", ["noise_scale"]),
    ("noise_scale=1e999", ["noise_scale", "finite"]),
    ("noise_scale=1e6", ["noise_scale", "100", "[-]"]),
    ("noise_scale=NaN", ["noise_scale", "finite"]),
    ("noise_scale=-1", ["noise_scale", "0"]),
    ("environment.pressure_mbar_mean=NaN", ["pressure_mbar_mean", "[mbar]"]),
    ("environment.pressure_mbar_mean=1e9", ["pressure_mbar_mean", "1100", "[mbar]"]),
    ("environment.pressure_mbar_mean=0", ["pressure_mbar_mean", "300", "[mbar]"]),
    ("environment.temperature_c=[NaN, 30]", ["temperature_c", "finite", "[degC]"]),
    ("noise.shot.scale=1e9", ["noise.shot.scale", "100"]),
    ("hardware.adc_bits=64", ["adc_bits", "24", "[bit]"]),
    ("hardware.adc_bit=14", ["did you mean hardware.adc_bits"]),
    ("adc_bits=14", ["did you mean hardware.adc_bits"]),
    ("noise_scale", ["key=value"]),
    ("=3", ["empty key"]),
]


@pytest.mark.parametrize(("setting", "words"), BAD_SETS, ids=[s for s, _ in BAD_SETS])
def test_bad_set_is_one_line(cli, workdir, setting, words):
    code, out, err = cli("simulate", "--out", "a.csv", "--subjects", 2, "--set", setting)
    assert_one_line_error(code, err, contains=words)
    assert not (workdir / "a.csv").exists()


@pytest.mark.parametrize("value", [float("inf"), float("nan"), 1e308])
def test_api_refuses_non_finite_or_huge(value):
    with pytest.raises(ConfigError, match="noise_scale"):
        ng.simulate("paper", 2, 1, seed=0, overrides={"noise_scale": value})


def test_adc_convert_refuses_nan_instead_of_int64_min():
    with pytest.raises(ConfigError, match="not finite"):
        adc_convert(np.array([1.0, np.nan]), 3.3, 12, 0.0, 0.0)


@pytest.mark.parametrize(("preset", "scale"), [("paper", 8), ("field", 8), ("paper", 100)])
def test_loud_noise_gives_valid_codes_or_one_line(cli, workdir, preset, scale):
    """Large (valid) noise scales: codes within 0..2^bits - 1, or a one-line refusal."""
    code, out, err = cli("simulate", "--out", "a.csv", "--subjects", 4, "--preset", preset,
                         "--set", f"noise_scale={scale}", "--set", "hardware.adc_bits=10")
    if code != 0:
        assert_one_line_error(code, err, contains=["noise"])
        assert not (workdir / "a.csv").exists()
        return
    adc = pd.read_csv(workdir / "a.csv").filter(regex=r"^adc_").to_numpy()
    assert adc.min() >= 0 and adc.max() <= 2**10 - 1


HUGE = ["hardware.adc_vref_v=1e300", "hardware.tia_gain_ohm=1e300", "glucose.signal_gain=1e308",
        "environment.pressure_mbar_sd=1e308", "hardware.bandwidth_hz=1e308",
        "hardware.led_age_h=[0,1e308]", "contact.coupling_sd=1e9",
        "physiology.variation_scale=1e308",
        "leds.emitters.0.power_mw=1e308", "measurement.age_yr=1e308"]


@pytest.mark.parametrize("setting", HUGE)
def test_absurd_magnitudes_are_one_line(cli, workdir, setting):
    """Beyond 1e9 always refused; below it, overflow is refused at the ADC: one line."""
    code, _, err = cli("simulate", "--out", "a.csv", "--subjects", 2, "--set", setting)
    assert_one_line_error(code, err, contains=[setting.split("=")[0].split(".")[-1]]
                          if "1e30" in setting else [])
    assert not (workdir / "a.csv").exists()


#: One out-of-range value per section: (setting, key as shown, range, unit).
OUT_OF_RANGE = [
    ("noise_scale=101", "noise_scale=101", "between 0 and 100", "[-]"),
    ("leds.emitters.0.power_mw=5000", "leds.emitters.0.power_mw=5000", "> 0 and <= 1000", "[mW]"),
    ("leds.band_points=0", "leds.band_points=0", "between 1 and 31", "[-]"),
    ("physiology.heart_rate_bpm_mean=400", "physiology.heart_rate_bpm_mean=400",
     "between 20 and 250", "[1/min]"),
    ("physiology.age_yr=[18,300]", "physiology.age_yr[1]=300", "between 0 and 122", "[yr]"),
    ("glucose.range_mgdl=[10,400]", "glucose.range_mgdl[0]=10", "between 20 and 600",
     "[mg/dL]"),
    ("glucose.status_probs={\"normal\":1.5,\"type2\":-0.5}", "glucose.status_probs[normal]=1.5",
     "between 0 and 1", "[-]"),
    ("environment.humidity_pct=[30,120]", "environment.humidity_pct[1]=120",
     "between 0 and 100", "[%]"),
    ("optics.detector_area_mm2=1000", "optics.detector_area_mm2=1000", "> 0 and <= 100",
     "[mm^2]"),
    ("optics.reference_tissue.glucose_mgdl=5", "optics.reference_tissue.glucose_mgdl=5",
     "between 20 and 600", "[mg/dL]"),
    ("hardware.led_self_heating_c=200", "hardware.led_self_heating_c=200", "between 0 and 75",
     "[degC]"),
    ("hardware.adc_bits=40", "hardware.adc_bits=40", "between 8 and 24", "[bit]"),
    ("contact.pressure_beta=[0,2]", "contact.pressure_beta[0]=0", "> 0 and <= 100", "[-]"),
    ("measurement.skin_temp_c=-1", "measurement.skin_temp_c=-1", "between 0 and 5", "[degC]"),
    ("device.spo2_error_pct=80", "device.spo2_error_pct=80", "between 0 and 50", "[%]"),
    ("noise.shot.scale=-2", "noise.shot.scale=-2", "between 0 and 100", "[-]"),
]


@pytest.mark.parametrize(("setting", "shown", "bounds", "unit"), OUT_OF_RANGE,
                         ids=[s for s, *_ in OUT_OF_RANGE])
def test_out_of_range_is_one_line_with_key_range_and_unit(cli, workdir, setting, shown, bounds,
                                                          unit):
    code, _, err = cli("simulate", "--out", "a.csv", "--subjects", 2, "--set", setting)
    line = assert_one_line_error(code, err, contains=[shown, "is out of range", bounds, unit])
    assert line.endswith(f"must be {bounds} {unit}"), line
    assert not (workdir / "a.csv").exists()


def test_keys_shows_each_range(cli):
    code, out, _ = cli("keys")
    assert code == 0
    lines = {ln.split(" = ")[0]: ln for ln in out.splitlines()}
    assert "[bit] (between 8 and 24)" in lines["hardware.adc_bits"]
    assert "[degC] (between -20 and 50)" in lines["environment.temperature_c"]
    assert "(between 0 and 100)" in lines["noise.shot.scale"]
