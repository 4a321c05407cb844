"""Accuracy of the five networks on the ``paper`` preset next to the study's numbers.

Protocol: for each seed 0-4, simulate the ``paper`` preset (80 subjects x 3 snapshots),
run subject-grouped 5-fold cross-validation (:class:`sklearn.model_selection.GroupKFold`
on ``subject_id``), fit every network with its defaults (``random_state`` = fold), pool
the held-out predictions of the five folds and score them: RMSE [mg/dL], MARD [%],
Clarke zone A [%] (a negative estimate placed at 0 mg/dL on the grid) and the share
within +/-15 % [%]. Reported per model: mean, SD, min and max over the five seeds,
beside the study's single-split figures. For context, the Enhanced Beer-Lambert ridge
(``ebl``, when available) is scored the same way, and so is ``train-mean``: each fold's
training mean as the prediction (the no-skill reference).

Usage::

    python studies/neural_accuracy.py [--seeds 0,1,2,3,4] [--threads 1]

The last line of the output is one JSON object.
"""

from __future__ import annotations

import argparse
import json
import os
import time

import numpy as np
import torch
from sklearn.model_selection import GroupKFold

import nirglucose as ng
from nirglucose.metrics import clarke_zones, mard, rmse, within_percent
from nirglucose.models import available_models, make_model

MODELS = ("original-pinn", "optimized-pinn", "rte-pinn", "selective-rte-pinn", "sdnn")
#: The study's test-set figures (single 60/20/20 split, n = 48): RMSE, MARD, Clarke A.
STUDY = {
    "original-pinn": {"rmse_mgdl": 14.6, "mard_pct": 10.8, "clarke_a_pct": 94.2},
    "optimized-pinn": {"rmse_mgdl": 28.7, "mard_pct": 19.2, "clarke_a_pct": 87.3},
    "rte-pinn": {"rmse_mgdl": 24.3, "mard_pct": 16.8, "clarke_a_pct": 89.7},
    "selective-rte-pinn": {"rmse_mgdl": 24.9, "mard_pct": 17.1, "clarke_a_pct": 89.2},
    "sdnn": {"rmse_mgdl": 35.1, "mard_pct": 23.4, "clarke_a_pct": 78.9},
    "ebl": {"rmse_mgdl": 13.6, "mard_pct": 9.7, "clarke_a_pct": 95.8},
}


def _scores(y: np.ndarray, p: np.ndarray) -> dict[str, float]:
    # The error grid is defined for non-negative glucose only: a negative estimate is
    # placed at 0 mg/dL on the grid (RMSE and MARD use the raw estimate).
    return {
        "rmse_mgdl": float(rmse(y, p)),
        "mard_pct": float(mard(y, p)),
        "clarke_a_pct": float(100.0 * np.mean(clarke_zones(y, np.clip(p, 0.0, None)) == "A")),
        "within15_pct": float(100.0 * within_percent(y, p, 15.0)),
        "n_negative": float(np.sum(p < 0)),
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", default="0,1,2,3,4")
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--models", default=",".join(MODELS))
    args = ap.parse_args()
    torch.set_num_threads(args.threads)
    seeds = [int(s) for s in args.seeds.split(",")]
    models = args.models.split(",")
    if "ebl" in available_models() and "ebl" not in models:
        models.append("ebl")

    t_start = time.perf_counter()
    per_seed: dict[str, list[dict[str, float]]] = {m: [] for m in models}
    per_seed["train-mean"] = []
    fit_s: dict[str, float] = {m: 0.0 for m in models}
    for seed in seeds:
        ds = ng.simulate("paper", n_subjects=80, per_subject=3, seed=seed)
        f = ds.frame
        y = f["glucose_mgdl"].to_numpy(float)
        groups = f["subject_id"].to_numpy()
        folds = list(GroupKFold(n_splits=5).split(f, y, groups))
        baseline = np.empty_like(y)  # each fold's training mean: the no-skill reference
        for tr, te in folds:
            baseline[te] = y[tr].mean()
        per_seed["train-mean"].append(_scores(y, baseline))
        for name in models:
            pred = np.empty_like(y)
            for k, (tr, te) in enumerate(folds):
                train = ng.Dataset(f.iloc[tr].reset_index(drop=True), ds.config, seed=seed)
                params = {"random_state": k} if name in MODELS else {}
                t0 = time.perf_counter()
                m = make_model(name, **params).fit(train)
                fit_s[name] += time.perf_counter() - t0
                pred[te] = m.predict(f.iloc[te].reset_index(drop=True))
            s = _scores(y, pred)
            per_seed[name].append(s)
            print(
                f"seed {seed} {name}: " + ", ".join(f"{k} {v:.1f}" for k, v in s.items()),
                flush=True,
            )

    fit_s["train-mean"] = 0.0
    models = [*models, "train-mean"]
    table = {}
    for name in models:
        rows = per_seed[name]
        table[name] = {
            key: {
                "mean": round(float(np.mean([r[key] for r in rows])), 2),
                "sd": round(float(np.std([r[key] for r in rows], ddof=1)), 2)
                if len(rows) > 1
                else None,
                "min": round(float(np.min([r[key] for r in rows])), 2),
                "max": round(float(np.max([r[key] for r in rows])), 2),
            }
            for key in rows[0]
        }
        table[name]["study"] = STUDY.get(name)
        table[name]["per_seed"] = [{k: round(v, 2) for k, v in r.items()} for r in rows]
        table[name]["fit_s_total"] = round(fit_s[name], 1)

    print()
    print(f"{'model':20s} {'RMSE mg/dL':>18s} {'MARD %':>16s} {'Clarke A %':>16s}   study")
    for name in models:
        t = table[name]
        st = STUDY.get(name, {})
        cells = [
            f"{t[k]['mean']:7.1f} +/- {t[k]['sd'] if t[k]['sd'] is not None else float('nan'):4.1f}"
            for k in ("rmse_mgdl", "mard_pct", "clarke_a_pct")
        ]
        study = " / ".join(str(st.get(k, "-")) for k in ("rmse_mgdl", "mard_pct", "clarke_a_pct"))
        print(f"{name:20s} {cells[0]:>18s} {cells[1]:>16s} {cells[2]:>16s}   {study}")
    out = {
        "benchmark": "neural_accuracy",
        "protocol": "paper preset 80x3, GroupKFold(5) on subject_id, pooled per seed",
        "seeds": seeds,
        "torch_threads": args.threads,
        "wall_s": round(time.perf_counter() - t_start, 1),
        "load_avg_end": os.getloadavg()[0],
        "models": table,
    }
    print(json.dumps(out))


if __name__ == "__main__":
    main()
