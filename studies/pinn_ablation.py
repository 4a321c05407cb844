"""The physics ablation that asks the question: each PINN with and without its physics term.

Protocol: ``nirglucose.simulate(preset, 80, 3, seed)`` for ``paper`` and ``wearable``,
seeds 0..N-1 (default 3); :func:`nirglucose.evaluation.run_benchmark` with the four
PINNs, ``ablation=True``, subject-grouped 5-fold CV, **one repeat** (the package's
default is 3), tuned parameters. Where tuning chose ``lambda_phys = 0`` the PINN *is*
its no-physics fit (no test, no verdict) and the benchmark also runs it at the best
λ > 0 of the tuning's validation curve (``<pinn>/lambda=<λ>``, the slice at the tuned
training parameters, recorded by ``tools/tune.py`` on the tuning seeds),
paired against ``<pinn>/no-physics``. Per preset, seed and pair: Δ RMSE (with physics
minus without, mg/dL) with its paired subject-bootstrap 95 % CI and Holm p over the
tested pairs; over seeds, the mean Δ with a Student-t 95 % interval.

Also prints each PINN's tuning validation curve (``lambda_curve``). Not a timed test.
Prints one JSON object on its last line.

Usage: python studies/pinn_ablation.py [--seeds 3] [--jobs 2] [--presets paper,wearable]
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np
from scipy import stats

PINNS = ("original-pinn", "optimized-pinn", "rte-pinn", "selective-rte-pinn")


def _one(preset: str, seed: int, jobs: int) -> list[dict]:
    import nirglucose as ng
    from nirglucose.evaluation import Protocol, run_benchmark

    ds = ng.simulate(preset, n_subjects=80, per_subject=3, seed=seed)
    res = run_benchmark(
        ds, list(PINNS), protocol=Protocol(n_splits=5, repeats=1, seed=seed), jobs=jobs,
        ablation=True,
        oracle_reference=False, drop_one_models="none",
        timing={"n_single": 2, "min_single": 1, "batch_rows": 50, "batch_repeats": 1},
    )
    keep = ("model", "ablated_model", "lambda_phys", "lambda_source", "tested", "verdict",
            "rmse_mgdl", "ablated_rmse_mgdl", "rmse_diff_mgdl", "ci_low", "ci_high", "p_holm")
    out = []
    for r in res.ablation.to_dict(orient="records"):
        row = {k: r[k] for k in keep}
        out.append({k: (round(v, 3) if isinstance(v, float) else v) for k, v in row.items()})
    return out


def _over_seeds(rows: list[dict]) -> dict:
    d = np.array([r["rmse_diff_mgdl"] for r in rows], float)
    if not rows[0]["tested"]:
        return {"tested": False, "verdict": rows[0]["verdict"]}
    m = float(d.mean())
    if len(d) > 1:
        h = float(stats.t.ppf(0.975, len(d) - 1) * d.std(ddof=1) / np.sqrt(len(d)))
    else:
        h = float("nan")
    return {"tested": True, "lambda_phys": rows[0]["lambda_phys"],
            "rmse_diff_mean_mgdl": round(m, 3), "t95": [round(m - h, 3), round(m + h, 3)],
            "n_seeds_significant_helps": sum(r["verdict"] == "physics helps" for r in rows),
            "n_seeds_significant_hurts": sum(r["verdict"] == "physics hurts" for r in rows)}


def main() -> None:
    from nirglucose.models.tuning import lambda_curve

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=3, help="seeds 0..N-1")
    ap.add_argument("--jobs", type=int, default=2, help="worker processes")
    ap.add_argument("--presets", default="paper,wearable")
    a = ap.parse_args()
    t0 = time.time()
    out = {"protocol": "grouped 5-fold CV x 1 repeat, 80 x 3 per seed, tuned parameters",
           "seeds": list(range(a.seeds))}
    for preset in a.presets.split(","):
        runs = [_one(preset, s, a.jobs) for s in range(a.seeds)]
        pairs = {}
        for k, row in enumerate(runs[0]):
            per_seed = [r[k] for r in runs]
            pairs[row["model"]] = {"ablated_model": row["ablated_model"],
                                   "per_seed": per_seed, "over_seeds": _over_seeds(per_seed)}
        out[preset] = {"pairs": pairs,
                       "lambda_curves": {p: lambda_curve(p, preset) for p in PINNS}}
        print(json.dumps({preset: {m: v["over_seeds"] for m, v in pairs.items()}}), flush=True)
    out["seconds"] = round(time.time() - t0, 1)
    print(json.dumps(out))


if __name__ == "__main__":
    main()
