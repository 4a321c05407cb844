"""design.averaging: readings in a window, the lag of an averaged estimate, emulation."""

from __future__ import annotations

import numpy as np
import pytest

from nirglucose.config import resolve_config
from nirglucose.design.averaging import (
    averaging_overrides,
    cycle_s,
    glucose_lag_rmse_mgdl,
    readings_in,
    window_error_rmse_mgdl,
)
from nirglucose.exceptions import ConfigError


def test_cycle_and_readings():
    assert cycle_s(4, 10.0) == pytest.approx(0.25)  # 5 frames of 1 / (2 x 10 Hz)
    assert readings_in(60.0, 4, 10.0) == 240
    assert readings_in(0.0, 9, 10.0) == 1
    assert readings_in(0.4, 4, 10.0) == 1
    with pytest.raises(ConfigError):
        readings_in(-1.0, 4, 10.0)
    with pytest.raises(ConfigError):
        cycle_s(0, 10.0)


def test_window_error_is_exact_for_a_ramp_and_zero_for_a_constant():
    ramp = (3.0 * np.arange(200.0))[None, :]  # 3 mg/dL per minute
    windows = [0.0, 0.25, 1.0, 2.5, 10.0]
    # the mean over [t - T, t] of a ramp lags it by rate x T / 2
    np.testing.assert_allclose(window_error_rmse_mgdl(ramp, windows),
                               [3.0 * w / 2 for w in windows], rtol=1e-12, atol=1e-12)
    assert np.all(window_error_rmse_mgdl(np.full((2, 50), 120.0), windows) == 0)


def test_window_error_of_a_parabola_matches_the_integral():
    t = np.arange(300.0)
    g = (0.01 * t**2)[None, :]  # linear between samples is not exact for a parabola...
    err = window_error_rmse_mgdl(g, [4.0])[0]
    # ...but the trapezoid error over whole minutes is small: exact mean over [t-4, t] of
    # 0.01 s^2 is 0.01 (t^2 - 4 t + 16 / 3); the trapezoid adds 0.01 / 6 per minute
    tt = t[5:]
    exact = 0.01 * tt**2 - 0.01 * (tt**2 - 4 * tt + 16 / 3)
    assert err == pytest.approx(np.sqrt(np.mean((exact - 0.01 / 6) ** 2)), rel=1e-9)


def test_lag_grows_with_the_window_from_zero():
    lag = glucose_lag_rmse_mgdl([0.0, 30.0, 60.0, 300.0, 1800.0], "physical", n_subjects=4,
                                wear_days=1)
    assert lag[0] == 0
    assert np.all(np.diff(lag) > 0)
    # the worn trajectories change by well under 5 mg/dL per minute on average
    assert lag[2] < 5.0 * 0.5


def test_emulation_overrides():
    cfg = resolve_config("physical")
    assert averaging_overrides(cfg, 1) == {}
    ov = averaging_overrides(cfg, 64)
    assert ov["hardware.bandwidth_hz"] == pytest.approx(cfg.hardware.bandwidth_hz / 64)
    assert ov["hardware.led_flicker_rel"] == pytest.approx(cfg.hardware.led_flicker_rel / 8)
    assert ov["hardware.adc_bits"] == cfg.hardware.adc_bits + 3
    assert averaging_overrides(resolve_config("physical", {"hardware.adc_bits": 22}),
                               4096)["hardware.adc_bits"] == 24
    resolve_config("physical", ov)  # real config keys
