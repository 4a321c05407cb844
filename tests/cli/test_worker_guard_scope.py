"""Only the commands that start worker processes run inside ``worker_guard`` (issue 42):
it sets joblib's backend (loky, each worker watching this process), which every other
command leaves alone."""

from __future__ import annotations

import contextlib

import pytest

from nirglucose.cli import main
from nirglucose.evaluation.engine import executors


@pytest.fixture
def guarded(monkeypatch):
    entered = []

    @contextlib.contextmanager
    def spy():
        entered.append(True)
        yield

    monkeypatch.setattr(executors, "worker_guard", spy)
    return entered


@pytest.mark.parametrize("argv", [["keys"], ["models"], ["parts"]])
def test_commands_without_workers_leave_joblib_alone(guarded, argv, capsys):
    assert main(argv) == 0
    assert guarded == []


def test_a_command_with_workers_runs_inside_the_guard(guarded, tmp_path, capsys):
    out = tmp_path / "d.parquet"
    assert main(["simulate", "--subjects", "2", "--per-subject", "1", "--out", str(out),
                 "--jobs", "1"]) == 0
    assert guarded == [True] and out.is_file()
