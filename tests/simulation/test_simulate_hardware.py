"""Hardware kernels against their formulas."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from nirglucose.simulation import hardware


@given(
    p0=st.floats(1e-4, 0.05),
    t=st.floats(-10.0, 80.0),
    age=st.floats(0.0, 50_000.0),
    n=st.floats(-0.005, 0.005),
)
def test_led_power_follows_the_thermal_formula(p0, t, age, n):
    # DESIGN.md: P = P0 [1 - 0.002 (T - 25) - 0.001 t/1000h + N]
    expected = p0 * (1 - 0.002 * (t - 25) - 0.001 * age / 1000 + n)
    assert hardware.led_power_w(p0, t, age, n) == pytest.approx(expected, rel=1e-12)


def test_led_power_falls_with_temperature():
    p = hardware.led_power_w(1e-3, np.array([15.0, 25.0, 45.0]), 0.0, 0.0)
    assert p[0] > p[1] > p[2] and p[1] == pytest.approx(1e-3)


def test_dark_current_and_noise_formulas():
    assert hardware.dark_current_a(1e-10, 25.0) == pytest.approx(1e-10)
    assert hardware.dark_current_a(1e-10, 32.0) == pytest.approx(1e-10 * np.exp(0.7))
    # sqrt(2 * 1.602176634e-19 * 1e-6 * 10) = 1.7900e-12 A
    assert hardware.shot_noise_sd_a(1e-6, 10.0) == pytest.approx(1.79004e-12, rel=1e-4)
    # sqrt(4 * 1.380649e-23 * 298.15 * 10 / 1e5) = 1.28312e-12 A
    assert hardware.johnson_noise_sd_a(25.0, 10.0, 1e5) == pytest.approx(1.28312e-12, rel=1e-4)


def test_adc_quantises_clips_and_bows():
    codes = hardware.adc_convert(np.array([-1.0, 0.0, 1.65, 3.3, 9.0]), 3.3, 12, 0.0, 0.0)
    np.testing.assert_array_equal(codes, [0, 0, 2048, 4095, 4095])
    assert codes.dtype == np.int64
    bowed = hardware.adc_convert(np.array([1.65]), 3.3, 12, 2.0, 0.0)
    assert bowed[0] == 2050  # 2047.5 + 2 LSB INL at mid-scale -> 2049.5 -> 2050 (round half even)
    shifted = hardware.adc_convert(np.array([1.0]), 3.3, 12, 0.0, 3.0)
    assert shifted[0] == round(1.0 / 3.3 * 4095) + 3
