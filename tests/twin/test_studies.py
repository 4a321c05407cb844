"""Every study takes a twin (issue 41): benchmark, sweep (grid, wavelengths, fleet, wear),
wear-benchmark and the design bound start from the twin's scenario; what makes no sense
with a twin is one line, exit 2.

The twin is built by hand (:mod:`.hand_twin`: no training), the runs are tiny.
"""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest

from nirglucose.cli import main
from nirglucose.config import resolve_config
from nirglucose.design import design_bound
from nirglucose.evaluation.sweep.wavelengths import wavelength_scenarios
from nirglucose.twin import twin_scenario
from nirglucose.twin.twin import LED_CARRIED

from .hand_twin import HAND_GAIN, hand_twin

#: The smallest benchmark of the CLI tests.
SMALL = ["--subjects", "12", "--per-subject", "3", "--folds", "2", "--repeats", "1",
         "--resamples", "100", "--jobs", "1"]


@pytest.fixture(scope="module")
def twin_dir(tmp_path_factory):
    folder = tmp_path_factory.mktemp("hand_twin")
    hand_twin().save(folder)
    return folder


def test_study_start_keeps_or_carries_the_leds():
    twin = hand_twin((850.0, 940.0))
    own = twin.study_start("map")
    assert own.preset == "physical" and own.overrides == twin.overrides("map")
    assert own.led_fields == {}
    free = twin.study_start("map", own_leds=False)
    assert not any(k == "leds" or k.startswith("leds.") for k in free.overrides)
    assert free.overrides["hardware.adc_bits"] == 10
    assert free.overrides["physiology.variation_scale"] == pytest.approx(
        twin.map_values[twin.fitted_keys.index("physiology.variation_scale")])
    assert set(free.led_fields) <= set(LED_CARRIED)
    # by hand: the geometric mean of the two channels' white noise is not their mean
    noise = [twin.map_values[twin.fitted_keys.index(f"leds.emitters.{i}.read_noise_lsb")]
             for i in (0, 1)]
    assert free.led_fields["read_noise_lsb"] == pytest.approx(np.mean(noise))
    assert free.led_fields["glucose_gain"] == pytest.approx(HAND_GAIN)


def test_benchmark_twin_simulates_the_twin(twin_dir, tmp_path, capsys):
    out = tmp_path / "b"
    code = main(["benchmark", "--twin", str(twin_dir), "--out", str(out), "--models", "ebl",
                 "--no-references", "--no-ablation", "--drop-one", "none", *SMALL])
    _, err = capsys.readouterr()
    assert code == 0, err
    cfg = json.loads((out / "meta.json").read_text())["config"]
    assert [e["wavelength_nm"] for e in cfg["leds"]["emitters"]] == [850.0, 940.0]
    assert cfg["leds"]["emitters"][0]["glucose_gain"] == pytest.approx(HAND_GAIN)
    assert cfg["hardware"]["adc_bits"] == 10


@pytest.mark.parametrize("argv, words", [
    (["benchmark", "--twin", "T", "--preset", "paper"], "--twin replaces --preset"),
    (["benchmark", "--twin-mode", "map"], "--twin-mode applies to a twin"),
    (["benchmark", "--twin", "T", "--twin-mode", "best"], "--twin-mode 'best'"),
    (["benchmark", "--twin", "T", "--data", "x.csv"], "--data reads a file"),
    (["benchmark", "--twin", "T", "--set", "leds=[]"], "replaces the twin's LEDs"),
    (["sweep", "--twin", "T", "--study", "data-size"], "compares presets"),
    (["sweep", "--twin", "T", "--vary", "noise_scale=1", "--preset", "wearable"],
     "--twin replaces --preset"),
    (["sweep", "--twin", "T", "--study", "wear", "--preset", "paper"],
     "--twin replaces --preset"),
    (["wear-benchmark", "--twin", "T", "--preset", "paper"], "--twin replaces --preset"),
    (["simulate", "--twin-mode", "posterior"], "--twin-mode applies to a twin"),
    (["benchmark", "--twin", "missing"], "no twin file"),
])
def test_twin_refusals_one_line(twin_dir, tmp_path, capsys, argv, words):
    argv = [str(twin_dir) if a == "T" else str(tmp_path / a) if a == "missing" else a
            for a in argv]
    out = tmp_path / ("x.csv" if argv[0] == "simulate" else "o")
    code = main([*argv, "--out", str(out)])
    _, err = capsys.readouterr()
    assert code == 2 and len(err.strip().splitlines()) == 1 and words in err, err


