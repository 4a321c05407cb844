"""Sweeps: scenarios, task hashing, backends (serial / Dask), resumability, aggregation."""

from __future__ import annotations

import json
import shutil

import numpy as np
import pandas as pd
import pytest

from nirglucose.config import NOISE_SOURCES
from nirglucose.evaluation.engine.executors import resolve_backend, run_unordered
from nirglucose.evaluation.engine.tasks import checksum, task_key
from nirglucose.evaluation.sweep.run import (
    SWEEP_METRICS,
    ablation_effects,
    grid_scenarios,
    load_sweep,
    parse_vary,
    plan_sweep,
    run_sweep,
    run_sweep_task,
    shift_effects,
    study_scenarios,
    summarize_sweep,
    threshold_crossing,
)
from nirglucose.exceptions import ConfigError

#: A tiny, fast sweep: 2 scenarios x 2 seeds x 1 linear model, one split per task.
TINY = dict(seeds=2, models=["pls"], n_subjects=24, per_subject=2, protocol="paper-split",
            n_boot=50)
VARY = {"noise_scale": [0.5, 2.0]}
METRICS = [c for c in SWEEP_METRICS if c != "n_parameters"]


@pytest.fixture(scope="module")
def serial(tmp_path_factory):
    out = tmp_path_factory.mktemp("sweep") / "serial"
    return out, run_sweep(VARY, out=out, jobs=1, **TINY)


# --------------------------------------------------------------------------- parsing
def test_parse_vary_forms():
    assert parse_vary("noise_scale=0.25,0.5,1") == ("noise_scale", [0.25, 0.5, 1])
    assert parse_vary("environment.temperature_c=[5,35],[20,25]") == (
        "environment.temperature_c", [[5, 35], [20, 25]])
    assert parse_vary("optics.water_source=kou1993,segelstein1981")[1] == [
        "kou1993", "segelstein1981"]
    assert parse_vary("noise.shot.enabled=true,false")[1] == [True, False]
    assert parse_vary("noise_scale=1,1,2")[1] == [1, 2]


@pytest.mark.parametrize("text", ["noise_scale", "noise_scale=", "=1,2", "noise_scale=1,,2"])
def test_parse_vary_rejects(text):
    with pytest.raises(ConfigError):
        parse_vary(text)


@pytest.mark.parametrize("vary, match", [
    ({"no_such.key": [1, 2]}, "unknown config key"),
    ({"noise_scale": ["a", 1]}, "not a number"),
    ({"noise_scale": [True]}, "not a number"),
    ({"noise_scale": []}, "non-empty"),
    ({"noise_scale": [-1.0]}, "out of range: must be between 0 and 100"),
    ({"noise.shot.enabled": [1]}, "true/false"),
    ({}, "nothing to vary"),
])
def test_grid_rejects_bad_values(vary, match):
    with pytest.raises(ConfigError, match=match):
        grid_scenarios(vary)


def test_grid_is_a_cartesian_product():
    sc = grid_scenarios({"noise_scale": [0.5, 1], "hardware.adc_bits": [10, 12, 14]})
    assert len(sc) == 6
    assert sc[1].overrides == {"noise_scale": 0.5, "hardware.adc_bits": 12}
    assert sc[1].labels == {"noise_scale": 0.5, "hardware.adc_bits": 12}


def test_study_scenarios():
    abl = study_scenarios("ablation")
    assert len(abl) == 2 + 2 * len(NOISE_SOURCES)
    only_shot = next(s for s in abl if s.name == "only:shot")
    assert "noise.shot.enabled" not in only_shot.overrides
    assert sum(v is False for v in only_shot.overrides.values()) == len(NOISE_SOURCES) - 1
    # water's temperature dependence is off by default: its rows switch it on to measure it
    by_name = {s.name: s.overrides for s in abl}
    key = "noise.water_temperature.enabled"
    assert by_name["all-on"] == {key: True}
    assert by_name["only:water_temperature"][key] is True
    assert by_name["off:water_temperature"] == {key: False}
    assert by_name["off:shot"] == {key: True, "noise.shot.enabled": False}
    assert key not in by_name["only:shot"] or by_name["only:shot"][key] is False
    cohort = study_scenarios("cohort")
    assert [s.kind for s in cohort] == ["shift"] * 4
    assert [s.labels["test_domain"] for s in cohort] == ["I-III", "IV-VI", "20-25 degC",
                                                         "5-35 degC"]
    with pytest.raises(ConfigError, match="unknown study"):
        study_scenarios("nope")


