"""How far a reading can be trusted: interval coverage and personal calibration (issue 23).

Acceptance: on ``paper`` and ``wearable``, simulation seeds 0-4, the benchmark's
subject-grouped conformal intervals (:mod:`nirglucose.calibration.conformal`; the
other folds' held-out residuals calibrate each test fold) cover held-out subjects'
readings within +-3 points of the nominal 90 % and 80 %, for every model: coverage is
averaged over the seeds per model and preset.

The same runs score the personal calibration protocol
(:mod:`nirglucose.calibration.personal`) with k = 1 calibration reading per test
subject; a second, smaller part varies the readings per subject (``--per-subject-sweep``)
with k = 1 and 2.

Usage::

    python studies/conformal.py [--presets paper,wearable] [--seeds 0,1,2,3,4]
        [--models ebl,pls,mean,gbr | all] [--subjects 80] [--per-subject 3]
        [--folds 5] [--repeats 1] [--per-subject-sweep 3,5] [--sweep-seeds 0,1,2]

Single-threaded; the last line of the output is one JSON object.
"""

from __future__ import annotations

import argparse
import json
import time
import warnings

import numpy as np

import nirglucose as ng
from nirglucose.evaluation import Protocol
from nirglucose.evaluation.benchmark.run import run_benchmark
from nirglucose.models.registry import available_models

#: Models run by default: every non-network row except the GP (cheap on 2 shared cores);
#: ``--models all`` runs every registered model.
DEFAULT_MODELS = "ebl,pls,mean,gbr"
#: Acceptance tolerance around the nominal coverage [percentage points] (issue 23).
TOLERANCE_PCT = 3.0
_TIMING = {"n_single": 1, "min_single": 1, "time_budget_s": 0.0, "warmup": 0}


def _ints(text: str) -> list[int]:
    return [int(v) for v in text.split(",") if v.strip()]


def _bench(preset, seed, models, subjects, per_subject, folds, repeats, k):
    ds = ng.simulate(preset, subjects, per_subject, seed=seed)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return run_benchmark(
            ds,
            models,
            protocol=Protocol(n_splits=folds, repeats=repeats, seed=seed, resamples=500,
                              calibration=k),
            timing=dict(_TIMING),
            drop_one_models="none",
            oracle_reference=False,
        )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--presets", default="paper,wearable")
    ap.add_argument("--seeds", default="0,1,2,3,4")
    ap.add_argument("--models", default=DEFAULT_MODELS)
    ap.add_argument("--subjects", type=int, default=80)
    ap.add_argument("--per-subject", type=int, default=3)
    ap.add_argument("--folds", type=int, default=5)
    ap.add_argument("--repeats", type=int, default=1)
    ap.add_argument("--per-subject-sweep", default="3,5")
    ap.add_argument("--sweep-seeds", default="0,1,2")
    ap.add_argument("--sweep-models", default="ebl")
    a = ap.parse_args()
    models = available_models() if a.models == "all" else a.models.split(",")
    presets = a.presets.split(",")
    t0 = time.perf_counter()

    cov: dict = {}
    cal: dict = {}
    for preset in presets:
        for seed in _ints(a.seeds):
            res = _bench(preset, seed, models, a.subjects, a.per_subject, a.folds, a.repeats, 1)
            for _, r in res.metrics.iterrows():
                d = cov.setdefault(preset, {}).setdefault(
                    r["model"],
                    {
                        "coverage90_pct": [],
                        "coverage80_pct": [],
                        "width90_mgdl": [],
                        "width80_mgdl": [],
                        "rmse_mgdl": [],
                    },
                )
                for key in d:
                    d[key].append(float(r[key]))
            for _, r in res.calibration.iterrows():
                key = f"{r['model']}/{r['method']}"
                cal.setdefault(preset, {}).setdefault(key, []).append(float(r["rmse_mgdl"]))
            print(f"{preset} seed {seed}: done at {time.perf_counter() - t0:.0f} s", flush=True)

    coverage, failures = {}, []
    for preset, per_model in cov.items():
        coverage[preset] = {}
        for model, d in per_model.items():
            row = {k: round(float(np.mean(v)), 2) for k, v in d.items()}
            row["coverage90_per_seed"] = [round(v, 1) for v in d["coverage90_pct"]]
            row["ok"] = bool(
                abs(row["coverage90_pct"] - 90) <= TOLERANCE_PCT
                and abs(row["coverage80_pct"] - 80) <= TOLERANCE_PCT
            )
            if not row["ok"]:
                failures.append(f"{preset}/{model}")
            coverage[preset][model] = row
    calibration = {
        preset: {k: round(float(np.mean(v)), 2) for k, v in rows.items()}
        for preset, rows in cal.items()
    }

    sweep = {}
    for preset in presets:
        for n in _ints(a.per_subject_sweep):
            for k in (1, 2):
                if n <= k:
                    continue
                vals: dict = {}
                for seed in _ints(a.sweep_seeds):
                    res = _bench(
                        preset, seed, a.sweep_models.split(","), a.subjects, n, a.folds, 1, k
                    )
                    for _, r in res.calibration.iterrows():
                        vals.setdefault(f"{r['model']}/{r['method']}", []).append(
                            float(r["rmse_mgdl"])
                        )
                sweep[f"{preset}/per_subject={n}/k={k}"] = {
                    m: round(float(np.mean(v)), 2) for m, v in vals.items()
                }
                print(f"sweep {preset} n={n} k={k}: {time.perf_counter() - t0:.0f} s", flush=True)

    print(
        json.dumps(
            {
                "benchmark": "conformal",
                "presets": presets,
                "seeds": _ints(a.seeds),
                "models": models,
                "subjects": a.subjects,
                "per_subject": a.per_subject,
                "folds": a.folds,
                "repeats": a.repeats,
                "tolerance_pct": TOLERANCE_PCT,
                "coverage": coverage,
                "acceptance_pass": not failures,
                "failures": failures,
                "calibration_k1_rmse_mgdl": calibration,
                "per_subject_sweep_rmse_mgdl": sweep,
                "wall_s": round(time.perf_counter() - t0, 1),
            }
        )
    )


if __name__ == "__main__":
    main()
