"""Units of a fleet: deterministic draws within the stated tolerances, relabelled data."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

import nirglucose as ng
from nirglucose.config import resolve_config
from nirglucose.config.detector import band_responsivity_a_per_w, responsivity_curve
from nirglucose.design.fleet import (
    FleetTolerances,
    apply_adc_offset,
    draw_units,
    simulate_unit,
)
from nirglucose.exceptions import ConfigError


def _draws(units):
    return [(u.wavelength_shift_nm, u.power_ratio, u.responsivity_ratio, u.adc_offset_lsb,
             u.overrides) for u in units]


def test_draws_are_deterministic_per_seed_and_unit_index():
    a = draw_units("paper", 5, 1.0, seed=3)
    assert _draws(a) == _draws(draw_units("paper", 5, 1.0, seed=3))
    # unit i depends on (seed, i) only, not on how many units are drawn
    assert _draws(draw_units("paper", 2, 1.0, seed=3)) == _draws(a[:2])
    assert _draws(draw_units("paper", 5, 1.0, seed=4)) != _draws(a)
    assert len({u.wavelength_shift_nm for u in a}) == 5  # distinct units


@pytest.mark.parametrize("scale", [0.5, 1.0, 2.0])
def test_draws_lie_within_the_scaled_tolerances(scale):
    tol = FleetTolerances()
    units = draw_units("paper", 40, scale, seed=0)
    shift = np.array([u.wavelength_shift_nm for u in units])
    power = np.array([u.power_ratio for u in units])
    resp = np.array([u.responsivity_ratio for u in units])
    offset = np.array([u.adc_offset_lsb for u in units])
    assert np.abs(shift).max() <= scale * tol.wavelength_half_width_nm + 1e-9
    assert power.max() <= 1.0 and power.min() >= 1 - scale * (1 - tol.power_min_ratio)
    assert np.abs(resp - 1).max() <= scale * tol.responsivity_rel + 1e-12
    assert np.abs(offset).max() <= round(scale * tol.adc_offset_lsb)
    # the draws fill the band (40 uniform draws per LED: the widest lies near the edge)
    assert np.abs(shift).max() > 0.8 * scale * tol.wavelength_half_width_nm
    # the records carry the draws
    nominal = resolve_config("paper").leds
    for u in units[:3]:
        recs = u.overrides["leds"]
        for j, r in enumerate(recs):
            assert r["wavelength_nm"] == pytest.approx(nominal.wavelengths_nm[j]
                                                       + u.wavelength_shift_nm[j])
            assert r["power_mw"] == pytest.approx(nominal.power_mw[j] * u.power_ratio[j])
            assert r["responsivity_a_per_w"] == pytest.approx(
                nominal.responsivity_a_per_w[j] * u.responsivity_ratio)


def test_scales_pair_the_same_units():
    one, two = draw_units("paper", 3, 1.0, seed=1), draw_units("paper", 3, 2.0, seed=1)
    for a, b in zip(one, two, strict=True):
        np.testing.assert_allclose(b.wavelength_shift_nm, 2 * np.array(a.wavelength_shift_nm),
                                   atol=0.011)
        assert b.responsivity_ratio - 1 == pytest.approx(2 * (a.responsivity_ratio - 1))


def test_scale_zero_unit_reads_as_the_design():
    (unit,) = draw_units("paper", 1, 0.0, seed=2)
    assert unit.wavelength_shift_nm == (0.0,) * 4 and unit.adc_offset_lsb == 0
    ds = simulate_unit(unit, "paper", 6, 2, seed=5)
    ref = ng.simulate("paper", 6, 2, 5)
    pd.testing.assert_frame_equal(ds.frame, ref.frame)


def test_shifted_unit_keeps_the_nominal_channel_names():
    (unit,) = draw_units("paper", 1, 2.0, seed=0)
    ds = simulate_unit(unit, "paper", 4, 2, seed=1)
    ref = ng.simulate("paper", 4, 2, 1)
    assert list(ds.frame.columns) == list(ref.frame.columns)
    assert ds.config.leds.wavelengths_nm == ref.config.leds.wavelengths_nm
    # another peak, another reading: the unit's codes differ from the nominal device's
    assert not ds.frame["adc_1150"].equals(ref.frame["adc_1150"])


def test_detector_responsivity_follows_the_units_peak():
    over = {"detector": "G17190-005K"}
    (unit,) = draw_units("paper", 1, 1.0, seed=0, overrides=over)
    curve = responsivity_curve(resolve_config("paper", over).detector)
    for r in unit.overrides["leds"]:
        want = band_responsivity_a_per_w(r["wavelength_nm"], r["fwhm_nm"], curve)
        assert r["responsivity_a_per_w"] == pytest.approx(want * unit.responsivity_ratio)


def test_adc_offset_shifts_codes_and_saturates():
    f = pd.DataFrame({"adc_850": [1, 2000, 4094], "adc_ref_850": [10, 20, 30],
                      "glucose_mgdl": [90.0, 100.0, 110.0]})
    out = apply_adc_offset(f, -2, 12)
    assert out["adc_850"].tolist() == [0, 1998, 4092]
    assert out["adc_ref_850"].tolist() == [8, 18, 28]
    assert out["glucose_mgdl"].tolist() == [90.0, 100.0, 110.0]
    assert apply_adc_offset(f, 5, 12)["adc_850"].tolist() == [6, 2005, 4095]


def test_catalogue_bin():
    from nirglucose.config.parts import led_part

    smc = led_part("SMC870")  # the default's source: its 860-880 nm bin
    want = (smc.wavelength_max_nm - smc.wavelength_min_nm) / 2
    assert FleetTolerances().wavelength_half_width_nm == want == 10.0
    assert FleetTolerances.from_catalogue("L8957").wavelength_half_width_nm == 30.0
    with pytest.raises(ConfigError, match="no wavelength bin"):
        FleetTolerances.from_catalogue("IR-1W-850")


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"n_units": 0}, "n_units"),
        ({"seed": -1}, "seed"),
        ({"tolerance_scale": -0.5}, "tolerance_scale"),
        ({"tolerance_scale": 9.0}, "tolerance_scale"),
        ({"tolerance_scale": "wide"}, "tolerance_scale"),
    ],
)
def test_bad_inputs_raise_one_line(kwargs, match):
    args = {"preset": "paper", "n_units": 2, "tolerance_scale": 1.0, "seed": 0, **kwargs}
    with pytest.raises(ConfigError, match=match) as err:
        draw_units(**args)
    assert "\n" not in str(err.value)


def test_adc_offset_must_be_integer():
    with pytest.raises(ConfigError, match="integer"):
        apply_adc_offset(pd.DataFrame({"adc_850": [1]}), 0.5, 12)