def test_task_hash_covers_the_specification(monkeypatch):
    from nirglucose.evaluation.engine import tasks

    base = plan_sweep(grid_scenarios(VARY), seeds=[0], models=["pls"])
    assert len({task_key(s) for s in base}) == 2
    again = plan_sweep(grid_scenarios(VARY), seeds=[0], models=["pls"])
    assert [task_key(s) for s in base] == [task_key(s) for s in again]
    for change in ({"seeds": [1]}, {"models": ["ebl"]}, {"n_splits": 3},
                   {"base_overrides": {"hardware.adc_bits": 14}}, {"n_boot": 7}):
        kw = {"seeds": [0], "models": ["pls"], **change}
        other = plan_sweep(grid_scenarios(VARY), **kw)
        assert task_key(other[0]) != task_key(base[0]), change
    monkeypatch.setattr(tasks, "source_digest", lambda: "edited code")
    edited = plan_sweep(grid_scenarios(VARY), seeds=[0], models=["pls"])
    assert task_key(edited[0]) != task_key(base[0])


# --------------------------------------------------------------------------- execution
def test_serial_sweep_outputs(serial):
    out, res = serial
    f = res.frame
    assert len(f) == 4 and list(f["seed"]) == [0, 1, 0, 1]
    assert list(f["noise_scale"]) == [0.5, 0.5, 2.0, 2.0]
    assert set(METRICS) <= set(f.columns)
    assert np.isfinite(f["rmse_mgdl"]).all()
    assert res.meta["tasks_computed"] == 4
    for name in ("sweep.csv", "summary.csv", "sweep_meta.json"):
        assert (out / name).exists()
    assert len(list((out / ".tasks").glob("*.json"))) == 4
    back = load_sweep(out)
    pd.testing.assert_frame_equal(back.frame[METRICS], f[METRICS], check_dtype=False)
    assert len(res.summary) == 2 and (res.summary["n_seeds"] == 2).all()


def test_dask_cluster_matches_serial(serial):
    distributed = pytest.importorskip("distributed")
    _, ref = serial
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=False,
                                  dashboard_address=None) as cluster:
        res = run_sweep(VARY, scheduler=cluster.scheduler_address, **TINY)
    assert res.meta["backend"] == "dask" and res.meta["tasks_computed"] == 4
    pd.testing.assert_frame_equal(res.frame[METRICS], ref.frame[METRICS])


def test_interrupted_sweep_resumes_only_missing_tasks(tmp_path, serial):
    _, ref = serial
    out = tmp_path / "resume"
    done = []

    def stop_after_two(spec, cached):
        done.append(spec)
        if len(done) == 2:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        run_sweep(VARY, out=out, jobs=1, on_task=stop_after_two, **TINY)
    assert len(list((out / ".tasks").glob("*.json"))) == 2
    assert not (out / "sweep.csv").exists()
    computed = []
    res = run_sweep(VARY, out=out, jobs=1, on_task=lambda s, c: None if c else computed.append(s),
                    **TINY)
    assert len(computed) == 2
    assert res.meta["tasks_cached"] == 2 and res.meta["tasks_computed"] == 2
    pd.testing.assert_frame_equal(res.frame[METRICS], ref.frame[METRICS])


