"""The deployable forward-model inversion beside the privileged one (issue 39).

Protocol: ``nirglucose.simulate(preset, 80, 3, seed)`` for ``paper``, ``wearable`` and
``physical``; :func:`nirglucose.evaluation.run_benchmark` with subject-grouped 5-fold
CV, one repeat, its subject-level bootstrap 95 % CIs, every model with its tuned
parameters where the package holds them (tools/tune.py) (``device-inversion`` is not tuned
yet: its defaults). Models: no skill (``mean``), EBL, ``device-inversion``
(deployable: the device's parts and published tables, glucose's response learned),
``physics-inversion`` and the oracle (privileged references: the generating scenario,
the true nuisances). Per preset and model: RMSE per seed with its CI, the mean over
seeds and the mean fit time per fold (``fit_time_s``, this machine, under whatever
else runs on it).

Not a timed test. Prints one JSON object on its last line.

Usage: python studies/deployable_inversion.py [--seeds 1] [--jobs 2]
    [--presets paper,wearable,physical]
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np

MODELS = ("mean", "ebl", "device-inversion", "physics-inversion", "oracle")
TIMING = {"n_single": 3, "min_single": 2, "batch_rows": 100, "batch_repeats": 1}


def _one(preset: str, seed: int, jobs: int) -> dict:
    import nirglucose as ng
    from nirglucose.evaluation import run_benchmark

    ds = ng.simulate(preset, n_subjects=80, per_subject=3, seed=seed)
    res = run_benchmark(ds, list(MODELS), n_splits=5, repeats=1, seed=seed, jobs=jobs,
                        timing=TIMING, drop_one_models="none", references=False)
    m = res.metrics.set_index("model")
    return {name: [float(m.loc[name, c]) for c in
                   ("rmse_mgdl", "rmse_ci_low", "rmse_ci_high", "fit_time_s")]
            for name in MODELS}


def main() -> None:
    from nirglucose.models import privileged_knowledge

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=1, help="seeds 0..N-1")
    ap.add_argument("--jobs", type=int, default=2, help="worker processes")
    ap.add_argument("--presets", default="paper,wearable,physical")
    a = ap.parse_args()
    t0 = time.time()
    out: dict = {"protocol": "grouped 5-fold CV x 1 repeat, 80 x 3 per seed, tuned where "
                             "the package holds tuned parameters",
                 "seeds": list(range(a.seeds)),
                 "privileged": {n: privileged_knowledge(n) for n in MODELS}}
    for preset in a.presets.split(","):
        runs = [_one(preset, s, a.jobs) for s in range(a.seeds)]
        out[preset] = {
            name: {
                "rmse_per_seed": [round(r[name][0], 2) for r in runs],
                "ci_per_seed": [[round(r[name][1], 2), round(r[name][2], 2)] for r in runs],
                "rmse_mean": round(float(np.mean([r[name][0] for r in runs])), 2),
                "fit_time_s_mean": round(float(np.mean([r[name][3] for r in runs])), 2),
            }
            for name in MODELS
        }
    out["seconds"] = round(time.time() - t0, 1)
    print(json.dumps(out))


if __name__ == "__main__":
    main()
