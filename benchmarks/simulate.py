"""Simulator speed: snapshots/s, the random-number floor ratio, peak memory.

rng_floor_ratio = simulator CPU time / CPU time to draw, in the same process, as many random
variates (standard normals, in arrays of the same sizes) as the simulator consumed; each
the fastest of ``ROUNDS`` runs (as ``timeit`` reports), the two run in turn so that both
see the machine in the same states, since one run of either swings by 10-20 % on a
shared machine.
Peak memory is measured in a fresh subprocess that builds the whole 1M-row dataset.

Prints one JSON object on its last line.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time

# one BLAS thread, set before numpy loads (BLAS reads it once, at load): the measure is
# the CPU time of one process's work, not of idle BLAS threads spinning
os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np  # noqa: E402

N_SNAPSHOTS = int(os.environ.get("NIRGLUCOSE_BENCH_SNAPSHOTS", 1_000_000))
PER_SUBJECT = 3
ROUNDS = int(os.environ.get("NIRGLUCOSE_BENCH_ROUNDS", 7))


def _simulate(preset: str, overrides: dict | None = None):
    import nirglucose as ng
    from nirglucose.simulation.simulator import block_ranges, scenario_tables, simulate_block

    cfg = ng.resolve_config(preset, overrides or {})
    n_subjects = -(-N_SNAPSHOTS // PER_SUBJECT)
    tables = scenario_tables(cfg)
    sizes, n_rows = [], 0
    start = time.process_time()
    for block, first, n_sub in block_ranges(n_subjects):
        cols, n_var = simulate_block(cfg, 0, block, first, n_sub, PER_SUBJECT, tables)
        sizes.append(n_var)
        n_rows += len(cols["glucose_mgdl"])
    elapsed = time.process_time() - start
    return elapsed, n_rows, sizes


def _rng_floor(sizes) -> float:
    rng = np.random.default_rng(0)
    start = time.process_time()
    for n in sizes:
        rng.standard_normal(n)
    return time.process_time() - start


def _peak_memory_mb() -> float:
    code = (
        "import resource, nirglucose as ng;"
        f"ds = ng.simulate('paper', {-(-N_SNAPSHOTS // PER_SUBJECT)}, {PER_SUBJECT}, 0);"
        "print(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024)"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    return float(out.stdout.strip().splitlines()[-1])


def main() -> dict:
    result = {"n_snapshots": N_SNAPSHOTS}
    for label, preset, over in (
        ("paper", "paper", None),
        ("paper_diffusion", "paper", {"optics.model": "diffusion"}),
    ):
        _, n_rows, sizes = _simulate(preset, over)  # warm caches (tables, imports)
        # simulator and floor in turn, so both see the machine in the same states
        times, floors = [], []
        for _ in range(ROUNDS):
            times.append(_simulate(preset, over)[0])
            floors.append(_rng_floor(sizes))
        elapsed, floor = min(times), min(floors)
        result[label] = {
            "rounds": ROUNDS,
            "seconds": round(elapsed, 3),
            "snapshots_per_s": round(n_rows / elapsed),
            "random_variates": int(sum(sizes)),
            "variates_per_snapshot": round(sum(sizes) / n_rows, 1),
            "rng_floor_seconds": round(floor, 3),
            "rng_floor_ratio": round(elapsed / floor, 2),
        }
    result["snapshots_per_s"] = result["paper"]["snapshots_per_s"]
    result["rng_floor_ratio"] = result["paper"]["rng_floor_ratio"]
    result["peak_memory_mb_1m_dataframe"] = round(_peak_memory_mb(), 1)
    return result


if __name__ == "__main__":
    print(json.dumps(main()))
