"""Model mismatch: the forward-model estimator when the data were made by another model.

Runs the built-in sweep study ``mismatch`` (:func:`nirglucose.evaluation.run_sweep`,
``study="mismatch"``): data from each forward model (``optics.model`` beer-lambert,
diffusion, rte-lut; the rte-lut table filled by the diffusion solver) on the ``paper``
preset, ``physics-inversion`` assuming each model (tuned parameters besides the assumed
model), EBL, the GP and the oracle for reference; subject-grouped CV. Defaults are a
small setting for two cores (40 subjects x 3, 3 folds x 1 repeat, seeds 0-1).

Prints, per (data model, assumed model), the inversion's RMSE per seed with its
subject-bootstrap 95 % CI and the mean over seeds; per data model the references'.
One JSON object on the last line.

Usage: python studies/mismatch.py [--seeds 2] [--subjects 40] [--folds 3] [--jobs 1]
    [--out DIR]
"""

from __future__ import annotations

import argparse
import json
import time


def main() -> None:
    from nirglucose.evaluation.sweep.run import run_sweep

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=2)
    ap.add_argument("--subjects", type=int, default=40)
    ap.add_argument("--folds", type=int, default=3)
    ap.add_argument("--jobs", type=int, default=1)
    ap.add_argument("--preset", default="paper")
    ap.add_argument("--out", default=None)
    a = ap.parse_args()
    t0 = time.time()
    res = run_sweep(study="mismatch", preset=a.preset, seeds=a.seeds, n_subjects=a.subjects,
                    per_subject=3, n_splits=a.folds, repeats=1, n_boot=500, jobs=a.jobs,
                    out=a.out)
    f = res.frame
    out = {"protocol": f"{a.preset}, {a.subjects} subjects x 3, grouped {a.folds}-fold CV x 1, "
                       f"seeds 0-{a.seeds - 1}", "inversion": {}, "references": {}}
    for (made, assumed, model), g in f.groupby(["data_model", "assumed_model", "model"]):
        row = {"rmse_per_seed": [round(v, 2) for v in g["rmse_mgdl"]],
               "ci_per_seed": [[round(lo, 2), round(hi, 2)] for lo, hi in
                               zip(g["rmse_ci_low"], g["rmse_ci_high"], strict=True)],
               "rmse_mean": round(float(g["rmse_mgdl"].mean()), 2)}
        if model == "physics-inversion":
            out["inversion"][f"data={made} assumed={assumed}"] = row
        elif made == assumed:  # the references do not depend on the assumed model
            out["references"][f"data={made} {model}"] = row
    out["seconds"] = round(time.time() - t0, 1)
    print(json.dumps(out))


if __name__ == "__main__":
    main()
