"""Sweep scaling and large-dataset simulation: speed-up, peak memory, snapshots/s.

1. Speed-up of a 40-task sweep (10 noise scales x 4 seeds x PLS, paper preset 80 x 3,
   grouped 5-fold CV x 3 repeats per task: a few seconds each) from 1 to 2 local worker
   processes. Each run is timed in a fresh subprocess around ``run_sweep`` only (the
   parent's imports are warm; worker start-up counts against the 2-worker run). The two
   runs must give identical metrics.
2. Simulating 10,000,000 snapshots to partitioned Parquet with ``nirglucose simulate
   --out DIR --jobs 2`` in a subprocess: peak memory of the whole process tree (the sum
   of the RSS of the process and its workers, sampled every 0.1 s with psutil; and the
   largest single process's ``ru_maxrss``, measured before anything else runs), wall
   time and snapshots/s.

Environment: ``NIRGLUCOSE_BENCH_SNAPSHOTS`` (default 10,000,000),
``NIRGLUCOSE_BENCH_SWEEP_TASKS`` (default 40), ``NIRGLUCOSE_BENCH_DIR`` (scratch
directory, default a temporary one; the Parquet output is deleted afterwards).

Prints one JSON object on its last line.
"""

from __future__ import annotations

import json
import os
import resource
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

N_SNAPSHOTS = int(os.environ.get("NIRGLUCOSE_BENCH_SNAPSHOTS", 10_000_000))
N_TASKS = int(os.environ.get("NIRGLUCOSE_BENCH_SWEEP_TASKS", 40))
PER_SUBJECT = 3
SEEDS = 4

_SWEEP_CODE = r"""
import json, sys, time, warnings
warnings.simplefilter("ignore")
from nirglucose.evaluation.sweep import run_sweep
from nirglucose.models.registry import available_models
available_models()  # warm the parent's imports; workers start cold
n_values, seeds, jobs = int(sys.argv[1]), int(sys.argv[2]), int(sys.argv[3])
values = [round(0.25 + 0.25 * k, 2) for k in range(n_values)]
t0 = time.perf_counter()
res = run_sweep({"noise_scale": values}, seeds=seeds, models=["pls"], jobs=jobs,
                n_subjects=80, per_subject=3, n_splits=5, repeats=3)
wall = time.perf_counter() - t0
print(json.dumps({"wall_s": wall, "tasks": res.meta["tasks_total"],
                  "task_s_total": res.meta["task_wall_s_total"],
                  "rmse": res.frame["rmse_mgdl"].round(9).tolist()}))
"""


def _sweep_run(jobs: int) -> dict:
    n_values = max(N_TASKS // SEEDS, 1)
    out = subprocess.run([sys.executable, "-c", _SWEEP_CODE, str(n_values), str(SEEDS),
                          str(jobs)], capture_output=True, text=True, check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def _tree_rss(proc) -> int:
    import psutil

    total = 0
    try:
        procs = [proc, *proc.children(recursive=True)]
    except psutil.NoSuchProcess:
        return 0
    for p in procs:
        try:
            total += p.memory_info().rss
        except psutil.NoSuchProcess:
            pass
    return total


def _simulate_big(scratch: Path, jobs: int = 2) -> dict:
    import psutil

    out = scratch / "big"
    n_subjects = -(-N_SNAPSHOTS // PER_SUBJECT)
    cmd = [sys.executable, "-c", "import sys; from nirglucose.cli import main; sys.exit(main())",
           "simulate", "--preset", "paper", "--subjects", str(n_subjects), "--per-subject",
           str(PER_SUBJECT), "--seed", "0", "--jobs", str(jobs), "--out", str(out)]
    t0 = time.perf_counter()
    proc = psutil.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    peak = 0
    while proc.poll() is None:
        peak = max(peak, _tree_rss(proc))
        time.sleep(0.1)
    wall = time.perf_counter() - t0
    stdout, stderr = proc.communicate()
    if proc.returncode != 0:
        raise RuntimeError(f"simulate failed: {stderr.strip()}")
    max_single = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss
    parts = sorted(out.glob("part-*.parquet"))
    manifest = json.loads((out / "manifest.json").read_text())
    size = sum(p.stat().st_size for p in parts)
    shutil.rmtree(out)
    return {
        "snapshots": manifest["n_rows"],
        "parts": len(parts),
        "jobs": jobs,
        "wall_s": round(wall, 1),
        "snapshots_per_s": round(manifest["n_rows"] / wall),
        "peak_tree_rss_mb": round(peak / 2**20, 1),
        "max_single_process_rss_mb": round(max_single / 1024, 1),
        "disk_gb": round(size / 1e9, 2),
    }


def main() -> None:
    scratch_root = os.environ.get("NIRGLUCOSE_BENCH_DIR")
    scratch = Path(tempfile.mkdtemp(prefix="nirglucose-bench-", dir=scratch_root))
    try:
        load_before = os.getloadavg()[0]
        big = _simulate_big(scratch)  # first: ru_maxrss of children is a running maximum
        one = _sweep_run(1)
        two = _sweep_run(2)
    finally:
        shutil.rmtree(scratch, ignore_errors=True)
    result = {
        "benchmark": "sweep",
        "cores": len(os.sched_getaffinity(0)),
        "load_avg_1min_at_start": round(load_before, 2),
        "sweep_tasks": one["tasks"],
        "sweep_task_s_mean": round(one["task_s_total"] / one["tasks"], 2),
        "sweep_1_worker_s": round(one["wall_s"], 1),
        "sweep_2_workers_s": round(two["wall_s"], 1),
        "sweep_speedup": round(one["wall_s"] / two["wall_s"], 2),
        "sweep_speedup_goal": 1.8,
        "sweep_results_identical": one["rmse"] == two["rmse"],
        "simulate_snapshots": big["snapshots"],
        "simulate_jobs": big["jobs"],
        "simulate_wall_s": big["wall_s"],
        "simulate_snapshots_per_s": big["snapshots_per_s"],
        "simulate_peak_tree_rss_mb": big["peak_tree_rss_mb"],
        "simulate_max_single_process_rss_mb": big["max_single_process_rss_mb"],
        "simulate_peak_memory_goal_mb": 2048,
        "simulate_disk_gb": big["disk_gb"],
        "simulate_parts": big["parts"],
    }
    print(json.dumps(result))


if __name__ == "__main__":
    main()
