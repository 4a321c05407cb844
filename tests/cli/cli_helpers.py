"""Helpers of the bad-input tests: run the CLI in-process, check the one-line contract."""

from __future__ import annotations

import os
import re
import time
from collections.abc import Callable, Iterable
from pathlib import Path

import pytest

from nirglucose.cli import main

#: A progress line on stderr (written when stderr is not a terminal).
PROGRESS = re.compile(r"^(benchmark|sweep): \d+/\d+ tasks")
#: This tree's package sources, for the PYTHONPATH of a subprocess.
SRC = str(Path(__file__).resolve().parents[2] / "src")


def subprocess_env() -> dict[str, str]:
    """This environment with :data:`SRC` first on PYTHONPATH and one BLAS/OpenMP thread."""
    env = dict(os.environ)
    env["PYTHONPATH"] = SRC + os.pathsep + env.get("PYTHONPATH", "")
    env.update(OMP_NUM_THREADS="1", MKL_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1")
    return env


def all_gone(procs: Iterable, alive: Callable[[object], bool], timeout_s: float = 5.0) -> bool:
    """Whether no process of ``procs`` is ``alive`` within ``timeout_s``. [s]"""
    procs = list(procs)
    t0 = time.monotonic()
    while time.monotonic() - t0 < timeout_s:
        if not any(alive(p) for p in procs):
            return True
        time.sleep(0.1)
    return False


def listing(root: Path) -> set[str]:
    """Every path under ``root`` (hidden ones included), relative to it."""
    return {str(p.relative_to(root)) for p in Path(root).rglob("*")}


@pytest.fixture
def cli(capsys):
    """``cli(*args) -> (code, out, err)``: ``nirglucose ARGS`` run in this process."""

    def run(*args):
        code = main([str(a) for a in args])
        out, err = capsys.readouterr()
        return code, out, err

    return run


def assert_one_line_error(code: int, err: str, *, status: int = 2, contains=()) -> str:
    """Exit ``status``, exactly one line on stderr starting with ``error:``, no traceback."""
    assert code == status, err
    # progress lines of a run that had started ("benchmark: 3/60 tasks ...") are log lines
    lines = [ln for ln in err.splitlines() if ln.strip() and not PROGRESS.match(ln)]
    assert len(lines) == 1, err
    assert lines[0].startswith("error: "), err
    assert "Traceback" not in err
    for text in contains:
        assert text in lines[0], lines[0]
    return lines[0]


@pytest.fixture
def workdir(tmp_path, monkeypatch):
    """An empty current directory; tests check that nothing is left in it."""
    monkeypatch.chdir(tmp_path)
    assert not os.listdir(tmp_path)
    return tmp_path
