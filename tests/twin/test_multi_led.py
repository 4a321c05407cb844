"""A three-LED device with start-up references: the twin's machinery end to end at a
tiny budget (mechanics only: the parameters per channel, the pair summaries, the
reference level; the calibration of a fit is the one-LED tests' and the benchmark's)."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import nirglucose as ng
from nirglucose.twin import InferenceSettings, load_twin

LEDS = [{"wavelength_nm": w, "fwhm_nm": 40.0, "power_mw": p, "responsivity_a_per_w": 0.5}
        for w, p in ((850.0, 2.0), (940.0, 3.0), (1150.0, 9.0))]


def test_three_leds_with_references(tmp_path, monkeypatch):
    monkeypatch.setenv("NIRGLUCOSE_CACHE", str(tmp_path / "cache"))
    ds = ng.simulate("wearable", n_subjects=8, per_subject=4, seed=5,
                     overrides={"leds": LEDS, "hardware.adc_bits": 14})
    cols = ["subject_id", "measurement_id", "glucose_mgdl"] + [
        f"adc_{w:g}" for w in (850, 940, 1150)] + [f"adc_ref_{w:g}" for w in (850, 940, 1150)]
    path = tmp_path / "three.csv"
    ds.frame[cols + ["bmi_kgm2"]].to_csv(path, index=False)
    settings = InferenceSettings(n_simulations=200, max_epochs=3, recalibration_devices=20)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        twin = ng.fit_twin(path, adc_bits=14, settings=settings, n_draws=200, ppc_devices=10)
    assert any("not identified" in str(w.message) for w in caught)  # 200 simulations
    keys = twin.fitted_keys
    for i in range(3):
        assert f"leds.emitters.{i}.glucose_gain" in keys
    assert "hardware.reference_transmission" in keys and "measurement.bmi_kgm2" in keys
    assert not twin.device.monitor and twin.device.reference
    assert {"corr_850_940", "corr_850_1150", "ref_level_1150"} <= set(twin.info["summaries"])
    twin.save(tmp_path / "tw")
    cfg = load_twin(tmp_path / "tw").scenario("posterior", seed=2)
    assert cfg.leds.wavelengths_nm == (850.0, 940.0, 1150.0) and cfg.hardware.adc_bits == 14
    sim = ng.simulate(ng.twin_scenario(tmp_path / "tw"), n_subjects=3, per_subject=2, seed=0)
    assert np.all(sim.frame[["adc_850", "adc_940", "adc_1150"]].to_numpy() <= 2 ** 14 - 1)

# Long-running (whole studies, end-to-end runs, Monte Carlo or every model): `make test-slow`,
# which CI runs beside the fast `make test` (tests/test_slow_marks.py)
pytestmark = pytest.mark.slow