@pytest.mark.parametrize("damage", ["truncate", "checksum", "schema"])
def test_corrupt_task_file_is_recomputed(tmp_path, serial, damage):
    src, ref = serial
    out = tmp_path / "copy"
    shutil.copytree(src, out)
    victim = sorted((out / ".tasks").glob("*.json"))[0]
    text = victim.read_text()
    if damage == "truncate":
        victim.write_text(text[: len(text) // 2])
    else:
        doc = json.loads(text)
        if damage == "checksum":
            doc["result"]["metrics"]["rmse_mgdl"] += 1.0
        else:
            del doc["result"]["metrics"]
        victim.write_text(json.dumps(doc))
    with pytest.warns(UserWarning, match="corrupt or partial"):
        res = run_sweep(VARY, out=out, jobs=1, **TINY)
    assert res.meta["tasks_computed"] == 1 and res.meta["tasks_corrupt"] == 1
    pd.testing.assert_frame_equal(res.frame[METRICS], ref.frame[METRICS])
    doc = json.loads(victim.read_text())  # rewritten whole
    assert doc["checksum"] == checksum(doc["result"])


def test_shift_task_splits_by_measured_column():
    fitz = next(s for s in study_scenarios("cohort") if s.name == "fitzpatrick:shifted")
    spec = plan_sweep([fitz], seeds=[3], models=["pls"], n_subjects=30, per_subject=2,
                      n_boot=50)[0]
    res = run_sweep_task(spec)
    m = res["metrics"]
    assert spec["kind"] == "shift" and spec["protocol"] == "train-test"
    assert 0 < m["n_train"] < 60 and 0 < m["n_predictions"] < 60
    assert np.isfinite(m["rmse_mgdl"]) and m["rmse_ci_low"] <= m["rmse_mgdl"] <= m["rmse_ci_high"]
    assert run_sweep_task(spec)["metrics"] == m  # seeded from the spec


def test_process_pool_and_backend_resolution():
    assert sorted(run_unordered(abs, [-1, -2, 3], jobs=2)) == [(0, 1), (1, 2), (2, 3)]
    assert resolve_backend(1) == ("serial", 1)
    assert resolve_backend(3) == ("processes", 3)
    assert resolve_backend(None, "tcp://host:8786") == ("dask", 0)
    with pytest.raises(ConfigError):
        resolve_backend(0)
    with pytest.raises(ConfigError, match="not an address"):
        resolve_backend(None, "host:8786")


# --------------------------------------------------------------------------- aggregation
def _ablation_frame() -> pd.DataFrame:
    rows = []
    for seed in range(3):
        rmse = {"all-on": 20.0 + seed, "all-off": 5.0 + seed}
        for k, s in enumerate(NOISE_SOURCES):
            rmse[f"off:{s}"] = 20.0 + seed - k * 0.5   # source k costs 0.5 k
            rmse[f"only:{s}"] = 5.0 + seed + k          # alone it adds k
        for sc, v in rmse.items():
            rows.append({"scenario": sc, "seed": seed, "model": "m", "rmse_mgdl": v})
    return pd.DataFrame(rows)


def test_ablation_effects_are_paired_by_seed():
    e = ablation_effects(_ablation_frame())
    assert len(e) == len(NOISE_SOURCES)
    assert e["source"].iloc[0] == NOISE_SOURCES[-1]  # most costly first
    k = NOISE_SOURCES.index("shot")
    row = e.set_index("source").loc["shot"]
    assert row["delta_off"] == pytest.approx(0.5 * k)
    assert row["delta_only"] == pytest.approx(k)
    assert row["delta_off_ci_low"] == pytest.approx(0.5 * k)  # no spread of the differences
    assert row["n_seeds"] == 3


def test_summary_interval_and_threshold_crossing():
    f = pd.DataFrame({"scenario": ["a"] * 3 + ["b"] * 3, "noise_scale": [1] * 3 + [4] * 3,
                      "seed": [0, 1, 2] * 2, "model": "m",
                      "mard_pct": [9.0, 10.0, 11.0, 19.0, 20.0, 21.0]})
    s = summarize_sweep(f, ["noise_scale"], ["mard_pct"])
    assert s["mard_pct_mean"].tolist() == [10.0, 20.0]
    half = 4.302652729911275 * 1.0 / np.sqrt(3)  # t(0.975, 2) * sd / sqrt(n)
    assert s["mard_pct_ci_high"].iloc[0] == pytest.approx(10.0 + half)
    c = threshold_crossing(s, "noise_scale", "mard_pct", 15.0)
    assert c["status"][0] == "crosses"
    assert c["crossing"][0] == pytest.approx(2.0)  # halfway in log2: 1 -> 4
    assert threshold_crossing(s, "noise_scale", "mard_pct", 25.0)["status"][0] == (
        "below at every x")
    assert threshold_crossing(s, "noise_scale", "mard_pct", 5.0)["status"][0] == (
        "above at every x")


def test_shift_effects():
    rows = []
    for seed in range(2):
        for which, v in (("in-domain", 10.0), ("shifted", 14.0 + seed)):
            rows.append({"scenario": f"fitzpatrick:{which}", "shift": "fitzpatrick",
                         "train_domain": "I-III",
                         "test_domain": "I-III" if which == "in-domain" else "IV-VI",
                         "seed": seed, "model": "m", "rmse_mgdl": v})
    e = shift_effects(pd.DataFrame(rows))
    assert e["delta"].iloc[0] == pytest.approx(4.5)
    assert e["test_domain"].iloc[0] == "IV-VI"
