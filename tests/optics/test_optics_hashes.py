"""Refactors change no optics result: hashes against those recorded at main.

``tests/optics/data/optics_hashes_main.json`` is the output of
``tools/optics_hashes.py --default-diffusion``, first at main 2a4031c (before the
photon engines were merged and ``lut.py`` was split), re-recorded after issue 27 routed
the optics' matrix products and elementary functions through :mod:`nirglucose.portable`
(same bits under every OpenBLAS kernel and NumPy/numba instruction set; checked under
``SkylakeX``, ``Haswell`` and NumPy/numba lowered to x86-64-v3). Floating-point bytes
still depend on the NumPy build, so the comparison is skipped under another NumPy
version than the recording's.
"""

from __future__ import annotations

import importlib.util
import json
from pathlib import Path

import numpy as np
import pytest

_ROOT = Path(__file__).resolve().parents[2]
_RECORDED = json.loads((Path(__file__).parent / "data" / "optics_hashes_main.json").read_text())


def _script():
    spec = importlib.util.spec_from_file_location(
        "optics_hashes", _ROOT / "tools" / "optics_hashes.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


needs_same_numpy = pytest.mark.skipif(
    np.__version__ != _RECORDED["numpy"],
    reason=f"hashes recorded under numpy {_RECORDED['numpy']}")


@needs_same_numpy
def test_photon_engine_runs_are_bit_identical_to_main():
    got = _script()._mc_hashes()
    assert set(got) == {"mc_layers", "mc_layers_semi_infinite", "mc_slab", "mc_slab_clear",
                        "mc_detected_paths", "reweight_detected"}
    assert got == {k: _RECORDED[k] for k in got}


@needs_same_numpy
@pytest.mark.slow
def test_tables_and_rte_lut_simulation_are_bit_identical_to_main(tmp_path, monkeypatch):
    monkeypatch.setenv("NIRGLUCOSE_CACHE", str(tmp_path))
    monkeypatch.delenv("NIRGLUCOSE_LUT_GRID", raising=False)
    mod = _script()
    got = {**mod._lut_hashes(False), **mod._sim_hashes(False)}
    assert len(got) == 7
    assert got == {k: _RECORDED[k] for k in got}


def test_a_changed_result_changes_its_hash():
    h = _script()._h
    a = np.linspace(0.0, 1.0, 11)
    b = a.copy()
    b[3] = np.nextafter(b[3], 2.0)
    assert h(a) == h(a.copy()) != h(b)

# Long-running (whole studies, end-to-end runs, Monte Carlo or every model): `make test-slow`,
# which CI runs beside the fast `make test` (tests/test_slow_marks.py)
pytestmark = pytest.mark.slow
