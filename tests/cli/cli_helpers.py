"""Helpers of the bad-input tests: run the CLI in-process, check the one-line contract."""

from __future__ import annotations

import os
import re
from pathlib import Path

import pytest

from nirglucose.cli import main

#: A progress line on stderr (written when stderr is not a terminal).
PROGRESS = re.compile(r"^(benchmark|sweep): \d+/\d+ tasks")


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
