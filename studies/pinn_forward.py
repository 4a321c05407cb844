"""The Beer-Lambert PINNs with the study's physics term, the forward-model term, and none.

Protocol: ``nirglucose.simulate(preset, 80, 3, seed)`` for ``paper`` and ``wearable``;
the benchmark's subject-grouped 5-fold CV (:func:`nirglucose.evaluation.splits.grouped_kfold`,
one repeat, seeded by the data seed), out-of-fold predictions pooled into one RMSE per
seed. Each PINN runs with its tuned training parameters (``tuned_params``) and:

* ``study``: its tuned ``lambda_phys`` with the study's residual (where tuning chose
  0 this *is* the no-physics fit);
* ``no-physics``: ``lambda_phys = 0``;
* ``forward``: ``physics_form='forward'`` at the λ > 0 of :data:`LAMBDAS` with the
  lowest CV RMSE on the disjoint tuning seed (``--tuning-seed``, 1000: a seed of
  ``TUNING_SEEDS``, never a reported one), the same folds and training parameters;
* ``forward+collocation`` (with ``--collocation N``): the same λ with N forward-model
  readings per training row.

Prints per preset and PINN: the tuning seed's λ curve, each variant's RMSE per seed,
their mean, and the mean paired difference forward - no-physics and study -
no-physics. With ``--inverse``: the inverse task (``inverse.csv`` of
:func:`nirglucose.evaluation.run_benchmark`, the same folds) of the forward RTE PINNs
(``rte-pinn-fm``, ``selective-rte-pinn-fm``, their default λ 1) beside
``physics-inversion``, mean over the seeds: the RMSE of the recovered blood, water,
melanin and skin thickness against the truth (read for scoring only), next to the
truth's SD. Not a timed test. One JSON object on the last line.

Cost on one core: about 4 min per Beer-Lambert PINN and preset with the default two
seeds (the Optimized PINN about twice that), about 10 min per RTE PINN and preset;
``--inverse`` about 3 min per preset and seed.

Usage: python studies/pinn_forward.py [--seeds 2] [--presets paper,wearable]
       [--pinns original-pinn,optimized-pinn] [--collocation 0] [--inverse]
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np

LAMBDAS = (0.01, 0.1, 1.0)
N_SPLITS = 5


def _cv_rmse(ds, name: str, params: dict, seed: int) -> float:
    """Pooled out-of-fold RMSE [mg/dL] of ``name`` on ``ds`` (grouped 5-fold, seeded)."""
    from nirglucose.evaluation.splits import grouped_kfold
    from nirglucose.models import make_model

    frame = ds.frame
    y = frame["glucose_mgdl"].to_numpy()
    pred = np.full(len(y), np.nan)
    for s in grouped_kfold(frame["subject_id"].to_numpy(), N_SPLITS, repeats=1, seed=seed):
        m = make_model(name, **{**params, "random_state": 1000 * seed + s.fold})
        pred[s.test] = m.fit(ds.rows(s.train)).predict(ds.rows(s.test))
    return float(np.sqrt(np.mean((pred - y) ** 2)))


def _one_pinn(preset: str, pinn: str, seeds: list[int], tuning_seed: int, colloc: int) -> dict:
    import nirglucose as ng
    from nirglucose.models import tuned_params

    base = tuned_params(pinn, preset)
    tune_ds = ng.simulate(preset, n_subjects=80, per_subject=3, seed=tuning_seed)
    curve = {lam: _cv_rmse(tune_ds, pinn, {**base, "physics_form": "forward",
                                          "lambda_phys": lam}, tuning_seed)
             for lam in LAMBDAS}
    best = min(curve, key=curve.get)
    variants = {
        "study": dict(base),
        "no-physics": {**base, "lambda_phys": 0.0},
        "forward": {**base, "physics_form": "forward", "lambda_phys": best},
    }
    if colloc:
        variants["forward+collocation"] = {**variants["forward"], "collocation": colloc}
    rmse: dict[str, list[float]] = {v: [] for v in variants}
    for seed in seeds:
        ds = ng.simulate(preset, n_subjects=80, per_subject=3, seed=seed)
        for v, params in variants.items():
            rmse[v].append(round(_cv_rmse(ds, pinn, params, seed), 3))
    none = np.array(rmse["no-physics"])
    return {
        "study_lambda_phys": base.get("lambda_phys"),
        "forward_lambda_curve_tuning_seed": {str(k): round(v, 3) for k, v in curve.items()},
        "forward_lambda_phys": best,
        "rmse_mgdl_per_seed": rmse,
        "rmse_mgdl_mean": {v: round(float(np.mean(r)), 3) for v, r in rmse.items()},
        "diff_vs_no_physics_mean_mgdl": {
            v: round(float(np.mean(np.array(r) - none)), 3)
            for v, r in rmse.items() if v != "no-physics"
        },
    }


INVERSE_MODELS = ("rte-pinn-fm", "selective-rte-pinn-fm", "physics-inversion")
INVERSE_QUANTITIES = ("blood_fraction", "water_fraction", "melanin_fraction",
                      "skin_thickness_mm")


def _inverse(preset: str, seeds: list[int]) -> dict:
    """Mean over seeds of the inverse table's RMSE (and the truth's SD) per model."""
    import pandas as pd

    import nirglucose as ng
    from nirglucose.evaluation import Protocol, run_benchmark

    rows = []
    for seed in seeds:
        ds = ng.simulate(preset, n_subjects=80, per_subject=3, seed=seed)
        res = run_benchmark(ds, list(INVERSE_MODELS),
                            protocol=Protocol(n_splits=N_SPLITS, repeats=1, seed=seed),
                            jobs=1, oracle_reference=False, drop_one_models="none",
                            timing={"n_single": 2, "min_single": 1, "batch_rows": 50,
                                    "batch_repeats": 1})
        rmse = res.metrics.set_index("model")["rmse_mgdl"]
        rows += [{**r, "glucose_rmse_mgdl": float(rmse[r["model"]])}
                 for r in res.inverse.to_dict(orient="records")
                 if r["quantity"] in INVERSE_QUANTITIES]
    t = pd.DataFrame(rows)
    g = t.groupby(["model", "quantity"])[["rmse", "truth_sd", "pearson_r",
                                          "glucose_rmse_mgdl"]].mean()
    return {f"{m} {q}": {k: float(f"{v:.4g}") for k, v in row.items()}
            for (m, q), row in g.iterrows()}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=2, help="seeds 0..N-1")
    ap.add_argument("--presets", default="paper,wearable")
    ap.add_argument("--pinns", default="original-pinn,optimized-pinn")
    ap.add_argument("--tuning-seed", type=int, default=1000)
    ap.add_argument("--collocation", type=int, default=0)
    ap.add_argument("--inverse", action="store_true", help="the RTE PINNs' inverse task")
    a = ap.parse_args()
    t0 = time.time()
    seeds = list(range(a.seeds))
    out: dict = {"protocol": f"grouped {N_SPLITS}-fold CV x 1 repeat, 80 x 3 per seed, tuned "
                             "training parameters; forward λ chosen on the tuning seed",
                 "seeds": seeds, "tuning_seed": a.tuning_seed, "lambdas": list(LAMBDAS)}
    for preset in a.presets.split(","):
        out[preset] = {}
        if a.inverse:
            out[preset]["inverse"] = _inverse(preset, seeds)
            print(json.dumps({preset: {"inverse": out[preset]["inverse"]}}), flush=True)
        for pinn in filter(None, a.pinns.split(",")):
            r = _one_pinn(preset, pinn, seeds, a.tuning_seed, a.collocation)
            out[preset][pinn] = r
            print(json.dumps({preset: {pinn: r["rmse_mgdl_mean"]}}), flush=True)
    out["seconds"] = round(time.time() - t0, 1)
    print(json.dumps(out))


if __name__ == "__main__":
    main()
