"""A failed or interrupted benchmark / sweep leaves no empty OUT/.tasks (issue 20)."""

from __future__ import annotations

import pytest
from cli_helpers import assert_one_line_error, listing

import nirglucose.evaluation.benchmark.run as bench_mod
import nirglucose.evaluation.sweep.run as sweep_mod
from nirglucose.exceptions import DataError

BENCH = ["benchmark", "--out", "res", "--subjects", 10, "--per-subject", 2, "--models", "ebl",
         "--folds", 2, "--repeats", 1, "--resamples", 10]
SWEEP = ["sweep", "--out", "res", "--vary", "noise_scale=0.5,1", "--seeds", 1, "--subjects", 10,
         "--per-subject", 2, "--models", "ebl", "--folds", 2, "--repeats", 1, "--resamples", 10,
         "--jobs", 1, "--no-figures"]


def _failing(exc):
    def task(*args, **kwargs):
        raise exc

    return task


@pytest.mark.parametrize(("exc", "status"), [(DataError("a task failed"), 2),
                                             (KeyboardInterrupt(), 130)])
@pytest.mark.parametrize("cmd", ["benchmark", "sweep"])
def test_failed_run_leaves_nothing(cli, workdir, monkeypatch, cmd, exc, status):
    if cmd == "benchmark":
        monkeypatch.setattr(bench_mod, "_run_task_of", _failing(exc))
        args = BENCH
    else:
        monkeypatch.setattr(sweep_mod, "run_sweep_task", _failing(exc))
        args = SWEEP
    code, _, err = cli(*args)
    assert code == status, err
    lines = [ln for ln in err.splitlines() if ln.startswith("error:")]
    assert len(lines) == 1 and "Traceback" not in err
    assert not (workdir / "res").exists(), listing(workdir)


def test_existing_out_kept_but_tasks_removed(cli, workdir, monkeypatch):
    (workdir / "res").mkdir()
    (workdir / "res" / "notes.txt").write_text("mine")
    monkeypatch.setattr(bench_mod, "_run_task_of", _failing(DataError("a task failed")))
    code, _, err = cli(*BENCH)
    assert_one_line_error(code, err, contains=["a task failed"])
    assert listing(workdir) == {"res", "res/notes.txt"}

# Long-running (whole studies, end-to-end runs, Monte Carlo or every model): `make test-slow`,
# which CI runs beside the fast `make test` (tests/test_slow_marks.py)
pytestmark = pytest.mark.slow
