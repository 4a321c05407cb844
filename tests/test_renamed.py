"""Old import paths of the renamed simulator package keep working for one release."""

from __future__ import annotations

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
