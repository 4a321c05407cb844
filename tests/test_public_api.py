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


def _documented_homes() -> list[str]:
    """Every name docs/api.rst documents (its autosummary entries)."""
    import re

    text = (Path(__file__).resolve().parents[1] / "docs" / "api.rst").read_text()
    return re.findall(r"^   (nirglucose(?:\.\w+)*)$", text, re.M)


def _resolve(dotted: str):
    import importlib

    home, _, name = dotted.rpartition(".")
    if home:  # an attribute first: ``nirglucose.simulate`` is the function
        try:
            return getattr(importlib.import_module(home), name)
        except AttributeError:
            pass
    return importlib.import_module(dotted)


def test_every_documented_name_is_importable_from_its_home():
    # issue 42: the public API's names are where docs/api.rst says, and each documented
    # module's __all__ resolves (a stale entry after a move fails here, not in the docs)
    import types
    import warnings

    homes = _documented_homes()
    assert {"nirglucose.dataset", "nirglucose.calibration.conformal",
            "nirglucose.evaluation.benchmark.run", "nirglucose.models.labels"} <= set(homes)
    missing = []
    with warnings.catch_warnings():
        warnings.simplefilter("error", DeprecationWarning)  # no documented home is an old one
        for dotted in homes:
            try:
                obj = _resolve(dotted)
            except (ImportError, AttributeError, DeprecationWarning) as exc:
                missing.append(f"{dotted}: {exc}")
                continue
            if isinstance(obj, types.ModuleType):
                missing += [f"{dotted}.{n}" for n in getattr(obj, "__all__", [])
                            if not hasattr(obj, n)]
    assert not missing, missing


def test_the_packages_front_names_resolve():
    # the lazily exported names of the packages that export lazily
    import importlib

    for package in ("nirglucose.evaluation", "nirglucose.evaluation.benchmark",
                    "nirglucose.evaluation.sweep", "nirglucose.calibration",
                    "nirglucose.dataset", "nirglucose.models"):
        module = importlib.import_module(package)
        assert module.__all__, package
        for name in module.__all__:
            assert getattr(module, name) is not None, (package, name)
        if package != "nirglucose.models":  # (its lazy classes are not in its dir())
            assert set(module.__all__) <= set(dir(module)), package
