"""Same seed, same bytes — across refactors and across CPUs (issue 27).

The frame hashes below were recorded once, after issue 27 routed the simulator's matrix
products and elementary functions through :mod:`nirglucose.portable` (before it, a CPU
with AVX-512 or another OpenBLAS kernel gave other bytes). They must hold

* in this process, whatever CPU runs the suite (``test_frames_byte_identical_to_recorded``);
* under every OpenBLAS kernel this CPU can run, and with NumPy's and numba's
  instruction sets lowered to what an AVX2-only (x86-64-v3) or a baseline (x86-64-v2)
  machine would use, each in a fresh interpreter (``test_same_bytes_under_...``): one set
  of hashes for every machine. A kernel this CPU cannot execute is skipped, not failed.

A change of physics that is meant to change the data updates these hashes in the same
commit, saying why.
"""

from __future__ import annotations

import hashlib
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

import nirglucose as ng
from device_data import LED_SETS, device_overrides

#: (preset, overrides) -> SHA-256 of the frame (12 subjects x 3, seed 11).
GOLDEN = {
    "paper": "0f861d5f3fa7704c98f2d832d85dd8feec56e3beb0c69a068c92a39b93682bd8",
    "wearable": "3929eca66d698a1882923eead6c6aeac1d61e5d08ae80b99418313fd1b39a014",
    "lab": "471eb2362338e51ecae8c62daeb257b23f28a91ba7483006e7588f8ae3a7e61a",
    "field": "2e9ca75e8ce8a7f3363a4a98c0b476d92f78a16dc5d58e19caa6bdb4b153c5c9",
    "physical": "c92017637d503b627a16a782043740c5d5395c19097e97b1429e221964037b1e",
    "wearable-3led": "6c0c656d7e278bd4681cdf1a66f375c2131f7bcbcf99afeadcedac2e70d604c7",
    "paper-3led": "d1a1fd492cb2d27dd2b0fd2656165e1bae9fae18bb340d4c9f12e75fc4527438",
    "paper-diffusion": "db1afc17e4067d04dfa97cc1e9270930d88e6e75b1396ba71134542a490f1f41",
}

_TESTS = Path(__file__).resolve().parents[1]
_SRC = _TESTS.parent / "src"


def frame_hash(frame: pd.DataFrame) -> str:
    """SHA-256 over every column's name, dtype and raw bytes (categories by code)."""
    h = hashlib.sha256()
    for c in frame.columns:
        s = frame[c]
        h.update(c.encode())
        h.update(str(s.dtype).encode())
        if isinstance(s.dtype, pd.CategoricalDtype):
            h.update("|".join(map(str, s.cat.categories)).encode())
            h.update(np.ascontiguousarray(s.cat.codes.to_numpy()).tobytes())
        else:
            h.update(np.ascontiguousarray(s.to_numpy()).tobytes())
    return h.hexdigest()


def golden_frame(name: str) -> pd.DataFrame:
    """The frame behind ``GOLDEN[name]``: ``preset[-3led|-diffusion]``."""
    preset, _, variant = name.partition("-")
    overrides = {
        "": None,
        "3led": device_overrides(LED_SETS[3], 14),
        "diffusion": {"optics.model": "diffusion"},
    }[variant]
    return ng.simulate(preset, 12, 3, 11, overrides=overrides).frame


@pytest.mark.parametrize("name", list(GOLDEN))
def test_frames_byte_identical_to_recorded(name):
    assert frame_hash(golden_frame(name)) == GOLDEN[name]


def test_hash_sees_a_one_ulp_change():
    frame = ng.simulate("lab", 2, 2, 0).frame
    moved = frame.copy()
    moved.loc[0, "glucose_mgdl"] = np.nextafter(moved.loc[0, "glucose_mgdl"], np.inf)
    assert frame_hash(moved) != frame_hash(frame)


# ------------------------------------------------------------------ across CPUs

def _cpu_flags() -> set[str]:
    try:
        text = Path("/proc/cpuinfo").read_text()
    except OSError:
        return set()
    line = next((ln for ln in text.splitlines() if ln.startswith("flags")), "")
    return set(line.partition(":")[2].split())


