"""design.exposure: LED power within the published skin and eye limits (hand-computed)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from nirglucose.design.exposure import (
    eye_limit_power_mw,
    max_led_power_mw,
    skin_irradiance_limit_w_per_m2,
)
from nirglucose.exceptions import ConfigError


def test_skin_limit_is_the_smaller_of_the_two_published_limits():
    # ICNIRP 2013 incoherent: 20,000 x 10^0.25 J/m^2 over 10 s = 3,556.6 W/m^2;
    # laser, 10 s - 30 ks: 2 C_A kW/m^2 (C_A = 10^(0.002 (l - 700)), max 5), 1 kW/m^2 > 1400 nm
    incoherent = 20_000 * 10**0.25 / 10
    for wl, laser in ((700, 2000.0), (750, 2000 * 10 ** (0.1)), (1200, 10_000.0),
                      (1450, 1000.0), (1700, 1000.0)):
        want = min(incoherent, laser)
        assert skin_irradiance_limit_w_per_m2(wl) == pytest.approx(want, rel=1e-12)


def test_power_cap_through_the_3_5_mm_aperture_and_the_eye_limit():
    area_m2 = math.pi * 1.75e-3**2
    assert max_led_power_mw(1300) == pytest.approx(20_000 * 10**0.25 / 10 * area_m2 * 1e3)
    assert max_led_power_mw(1550) == pytest.approx(1000 * area_m2 * 1e3)  # 9.62 mW
    assert eye_limit_power_mw() == pytest.approx(100 * math.pi * 0.04 * 1e3)
    caps = max_led_power_mw(np.arange(700, 1701, 10))
    assert np.all(caps <= eye_limit_power_mw())
    assert np.all(caps > 0)


@pytest.mark.parametrize("bad", [650, 1750, float("nan")])
def test_out_of_range_wavelength_is_refused_in_one_line(bad):
    with pytest.raises(ConfigError, match="700-1700 nm"):
        max_led_power_mw(bad)
