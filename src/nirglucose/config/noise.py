"""The noise sources, each with an on/off switch and a scale (``noise.<name>``).

Most are on by default. :data:`DEFAULT_OFF_NOISE_SOURCES` are off unless a scenario
switches them on: confounders at published magnitude added after the presets were
calibrated, kept off so that every preset's data stay byte-identical (issue 40).
"""

from __future__ import annotations

from pydantic import Field

from ._base import _Model

#: Noise sources, each with an on/off switch and a scale in ``noise.<name>``.
NOISE_SOURCES = (
    "led_thermal_drift",
    "led_ageing",
    "led_flicker",
    "led_wavelength_shift",
    "dark_current",
    "shot",
    "johnson",
    "adc_inl",
    "adc_offset_drift",
    "ambient_light",
    "humidity_coupling",
    "contact_pressure",
    "pulsation",
    "pmf_measurement",
    "water_temperature",
)

#: Sources off by default (``noise.<name>.enabled = false``): ``water_temperature``, water's
#: absorption following the skin temperature (Röttgers et al., Opt. Express 22, 25093
#: (2014); :func:`nirglucose.optics.absorption.water_mua_at_temperature_per_cm`).
DEFAULT_OFF_NOISE_SOURCES = ("water_temperature",)


class NoiseSource(_Model):
    """One noise source's switch and scale."""

    enabled: bool = True
    scale: float = Field(1.0, ge=0, le=100)  # as noise_scale


class NoiseConfig(_Model):
    """A switch and a scale for every noise source in :data:`NOISE_SOURCES`."""

    led_thermal_drift: NoiseSource = NoiseSource()
    led_ageing: NoiseSource = NoiseSource()
    led_flicker: NoiseSource = NoiseSource()
    led_wavelength_shift: NoiseSource = NoiseSource()
    dark_current: NoiseSource = NoiseSource()
    shot: NoiseSource = NoiseSource()
    johnson: NoiseSource = NoiseSource()
    adc_inl: NoiseSource = NoiseSource()
    adc_offset_drift: NoiseSource = NoiseSource()
    ambient_light: NoiseSource = NoiseSource()
    humidity_coupling: NoiseSource = NoiseSource()
    contact_pressure: NoiseSource = NoiseSource()
    pulsation: NoiseSource = NoiseSource()
    pmf_measurement: NoiseSource = NoiseSource()
    # scale multiplies water's d(mua)/dT; off by default (DEFAULT_OFF_NOISE_SOURCES)
    water_temperature: NoiseSource = NoiseSource(enabled=False)
