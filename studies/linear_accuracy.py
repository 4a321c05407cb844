"""Accuracy of EBL, PLS and the oracle on the paper preset, seeds 0-9.

Protocol: ``nirglucose.simulate("paper", 80, 3, seed)`` for seeds 0-9; subject-grouped
5-fold cross-validation (:class:`sklearn.model_selection.GroupKFold` on ``subject_id``);
each model fitted on four folds (its own hyperparameter chosen by inner grouped CV on
those) and predicting the fifth; metrics on the 240 pooled out-of-fold predictions of a
seed; mean ± SD over the ten seeds. The oracle is reported with its default Gaussian
prior on glucose (posterior mode, ``oracle``) and as the pure least-squares inversion
(``oracle_ls``); ratios are to ``oracle``. Negative estimates (a linear model can
extrapolate below zero) are clipped to 0 for the Clarke grid only, and counted.

Not a tuned or timed test. Prints one JSON object on its last line.
"""

from __future__ import annotations

import json
import os
import time

import numpy as np

SEEDS = tuple(range(int(os.environ.get("NIRGLUCOSE_ACC_SEEDS", 10))))
MODELS = ("ebl", "pls", "oracle", "oracle_ls")


def _make(name):
    from nirglucose.models import EnhancedBeerLambert, Oracle, PLSBaseline

    return {
        "ebl": EnhancedBeerLambert,
        "pls": PLSBaseline,
        "oracle": Oracle,
        "oracle_ls": lambda: Oracle(prior=False),
    }[name]()


def _metrics(y, pred) -> dict:
    n_negative = int(np.sum(pred < 0))
    try:
        from nirglucose.metrics import clarke_zones, mard, rmse
    except ImportError:  # metrics not installed: RMSE and MARD by hand
        return {
            "rmse": float(np.sqrt(np.mean((pred - y) ** 2))),
            "mard": float(100 * np.mean(np.abs(pred - y) / y)),
            "clarke_a": float("nan"),
            "n_negative": n_negative,
        }
    # The error grid needs non-negative estimates; a linear model can extrapolate below
    # zero: those are clipped for the grid only (and counted).
    zones = clarke_zones(y, np.clip(pred, 0.0, None))
    return {
        "rmse": rmse(y, pred),
        "mard": mard(y, pred),
        "clarke_a": 100.0 * float(np.mean(zones == "A")),
        "n_negative": n_negative,
    }


def main() -> dict:
    from sklearn.model_selection import GroupKFold

    import nirglucose as ng

    t0 = time.perf_counter()
    per_seed = {m: [] for m in MODELS}
    for seed in SEEDS:
        ds = ng.simulate("paper", 80, 3, seed=seed)
        frame = ds.frame
        y = frame["glucose_mgdl"].to_numpy(float)
        groups = frame["subject_id"].to_numpy()
        preds = {m: np.empty_like(y) for m in MODELS}
        for tr, te in GroupKFold(n_splits=5).split(frame, y, groups):
            train = ng.Dataset(frame.iloc[tr].reset_index(drop=True), config=ds.config)
            test = ng.Dataset(frame.iloc[te].reset_index(drop=True), config=ds.config)
            for m in MODELS:
                preds[m][te] = _make(m).fit(train).predict(test)
        for m in MODELS:
            per_seed[m].append(_metrics(y, preds[m]))

    def stats(values) -> dict:
        v = np.asarray(values, dtype=float)
        return {"mean": round(float(v.mean()), 3), "sd": round(float(v.std(ddof=1)), 3)}

    table = {
        m: {k: stats([r[k] for r in per_seed[m]]) for k in ("rmse", "mard", "clarke_a")}
        for m in MODELS
    }
    ratios = {
        f"{m}_over_oracle_rmse": stats(
            [a["rmse"] / b["rmse"] for a, b in zip(per_seed[m], per_seed["oracle"], strict=True)]
        )
        for m in ("ebl", "pls", "oracle_ls")
    }
    return {
        "benchmark": "linear_accuracy",
        "preset": "paper",
        "n_subjects": 80,
        "per_subject": 3,
        "seeds": list(SEEDS),
        "cv": "GroupKFold(5) by subject, pooled out-of-fold predictions per seed",
        "units": {"rmse": "mg/dL", "mard": "%", "clarke_a": "% in zone A"},
        "metrics": table,
        "ratios": ratios,
        "rmse_per_seed": {m: [round(r["rmse"], 2) for r in per_seed[m]] for m in MODELS},
        "negative_predictions": {m: sum(r["n_negative"] for r in per_seed[m]) for m in MODELS},
        "elapsed_s": round(time.perf_counter() - t0, 1),
    }


if __name__ == "__main__":
    print(json.dumps(main()))
