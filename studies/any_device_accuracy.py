"""Accuracy of EBL, PLS, the SDNN and the oracle on a three-LED `paper` device.

Protocol: ``nirglucose.simulate("paper", 80, 3, seed)`` for seeds 0-2 with the LEDs
changed to 850, 940 and 1150 nm (band 40 nm FWHM, 3 mW, 0.5 A/W each; 12-bit ADC), and,
for comparison, the study's four-LED device at the same seeds; subject-grouped 5-fold
cross-validation (``nirglucose.evaluation.splits.grouped_kfold``, one repeat, seed 0);
each model fitted on four folds (hyperparameters by its own inner grouped CV or
validation split) and predicting the fifth; RMSE and MARD of the 240 pooled
out-of-fold predictions of a seed; mean and SD over seeds. The SDNN trains with its
defaults (up to 300 epochs, early stopping, random_state 0).

Not a test. Prints one JSON object on its last line.
"""

from __future__ import annotations

import json
import os
import sys
import time
from pathlib import Path

import numpy as np

SEEDS = tuple(range(int(os.environ.get("NIRGLUCOSE_ACC_SEEDS", 3))))
MODELS = ("ebl", "pls", "sdnn", "oracle")
DEVICES = {"three_led": (850.0, 940.0, 1150.0), "study_four_led": None}


def main() -> dict:
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
    import nirglucose as ng
    from device_data import device_overrides
    from nirglucose.evaluation.splits import grouped_kfold
    from nirglucose.models import make_model

    t0 = time.perf_counter()
    out: dict = {}
    for device, wl in DEVICES.items():
        res = {m: {"rmse": [], "mard": []} for m in MODELS}
        for seed in SEEDS:
            over = device_overrides(wl, 12) if wl else {}
            ds = ng.simulate("paper", 80, 3, seed=seed, overrides=over)
            f = ds.frame
            y = f["glucose_mgdl"].to_numpy(float)
            preds = {m: np.empty_like(y) for m in MODELS}
            for sp in grouped_kfold(f["subject_id"].to_numpy(), n_splits=5, repeats=1, seed=0):
                train = ng.Dataset(f.iloc[sp.train].reset_index(drop=True), config=ds.config)
                test = ng.Dataset(f.iloc[sp.test].reset_index(drop=True), config=ds.config)
                for m in MODELS:
                    kw = {"random_state": 0} if m == "sdnn" else {}
                    preds[m][sp.test] = make_model(m, **kw).fit(train).predict(test)
            for m in MODELS:
                res[m]["rmse"].append(float(np.sqrt(np.mean((preds[m] - y) ** 2))))
                res[m]["mard"].append(float(100 * np.mean(np.abs(preds[m] - y) / y)))
        out[device] = {
            m: {
                "rmse_mgdl_mean": round(float(np.mean(v["rmse"])), 2),
                "rmse_mgdl_sd": round(float(np.std(v["rmse"], ddof=1)), 2),
                "mard_pct_mean": round(float(np.mean(v["mard"])), 2),
            }
            for m, v in res.items()
        }
    out["seeds"] = list(SEEDS)
    out["wall_s"] = round(time.perf_counter() - t0, 1)
    return out


if __name__ == "__main__":
    print(json.dumps(main()))
