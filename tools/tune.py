"""Tune every model family on the same footing; write ``src/nirglucose/data/tuned_params.json``.

For each preset (every preset of :data:`~nirglucose.models.tuning.TUNED_PRESETS` by
default) and each family with a search space (EBL, PLS, gradient boosting and every
network, a newly registered one included; the GP tunes itself inside each fit),
:data:`~nirglucose.models.tuning.N_CONFIGS` configurations are drawn from the family's
grid (:func:`~nirglucose.models.tuning.search_space`; the networks share one training
grid and the same draws, the PINNs add ``lambda_phys`` with every grid
value, 0 included, drawn equally often) and scored by subject-grouped
:data:`~nirglucose.models.tuning.N_FOLDS`-fold cross-validation on 80 subjects x 3 of
each tuning seed (:data:`~nirglucose.models.tuning.TUNING_SEEDS`, disjoint from the
reported seeds 0-4). The configuration with the lowest pooled RMSE is written. The same
budget (configurations x folds x seeds) for every family; nothing here reads the
reported seeds or the study's numbers.

Presets are simulated as they are (``config.PRESETS``); re-run this script after
changing the simulator or a model.

Usage::

    python tools/tune.py [--presets wearable,paper] [--models ...] [--out PATH]
    python tools/tune.py --lambda-curve-only [--presets ...]

The validation curve of each PINN (its ``lambda_curve`` in ``scores``): the tuned
training parameters refitted with every value of ``LAMBDA_PHYS_GRID`` on the same
seeds, folds and random states (the ``slice``), next to the best tuning draw per λ
(the ``profile``). ``--lambda-curve-only`` adds the curve to PINNs already tuned (their
tuned configuration is found among the deterministic draws, which must reproduce
the recorded RMSEs' argmin) without re-tuning them. The benchmark's ablation reads the
slice's best λ > 0 where tuning chose λ = 0.

Torch runs on one thread. The last line of the output is one JSON object (budget,
time, the chosen parameters and their tuning-CV RMSE next to the no-skill RMSE).
"""

from __future__ import annotations

import argparse
import itertools
import json
import time
from pathlib import Path

import numpy as np
import torch
from sklearn.model_selection import GroupKFold

import nirglucose as ng
from nirglucose.dataset import Dataset
from nirglucose.exceptions import ConfigError
from nirglucose.models import make_model
from nirglucose.models.registry import MODELS, get_model_class, is_pinn
from nirglucose.models.tuning import (
    LAMBDA_PHYS_GRID,
    N_CONFIGS,
    N_FOLDS,
    TUNED_PRESETS,
    TUNING_SEEDS,
    search_space,
)


def _has_search_space(name: str) -> bool:
    try:
        search_space(name)
    except ConfigError:
        return False
    return True


#: Every registered family with a search space (the linear models, gradient boosting
#: and every network), in the registry's order.
FAMILIES = tuple(name for name in MODELS if _has_search_space(name))
N_SUBJECTS, PER_SUBJECT = 80, 3
OUT = Path(__file__).resolve().parents[1] / "src" / "nirglucose" / "data" / "tuned_params.json"
SAMPLING_SEED = 0  # draws the configurations (the same draws for every network)


def configurations(name: str) -> list[dict]:
    """:data:`N_CONFIGS` configurations of ``name``'s grid (deterministic)."""
    space = search_space(name)
    if name in ("ebl", "pls"):
        ((key, values),) = space.items()
        return [{key: v} for v in values[:N_CONFIGS]]
    train_keys = [k for k in space if k != "lambda_phys"]
    grid = list(itertools.product(*(space[k] for k in train_keys)))
    rng = np.random.default_rng(SAMPLING_SEED)
    picks = rng.choice(len(grid), size=N_CONFIGS, replace=False)
    configs = [
        dict(zip(train_keys, (v.item() if hasattr(v, "item") else v for v in grid[i]), strict=True))
        for i in picks
    ]
    if "lambda_phys" in space:
        lam = np.resize(np.asarray(LAMBDA_PHYS_GRID), N_CONFIGS)
        np.random.default_rng(SAMPLING_SEED + 1).shuffle(lam)
        for c, v in zip(configs, lam, strict=True):
            c["lambda_phys"] = float(v)
    return configs


