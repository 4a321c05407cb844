"""The named presets, their descriptions and the device capabilities each assumes."""

from __future__ import annotations

from typing import Any

from .scenario import ScenarioConfig

#: Device capability -> (config key, value when on, value when off). Every preset
#: sets each key to one of the two values; :func:`device_capabilities` reads them back.
DEVICE_CAPABILITIES: dict[str, tuple[str, Any, Any]] = {
    "monitor_photodiode": ("device.monitor_photodiode", True, False),
    "constant_force_probe": ("device.constant_force_probe", True, False),
    "exact_physiology": ("device.physiology", "exact", "measured"),
    "ppg_perfusion_spo2": ("device.ppg_perfusion_spo2", True, False),
    "humidity_compensation": ("device.humidity_compensation", True, False),
}

#: Glucose-signal gain of a basic wearable (``wearable``, ``lab``, ``field``): with
#: literature noise and physiology and none of the device capabilities, the raw
#: glucose-NIR correlation reaches the study's 0.21 only when glucose's optical effects
#: are 12.5 times the literature magnitudes (calibrated on 20,000 snapshots; README,
#: "Presets and calibration").
WEARABLE_SIGNAL_GAIN = 12.5
#: Glucose-signal gain of ``paper`` (the study's regime with the capabilities its
#: accuracy implies), chosen for the raw correlation alone: the gain whose raw
#: correlation (20,000 snapshots, mean over seeds 0-4) is closest to the study's 0.21,
#: on a grid of 0.5 (README, "Presets and calibration"; studies/presets.py).
PAPER_SIGNAL_GAIN = 11.0


def _capabilities(*on: str) -> dict[str, Any]:
    """Overrides that switch the named device capabilities on and every other one off."""
    return {key: (v_on if name in on else v_off) for name, (key, v_on, v_off) in
            DEVICE_CAPABILITIES.items()}


#: The capabilities the study's accuracy implies (README, "Presets and calibration").
_PAPER_CAPABILITIES = (
    "monitor_photodiode",
    "constant_force_probe",
    "exact_physiology",
    "ppg_perfusion_spo2",
    "humidity_compensation",
)

#: Preset name -> overrides on the defaults.
PRESETS: dict[str, dict[str, Any]] = {
    # The study's regime with the capabilities its accuracy implies.
    "paper": {
        "glucose.signal_gain": PAPER_SIGNAL_GAIN,
        **_capabilities(*_PAPER_CAPABILITIES),
    },
    # A basic four-LED wearable with none of the capabilities (the former ``paper``).
    "wearable": {"glucose.signal_gain": WEARABLE_SIGNAL_GAIN, **_capabilities()},
    # Literature glucose magnitudes everywhere, whatever correlation they give.
    "physical": {"glucose.signal_gain": 1.0, **_capabilities()},
    # Cuvette-like: one nominal 'subject', no ambient light, a quiet instrument.
    "lab": {
        "glucose.signal_gain": WEARABLE_SIGNAL_GAIN,
        **_capabilities(),
        "physiology.variation_scale": 0.0,
        "environment.temperature_c": (24.5, 25.5),
        "environment.temperature_within_sd_c": 0.2,
        "environment.ambient_lux": (0.1, 0.2),
        "environment.pressure_mbar_sd": 0.0,
        "noise.contact_pressure.enabled": False,
        "noise.pulsation.enabled": False,
        "noise.humidity_coupling.enabled": False,
        "noise.led_thermal_drift.scale": 0.1,
    },
    # Harsher than wearable: outdoor light, wide temperatures, motion and contact.
    "field": {
        "glucose.signal_gain": WEARABLE_SIGNAL_GAIN,
        **_capabilities(),
        "environment.temperature_c": (5.0, 35.0),
        "environment.temperature_within_sd_c": 4.0,
        "environment.ambient_lux": (1.0, 100000.0),
        "environment.light_source_probs": {"sun": 0.5, "fluorescent": 0.25, "led": 0.25},
        "contact.coupling_sd": 0.08,
        "noise_scale": 2.0,
    },
}

#: Preset name -> one-line description (``nirglucose`` help, README table).
PRESET_DESCRIPTIONS: dict[str, str] = {
    "paper": "the study's regime (raw correlation 0.21) with the device capabilities its "
    "accuracy implies",
    "wearable": "a basic four-LED wearable, no device capabilities, raw correlation 0.21 "
    "(the former 'paper')",
    "physical": "literature glucose magnitudes throughout, basic wearable",
    "lab": "cuvette-like: one nominal subject, no ambient light, a quiet instrument",
    "field": "outdoor light, 5-35 degC, motion and contact, noise x 2, basic wearable",
}


def device_capabilities(cfg: ScenarioConfig) -> tuple[str, ...]:
    """Names of the :data:`DEVICE_CAPABILITIES` switched on in a scenario.

    Examples
    --------
    >>> from nirglucose.config import resolve_config
    >>> device_capabilities(resolve_config("wearable"))
    ()
    """
    out = []
    for name, (key, v_on, _) in DEVICE_CAPABILITIES.items():
        node: Any = cfg
        for part in key.split("."):
            node = getattr(node, part)
        if node == v_on:
            out.append(name)
    return tuple(out)


#: Preset name -> the device capabilities it assumes (kept as data; a test checks it
#: against the resolved presets).
PRESET_CAPABILITIES: dict[str, tuple[str, ...]] = {
    "paper": _PAPER_CAPABILITIES,
    "wearable": (),
    "physical": (),
    "lab": (),
    "field": (),
}
