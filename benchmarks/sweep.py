"""Sweep scaling and large-dataset simulation: speed-up, peak memory, snapshots/s.

1. Speed-up of a 40-task sweep (5 noise scales x 4 seeds x EBL and PLS, paper preset
   1500 subjects x 5, grouped 5-fold CV x 15 repeats per task: a few seconds each) from
   1 to 2 local worker processes. Each run is timed in a fresh subprocess around
   ``run_sweep`` only (the parent's imports are warm; worker start-up, about 7 s of
   imports per worker, counts against the 2-worker run). BLAS/OpenMP use one thread
   per process in both runs, so the comparison is of processes. The runs alternate
   (1, 2, 1, 2 workers) and the faster of each pair counts, which damps load from other
   users of a shared machine. All runs must give identical metrics.
2. Simulating 10,000,000 snapshots to partitioned Parquet with ``nirglucose simulate
   --out DIR --jobs 2`` in a subprocess: peak memory of the whole process tree (the sum
   of the RSS of the process and its workers, sampled every 0.1 s with psutil; and the
   largest single process's ``ru_maxrss``, measured before anything else runs), wall
   time and snapshots/s.

Environment: ``NIRGLUCOSE_BENCH_SNAPSHOTS`` (default 10,000,000; 0 skips part 2),
``NIRGLUCOSE_BENCH_SWEEP_TASKS`` (default 40), ``NIRGLUCOSE_BENCH_ROUNDS`` (default 2),
``NIRGLUCOSE_BENCH_DIR`` (scratch directory, default a temporary one; the Parquet output
is deleted afterwards).

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
ROUNDS = int(os.environ.get("NIRGLUCOSE_BENCH_ROUNDS", 2))
_THREAD_VARS = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")

_SWEEP_CODE = r"""
import json, sys, time, warnings
warnings.simplefilter("ignore")
from nirglucose.evaluation.sweep import run_sweep
from nirglucose.models.registry import available_models
available_models()  # warm the parent's imports; workers start cold
n_values, seeds, jobs = int(sys.argv[1]), int(sys.argv[2]), int(sys.argv[3])
values = [0.25, 0.5, 1.0, 2.0, 4.0, 0.75, 1.5, 3.0, 6.0, 8.0][:n_values]
t0 = time.perf_counter()
res = run_sweep({"noise_scale": values}, seeds=seeds, models=["ebl", "pls"], jobs=jobs,
                n_subjects=1500, per_subject=5, n_splits=5, repeats=15)
wall = time.perf_counter() - t0
print(json.dumps({"wall_s": wall, "tasks": res.meta["tasks_total"],
                  "task_s_total": res.meta["task_wall_s_total"],
                  "rmse": res.frame["rmse_mgdl"].round(9).tolist()}))
"""


def _sweep_run(jobs: int) -> dict:
    n_values = min(max(N_TASKS // (2 * SEEDS), 1), 10)
    env = {**os.environ, **{k: "1" for k in _THREAD_VARS}}
    out = subprocess.run([sys.executable, "-c", _SWEEP_CODE, str(n_values), str(SEEDS),
                          str(jobs)], capture_output=True, text=True, check=True, env=env)
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
        big = _simulate_big(scratch) if N_SNAPSHOTS else {}  # first: ru_maxrss is a running max
        runs = [_sweep_run(jobs) for _ in range(ROUNDS) for jobs in (1, 2)]
        one = min(runs[0::2], key=lambda r: r["wall_s"])
        two = min(runs[1::2], key=lambda r: r["wall_s"])
    finally:
        shutil.rmtree(scratch, ignore_errors=True)
    result = {
        "benchmark": "sweep",
        "cores": len(os.sched_getaffinity(0)),
        "load_avg_1min_at_start": round(load_before, 2),
        "load_avg_1min_at_end": round(os.getloadavg()[0], 2),
        "sweep_tasks": one["tasks"],
        "sweep_task_s_mean": round(one["task_s_total"] / one["tasks"], 2),
        "sweep_1_worker_s": round(one["wall_s"], 1),
        "sweep_2_workers_s": round(two["wall_s"], 1),
        "sweep_speedup": round(one["wall_s"] / two["wall_s"], 2),
        "sweep_speedup_goal": 1.8,
        "sweep_1_worker_runs_s": [round(r["wall_s"], 1) for r in runs[0::2]],
        "sweep_2_workers_runs_s": [round(r["wall_s"], 1) for r in runs[1::2]],
        "sweep_results_identical": all(r["rmse"] == runs[0]["rmse"] for r in runs),
        "simulate_snapshots": big.get("snapshots"),
        "simulate_jobs": big.get("jobs"),
        "simulate_wall_s": big.get("wall_s"),
        "simulate_snapshots_per_s": big.get("snapshots_per_s"),
        "simulate_peak_tree_rss_mb": big.get("peak_tree_rss_mb"),
        "simulate_max_single_process_rss_mb": big.get("max_single_process_rss_mb"),
        "simulate_peak_memory_goal_mb": 2048,
        "simulate_disk_gb": big.get("disk_gb"),
        "simulate_parts": big.get("parts"),
    }
    print(json.dumps(result))


if __name__ == "__main__":
    main()
