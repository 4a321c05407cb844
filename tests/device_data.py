"""Simulated devices other than the study's, for the any-device tests."""

from __future__ import annotations

import nirglucose as ng

#: LED sets: one LED, three, six (all inside the first optics tables' 700-1300 nm).
LED_SETS = {
    1: (940.0,),
    3: (850.0, 940.0, 1150.0),
    6: (760.0, 850.0, 940.0, 1050.0, 1150.0, 1250.0),
}


def device_overrides(wavelengths_nm, adc_bits: int) -> dict:
    """Simulator overrides for a device with these LEDs and ADC resolution."""
    led = {"fwhm_nm": 40.0, "power_mw": 3.0, "responsivity_a_per_w": 0.5}
    return {
        "leds": [{"wavelength_nm": float(w), **led} for w in wavelengths_nm],
        "hardware.adc_bits": adc_bits,
    }


def simulate_device(
    n_leds: int,
    adc_bits: int,
    n_subjects: int = 8,
    per_subject: int = 3,
    seed: int = 0,
    preset: str = "wearable",
):
    """A small simulated dataset of a device with ``n_leds`` LEDs at ``adc_bits`` bits."""
    return ng.simulate(
        preset,
        n_subjects=n_subjects,
        per_subject=per_subject,
        seed=seed,
        overrides=device_overrides(LED_SETS[n_leds], adc_bits),
    )
