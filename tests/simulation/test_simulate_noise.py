"""Each noise source has a switch; turning one off removes exactly its contribution.

Every source draws from its own random stream, so with the same seed the other
sources' draws are unchanged: the difference between the analog voltages with the
source on and off is that source's noise alone, and its variance must match the
source's physics.
"""

from __future__ import annotations

import numpy as np
import pytest

import nirglucose as ng
from nirglucose.constants import BOLTZMANN_J_PER_K, ELEMENTARY_CHARGE_C, ZERO_CELSIUS_K

N_SUBJECTS, PER = 2500, 4
WL = ("850", "940", "1050", "1150")


def _voltages(ds):
    return ds.frame[[f"true_voltage_v_{w}" for w in WL]].to_numpy()


def _pair(source, preset="paper", **extra):
    on = ng.simulate(preset, N_SUBJECTS, PER, 11, overrides=extra)
    off = ng.simulate(
        preset, N_SUBJECTS, PER, 11, overrides={**extra, f"noise.{source}.enabled": False}
    )
    return on, off


def test_shot_noise_removed_exactly():
    on, off = _pair("shot")
    cfg = on.config.hardware
    diff = _voltages(on) - _voltages(off)
    current = _voltages(off) / cfg.tia_gain_ohm
    expected_sd = np.sqrt(2 * ELEMENTARY_CHARGE_C * current * cfg.bandwidth_hz) * cfg.tia_gain_ohm
    z = diff / expected_sd
    assert abs(z.var() - 1.0) < 0.05
    assert abs(z.mean()) < 0.05


def test_johnson_noise_removed_exactly():
    on, off = _pair("johnson")
    cfg = on.config.hardware
    diff = _voltages(on) - _voltages(off)
    t_k = on.frame["true_board_temperature_c"].to_numpy()[:, None] + ZERO_CELSIUS_K
    expected_sd = np.sqrt(4 * BOLTZMANN_J_PER_K * t_k * cfg.bandwidth_hz / cfg.tia_gain_ohm)
    z = diff / (expected_sd * cfg.tia_gain_ohm)
    assert abs(z.var() - 1.0) < 0.05


def test_led_flicker_removed_exactly():
    on, off = _pair("led_flicker")
    rel = (_voltages(on) - _voltages(off)) / on.frame[[f"true_signal_v_{w}" for w in WL]].to_numpy()
    assert abs(rel.std() / on.config.hardware.led_flicker_rel - 1.0) < 0.05


def test_flicker_variance_adds_on_a_fixed_phantom():
    # lab preset: one nominal subject, so glucose and flicker make most of the spread;
    # independent sources' variances add: Var(on) - Var(off) = Var(flicker). Flicker is
    # scaled x10 so its share dominates the sampling error of the covariance term.
    on, off = _pair("led_flicker", preset="lab", **{"noise.led_flicker.scale": 10.0})
    v_on, v_off = _voltages(on), _voltages(off)
    contribution = v_on.var(axis=0) - v_off.var(axis=0)
    expected = (v_on - v_off).var(axis=0)
    np.testing.assert_allclose(contribution, expected, rtol=0.15)


@pytest.mark.parametrize("source", ["led_thermal_drift", "ambient_light", "contact_pressure"])
def test_switching_a_source_off_changes_nothing_else(source):
    # the off run differs from the on run only through that source: the detected
    # optical fraction is untouched unless the source acts on the optics
    on, off = _pair(source)
    for col in ("glucose_mgdl", "true_melanin_fraction", "true_saturation", "true_water_fraction"):
        np.testing.assert_array_equal(on.frame[col], off.frame[col])
    assert not np.array_equal(_voltages(on), _voltages(off))


def test_noise_scale_zero_gives_deterministic_voltage():
    ds = ng.simulate("paper", 50, 2, 0, overrides={"noise_scale": 0.0})
    sig = ds.frame[[f"true_signal_v_{w}" for w in WL]].to_numpy()
    # with every source off the analog voltage is the noise-free signal (the reference
    # temperature drift and dark-current residual are noise sources too)
    np.testing.assert_allclose(_voltages(ds), sig, rtol=1e-12)


def test_noise_scale_grows_error():
    def spread(scale):
        on = ng.simulate("lab", 500, 2, 5, overrides={"noise_scale": scale})
        off = ng.simulate("lab", 500, 2, 5, overrides={"noise_scale": 0.0})
        return np.std(_voltages(on) - _voltages(off))

    s1, s2, s4 = spread(1.0), spread(2.0), spread(4.0)
    assert s1 < s2 < s4
