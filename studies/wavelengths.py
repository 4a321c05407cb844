"""The ``wavelengths`` study end to end: LED sets ranked by the bound, the best confirmed.

Runs :func:`nirglucose.design.rank_designs` (every subset of 1-6 of the default
candidates, 800-1,650 nm every 50 nm plus the study's 940 nm, per detector: Si BPW34
and InGaAs G17190-010K) and the sweep study ``wavelengths``
(:func:`nirglucose.evaluation.run_sweep`, ``study="wavelengths"``): the best design of
each size per detector simulated and scored by the oracle, EBL and the GP
(subject-grouped CV). Defaults are a small setting for two cores (60 subjects x 3,
3 folds x 1 repeat, one seed, 2 worker processes), in a fresh directory so nothing is
reused.

Prints one JSON object on the last line: the wall time of the whole study and of the
ranking alone, the subsets ranked, per confirmed design its bounds and RMSEs (mg/dL,
``[point, low, high]`` with the subject-bootstrap 95 % interval for one seed), the
designs whose oracle interval lies wholly below the oracle-conditioned bound (should be
none), and the machine's 1-minute load average at the end (other work inflates times).

Usage: python studies/wavelengths.py [--preset wearable] [--subjects 60] [--folds 3]
    [--seeds 1] [--jobs 2] [--out DIR]
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import tempfile
import time


def main() -> None:
    from nirglucose.design import rank_designs
    from nirglucose.evaluation.sweep.run import run_sweep

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--preset", default="wearable")
    ap.add_argument("--subjects", type=int, default=60)
    ap.add_argument("--folds", type=int, default=3)
    ap.add_argument("--seeds", type=int, default=1)
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--out", default=None, help="sweep directory (default: a fresh temporary one)")
    a = ap.parse_args()

    t0 = time.perf_counter()
    ranking = rank_designs(a.preset)
    rank_s = time.perf_counter() - t0
    with tempfile.TemporaryDirectory() as tmp:
        out = a.out or os.path.join(tmp, "sweep")
        t1 = time.perf_counter()
        res = run_sweep(study="wavelengths", preset=a.preset, seeds=a.seeds,
                        n_subjects=a.subjects, per_subject=3, n_splits=a.folds, repeats=1,
                        n_boot=500, jobs=a.jobs, out=out)
        sweep_s = time.perf_counter() - t1
    designs = []
    e = res.effects
    for (det, k, wl), d in e.groupby(["detector", "n_leds", "wavelengths_nm"], sort=False):
        r = d.iloc[0]
        designs.append({
            "detector": det, "n_leds": int(k), "wavelengths_nm": wl,
            "study_leds_kept": r["study_leds_kept"],
            "device_bound_mgdl": round(float(r["bound_rmse_mgdl"]), 2),
            "oracle_bound_mgdl": round(float(r["oracle_bound_rmse_mgdl"]), 2),
            **{f"{m}_rmse_mgdl": [round(float(x), 2) for x in
                                  (g["rmse_mgdl"].iloc[0], g["rmse_ci_low"].iloc[0],
                                   g["rmse_ci_high"].iloc[0])]
               for m, g in d.groupby("model", sort=False)},
        })
    for row in designs:
        print(row)
    # the oracle cannot beat its bound beyond sampling error: its interval's top above it
    below = [f"{d['detector']} k={d['n_leds']}" for d in designs
             if "oracle_rmse_mgdl" in d and d["oracle_rmse_mgdl"][2] < d["oracle_bound_mgdl"]]
    print(json.dumps({
        "benchmark": "wavelengths",
        "python": platform.python_version(),
        "cpus": os.cpu_count(),
        "jobs": a.jobs,
        "preset": a.preset,
        "subjects": a.subjects,
        "folds": a.folds,
        "seeds": a.seeds,
        "subsets_ranked": int(len(ranking)),
        "rank_s": round(rank_s, 2),
        "sweep_wall_s": round(sweep_s, 1),
        "total_wall_s": round(time.perf_counter() - t0, 1),
        "tasks": res.meta["tasks_total"],
        "oracle_interval_below_its_bound": below,
        "load_average_1min": round(os.getloadavg()[0], 1),
        "designs": designs,
    }))


if __name__ == "__main__":
    main()
