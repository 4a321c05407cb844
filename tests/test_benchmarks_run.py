"""The speed benchmarks of issue 43's budgets still run (one had stopped importing): each
at a tiny size, in a fresh interpreter, prints one JSON object on its last line."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

_ROOT = Path(__file__).resolve().parents[1]

pytestmark = pytest.mark.slow


@pytest.mark.parametrize(("script", "env", "keys"), [
    ("simulate.py", {"NIRGLUCOSE_BENCH_SNAPSHOTS": "3000"},
     ("rng_floor_ratio", "snapshots_per_s")),
    ("wear_simulate.py", {"NIRGLUCOSE_BENCH_WEAR_SUBJECTS": "2",
                          "NIRGLUCOSE_BENCH_WEAR_DAYS": "1", "NIRGLUCOSE_BENCH_WEAR_JOBS": "1"},
     ("wall_s", "rows", "peak_rss_worker_mb")),
])
def test_benchmark_prints_one_json_object(script, env, keys):
    path = os.pathsep.join([str(_ROOT / "src"), os.environ.get("PYTHONPATH", "")])
    run_env = {**os.environ, **env, "PYTHONPATH": path}
    out = subprocess.run([sys.executable, str(_ROOT / "benchmarks" / script)], env=run_env,
                         capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr[-2000:]
    result = json.loads(out.stdout.strip().splitlines()[-1])
    assert all(k in result for k in keys), result