def _numpy_targets_above(level: str) -> str:
    """NumPy's dispatch targets above ``level`` (``X86_V2`` baseline, ``X86_V3``), for
    ``NPY_DISABLE_CPU_FEATURES``: NumPy then runs the loops such a CPU would."""
    from numpy._core import _multiarray_umath as umath

    dispatch = list(umath.__cpu_dispatch__)
    keep = dispatch[: dispatch.index(level) + 1] if level in dispatch else []
    found = umath.__cpu_features__
    return " ".join(t for t in dispatch if t not in keep and found.get(t))


#: name -> (CPU flags it needs, environment). Each OpenBLAS kernel the issue names, two
#: of them with NumPy and numba lowered to an older instruction set.
ENVIRONMENTS = {
    "openblas-Prescott-numpy-baseline": (
        {"pni"},  # SSE3 ("pni" in /proc/cpuinfo)
        lambda: {"OPENBLAS_CORETYPE": "Prescott", "NUMBA_CPU_NAME": "generic",
                 "NPY_DISABLE_CPU_FEATURES": _numpy_targets_above("X86_V2")},
    ),
    "openblas-Haswell-numpy-x86-64-v3": (
        {"avx2", "fma"},
        lambda: {"OPENBLAS_CORETYPE": "Haswell", "NUMBA_CPU_NAME": "haswell",
                 "NPY_DISABLE_CPU_FEATURES": _numpy_targets_above("X86_V3")},
    ),
    "openblas-SkylakeX": (
        {"avx512f", "avx512cd", "avx512bw", "avx512dq", "avx512vl"},
        lambda: {"OPENBLAS_CORETYPE": "SkylakeX"},
    ),
    "openblas-Zen": ({"avx2", "fma"}, lambda: {"OPENBLAS_CORETYPE": "Zen"}),
}

_PROBE = """
import json, sys
sys.path[:0] = [{tests!r}, {here!r}]
from test_simulate_golden import GOLDEN, frame_hash, golden_frame
from threadpoolctl import threadpool_info
import hashlib, numpy as np
np_exp = hashlib.sha256(np.exp(np.linspace(0.1, 5.0, 1001)).tobytes()).hexdigest()
blas = sorted({{i.get("architecture") for i in threadpool_info()
               if i.get("internal_api") == "openblas"}})
print(json.dumps({{"np_exp": np_exp, "blas": blas,
                  "hashes": {{n: frame_hash(golden_frame(n)) for n in GOLDEN}}}}))
"""


# fresh interpreters compiling every kernel for other CPUs (about 15 s each once the
# simulator's layers were compiled): `make test-slow`, which CI runs too
@pytest.mark.slow
@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="CPU flags read from /proc")
@pytest.mark.parametrize("env_name", list(ENVIRONMENTS))
def test_same_bytes_under_every_kernel_and_instruction_set(env_name):
    needs, make_env = ENVIRONMENTS[env_name]
    missing = needs - _cpu_flags()
    if missing:
        pytest.skip(f"this CPU cannot run {env_name} (no {', '.join(sorted(missing))})")
    env = dict(os.environ)
    for key in ("OPENBLAS_CORETYPE", "NPY_DISABLE_CPU_FEATURES", "NUMBA_CPU_NAME"):
        env.pop(key, None)
    env.update(make_env())
    env["PYTHONPATH"] = os.pathsep.join([str(_SRC), env.get("PYTHONPATH", "")])
    env.update(OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1")
    code = _PROBE.format(tests=str(_TESTS), here=str(Path(__file__).parent))
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True,
                         text=True, timeout=300)
    assert out.returncode == 0, out.stderr[-2000:]
    got = json.loads(out.stdout.strip().splitlines()[-1])
    kernel = env["OPENBLAS_CORETYPE"] if "OPENBLAS_CORETYPE" in env else None
    if kernel in ("Haswell", "SkylakeX"):  # the probe ran the kernel it asked for
        assert got["blas"] == [kernel], got["blas"]
    if "X86_V4" in env.get("NPY_DISABLE_CPU_FEATURES", "").split():
        # NumPy really ran other elementary-function loops there (else this tests nothing)
        here = hashlib.sha256(np.exp(np.linspace(0.1, 5.0, 1001)).tobytes()).hexdigest()
        assert got["np_exp"] != here, "NPY_DISABLE_CPU_FEATURES did not change np.exp"
    wrong = {n: h[:12] for n, h in got["hashes"].items() if h != GOLDEN[n]}
    assert not wrong, f"{env_name}: frames differ from the recorded bytes: {wrong}"
