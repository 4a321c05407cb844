"""The forward-model estimator and the hybrids against EBL, GP, no skill and the oracle.

Protocol: ``nirglucose.simulate(preset, 80, 3, seed)`` for ``paper`` and ``wearable``,
seeds 0-4; :func:`nirglucose.evaluation.run_benchmark` with subject-grouped 5-fold CV,
**one repeat** (the package's default is 3; one keeps the run to a few minutes on two
cores), its subject-level bootstrap CIs, and every model with its tuned parameters
(``tuned_params``: ``tools/tune.py`` tunes the new models on the same footing as
every family where ``tuned_params.json`` holds them; ``--untuned`` runs their defaults,
with ``physics-inversion+gp`` at ``cv=0`` to keep the run short, as before they were
tuned). Per preset and model: the RMSE of each seed with its 95 % CI, the mean and SD
over seeds, and the mean paired difference to the GP (model - gp) over seeds. The
inverse task (``inverse.csv``): per state-predicting model and quantity, the RMSE of
the recovered tissue state against the truth, mean over seeds, next to the truth's SD.

Not a timed test. Prints one JSON object on its last line.

Usage: python studies/physics_inversion.py [--seeds 5] [--jobs 2]
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np

PRESETS = ("paper", "wearable")
MODELS = ("mean", "ebl", "gp", "physics-inversion", "ebl+gp", "physics-inversion+gp", "oracle")
UNTUNED_PARAMS = {"physics-inversion+gp": {"cv": 0}}
TIMING = {"n_single": 3, "min_single": 2, "batch_rows": 100, "batch_repeats": 1}


def _one(preset: str, seed: int, jobs: int, params: dict) -> tuple[dict, list]:
    import nirglucose as ng
    from nirglucose.evaluation import Protocol, run_benchmark

    ds = ng.simulate(preset, n_subjects=80, per_subject=3, seed=seed)
    res = run_benchmark(
        ds, list(MODELS), protocol=Protocol(n_splits=5, repeats=1, seed=seed), jobs=jobs,
        model_params=params, timing=TIMING, drop_one_models="none",
    )
    m = res.metrics.set_index("model")
    return {
        name: [float(m.loc[name, c]) for c in ("rmse_mgdl", "rmse_ci_low", "rmse_ci_high")]
        for name in MODELS
    }, res.inverse.to_dict(orient="records")


def _inverse_summary(tables: list[list[dict]]) -> dict:
    """Mean over seeds of each (model, quantity)'s RMSE, bias and r; the truth's SD."""
    import pandas as pd

    t = pd.DataFrame([r for tab in tables for r in tab])
    if t.empty:
        return {}
    g = t.groupby(["model", "quantity"])[["rmse", "bias", "pearson_r", "truth_sd"]].mean()
    return {f"{m} {q}": {k: float(f"{v:.4g}") for k, v in row.items()}
            for (m, q), row in g.iterrows()}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=5, help="seeds 0..N-1")
    ap.add_argument("--jobs", type=int, default=2, help="worker processes")
    ap.add_argument("--untuned", action="store_true",
                    help="the new models' defaults (physics-inversion+gp at cv=0)")
    a = ap.parse_args()
    params = UNTUNED_PARAMS if a.untuned else None
    t0 = time.time()
    out = {"protocol": "grouped 5-fold CV x 1 repeat (package default 3), 80 x 3 per seed",
           "seeds": list(range(a.seeds)), "models": list(MODELS), "params": params or "tuned"}
    for preset in PRESETS:
        both = [_one(preset, s, a.jobs, params) for s in range(a.seeds)]
        runs = [r for r, _ in both]
        summary = {}
        for name in MODELS:
            rmse = np.array([r[name][0] for r in runs])
            gp = np.array([r["gp"][0] for r in runs])
            summary[name] = {
                "rmse_per_seed": [round(v, 2) for v in rmse],
                "ci_per_seed": [[round(r[name][1], 2), round(r[name][2], 2)] for r in runs],
                "rmse_mean": round(float(rmse.mean()), 2),
                "rmse_sd_over_seeds": round(float(rmse.std(ddof=1)), 2) if len(rmse) > 1 else 0.0,
                "minus_gp_mean": round(float((rmse - gp).mean()), 2),
            }
        summary["inverse"] = _inverse_summary([inv for _, inv in both])
        out[preset] = summary
    out["seconds"] = round(time.time() - t0, 1)
    print(json.dumps(out))


if __name__ == "__main__":
    main()
