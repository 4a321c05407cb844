"""The public modules pass a static type checker (issue 33): mypy, with pydantic's plugin.

Left out, and why: the pydantic config models (``config/_base``, ``subject``,
``environment``, ``instrument``, ``leds``, ``noise``, ``device``) build constrained types by
function calls (``_pair(0, 100)``) that no static checker can read; pydantic checks them
at run time and ``tests/test_config.py`` walks every bound. The rest of the package is
typed where it is public (``py.typed`` ships with it).
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

pytest.importorskip("mypy")

ROOT = Path(__file__).resolve().parents[1]
PUBLIC = [
    "src/nirglucose/__init__.py",
    "src/nirglucose/api.py",
    "src/nirglucose/dataset/__init__.py",
    "src/nirglucose/dataset/container.py",
    "src/nirglucose/exceptions.py",
    "src/nirglucose/portable.py",
    "src/nirglucose/prediction.py",
    "src/nirglucose/dataset/schema.py",
    "src/nirglucose/fitted.py",
    "src/nirglucose/config/keys.py",
    "src/nirglucose/config/overrides.py",
    "src/nirglucose/config/presets.py",
    "src/nirglucose/config/scenario.py",
    "src/nirglucose/metrics",
    "src/nirglucose/models/registry.py",
    "src/nirglucose/export",
]


def _mypy(*targets: str, cwd: Path = ROOT) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "mypy", "--no-incremental",
                           "--config-file", str(ROOT / "pyproject.toml"), *targets],
                          cwd=cwd, capture_output=True, text=True, timeout=300)


def test_public_modules_pass_mypy():
    out = _mypy(*PUBLIC)
    assert out.returncode == 0, out.stdout[-3000:]


def test_the_checker_sees_the_package_types(tmp_path):
    """A user's wrong use of the public API is an error (the check can fail)."""
    bad = tmp_path / "user_code.py"
    bad.write_text("import nirglucose as ng\n\nn: int = ng.simulate('paper')\n")
    out = _mypy(str(bad), cwd=ROOT)
    assert out.returncode == 1 and "Dataset" in out.stdout, out.stdout

# Long-running (whole studies, end-to-end runs, Monte Carlo or every model): `make test-slow`,
# which CI runs beside the fast `make test` (tests/test_slow_marks.py)
pytestmark = pytest.mark.slow
