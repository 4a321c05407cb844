"""Device capabilities (``device.*``): each does what it claims, and only that.

Pairs of runs share the seed, so every other noise source draws the same numbers
(per-source random streams): a difference between the two runs is the toggled source's.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

import nirglucose as ng
from nirglucose.config import DEVICE_CAPABILITIES, resolve_config
from nirglucose.simulation.measurement import PMF_COLUMNS, PPG_COLUMNS

WL = ("850", "940", "1050", "1150")
N_SUBJECTS, PER = 500, 4


def _log_ratio(ds) -> np.ndarray:
    f = ds.frame
    adc = f[[f"adc_{w}" for w in WL]].to_numpy(float)
    ref = f[[f"adc_ref_{w}" for w in WL]].to_numpy(float)
    return np.log(adc / ref)


def _toggle_effect(source: str, monitor: bool, **extra) -> float:
    """SD of the change of log(adc/adc_ref) when one noise source is switched off."""
    over = {"device.monitor_photodiode": monitor, **extra}
    on = ng.simulate("wearable", N_SUBJECTS, PER, 5, overrides=over)
    off = ng.simulate(
        "wearable", N_SUBJECTS, PER, 5, overrides={**over, f"noise.{source}.enabled": False}
    )
    return float((_log_ratio(on) - _log_ratio(off)).std())


# Scales make each LED-power source large enough to see against 12-bit quantisation;
# thermal drift is taken without the wavelength shift (the power part alone).
LED_POWER_SOURCES = {
    "led_flicker": {"noise.led_flicker.scale": 10.0},
    "led_ageing": {"noise.led_ageing.scale": 100.0},
    "led_thermal_drift": {
        "noise.led_thermal_drift.scale": 5.0,
        "noise.led_wavelength_shift.enabled": False,
    },
}


@pytest.mark.parametrize("source", list(LED_POWER_SOURCES))
def test_monitor_photodiode_cancels_led_power_noise(source):
    extra = LED_POWER_SOURCES[source]
    without = _toggle_effect(source, False, **extra)
    with_monitor = _toggle_effect(source, True, **extra)
    assert without > 3e-3, without  # the source matters with a start-up reference
    # with the monitor only its own conversion (about 1 LSB of ~2,900) remains
    assert 0 < with_monitor < 1e-3, with_monitor
    assert with_monitor < 0.1 * without


def test_monitor_photodiode_does_not_cancel_the_wavelength_shift():
    without = _toggle_effect("led_wavelength_shift", False)
    with_monitor = _toggle_effect("led_wavelength_shift", True)
    assert with_monitor > 2e-3
    assert with_monitor > 0.9 * without


def test_monitor_reference_is_per_reading_with_its_own_noise():
    base = ng.simulate("wearable", 50, 4, 2).frame
    mon = ng.simulate("wearable", 50, 4, 2, overrides={"device.monitor_photodiode": True}).frame
    ref = [f"adc_ref_{w}" for w in WL]
    # start-up reference: one value per subject; monitor: one per reading
    assert (base.groupby("subject_id")[ref].nunique() == 1).all().all()
    assert (mon.groupby("subject_id")[ref].nunique() > 1).any().any()
    # the measurement codes themselves are untouched
    np.testing.assert_array_equal(base[[f"adc_{w}" for w in WL]], mon[[f"adc_{w}" for w in WL]])
    # one monitor code per reading, mid- to high-scale like the start-up reference
    assert int(mon[ref].to_numpy().min()) > 0.5 * 4095


def test_constant_force_probe_removes_contact_variation():
    cfg = {"device.constant_force_probe": True}
    f = ng.simulate("wearable", 200, 3, 4, overrides=cfg).frame
    free = ng.simulate("wearable", 200, 3, 4).frame
    c = resolve_config("wearable").contact
    CONSTANT_FORCE_CONTACT = c.constant_force_pressure  # noqa: N806
    assert (f["true_contact_pressure"] == CONSTANT_FORCE_CONTACT).all()
    assert free["true_contact_pressure"].std() > 0.1
    blanch = f["true_blood_fraction_detected"] / f["true_blood_fraction"]
    np.testing.assert_allclose(blanch, np.exp(-c.blanching * CONSTANT_FORCE_CONTACT), rtol=1e-12)
    thick = f["true_skin_thickness_probe_mm"] / f["true_skin_thickness_mm"]
    np.testing.assert_allclose(thick, np.exp(-c.compression * CONSTANT_FORCE_CONTACT), rtol=1e-12)
    # the coupling keeps only the humidity term: identical to a run without contact noise
    no_contact = ng.simulate(
        "wearable", 200, 3, 4, overrides={"noise.contact_pressure.enabled": False}
    ).frame
    np.testing.assert_allclose(f["true_coupling"], no_contact["true_coupling"], rtol=1e-12)
    assert not np.allclose(free["true_coupling"], no_contact["true_coupling"])


def test_exact_physiology_equals_the_truth():
    f = ng.simulate("wearable", 100, 2, 1, overrides={"device.physiology": "exact"}).frame
    for col in PMF_COLUMNS:
        truth = "true_fitzpatrick_type" if col == "fitzpatrick_type" else f"true_{col}"
        np.testing.assert_array_equal(f[col].to_numpy(), f[truth].to_numpy(), err_msg=col)
    measured = ng.simulate("wearable", 100, 2, 1).frame
    assert not np.array_equal(measured["bmi_kgm2"], measured["true_bmi_kgm2"])


def test_ppg_columns_only_when_on():
    off = ng.simulate("wearable", 20, 2, 0).frame
    on = ng.simulate("wearable", 20, 2, 0, overrides={"device.ppg_perfusion_spo2": True}).frame
    assert not set(PPG_COLUMNS) & set(off.columns)
    assert set(PPG_COLUMNS) <= set(on.columns)
    assert set(PPG_COLUMNS) <= set(ng.simulate("paper", 5, 2, 0).frame.columns)


def test_ppg_columns_track_the_truth_within_the_stated_error():
    cfg = resolve_config("wearable", {"device.ppg_perfusion_spo2": True})
    f = ng.simulate("wearable", 2500, 4, 3, overrides={"device.ppg_perfusion_spo2": True}).frame
    err_spo2 = f["spo2_pct"] - 100 * f["true_saturation"]
    err_bv = np.log(f["blood_volume_pct"] / (100 * f["true_blood_fraction_detected"]))
    assert abs(err_spo2.std() / cfg.device.spo2_error_pct - 1) < 0.05
    assert abs(err_spo2.mean()) < 0.1
    assert abs(err_bv.std() / cfg.device.blood_volume_error_rel - 1) < 0.05
    exact = ng.simulate(
        "wearable",
        50,
        2,
        3,
        overrides={"device.ppg_perfusion_spo2": True, "device.physiology": "exact"},
    ).frame
    np.testing.assert_allclose(exact["spo2_pct"], 100 * exact["true_saturation"], rtol=1e-12)
    np.testing.assert_allclose(
        exact["blood_volume_pct"], 100 * exact["true_blood_fraction_detected"], rtol=1e-12
    )


def test_humidity_compensation_leaves_only_the_sensor_error():
    on = {"device.humidity_compensation": True}
    lo, hi = resolve_config("wearable").environment.humidity_pct
    loss = resolve_config("wearable").environment.humidity_coupling_loss
    comp = ng.simulate("wearable", 200, 3, 6, overrides=on).frame
    dry = ng.simulate(
        "wearable", 200, 3, 6, overrides={"noise.humidity_coupling.enabled": False}
    ).frame
    residual = np.log(comp["true_coupling"] / dry["true_coupling"])
    expected = -loss * (comp["true_humidity_pct"] - comp["humidity_pct"]) / (hi - lo)
    np.testing.assert_allclose(residual, expected, atol=1e-12)
    exact = ng.simulate(
        "wearable", 200, 3, 6, overrides={**on, "device.physiology": "exact"}
    ).frame
    np.testing.assert_allclose(exact["true_coupling"], dry["true_coupling"], rtol=1e-12)


@pytest.mark.parametrize("capability", list(DEVICE_CAPABILITIES))
def test_a_capability_leaves_glucose_and_physiology_untouched(capability):
    key, v_on, _ = DEVICE_CAPABILITIES[capability]
    a = ng.simulate("wearable", 30, 2, 8).frame
    b = ng.simulate("wearable", 30, 2, 8, overrides={key: v_on}).frame
    for col in ("glucose_mgdl", "true_saturation", "true_blood_fraction", "true_bmi_kgm2"):
        np.testing.assert_array_equal(a[col], b[col])


def test_wearable_is_byte_identical_to_the_former_paper():
    # Frame hashes (Dataset.content_hash) of `wearable` (the `paper` preset of main's
    # 84c2453, before the device capabilities existed, renamed). Re-recorded once by issue
    # 27, whose CPU-independent arithmetic moved the last bits (nirglucose.portable); the
    # renaming itself had been checked against 84c2453's hashes before that.
    assert ng.simulate("wearable", 40, 3, 7).content_hash() == "1319179e4334fcd0"
    assert ng.simulate("wearable", 4100, 1, 0).content_hash() == "e1be0ab34bfaaa83"
    diffusion = ng.simulate("wearable", 40, 3, 7, overrides={"optics.model": "diffusion"})
    assert diffusion.content_hash() == "ea6ae21681803eb0"


def test_paper_is_deterministic_across_chunks_and_workers(monkeypatch):
    # test_simulate_determinism covers `paper` too; here the PPG stream and the
    # monitor's streams are checked across blocks and workers explicitly
    from nirglucose.simulation import _random
    from nirglucose.simulation.simulator import block_ranges, simulate_frame

    monkeypatch.setattr(_random, "BLOCK_SUBJECTS", 10)
    cfg = resolve_config("paper", {"device.physiology": "measured"})
    assert len(block_ranges(40)) == 4
    one = simulate_frame(cfg, 40, 2, 9, n_jobs=1)
    two = simulate_frame(cfg, 40, 2, 9, n_jobs=2)
    pd.testing.assert_frame_equal(one, two)
    small = simulate_frame(cfg, 20, 2, 9)
    pd.testing.assert_frame_equal(small, one.iloc[: len(small)].reset_index(drop=True))


def test_measured_physiology_stays_within_instrument_display_ranges():
    """At measurement errors scaled far beyond the instruments' (noise_scale 8) the
    reported values stay inside the display ranges, so every estimator accepts the data;
    without the clip systolic pressure and humidity left them (44 mmHg, 101 %RH)."""
    from nirglucose.constants import PHYSIOLOGICAL_RANGES

    ds = ng.simulate(
        preset="paper", n_subjects=60, per_subject=3, seed=3,
        overrides={"noise_scale": 8, "device.physiology": "measured"},
    )
    for col, (lo, hi, _) in PHYSIOLOGICAL_RANGES.items():
        if col in ds.frame:
            values = ds.frame[col].to_numpy(float)
            assert values.min() >= lo and values.max() <= hi, col
    # and the errors are really that large: some value sits at a range end
    assert (ds.frame["humidity_pct"] == 100.0).any() or (ds.frame["humidity_pct"] == 0).any() or (
        ds.frame["systolic_bp_mmhg"].min() == PHYSIOLOGICAL_RANGES["systolic_bp_mmhg"][0]
    )
