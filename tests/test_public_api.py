"""The front door (issue 33): ``import nirglucose as ng`` reaches every subpackage.

``ng.models``, ``ng.metrics``, ``ng.evaluation``, ... were AttributeErrors until imported
by hand; they are imported on first access, so ``import nirglucose`` stays light.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

import nirglucose as ng

SRC = str(Path(__file__).resolve().parents[1] / "src")


def _fresh(code: str) -> str:
    prelude = f"import sys; sys.path.insert(0, {SRC!r}); "
    out = subprocess.run([sys.executable, "-c", prelude + code],
                         capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr[-1500:]
    return out.stdout.strip()


def test_every_subpackage_is_an_attribute_in_a_fresh_interpreter():
    names = ",".join(repr(n) for n in ng.SUBPACKAGES)
    got = _fresh("import nirglucose as ng, types; "
                 f"print(all(isinstance(getattr(ng, n), types.ModuleType) for n in ({names},)))")
    assert got == "True"


def test_import_nirglucose_stays_light():
    got = _fresh("import nirglucose, sys; print(sorted(m for m in ('torch', 'numba', "
                 "'matplotlib', 'dask') if m in sys.modules))")
    assert got == "[]"


def test_simulate_is_still_the_function():
    assert callable(ng.simulate) and ng.simulate.__module__ == "nirglucose.api"


def test_unknown_attribute_is_an_attribute_error():
    with pytest.raises(AttributeError, match="no attribute 'nope'"):
        ng.nope  # noqa: B018
    assert {"models", "metrics", "evaluation"} <= set(dir(ng))


def test_loading_a_model_does_not_import_the_evaluation_package(tmp_path):
    from nirglucose.calibration.conformal import attach
    from nirglucose.models import make_model

    model = make_model("ebl").fit(ng.simulate("paper", 12, 2, seed=0))
    # with a calibration: the loader checks it (that check once imported evaluation)
    attach(model, {"method": "split", "half_width_mgdl": {"90": 10.0}}).save(tmp_path / "m.json")
    assert "conformal" in (tmp_path / "m.json").read_text()
    got = _fresh("from nirglucose.models import load_model; "
                 f"load_model({str(tmp_path / 'm.json')!r}); "
                 "print(sorted(m for m in sys.modules if m.startswith('nirglucose.evaluation')))")
    assert got == "[]"
