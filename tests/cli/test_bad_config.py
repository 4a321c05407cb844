"""Non-finite, overflowing or out-of-range settings: exit 2, one line, no file (issue 20)."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from cli_helpers import assert_one_line_error

import nirglucose as ng
from nirglucose.exceptions import ConfigError
from nirglucose.simulate.hardware import adc_convert

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
