"""The hybrids' stacking shrinkage (issue 29): grouped-CV RMSE with and without it.

Protocol: ``nirglucose.simulate(preset, 80, 3, seed=1000)`` for ``field`` (the residual
holds no signal) and ``paper`` (it does); subject-grouped 3-fold CV (scikit-learn
``GroupKFold`` over ``subject_id``); pooled RMSE over the held-out rows. Models:
``mean``, ``ebl``, ``physics-inversion`` and both hybrids with their tuned parameters
(``tuned_params``), and a hybrid tuned to ``cv`` 0 again with ``cv=3``. Per hybrid fit:
the learned stacking weights ``(backbone_weight_, shrinkage_)`` (absent before issue
29's fix) and the mean fit wall time.

Not a timed test. Prints one JSON object on its last line.

Usage: python studies/hybrid_shrinkage.py [--presets field paper] [--seed 1000]
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np
from sklearn.model_selection import GroupKFold

import nirglucose as ng
from nirglucose.models import make_model
from nirglucose.models.tuning import tuned_params

MODELS = ("mean", "ebl", "ebl+gp", "physics-inversion", "physics-inversion+gp")
HYBRIDS = ("ebl+gp", "physics-inversion+gp")


def _cv(ds, name: str, params: dict, folds: int) -> dict:
    """Pooled grouped-CV RMSE, mean fit seconds and the shrinkage of each fold's fit."""
    y = ds.frame["glucose_mgdl"].to_numpy()
    groups = ds.frame["subject_id"].to_numpy()
    pred = np.empty(len(y))
    seconds, shrink = [], []
    for tr, te in GroupKFold(n_splits=folds).split(y, y, groups):
        t0 = time.perf_counter()
        model = make_model(name, **params).fit(ds.rows(tr))
        seconds.append(time.perf_counter() - t0)
        pred[te] = model.predict(ds.rows(te))
        if hasattr(model, "shrinkage_"):  # (backbone weight, GP weight) of the stack
            shrink.append([float(model.backbone_weight_), round(float(model.shrinkage_), 4)])
    out = {"rmse_mgdl": round(float(np.sqrt(np.mean((pred - y) ** 2))), 3),
           "fit_s": round(float(np.mean(seconds)), 3)}
    if shrink:
        out["weights_a_s"] = shrink
    return out


def main(argv=None) -> dict:
    ap = argparse.ArgumentParser()
    ap.add_argument("--presets", nargs="+", default=["field", "paper"])
    ap.add_argument("--seed", type=int, default=1000)
    ap.add_argument("--folds", type=int, default=3)
    args = ap.parse_args(argv)
    result: dict = {"seed": args.seed, "folds": args.folds, "n": "80 x 3", "presets": {}}
    for preset in args.presets:
        ds = ng.simulate(preset, 80, 3, seed=args.seed)
        row = {}
        for name in MODELS:
            params = {**tuned_params(name, preset), "random_state": 0} if name in HYBRIDS \
                else tuned_params(name, preset)
            row[name] = {"params": params, **_cv(ds, name, params, args.folds)}
            if name in HYBRIDS and params.get("cv", 3) < 2:
                row[name + " (cv=3)"] = _cv(ds, name, {**params, "cv": 3}, args.folds)
            print(preset, name, row[name], row.get(name + " (cv=3)", ""), flush=True)
        result["presets"][preset] = row
    print(json.dumps(result))
    return result


if __name__ == "__main__":
    main()
