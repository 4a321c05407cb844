"""Drift over time (issue 41): a drift parameter per channel, fitted from a file's reading
times and held at its prior ("not identified", with the reason) without them."""

from __future__ import annotations

import json
import warnings

import numpy as np
import pandas as pd
import pytest

import nirglucose as ng
from nirglucose.exceptions import DataError
from nirglucose.report.twin import _drift_lines
from nirglucose.twin import load_twin
from nirglucose.twin.device import TwinDevice, base_overrides, device_of
from nirglucose.twin.parameters import fitted_parameters, held_parameters
from nirglucose.twin.summaries import summaries, summary_names

from .hand_twin import hand_twin

LED = {"wavelength_nm": 940.0, "fwhm_nm": 40.0, "power_mw": 3.0,
       "responsivity_a_per_w": 0.5}


def _worn(ageing: float, seed: int = 3) -> ng.Dataset:
    return ng.simulate("physical", 12, 6, seed, overrides={
        "device.reading_times": True, "hardware.hours_since_reference_h": [0, 336],
        "hardware.adc_bits": 12, "leds": [{**LED, "ageing_per_1000h": ageing}]})


def test_reading_times_column_and_per_led_ageing():
    plain = ng.simulate("physical", 4, 3, 0).frame
    assert "time_min" not in plain.columns  # off by default: the presets' bytes kept
    frame = _worn(0.0).frame
    t = frame["time_min"].to_numpy()
    assert (t >= 0).all() and t.max() <= 336 * 60  # within hours_since_reference_h
    # the same draws, the LED aged faster: within a person, later readings lose more
    fast = _worn(0.5).frame
    both = pd.DataFrame({"s": frame["subject_id"], "t": t,
                         "r": fast["true_voltage_v_940"] / frame["true_voltage_v_940"]})
    dev = both[["t", "r"]] - both.groupby("s")[["t", "r"]].transform("mean")
    assert np.corrcoef(dev["t"], dev["r"])[0, 1] < -0.9


def test_drift_summary_grows_with_ageing():
    values = []
    for ageing in (0.0, 0.1):
        ds = _worn(ageing)
        dev = device_of(ds)
        assert dev.times and dev.time_sd_h > 0
        s = dict(zip(summary_names(dev), summaries(ds.frame, dev), strict=True))
        values.append(s["drift_940"])
    # 10 % per 1000 h over a two-week spread: asinh(100) ~ 5.3 against ~0 without
    assert values[1] > values[0] + 2


def test_time_spread_by_hand():
    frame = pd.DataFrame({"subject_id": np.repeat([1, 2, 3, 4, 5], 2),
                          "glucose_mgdl": [90.0, 150.0] * 5,
                          "adc_940": [500, 510, 600, 612, 550, 560, 520, 530, 580, 590],
                          "time_min": [0.0, 120, 60, 180, 0, 120, 30, 150, 0, 120]})
    dev = device_of(ng.Dataset(frame), adc_bits=10)
    # every person: two readings 120 min apart, deviations +-60 min; 10 - 5 dof:
    # sqrt(10 x 60^2 / 5) = 84.85 min = 1.4142 h
    assert dev.time_sd_h == pytest.approx(np.sqrt(2), abs=1e-4)
    assert base_overrides(dev)["hardware.hours_since_reference_h"] == pytest.approx(
        [0.0, np.sqrt(12) * np.sqrt(2)], abs=1e-3)
    frame.loc[0, "time_min"] = np.inf
    with pytest.raises(DataError, match="time_min"):
        device_of(ng.Dataset(frame), adc_bits=10)


def test_drift_is_fitted_per_channel_only_with_times():
    with_t = TwinDevice((850.0, 940.0), 10, False, False, (), True, 25, 8, 24.0)
    without = TwinDevice((850.0, 940.0), 10, False, False, (), False, 25, 8)
    keys = {p.key for p in fitted_parameters(with_t) if p.kind == "drift"}
    assert keys == {"leds.emitters.0.ageing_per_1000h", "leds.emitters.1.ageing_per_1000h"}
    assert not any(p.kind == "drift" for p in held_parameters(with_t))
    held = [p for p in held_parameters(without) if p.kind == "drift"]
    assert [p.channel for p in held] == [850.0, 940.0]
    assert all("no reading times" in p.reason for p in held)
    assert not any(p.kind == "drift" for p in fitted_parameters(without))
    assert [n for n in summary_names(with_t) if n.startswith("drift")] == [
        "drift_850", "drift_940"]
    assert not any(n.startswith("drift") for n in summary_names(without))


def test_twin_with_times_round_trip_and_scenario(tmp_path):
    twin = hand_twin((940.0,), times=True)
    twin.save(tmp_path)
    doc = json.loads((tmp_path / "twin.json").read_text())
    assert doc["device"]["time_sd_h"] == 24.0
    drift = [p for p in doc["parameters"] if p["kind"] == "drift"]
    assert drift and all(p["fitted"] and {"median", "lower", "upper", "identified"} <= set(p)
                         for p in drift)
    back = load_twin(tmp_path)
    cfg = back.scenario("map")
    assert cfg.device.reading_times and cfg.leds.emitters[0].ageing_per_1000h is not None
    frame = ng.simulate(cfg, 3, 3, 0).frame
    assert "time_min" in frame.columns


def test_report_says_why_drift_is_not_known():
    lines = _drift_lines(hand_twin((940.0,)))
    assert len(lines) == 1 and "not identified (the file has no reading times" in lines[0]
    lines = _drift_lines(hand_twin((850.0, 940.0), times=True))
    assert [ln.split(":")[0] for ln in lines] == [
        "LED power drift at 850 nm", "LED power drift at 940 nm"]


@pytest.mark.slow
def test_fit_identifies_a_drift_that_the_times_show(tmp_path, monkeypatch):
    """A 25-person file over two weeks, the LED losing 5 % per 1000 h: the twin's drift is
    identified and its 90 % interval holds the truth (a training of its own: slow)."""
    from .conftest import TEST_SETTINGS

    monkeypatch.setenv("NIRGLUCOSE_CACHE", str(tmp_path / "cache"))
    truth = 0.05
    ds = ng.simulate("physical", 25, 8, 21, overrides={
        "device.reading_times": True, "hardware.hours_since_reference_h": [0, 336],
        "hardware.adc_bits": 10, "leds": [{**LED, "ageing_per_1000h": truth,
                                           "glucose_gain": 11.0}]})
    f = ds.frame[["subject_id", "glucose_mgdl", "adc_940", "time_min", "age_yr"]]
    path = tmp_path / "worn.csv"
    f.to_csv(path, index=False)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the parameters a file does not identify
        twin = ng.fit_twin(path, adc_bits=10, settings=TEST_SETTINGS, ppc_devices=20)
    e = twin.entry("leds.emitters.0.ageing_per_1000h")
    assert e["fitted"] and e["identified"], e
    assert e["lower"] <= truth <= e["upper"], e
