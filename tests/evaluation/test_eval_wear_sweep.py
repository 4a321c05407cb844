"""``sweep --study wear`` on local processes and on Dask: the same rows as in this
process, one task file each, one-line errors (issue 31)."""

from __future__ import annotations

import pandas as pd
import pytest

from nirglucose.cli import main
from nirglucose.evaluation.wear import run_wear_sweep
from nirglucose.exceptions import ConfigError

#: Two tasks (two seeds) of a tiny worn run: 6 subjects, one day, a reading an hour.
TINY = dict(presets=["paper"], wear_days=[1], seeds=[0, 1], models=["mean"],
            schedules=["factory", "every-24h"], n_subjects=6, every_min=60, folds=2,
            n_boot=100)


@pytest.fixture(scope="module")
def serial(tmp_path_factory):
    out = tmp_path_factory.mktemp("wear-serial")
    return out, run_wear_sweep(out, **TINY)


def test_dask_cluster_gives_the_serial_rows(serial, tmp_path):
    distributed = pytest.importorskip("distributed")
    ref_dir, ref = serial
    seen = []
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=False,
                                  dashboard_address=None) as cluster:
        res = run_wear_sweep(tmp_path, scheduler=cluster.scheduler_address,
                             on_task=lambda spec, cached: seen.append(cached), **TINY)
    assert seen == [False, False]
    pd.testing.assert_frame_equal(res, ref)
    pd.testing.assert_frame_equal(pd.read_csv(tmp_path / "wear_sweep.csv"),
                                  pd.read_csv(ref_dir / "wear_sweep.csv"))
    assert len(list((tmp_path / ".tasks").glob("wear-paper-1d-s*.json"))) == 2


def test_local_processes_give_the_serial_rows(serial, tmp_path):
    """jobs=2 runs the pending tasks in worker processes (each checked against this
    process's version and code) and writes the serial run's files."""
    ref_dir, ref = serial
    seen = []
    res = run_wear_sweep(tmp_path, jobs=2, on_task=lambda spec, cached: seen.append(cached),
                         **TINY)
    assert seen == [False, False]
    pd.testing.assert_frame_equal(res, ref)
    for name in ("wear_sweep.csv", "wear_summary.csv"):
        assert (tmp_path / name).read_bytes() == (ref_dir / name).read_bytes()


def test_a_finished_sweep_is_reused_whatever_the_backend(serial):
    out, ref = serial
    seen = []
    # every task is cached: nothing runs, whatever jobs
    res = run_wear_sweep(out, jobs=2, on_task=lambda spec, cached: seen.append(cached),
                         **TINY)
    assert seen == [True, True]
    pd.testing.assert_frame_equal(res, ref)


@pytest.mark.parametrize("kwargs, says", [
    ({"scheduler": "nohost:8786"}, "is not an address"),
    ({"jobs": 0}, "jobs"),
])
def test_bad_backend_fails_before_any_task(tmp_path, kwargs, says):
    with pytest.raises(ConfigError, match=says) as err:
        run_wear_sweep(tmp_path / "o", **{**TINY, **kwargs})
    assert "\n" not in str(err.value)
    assert not (tmp_path / "o" / ".tasks").exists()


def test_cli_bad_scheduler_is_one_line(tmp_path, capsys):
    code = main(["sweep", "--study", "wear", "--out", str(tmp_path / "o"), "--vary",
                 "wear_days=1", "--preset", "paper", "--scheduler", "nohost:8786"])
    err = capsys.readouterr().err.strip()
    assert code == 2 and err.count("\n") == 0 and "not an address" in err

# Long-running (whole studies, end-to-end runs, Monte Carlo or every model): `make test-slow`,
# which CI runs beside the fast `make test` (tests/test_slow_marks.py)
pytestmark = pytest.mark.slow
