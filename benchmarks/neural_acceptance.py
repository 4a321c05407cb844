"""Do the tuned networks beat the no-skill RMSE? (issue 18 acceptance, model side)

For each preset (``wearable`` and the quiet ``paper``; before the simulator's presets land,
the stand-ins of ``benchmarks/tune.py``) and each simulation seed (default 0-2), 80
subjects x 3, subject-grouped 5-fold CV: every network (and EBL for scale) with its tuned
hyper-parameters (:func:`nirglucose.models.tuned_params`), pooled RMSE against the
no-skill RMSE (the training-fold mean predicted for every held-out row, same folds),
the ratio of prediction to target spread on held-out subjects, and the CPU seconds per
fit. This reads the reported seeds to *check* the tuned models; the tuning itself
(``benchmarks/tune.py``) never does.

Usage::

    python benchmarks/neural_acceptance.py [--seeds 0,1,2] [--presets wearable,paper]

Torch runs on one thread. The last line of the output is one JSON object.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np
import torch
from sklearn.model_selection import GroupKFold

import nirglucose as ng
from nirglucose.dataset import Dataset
from nirglucose.models import make_model, tuned_params

sys.path.insert(0, str(Path(__file__).resolve().parent))
from tune import preset_source  # noqa: E402

MODELS = ("ebl", "sdnn", "original-pinn", "optimized-pinn", "rte-pinn", "selective-rte-pinn")


def _rows(ds: Dataset, idx: np.ndarray) -> Dataset:
    return Dataset(ds.frame.iloc[idx].reset_index(drop=True), config=ds.config, seed=ds.seed)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--seeds", default="0,1,2")
    ap.add_argument("--presets", default="wearable,paper")
    ap.add_argument("--models", default=",".join(MODELS))
    args = ap.parse_args()
    torch.set_num_threads(1)
    seeds = [int(s) for s in args.seeds.split(",")]
    out: dict = {"seeds": seeds, "folds": 5, "n_subjects": 80, "per_subject": 3, "presets": {}}
    for preset in args.presets.split(","):
        base, overrides, standin = preset_source(preset)
        sq = {m: [] for m in args.models.split(",")}
        spread = {m: [] for m in sq}
        cpu = {m: 0.0 for m in sq}
        base_sq, n_fits = [], 0
        for seed in seeds:
            ds = ng.simulate(base, 80, 3, seed=seed, overrides=overrides or None)
            y = ds.frame["glucose_mgdl"].to_numpy()
            g = ds.frame["subject_id"].to_numpy()
            for fold, (tr, te) in enumerate(GroupKFold(5).split(y, groups=g)):
                base_sq.append((y[tr].mean() - y[te]) ** 2)
                n_fits += 1
                for name in sq:
                    extra = {} if name == "ebl" else {"random_state": 10 * seed + fold}
                    t0 = time.process_time()
                    m = make_model(name, **tuned_params(name, preset), **extra).fit(_rows(ds, tr))
                    cpu[name] += time.process_time() - t0
                    p = m.predict(_rows(ds, te))
                    sq[name].append((p - y[te]) ** 2)
                    spread[name].append(float(np.std(p) / np.std(y[te])))
        no_skill = float(np.sqrt(np.mean(np.concatenate(base_sq))))
        rows = {}
        for name in sq:
            rmse = float(np.sqrt(np.mean(np.concatenate(sq[name]))))
            rows[name] = {
                "rmse_mgdl": round(rmse, 2),
                "no_skill_rmse_mgdl": round(no_skill, 2),
                "below_no_skill": rmse < no_skill,
                "spread_ratio": round(float(np.mean(spread[name])), 3),
                "cpu_s_per_fit": round(cpu[name] / n_fits, 3),
                "params": tuned_params(name, preset),
            }
            print(
                f"{preset:9s} {name:19s} RMSE {rmse:6.2f}  no-skill {no_skill:6.2f}  "
                f"spread {rows[name]['spread_ratio']:.2f}  "
                f"cpu/fit {rows[name]['cpu_s_per_fit']:.3f} s",
                flush=True,
            )
        out["presets"][preset] = {"simulated_as": base, "standin": standin, "models": rows}
    print(json.dumps(out, default=list))


if __name__ == "__main__":
    main()
