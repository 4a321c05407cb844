"""``make docs``: the documentation site builds with warnings as errors.

Skipped where the docs tools are not installed (``make test`` installs ``.[dev]`` only;
``make docs`` and CI install ``.[docs]``). The build runs the gallery scripts and
regenerates the API and CLI reference, about 40-55 s on 2 cores, so it is marked slow.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

for _name in ("sphinx", "numpydoc", "pydata_sphinx_theme", "myst_parser", "sphinx_gallery"):
    pytest.importorskip(_name)

DOCS = Path(__file__).resolve().parents[1] / "docs"


@pytest.mark.slow
def test_docs_build_without_warnings(tmp_path):
    out = tmp_path / "html"
    env = {**os.environ, "MPLBACKEND": "agg"}
    done = subprocess.run(
        [sys.executable, "-m", "sphinx", "-W", "--keep-going", "-q", "-b", "html",
         "-d", str(tmp_path / "doctrees"), str(DOCS), str(out)],
        capture_output=True, text=True, env=env, timeout=900,
    )
    assert done.returncode == 0, done.stderr[-5000:]
    for page in ("index", "getting_started", "api", "cli", "design", "style",
                 "user_guide/simulator", "auto_examples/index",
                 "auto_examples/plot_three_led_device",
                 "generated/nirglucose.models.EnhancedBeerLambert"):
        assert (out / f"{page}.html").is_file(), page
    cli = (out / "cli.html").read_text(encoding="utf-8")
    assert "export-c" in cli and "--preset" in cli  # the help text, generated at build time
