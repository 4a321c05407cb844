"""Wear simulation speed and memory: 100 subjects x 14 days, a reading every 5 min.

403,200 readings (4032 per subject) written as partitioned Parquet by 2 worker
processes, chunk by chunk (``nirglucose.simulation.wear.WEAR_CHUNK_SUBJECTS`` subjects a
chunk). Peak memory: ``resource.getrusage`` of this process (``ru_maxrss``) and of its
worker processes (``RUSAGE_CHILDREN``, after the workers are shut down and reaped).

Sizes can be changed with NIRGLUCOSE_BENCH_WEAR_SUBJECTS / _DAYS / _EVERY_MIN / _JOBS.
Prints one JSON object on its last line.
"""

from __future__ import annotations

import json
import os
import resource
import tempfile
import time
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")

SUBJECTS = int(os.environ.get("NIRGLUCOSE_BENCH_WEAR_SUBJECTS", 100))
DAYS = int(os.environ.get("NIRGLUCOSE_BENCH_WEAR_DAYS", 14))
EVERY_MIN = int(os.environ.get("NIRGLUCOSE_BENCH_WEAR_EVERY_MIN", 5))
JOBS = int(os.environ.get("NIRGLUCOSE_BENCH_WEAR_JOBS", 2))


def main() -> dict:
    import nirglucose as ng
    from nirglucose.simulation import wear

    cfg = ng.resolve_config("paper")
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "wear"
        start, cpu = time.perf_counter(), time.process_time()
        n = wear.write_wear_partitioned(cfg, out, SUBJECTS, DAYS, EVERY_MIN, seed=0,
                                        n_jobs=JOBS)
        wall = time.perf_counter() - start
        parent_cpu = time.process_time() - cpu
        size_mb = sum(p.stat().st_size for p in out.glob("*.parquet")) / 2**20
    if JOBS > 1:
        from joblib.externals.loky import get_reusable_executor

        get_reusable_executor().shutdown(wait=True)
    return {
        "benchmark": "wear_simulate",
        "preset": "paper",
        "subjects": SUBJECTS,
        "wear_days": DAYS,
        "every_min": EVERY_MIN,
        "rows": n,
        "jobs": JOBS,
        "chunk_subjects": wear.WEAR_CHUNK_SUBJECTS,
        "wall_s": round(wall, 1),
        "rows_per_s": round(n / wall),
        "parent_cpu_s": round(parent_cpu, 1),
        "parquet_mb": round(size_mb, 1),
        "peak_rss_parent_mb": round(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024),
        "peak_rss_worker_mb": round(
            resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024),
    }


if __name__ == "__main__":
    print(json.dumps(main()))