def _rows(ds: Dataset, idx: np.ndarray) -> Dataset:
    return Dataset(ds.frame.iloc[idx].reset_index(drop=True), config=ds.config, seed=ds.seed)


def _seeded(name: str) -> bool:
    return "random_state" in get_model_class(name)().get_params()


def cv_rmse(name: str, cfg: dict, k: int, data) -> tuple[float, int]:
    """Pooled held-out RMSE of configuration ``k`` over the tuning seeds' folds, and
    the number of fits (random state ``100 k + fold`` where the model takes one)."""
    sq = []
    for ds, y, folds in data:
        for f, (tr, te) in enumerate(folds):
            extra = {"random_state": 100 * k + f} if _seeded(name) else {}
            m = make_model(name, **cfg, **extra).fit(_rows(ds, tr))
            sq.append((m.predict(_rows(ds, te)) - y[te]) ** 2)
    return float(np.sqrt(np.mean(np.concatenate(sq)))), len(sq)


def lambda_curve(name: str, scores: list[float], k_best: int, data) -> tuple[dict, int]:
    """The PINN's validation curve: ``slice`` (tuned training parameters, every λ, the
    same random states) and ``profile`` (best draw per λ); and the fits it took."""
    configs = configurations(name)
    tuned = configs[k_best]
    slice_, fits = [], 0
    for lam in LAMBDA_PHYS_GRID:
        if lam == tuned["lambda_phys"]:
            slice_.append(round(scores[k_best], 3))  # the tuning's own fit
            continue
        rmse, n = cv_rmse(name, {**tuned, "lambda_phys": float(lam)}, k_best, data)
        slice_.append(round(rmse, 3))
        fits += n
    profile = [
        round(min(r for c, r in zip(configs, scores, strict=True) if c["lambda_phys"] == lam), 3)
        for lam in LAMBDA_PHYS_GRID
    ]
    curve = {
        "lambda_phys": list(LAMBDA_PHYS_GRID),
        "slice_cv_rmse_mgdl": slice_,
        "profile_cv_rmse_mgdl": profile,
        "slice_training_params": f"the tuned configuration (draw {k_best})",
    }
    return curve, fits


def _tuning_data(preset: str) -> tuple[list, float]:
    """Each tuning seed's data, targets and grouped folds, and the no-skill RMSE."""
    data = []
    for seed in TUNING_SEEDS:
        ds = ng.simulate(preset, N_SUBJECTS, PER_SUBJECT, seed=seed)
        y = ds.frame["glucose_mgdl"].to_numpy()
        groups = ds.frame["subject_id"].to_numpy()
        folds = list(GroupKFold(N_FOLDS).split(y, groups=groups))
        data.append((ds, y, folds))
    sq = [(y[te] - y[tr].mean()) ** 2 for _, y, folds in data for tr, te in folds]
    return data, float(np.sqrt(np.mean(np.concatenate(sq))))


