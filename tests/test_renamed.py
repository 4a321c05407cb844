"""Old import paths of the renamed simulator package keep working for one release."""

from __future__ import annotations

import ast
import subprocess
import sys
import textwrap

import pytest

import nirglucose as ng
from nirglucose import _renamed


def _run(code: str) -> subprocess.CompletedProcess:
    # a fresh interpreter: an old import binds ``nirglucose.simulate`` to the alias module
    return subprocess.run([sys.executable, "-W", "error::DeprecationWarning:__main__", "-c",
                           textwrap.dedent(code)], capture_output=True, text=True, check=False)


def test_the_package_and_the_function_no_longer_share_a_name():
    import nirglucose.simulation as simulation

    assert callable(ng.simulate) and not isinstance(ng.simulate, type(simulation))
    assert "nirglucose.simulate" not in sys.modules or callable(sys.modules["nirglucose.simulate"])


def test_an_old_import_warns_and_gives_the_new_module():
    res = _run("""
        import warnings
        import nirglucose as ng
        import nirglucose.simulation.wear as new
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            import nirglucose.simulate.wear as old
            from nirglucose.simulate.simulator import simulate_frame
        assert old is new, (old, new)
        msgs = [str(w.message) for w in caught if w.category is DeprecationWarning]
        assert any("nirglucose.simulate.wear was renamed nirglucose.simulation.wear" in m
                   for m in msgs), msgs
        assert any("simulator" in m for m in msgs), msgs
        # the function still works after the old package name was imported
        ds = ng.simulate("paper", n_subjects=2, per_subject=1, seed=0)
        assert ds.frame.shape[0] == 2
        import nirglucose.simulation.simulator as sim
        assert sim.__spec__.name == "nirglucose.simulation.simulator"
        print("ok")
    """)
    assert res.returncode == 0 and res.stdout.strip() == "ok", res.stderr[-2000:]


def test_the_old_import_gives_byte_identical_data():
    res = _run("""
        import warnings
        warnings.simplefilter("ignore", DeprecationWarning)
        import nirglucose as ng
        a = ng.simulate("paper", n_subjects=3, per_subject=1, seed=1).frame
        from nirglucose.simulate import simulator  # noqa: F401
        b = ng.simulate("paper", n_subjects=3, per_subject=1, seed=1).frame
        assert a.equals(b)
        print("ok")
    """)
    assert res.returncode == 0 and res.stdout.strip() == "ok", res.stderr[-2000:]


def test_unrelated_names_are_not_answered():
    finder = _renamed.RenamedModuleFinder()
    assert finder.find_spec("nirglucose.simulation") is None
    assert finder.find_spec("nirglucose.simulated") is None
    assert finder.find_spec("numpy") is None


def test_a_missing_old_submodule_is_an_import_error():
    res = _run("""
        import warnings
        warnings.simplefilter("ignore", DeprecationWarning)
        import nirglucose
        try:
            import nirglucose.simulate.no_such_module
        except ModuleNotFoundError as exc:
            print("missing", exc.name)
    """)
    assert "missing nirglucose.simulation.no_such_module" in res.stdout, res.stderr[-2000:]


@pytest.mark.parametrize("name", sorted(_renamed.RENAMED_MODULES))
def test_every_renamed_module_exists_under_its_new_name(name):
    import importlib

    assert importlib.import_module(_renamed.RENAMED_MODULES[name])


# --------------------------------------------------------------------------- issue 42
def _release(version: str) -> tuple[int, ...]:
    """``"0.2.0"`` -> ``(0, 2)``: the release a version belongs to (major, minor)."""
    return tuple(int(p) for p in version.split("+")[0].split(".")[:2])


def overdue(version: str) -> list[str]:
    """The old names still served at ``version`` though their release removed them."""
    if _release(version) < _release(_renamed.REMOVED_IN):
        return []
    return sorted([*_renamed.RENAMED_MODULES, *_renamed.MOVED_NAMES])


def test_the_old_names_are_removed_on_schedule():
    # fails once the package's version reaches REMOVED_IN while old paths remain
    import tomllib
    from pathlib import Path

    pyproject = tomllib.loads((Path(__file__).resolve().parents[1] / "pyproject.toml")
                              .read_text())
    for version in (pyproject["project"]["version"], ng.__version__):
        assert not overdue(version), (f"nirglucose {version} still serves the old names it "
                                      f"promised to remove in {_renamed.REMOVED_IN}: "
                                      f"{overdue(version)[:5]}...")


def test_the_schedule_check_can_fail():
    assert overdue("0.2.0") == [] and overdue("0.2.9+dev") == []
    assert "nirglucose.schema" in overdue("0.3.0") and "nirglucose.simulate" in overdue("1.0")


def test_every_old_path_warns_once_and_gives_the_new_objects():
    # one fresh interpreter for every old module path and departed name
    res = _run("""
        import importlib, sys, warnings
        import nirglucose
        from nirglucose import _renamed
        bad = []
        for old, new in sorted(_renamed.RENAMED_MODULES.items()):
            with warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter("always")
                alias = importlib.import_module(old)
                importlib.import_module(old)  # a second import: no second warning
            msgs = [str(w.message) for w in caught if w.category is DeprecationWarning]
            if len(msgs) != 1 or f"{old} was renamed {new}" not in msgs[0]:
                bad.append((old, msgs))
            module = importlib.import_module(new)
            names = getattr(module, "__all__", [])
            same = all(getattr(alias, n) is getattr(module, n) for n in names)
            if not same or not (alias is module or callable(alias)
                                or type(alias).__name__ == "_AliasModule"):
                bad.append((old, "not the new module's objects"))
        for old, new in sorted(_renamed.MOVED_NAMES.items()):
            module, _, name = old.rpartition(".")
            home, _, attr = new.rpartition(".")
            with warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter("always")
                got = getattr(importlib.import_module(module), name)
            msgs = [str(w.message) for w in caught if w.category is DeprecationWarning]
            if got is not getattr(importlib.import_module(home), attr):
                bad.append((old, "another object"))
            if not any(f"{old} was renamed {new}" in m for m in msgs):
                bad.append((old, msgs))
        print(bad or "ok")
    """)
    assert res.returncode == 0 and res.stdout.strip() == "ok", (res.stdout[-3000:],
                                                                res.stderr[-2000:])


def test_the_package_uses_no_old_path():
    # the package's own code and tests import the new homes (pyproject turns a
    # DeprecationWarning raised from nirglucose.* into an error, this checks the source)
    from pathlib import Path

    root = Path(__file__).resolve().parents[1]
    old = sorted(_renamed.RENAMED_MODULES, key=len, reverse=True)
    found = []
    for path in [*root.glob("src/**/*.py"), *root.glob("tests/**/*.py"),
                 *root.glob("benchmarks/*.py"), *root.glob("studies/*.py"),
                 *root.glob("tools/*.py"), *root.glob("examples/*.py")]:
        if path.name in ("_renamed.py", "test_renamed.py"):
            continue
        for node in ast.walk(ast.parse(path.read_text())):
            mod = None
            if isinstance(node, ast.ImportFrom) and not node.level:
                mod = node.module
            elif isinstance(node, ast.Import):
                mod = node.names[0].name
            if mod and any(mod == o or mod.startswith(o + ".") for o in old):
                found.append(f"{path.relative_to(root)}: {mod}")
    assert not found, found