def test_sweep_grid_starts_from_the_twin(twin_dir, tmp_path, capsys):
    out = tmp_path / "s"
    code = main(["sweep", "--twin", str(twin_dir), "--vary", "noise_scale=0.5,2",
                 "--models", "oracle", "--seeds", "1", "--no-figures", "--out", str(out),
                 *SMALL])
    _, err = capsys.readouterr()
    assert code == 0, err
    meta = json.loads((out / "sweep_meta.json").read_text())
    assert meta["preset"] == "physical" and meta["twin"] == str(twin_dir)
    assert meta["base_overrides"]["leds.emitters.1.glucose_gain"] == pytest.approx(HAND_GAIN)
    rmse = pd.read_csv(out / "sweep.csv").set_index("noise_scale")["rmse_mgdl"]
    assert rmse[2.0] > rmse[0.5]  # the twin's noise, scaled, still costs the oracle


def test_wavelengths_study_carries_the_twin_to_each_led():
    start = hand_twin().study_start("map", own_leds=False)
    scen = wavelength_scenarios(start.preset, {"detector": ["BPW34"], "n_leds": [1, 2]},
                                start.overrides, start.led_fields)
    assert scen
    for sc in scen:
        for led in sc.overrides["leds"]:
            assert led["glucose_gain"] == pytest.approx(HAND_GAIN)
            assert led["read_noise_lsb"] == pytest.approx(start.led_fields["read_noise_lsb"])
        resolve_config(sc.preset, {**start.overrides, **sc.overrides})  # a valid scenario


def test_sweep_wavelengths_cli_twin(twin_dir, tmp_path, capsys):
    out = tmp_path / "w"
    code = main(["sweep", "--twin", str(twin_dir), "--study", "wavelengths", "--vary",
                 "detector=BPW34", "--vary", "n_leds=1", "--models", "oracle", "--seeds", "1",
                 "--no-figures", "--out", str(out), *SMALL])
    _, err = capsys.readouterr()
    assert code == 0, err
    meta = json.loads((out / "sweep_meta.json").read_text())
    assert meta["twin_led_fields"]["glucose_gain"] == pytest.approx(HAND_GAIN)
    assert "leds" not in meta["base_overrides"]


@pytest.mark.parametrize("argv, table", [
    (["sweep", "--study", "fleet", "--vary", "tolerance_scale=1", "--models", "oracle",
      "--seeds", "1", "--no-figures", *SMALL], "sweep.csv"),
    (["sweep", "--study", "wear", "--vary", "wear_days=1", "--models", "oracle",
      "--subjects", "6", "--folds", "2", "--resamples", "100", "--jobs", "1"],
     "wear_summary.csv"),
])
def test_fleet_and_wear_studies_take_the_twin(twin_dir, tmp_path, capsys, argv, table):
    out = tmp_path / "f"
    code = main([*argv, "--twin", str(twin_dir), "--out", str(out)])
    _, err = capsys.readouterr()
    assert code == 0, err
    frame = pd.read_csv(out / table)
    assert len(frame) and np.isfinite(frame["rmse_mgdl"]).all()
    if table == "wear_summary.csv":
        assert set(frame["preset"]) == {"twin"}


def test_design_bound_of_a_twin_follows_its_noise():
    quiet, loud = hand_twin(), hand_twin()
    i = loud.fitted_keys.index("leds.emitters.0.read_noise_lsb")
    j = loud.fitted_keys.index("leds.emitters.1.read_noise_lsb")
    loud.map_values[[i, j]] = 20.0  # 2 % of the 10-bit full scale: the prior's top
    b_quiet = design_bound(twin_scenario(quiet), n_states=64).rmse_mgdl
    b_loud = design_bound(twin_scenario(loud), n_states=64).rmse_mgdl
    assert np.isfinite(b_quiet) and b_loud > b_quiet


def test_bound_per_led_gain_equals_signal_gain():
    """Every LED at glucose_gain g is the scenario at glucose.signal_gain g."""
    leds = [{"wavelength_nm": w, "fwhm_nm": 40.0, "power_mw": 2.0, "responsivity_a_per_w": 0.5}
            for w in (850.0, 940.0)]
    per_led = design_bound("physical", leds=[{**d, "glucose_gain": 11.0} for d in leds],
                           n_states=64).rmse_mgdl
    scalar = design_bound("physical", leds=leds, overrides={"glucose.signal_gain": 11.0},
                          n_states=64).rmse_mgdl
    assert per_led == pytest.approx(scalar, rel=1e-9)