def _curves_only(preset: str, models: list[str], params: dict, scores: dict) -> int:
    """Add the λ curve to PINNs already tuned on ``preset`` (no re-tuning)."""
    data, _ = _tuning_data(preset)
    fits = 0
    for name in (m for m in models if is_pinn(m) and m in params.get(preset, {})):
        recorded = scores[preset][name]["all_configs_rmse_mgdl"]
        k = int(np.argmin(recorded))
        if configurations(name)[k] != params[preset][name]:
            raise SystemExit(f"{preset} {name}: the draws no longer reproduce the tuning")
        curve, n = lambda_curve(name, recorded, k, data)
        scores[preset][name]["lambda_curve"] = curve
        fits += n
        print(f"{preset} {name} lambda curve {curve['slice_cv_rmse_mgdl']}", flush=True)
    return fits


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--presets", default=",".join(TUNED_PRESETS))
    ap.add_argument("--models", default=",".join(FAMILIES))
    ap.add_argument("--out", type=Path, default=OUT)
    ap.add_argument("--lambda-curve-only", action="store_true",
                    help="add the PINNs' lambda curves to their recorded tuning")
    args = ap.parse_args()
    torch.set_num_threads(1)
    presets = [p for p in args.presets.split(",") if p]
    models = [m for m in args.models.split(",") if m]
    unknown = [m for m in models if m not in FAMILIES]
    if unknown:
        ap.error(f"no search space for {unknown}; tuned families: {', '.join(FAMILIES)}")
    t_start = time.perf_counter()
    doc = json.loads(args.out.read_text()) if args.out.exists() else {}
    params = doc.get("params", {})
    scores = doc.get("scores", {})
    sources = doc.get("presets", {})
    fits = 0
    for preset in presets:
        if args.lambda_curve_only:
            fits += _curves_only(preset, models, params, scores)
            continue
        sources[preset] = {"simulated_as": preset}
        data, no_skill = _tuning_data(preset)
        for name in models:
            results = []
            for k, cfg in enumerate(configurations(name)):
                t0 = time.perf_counter()
                rmse, n = cv_rmse(name, cfg, k, data)
                fits += n
                results.append((rmse, k, cfg))
                print(
                    f"{preset} {name} {k:2d} {rmse:6.2f} ({time.perf_counter() - t0:.1f} s) {cfg}",
                    flush=True,
                )
            rmse, k, cfg = min(results, key=lambda r: (r[0], r[1]))
            params.setdefault(preset, {})[name] = json.loads(json.dumps(cfg))
            scores.setdefault(preset, {})[name] = {
                "tuning_cv_rmse_mgdl": round(rmse, 3),
                "no_skill_rmse_mgdl": round(no_skill, 3),
                "all_configs_rmse_mgdl": [round(r[0], 3) for r in results],
            }
            if is_pinn(name):
                curve, n = lambda_curve(name, [r[0] for r in results], k, data)
                scores[preset][name]["lambda_curve"] = curve
                fits += n
    elapsed = time.perf_counter() - t_start
    doc = {
        "format": "nirglucose-tuned-params",
        "format_version": 1,
        "made_by": "tools/tune.py",
        "budget": {
            "configurations_per_family": N_CONFIGS,
            "folds": N_FOLDS,
            "cv": "GroupKFold by subject_id",
            "tuning_seeds": list(TUNING_SEEDS),
            "reported_seeds_never_used": [0, 1, 2, 3, 4],
            "n_subjects": N_SUBJECTS,
            "per_subject": PER_SUBJECT,
            "lambda_phys_grid": list(LAMBDA_PHYS_GRID),
            "criterion": "pooled RMSE over the tuning seeds' held-out folds",
            "lambda_curve": (
                "each PINN's tuned training parameters refitted at every lambda_phys of the "
                "grid on the same seeds, folds and random states (slice); best draw per "
                "lambda (profile)"
            ),
        },
        "presets": sources,
        "params": params,
        "scores": scores,
        "previous_runs": doc.get("previous_runs", [])
        + ([doc["last_run"]] if "last_run" in doc else []),
        "last_run": {
            "lambda_curve_only": bool(args.lambda_curve_only),
            "presets": presets,
            "models": models,
            "fits": fits,
            "time_s": round(elapsed, 1),
            "torch_threads": 1,
        },
    }
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(doc, indent=1, sort_keys=True) + "\n")
    summary = {
        "out": str(args.out),
        "budget": doc["budget"],
        "time_s": round(elapsed, 1),
        "fits": fits,
        "params": params,
        "scores": {
            p: {m: s["tuning_cv_rmse_mgdl"] for m, s in v.items()} for p, v in scores.items()
        },
        "no_skill_rmse_mgdl": {
            p: next(iter(v.values()))["no_skill_rmse_mgdl"] for p, v in scores.items() if v
        },
    }
    print(json.dumps(summary))


if __name__ == "__main__":
    main()
