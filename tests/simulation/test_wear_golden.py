"""Same seed, same wear bytes — across the compiled RK4 and across CPUs (issue 43).

The hashes below were recorded from the NumPy RK4 loop, before
:func:`nirglucose.simulation.uva_padova.integrate` moved to a compiled kernel
(:mod:`nirglucose.simulation.kernels.uva_padova_rk4`); the kernel must give the same
bytes, in this process and in a fresh interpreter with numba's code generated for a
generic x86-64 (``NUMBA_CPU_NAME=generic``). The frames hold subjects of every status,
type 1 (boluses, a day's insulin sensitivity) among them. A change of physics that is
meant to change the data updates these hashes in the same commit, saying why.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest
from test_simulate_golden import frame_hash

import nirglucose as ng
from nirglucose.simulation import wear

#: preset -> SHA-256 (``frame_hash``) of its wear frame: 7 subjects, 2 days, a reading
#: every 30 min, seed 3.
GOLDEN = {
    "paper": "0e8b5110f2eb945a8d121eff75911d61a0634c2c8c09222c56f35ef5b2e7a3c4",
    "wearable": "5ba498ccca66958b9319a7cedda21a5a712ccd72eda1253d865b649ec3dc695d",
}

_HERE = Path(__file__).resolve().parent
_SRC = _HERE.parents[1] / "src"


def golden_wear_frame(preset: str):
    """The frame behind ``GOLDEN[preset]``."""
    return wear.simulate_wear_frame(ng.resolve_config(preset), 7, 2, 30, seed=3)


@pytest.mark.parametrize("preset", list(GOLDEN))
def test_wear_frames_byte_identical_to_recorded(preset):
    frame = golden_wear_frame(preset)
    assert set(frame["diabetes_status"].astype(str)) == {"normal", "prediabetes", "type1",
                                                         "type2"}
    assert frame_hash(frame) == GOLDEN[preset]


_PROBE = """
import json, sys
sys.path[:0] = [{tests!r}, {here!r}]
from test_wear_golden import GOLDEN, golden_wear_frame
from test_simulate_golden import frame_hash
print(json.dumps({{p: frame_hash(golden_wear_frame(p)) for p in GOLDEN}}))
"""


# a fresh interpreter compiling every kernel for another CPU: `make test-slow` (CI runs it)
@pytest.mark.slow
def test_same_wear_bytes_with_numba_generating_for_a_generic_cpu():
    env = {k: v for k, v in os.environ.items()
           if k not in ("OPENBLAS_CORETYPE", "NPY_DISABLE_CPU_FEATURES")}
    env.update(NUMBA_CPU_NAME="generic", OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1")
    env["PYTHONPATH"] = os.pathsep.join([str(_SRC), env.get("PYTHONPATH", "")])
    code = _PROBE.format(tests=str(_HERE.parent), here=str(_HERE))
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True,
                         text=True, timeout=600)
    assert out.returncode == 0, out.stderr[-2000:]
    assert json.loads(out.stdout.strip().splitlines()[-1]) == GOLDEN
