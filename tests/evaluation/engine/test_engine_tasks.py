"""The task engine shared by the benchmark and the sweep (issue 22): one identity rule."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

import nirglucose as ng
from nirglucose.evaluation import Protocol
from nirglucose.evaluation.benchmark.run import run_benchmark
from nirglucose.evaluation.engine import tasks
from nirglucose.evaluation.sweep.run import run_sweep

BENCH = dict(protocol=Protocol(n_splits=2, repeats=1, seed=0, resamples=20),
             drop_one_models="none",
             oracle_reference=False,
             timing={"n_single": 1, "min_single": 1, "warmup": 0, "batch_rows": 8,
                     "batch_repeats": 1})
SWEEP = dict(seeds=1, models=["pls"], n_subjects=16, per_subject=2, protocol="paper-split",
             n_boot=20, jobs=1)
VARY = {"noise_scale": [0.5, 2.0]}


@pytest.fixture(scope="module")
def data():
    return ng.simulate("paper", n_subjects=10, per_subject=2, seed=0)


def _bench(data, out):
    seen = []
    run_benchmark(data, ["pls", "mean"], out=out,
                  on_task=lambda spec, cached: seen.append(cached), **BENCH)
    return seen


def _sweep(out):
    seen = []
    run_sweep(VARY, out=out, on_task=lambda spec, cached: seen.append(cached), **SWEEP)
    return seen


def test_an_edited_package_invalidates_benchmark_and_sweep_tasks(data, tmp_path, monkeypatch):
    bench_out, sweep_out = tmp_path / "bench", tmp_path / "sweep"
    assert _bench(data, bench_out) == [False] * 4
    assert _sweep(sweep_out) == [False] * 2
    # unchanged code: every task is reused
    assert _bench(data, bench_out) == [True] * 4
    assert _sweep(sweep_out) == [True] * 2
    # an edit anywhere in the package (the simulator, say) changes the source digest
    monkeypatch.setattr(tasks, "source_digest", lambda: "edited simulator")
    assert _bench(data, bench_out) == [False] * 4
    assert _sweep(sweep_out) == [False] * 2
    assert _bench(data, bench_out) == [True] * 4  # and the edited code's tasks are kept
    for path in (bench_out / ".tasks").glob("*.json"):
        spec = json.loads(path.read_text())["spec"]
        assert spec["format"] == tasks.TASK_FORMAT and "source_sha256" in spec


def test_one_key_rule_for_both():
    spec = tasks.stamp({"model": "pls", "seed": 0})
    assert spec["source_sha256"] == tasks.source_digest()
    assert tasks.task_key(spec) == tasks.task_key(dict(reversed(spec.items())))
    assert tasks.task_key(spec) != tasks.task_key({**spec, "seed": 1})


def test_cache_load_rejects_bad_files(tmp_path):
    cache = tasks.TaskCache(tmp_path / "out", valid=lambda spec, res: "x" in res)
    spec = tasks.stamp({"model": "m"})
    key = tasks.task_key(spec)
    path = cache.path(key, spec, "t")
    assert cache.load(path, spec) is None and cache.n_corrupt == 0  # absent: not corrupt
    cache.save(path, spec, {"x": 1.0})
    assert cache.load(path, spec) == {"x": 1.0}
    assert not list(path.parent.glob(".*.tmp"))  # atomic: no temporary file left
    for bad in ({"x": 2.0, "extra": 1}, {"y": 1.0}):
        doc = json.loads(path.read_text())
        doc["result"] = bad  # checksum mismatch; then schema rejected by `valid`
        if "y" in bad:
            doc["checksum"] = tasks.checksum(bad)
        path.write_text(json.dumps(doc))
        with pytest.warns(UserWarning, match="corrupt or partial"):
            assert cache.load(path, spec) is None
    assert cache.n_corrupt == 2
    with pytest.warns(UserWarning, match="corrupt"):
        assert cache.load(path, {**spec, "model": "other"}) is None


def test_the_source_digest_covers_the_whole_package():
    import nirglucose

    root = tasks._package_root()
    assert root == Path(nirglucose.__file__).resolve().parent
    assert (root / "dataset" / "container.py").is_file() and (root / "api.py").is_file()


def test_external_code_digest():
    from nirglucose.models.linear import PLSBaseline

    assert tasks.external_code_digest(PLSBaseline) is None  # covered by the source digest

    class Local:
        pass

    assert isinstance(tasks.external_code_digest(Local), str)


def test_a_worker_result_from_another_version_is_refused_from_other_code_warned():
    from nirglucose.exceptions import DataError

    T = tasks
    spec = T.stamp({"model": "x"})
    same = {"version": spec["version"], "source_sha256": spec["source_sha256"]}
    T.check_worker(spec, same)  # the same code: silent
    with pytest.raises(DataError, match="install the same version on every worker"):
        T.check_worker(spec, {**same, "version": "0.0.0"})
    with pytest.warns(UserWarning, match="different nirglucose code"):
        T.check_worker(spec, {**same, "source_sha256": "0" * 64})
