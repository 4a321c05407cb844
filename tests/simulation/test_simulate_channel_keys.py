"""Per-channel LED keys (issue 41, the twin): glucose_gain, read_noise_lsb, flicker_rel."""

from __future__ import annotations

import numpy as np
import pytest

import nirglucose as ng

_LEDS = [{"wavelength_nm": 940.0, "fwhm_nm": 40.0, "power_mw": 3.0, "responsivity_a_per_w": 0.5},
         {"wavelength_nm": 1150.0, "fwhm_nm": 40.0, "power_mw": 8.0, "responsivity_a_per_w": 0.3}]


def _frame(leds, **over):
    return ng.simulate("physical", n_subjects=30, per_subject=4, seed=3,
                       overrides={"leds": leds, "hardware.adc_bits": 16, **over}).frame


def test_led_glucose_gain_equal_to_signal_gain_is_the_same_data():
    same = [{**e, "glucose_gain": 7.0} for e in _LEDS]
    a = _frame(_LEDS, **{"glucose.signal_gain": 7.0})
    b = _frame(same, **{"glucose.signal_gain": 1.0})
    cols = ["adc_940", "adc_1150", "true_detected_fraction_940", "true_detected_fraction_1150"]
    np.testing.assert_array_equal(a[cols].to_numpy(), b[cols].to_numpy())


def test_led_glucose_gain_moves_only_its_own_channel():
    base = _frame(_LEDS)
    one = _frame([_LEDS[0], {**_LEDS[1], "glucose_gain": 50.0}])
    np.testing.assert_array_equal(base["true_detected_fraction_940"],
                                  one["true_detected_fraction_940"])
    # glucose (about 5-20 mM) at 50x the published effect changes the 1150 nm light
    d = one["true_detected_fraction_1150"] / base["true_detected_fraction_1150"] - 1.0
    assert np.abs(d).max() > 1e-3
    # and more for more glucose: the change follows the row's glucose (through each
    # person's tissue, so not exactly)
    assert abs(np.corrcoef(d, base["glucose_mgdl"])[0, 1]) > 0.9


def test_read_noise_adds_white_noise_of_its_size_to_its_channel_only():
    quiet = _frame(_LEDS)
    noisy = _frame([{**_LEDS[0], "read_noise_lsb": 200.0}, _LEDS[1]])
    np.testing.assert_array_equal(quiet["adc_1150"], noisy["adc_1150"])
    diff = (noisy["adc_940"] - quiet["adc_940"]).to_numpy(float)
    assert 170 < diff.std() < 230  # 120 draws of SD 200 LSB


def test_flicker_rel_per_led():
    base = _frame(_LEDS)
    flick = _frame([{**_LEDS[0], "flicker_rel": 0.02}, _LEDS[1]])
    np.testing.assert_array_equal(base["adc_1150"], flick["adc_1150"])
    rel = (flick["adc_940"] / base["adc_940"] - 1.0).to_numpy(float)
    assert 0.015 < rel.std() < 0.025


@pytest.mark.parametrize("bad", [{"glucose_gain": 0.0}, {"read_noise_lsb": -1.0},
                                 {"flicker_rel": 0.5}])
def test_channel_keys_out_of_range_refused(bad):
    with pytest.raises(ng.ConfigError):
        ng.resolve_config("physical", {"leds": [{**_LEDS[0], **bad}]})
