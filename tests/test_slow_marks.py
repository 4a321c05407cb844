"""``make test`` is the fast suite and ``make test-slow`` the tests marked ``slow``; CI
runs both, so a slow mark schedules a test apart and never skips it (issue 43)."""

from __future__ import annotations

import re
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def _recipe(target: str) -> str:
    text = (ROOT / "Makefile").read_text()
    match = re.search(rf"^{re.escape(target)}:[^\n]*\n((?:\t[^\n]*\n)+)", text, re.M)
    assert match, f"the Makefile has no {target} target"
    return match.group(1)


def test_the_fast_and_the_slow_targets_split_the_suite_by_the_mark():
    assert '-m "not slow"' in _recipe("test")
    assert "-m slow" in _recipe("test-slow")


def test_ci_runs_both_targets():
    ci = (ROOT / ".ci" / "run").read_text()
    lines = [ln.strip() for ln in ci.splitlines() if not ln.strip().startswith("#")]
    assert "make test" in lines and "make test-slow" in lines


def test_the_slow_mark_is_registered():
    pyproject = tomllib.loads((ROOT / "pyproject.toml").read_text())
    opts = pyproject["tool"]["pytest"]["ini_options"]
    assert "--strict-markers" in opts["addopts"]
    assert any(m.startswith("slow:") for m in opts["markers"])
