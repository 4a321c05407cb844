"""One protocol value (issues 33, 42): a frozen :class:`Protocol` is run_benchmark's
protocol (its former loose keywords warn until 0.3, giving the same result) and is
accepted by run_sweep in place of the loose keywords."""

from __future__ import annotations

import dataclasses
import inspect

import pandas as pd
import pytest

import nirglucose as ng
from nirglucose.evaluation import Protocol
from nirglucose.evaluation.benchmark.run import run_benchmark
from nirglucose.evaluation.protocol import LEGACY_KEYWORDS, resolve_protocol
from nirglucose.evaluation.sweep.run import SWEEP_METRICS, run_sweep
from nirglucose.exceptions import ConfigError

FAST = {"timing": {"n_single": 2, "min_single": 1, "warmup": 0, "batch_rows": 20,
                   "batch_repeats": 1},
        "oracle_reference": False, "drop_one_models": "none"}
TIMED = ["latency_single_ms", "latency_single_p90_ms", "throughput_per_s", "fit_time_s"]


@pytest.mark.parametrize("bad", [{"splitter": "k-fold"}, {"n_splits": 0}, {"repeats": 1.5},
                                 {"seed": -1}, {"seed": True}, {"resamples": 0},
                                 {"calibration": 3}])
def test_a_bad_protocol_is_refused_when_made(bad):
    with pytest.raises(ConfigError, match=next(iter(bad)).replace("splitter", "protocol")):
        Protocol(**bad)


def test_a_protocol_is_frozen_and_its_defaults_are_the_benchmarks():
    p = Protocol()
    with pytest.raises(dataclasses.FrozenInstanceError):
        p.seed = 1  # type: ignore[misc]
    sig = inspect.signature(run_benchmark).parameters
    # the Protocol holds the options: run_benchmark's own signature no longer repeats them
    assert sig["protocol"].default == p.splitter
    assert not set(LEGACY_KEYWORDS) & set(sig)
    assert set(LEGACY_KEYWORDS.values()) == {f.name for f in dataclasses.fields(p)} - {"splitter"}
    # run_sweep keeps its keywords, with the same defaults (but a sweep's own, smaller,
    # bootstrap: each of its many tasks resamples)
    sweep = inspect.signature(run_sweep).parameters
    names = {"splitter": "protocol", "n_splits": "n_splits", "repeats": "repeats",
             "calibration": "calibration"}
    assert {f: getattr(p, f) for f in names} == {f: sweep[k].default for f, k in names.items()}


def test_an_unknown_keyword_is_a_type_error():
    data = ng.simulate("paper", n_subjects=6, per_subject=2, seed=0)
    with pytest.raises(TypeError, match="unexpected keyword argument 'n_fold'"):
        run_benchmark(data, ["mean"], n_fold=3, **FAST)


def test_a_protocol_beside_a_changed_keyword_is_refused():
    with pytest.raises(ConfigError, match="not both: repeats=5"):
        resolve_protocol(Protocol(), {"repeats": 5, "seed": 0}, {"repeats": 3, "seed": 0})
    with pytest.raises(ConfigError, match="splitter name or a Protocol"):
        resolve_protocol(3, {}, {})
    data = ng.simulate("paper", n_subjects=12, per_subject=2, seed=0)
    with pytest.raises(ConfigError, match="not both: n_splits=4"), \
            pytest.warns(DeprecationWarning, match="n_splits="):
        run_benchmark(data, ["mean"], protocol=Protocol(), n_splits=4, **FAST)
    with pytest.raises(ConfigError, match="seeds are its seeds argument"):
        run_sweep({"noise_scale": [1.0]}, protocol=Protocol(seed=2), seeds=1, models=["pls"])


@pytest.mark.slow  # make test-slow (CI runs it)
def test_run_benchmark_takes_the_protocol_as_one_value():
    data = ng.simulate("paper", n_subjects=16, per_subject=2, seed=0)
    with pytest.warns(DeprecationWarning, match=r"removed in nirglucose 0\.3: give "
                      r"protocol=Protocol\(n_splits=, repeats=, seed=, resamples=\.\.\.\)"):
        loose = run_benchmark(data, ["mean", "pls"], n_splits=4, repeats=2, seed=3, n_boot=100,
                              **FAST)
    whole = run_benchmark(data, ["mean", "pls"], **FAST,
                          protocol=Protocol(n_splits=4, repeats=2, seed=3, resamples=100))
    pd.testing.assert_frame_equal(whole.metrics.drop(columns=TIMED),
                                  loose.metrics.drop(columns=TIMED))
    pd.testing.assert_frame_equal(whole.predictions, loose.predictions)
    for key in ("protocol", "n_splits", "repeats", "seed", "n_boot"):
        assert whole.meta[key] == loose.meta[key], key
    assert loose.meta["seed"] == 3 and loose.meta["n_splits"] == 4


def test_run_sweep_takes_the_protocol_as_one_value():
    tiny = {"seeds": 1, "models": ["pls"], "n_subjects": 16, "per_subject": 2, "jobs": 1}
    loose = run_sweep({"noise_scale": [1.0]}, protocol="paper-split", n_boot=50, **tiny)
    whole = run_sweep({"noise_scale": [1.0]}, protocol=Protocol("paper-split", resamples=50),
                      **tiny)
    metrics = [c for c in SWEEP_METRICS if c in loose.frame and c != "n_parameters"]
    pd.testing.assert_frame_equal(whole.frame[metrics], loose.frame[metrics])
    for key in ("protocol", "n_splits", "repeats", "n_boot", "seeds"):
        assert whole.meta[key] == loose.meta[key], key
    assert whole.meta["n_boot"] == 50
