"""Does each PINN's physics term move its fit? Gradient probes at lambda_phys = 1.

Protocol: ``nirglucose.simulate(preset, 40, 3, seed=0)`` for ``paper`` and
``wearable``; one subject-grouped split (the first fold of
:func:`nirglucose.evaluation.splits.grouped_kfold`, 5 folds, seed 0: 32 training
subjects, 8 held out). Each of the four study PINNs and its forward-model variant
(``-fm``) is fitted with its tuned training parameters (``tuned_params``) and
``lambda_phys = 1``, random_state 0, on one torch thread:

* ``probed``: the training loop's gradient probes on (the default), the CPU time
  inside them counted (a wrapper around ``gradient_norms``);
* ``unprobed``: the probes off (``is_probe_epoch`` patched to never probe): a check
  that the probes leave the trained network bit-identical (same held-out predictions);
* ``lambda=0``: the plain network (the physics term out of the loss).

Per model: from the probed fit's ``history_``,
:func:`~nirglucose.models.physics_effect.physics_verdict` (the medians over the probed
epochs of the pull on the predictions, in training SD and mg/dL, of the indirect and
the total gradient ratio, the maximum gradient ratio, the training physics loss first
and last and its relative change, the verdict); the RMS difference of the held-out
predictions between ``lambda_phys`` 1 and 0, and the held-out RMSE of both (one split:
a term's systematic effect and the trajectory's sensitivity to any change of the loss
are mixed in that difference); the fit's CPU time and the probes' share of it. The
overhead is the probes' CPU time over the rest of the fit, per model and summed per
family (the study PINNs; the -fm fits include a physics-inversion fit each). Not a
timed test. Prints one JSON object on the last line; the record is
``studies/records/pinn_physics_gradient.json``.

Usage: python studies/pinn_physics_gradient.py [--presets paper,wearable]
       [--models original-pinn,...] [--subjects 40]
"""

from __future__ import annotations

import argparse
import json
import time
from unittest import mock

import numpy as np

STUDY = ("original-pinn", "optimized-pinn", "rte-pinn", "selective-rte-pinn")
MODELS = STUDY + tuple(f"{m}-fm" for m in STUDY)
LAMBDA = 1.0


def _fit(name: str, params: dict, train, test, probes: bool) -> tuple[object, np.ndarray, float,
                                                                     float]:
    """The fitted model, its held-out predictions [mg/dL], its fit CPU time and the part
    of it spent in the gradient probes [s]."""
    from nirglucose.models import _torch_base, make_model

    model = make_model(name, **params)
    spent = [0.0]
    probe = _torch_base.gradient_norms

    def timed(*args, **kwargs):
        t = time.process_time()
        try:
            return probe(*args, **kwargs)
        finally:
            spent[0] += time.process_time() - t

    patch = (mock.patch.object(_torch_base, "gradient_norms", timed) if probes else
             mock.patch.object(_torch_base, "is_probe_epoch", lambda epoch, n: False))
    t0 = time.process_time()
    with patch:
        model.fit(train)
    cpu = time.process_time() - t0
    return model, model.predict(test), cpu, spent[0]


def _one(name: str, preset: str, train, test) -> dict:
    from nirglucose.models import tuned_params
    from nirglucose.models.physics_effect import physics_verdict

    tuned = tuned_params(name, preset)
    params = {**tuned, "lambda_phys": LAMBDA, "random_state": 0}
    on, pred_on, cpu, cpu_probes = _fit(name, params, train, test, probes=True)
    pred_off = _fit(name, params, train, test, probes=False)[1]
    pred_0 = _fit(name, {**params, "lambda_phys": 0.0}, train, test, probes=True)[1]
    if not np.array_equal(pred_on, pred_off):
        raise AssertionError(f"{name} on {preset}: the gradient probes changed the fit")
    y = test.frame["glucose_mgdl"].to_numpy(float)
    v = physics_verdict(on.history_)

    def r(x):
        return None if x is None else float(f"{x:.4g}")

    keys = ("median_pull_sd", "median_indirect_ratio", "median_grad_ratio", "max_grad_ratio",
            "physics_first", "physics_last", "physics_relative_change")
    pull = v["median_pull_sd"]
    return {
        "tuned_lambda_phys": tuned.get("lambda_phys"),
        "physics_form": on.physics_form,
        "verdict": v["verdict"],
        "probes": v["probes"],
        **{k: r(v[k]) for k in keys},
        "median_pull_mgdl": r(None if pull is None else pull * on.scaler_["y_scale"]),
        "physics_constant": v["physics_constant"],
        "prediction_shift_rms_mgdl": r(float(np.sqrt(np.mean((pred_on - pred_0) ** 2)))),
        "rmse_mgdl": r(float(np.sqrt(np.mean((pred_on - y) ** 2)))),
        "rmse_lambda0_mgdl": r(float(np.sqrt(np.mean((pred_0 - y) ** 2)))),
        "fit_cpu_s": round(cpu, 3),
        "probe_cpu_s": round(cpu_probes, 4),
        "probe_overhead": round(cpu_probes / (cpu - cpu_probes), 4),
    }


def _overhead(rows: dict, names: list[str]) -> float | None:
    probes = sum(rows[n]["probe_cpu_s"] for n in names if n in rows)
    rest = sum(rows[n]["fit_cpu_s"] - rows[n]["probe_cpu_s"] for n in names if n in rows)
    return round(probes / rest, 4) if rest else None


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--presets", default="paper,wearable")
    ap.add_argument("--models", default=",".join(MODELS))
    ap.add_argument("--subjects", type=int, default=40)
    a = ap.parse_args()
    import torch

    import nirglucose as ng
    from nirglucose.evaluation.splits import grouped_kfold
    from nirglucose.models.physics_effect import CONSTANT_CHANGE, INERT_RATIO, PULL_INERT_SD

    torch.set_num_threads(1)
    t0 = time.time()
    out: dict = {
        "protocol": f"simulate(preset, {a.subjects}, 3, seed=0); first fold of grouped 5-fold "
                    "(seed 0); tuned training parameters, lambda_phys = 1, random_state 0, "
                    "one torch thread",
        "rule": f"inert: median pull < {PULL_INERT_SD:g} training SD and median indirect "
                f"gradient ratio < {INERT_RATIO:g}; constant: relative change of the "
                f"training physics loss < {CONSTANT_CHANGE:g} (physics_verdict)",
    }
    for preset in a.presets.split(","):
        ds = ng.simulate(preset, n_subjects=a.subjects, per_subject=3, seed=0)
        split = grouped_kfold(ds.frame["subject_id"].to_numpy(), 5, repeats=1, seed=0)[0]
        train, test = ds.rows(split.train), ds.rows(split.test)
        _fit("sdnn", {"max_epochs": 20}, train, test, probes=True)  # warm-up, not timed
        rows = {}
        for name in filter(None, a.models.split(",")):
            rows[name] = _one(name, preset, train, test)
            print(json.dumps({preset: {name: rows[name]}}), flush=True)
        out[preset] = {
            "models": rows,
            "probe_overhead_study": _overhead(rows, list(STUDY)),
            "probe_overhead_fm": _overhead(rows, [f"{m}-fm" for m in STUDY]),
        }
    out["seconds"] = round(time.time() - t0, 1)
    print(json.dumps(out))


if __name__ == "__main__":
    main()
