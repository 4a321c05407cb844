"""The benchmark's aggregation: task results -> metrics, comparisons, ablation.

:func:`aggregate` turns the per-task results of
:func:`~nirglucose.evaluation.benchmark.run_benchmark` into the tables of a
:class:`~nirglucose.evaluation.benchmark.result.BenchmarkResult`: the scored
out-of-fold predictions with their conformal intervals, one metrics row per model
(point values per repeat averaged over repeats, cluster-bootstrap CIs), the paired
comparisons (``vs_best`` and the study's orderings) and the physics ablation. (The
drop-one-LED refits are scored by :mod:`~nirglucose.evaluation.benchmark.drop_one`.)
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pandas as pd

from ...calibration.conformal import LEVELS, coverage_summary, out_of_fold_intervals
from ...dataset.small_data import significance_withheld
from ...metrics import summary
from ...metrics.resampling import cluster_bootstrap_metrics, compare_models
from ...models.labels import label, row_privilege
from ..reference import STUDY_ORDER
from .result import (
    ABLATION_COLUMNS,
    COMPARISON_COLUMNS,
    METRIC_COLUMNS,
    NO_PHYSICS,
    ORACLE,
    PREDICTION_COLUMNS,
)

__all__ = ["aggregate", "count_invalid", "fallback_mgdl", "scored"]


def _rank(preds: pd.DataFrame, comparisons: pd.DataFrame, metrics: pd.DataFrame,
          meta: dict[str, Any]) -> pd.DataFrame:
    """``meta``'s ``significance_withheld`` and ``best_model``; the comparisons kept.

    The small-data policy: from too few test subjects no comparison and no best model.
    """
    meta["significance_withheld"] = significance_withheld(int(preds["subject_id"].nunique()))
    if meta["significance_withheld"]:
        comparisons = comparisons.iloc[:0]
    meta["best_model"] = None if meta["significance_withheld"] else (
        comparisons.loc[comparisons["family"] == "vs_best", "reference_model"].iloc[0]
        if (comparisons["family"] == "vs_best").any()
        else (metrics["model"].iloc[0] if len(metrics) else None)
    )
    return comparisons


def aggregate(
    dataset: Any,
    runs: list[tuple[dict[str, Any], Any, dict[str, Any]]],
    names: list[str],
    aux: list[str],
    meta: dict[str, Any],
    *,
    n_boot: int,
    alpha: float,
    seed: int,
) -> dict[str, Any]:
    """The benchmark's tables from its finished tasks, as
    :class:`~nirglucose.evaluation.benchmark.result.BenchmarkResult`'s
    keyword arguments (the run adds its other tables and builds the result once).

    Parameters
    ----------
    dataset : Dataset
        The data benchmarked.
    runs : list of (spec, Split, result)
        Every task in plan order with its result.
    names, aux : list of str
        Reported rows and auxiliary ones (the oracle run only for ``rmse_vs_oracle``).
    meta : dict
        The run's metadata; ``oracle_rmse_mgdl``, ``best_model`` and
        ``study_orderings`` are added.
    n_boot, alpha, seed : int, float, int
        Bootstrap resamples, significance level and bootstrap seed.
    """
    preds_all = _predictions(dataset, runs, [*names, *aux])
    by_model: dict[str, list[tuple[dict, dict]]] = {}
    for spec, _split, res in runs:
        by_model.setdefault(spec["model"], []).append((spec, res))
    allm = pd.DataFrame(
        [_metric_row(name, preds_all, by_model[name], n_boot, seed) for name in [*names, *aux]]
    )
    oracle_rmse = (
        float(allm.loc[allm["model"] == ORACLE, "rmse_mgdl"].iloc[0])
        if ORACLE in set(allm["model"])
        else np.nan
    )
    allm["rmse_vs_oracle"] = allm["rmse_mgdl"] / oracle_rmse
    meta["oracle_rmse_mgdl"] = oracle_rmse
    metrics = (
        allm[allm["model"].isin(names)]
        .sort_values("rmse_mgdl", kind="stable")
        .reset_index(drop=True)
    )
    metrics = metrics[list(METRIC_COLUMNS)]

    preds = preds_all[preds_all["model"].isin(names)].reset_index(drop=True)
    preds = preds[list(PREDICTION_COLUMNS)]
    comparisons = _comparisons(preds, names, n_boot=n_boot, alpha=alpha, seed=seed,
                               study=dataset.config is not None)
    comparisons = _rank(preds, comparisons, metrics, meta)
    ablation = _ablation(
        preds, names, meta.get("ablation_pairs"), metrics.set_index("model")["rmse_mgdl"],
        n_boot=n_boot, alpha=alpha, seed=seed,
    )
    meta["study_orderings"] = _study_orderings(comparisons)
    meta["timing_machine"] = next(
        (res["timing"]["machine"] for _, _, res in runs if res.get("timing", {}).get("machine")),
        None,
    )
    return {
        "metrics": metrics,
        "predictions": preds,
        "comparisons": comparisons,
        "histories": {name: _timed(by_model[name])["history"] for name in names},
        "meta": meta,
        "dataset": dataset,
        "ablation": ablation,
    }


def _timed(runs: list[tuple[dict, dict]]) -> dict[str, Any]:
    """The result of a model's timed task (first fold of the first repeat)."""
    return next(res for spec, res in runs if spec["timed"])


def scored(raw: np.ndarray, fallback: float) -> np.ndarray:
    """Below 0 mg/dL scored as 0, non-finite as the fold's fallback."""
    return np.where(np.isfinite(raw), np.maximum(raw, 0.0), fallback)


def fallback_mgdl(train: Any) -> float:
    """The fold's fallback prediction: the median training glucose. [mg/dL]"""
    return float(np.median(train.frame["glucose_mgdl"].to_numpy(float)))


def count_invalid(raw: np.ndarray) -> int:
    """Raw predictions that are non-finite or below 0 mg/dL (scored otherwise)."""
    return int(np.count_nonzero(~np.isfinite(raw) | (raw < 0)))


def _predictions(dataset: Any, runs: list, order_names: list[str]) -> pd.DataFrame:
    """Every out-of-fold prediction, scored, with its conformal interval, in plan order."""
    frame = dataset.frame
    sid = frame["subject_id"].to_numpy()
    mid = frame["measurement_id"].to_numpy() if "measurement_id" in frame else np.arange(len(frame))
    yref = frame["glucose_mgdl"].to_numpy(float)
    parts = []
    val_parts = []
    for spec, split, res in runs:
        raw = np.asarray(res["predicted_mgdl"], dtype=float)
        parts.append(
            pd.DataFrame(
                {
                    "model": spec["model"],
                    "subject_id": sid[split.test],
                    "measurement_id": mid[split.test],
                    "repeat": split.repeat,
                    "fold": split.fold,
                    "reference_mgdl": yref[split.test],
                    "predicted_mgdl": raw,
                    "scored_mgdl": scored(raw, res["fallback_mgdl"]),
                }
            )
        )
        val_raw = res.get("val_predicted_mgdl")
        if split.val is not None and val_raw is not None:
            vraw = np.asarray(val_raw, dtype=float)
            val_parts.append(
                pd.DataFrame(
                    {
                        "model": spec["model"],
                        "subject_id": sid[split.val],
                        "repeat": split.repeat,
                        "fold": split.fold,
                        "reference_mgdl": yref[split.val],
                        "scored_mgdl": scored(vraw, res["fallback_mgdl"]),
                    }
                )
            )
    preds_all = pd.concat(parts, ignore_index=True)
    val_cal = pd.concat(val_parts, ignore_index=True) if val_parts else None
    return _with_intervals(preds_all, val_cal, order_names)


def _with_intervals(preds_all: pd.DataFrame, val_cal, order_names: list[str]) -> pd.DataFrame:
    """Add the 90 % conformal bounds and sort by model (plan order), repeat, fold."""
    preds_all = out_of_fold_intervals(preds_all, val_cal)
    preds_all["lower90_mgdl"] = np.maximum(preds_all["scored_mgdl"] - preds_all["half90_mgdl"], 0)
    preds_all["upper90_mgdl"] = preds_all["scored_mgdl"] + preds_all["half90_mgdl"]
    order = {m: k for k, m in enumerate(order_names)}
    return (
        preds_all.assign(_o=preds_all["model"].map(order))
        .sort_values(["_o", "repeat", "fold", "measurement_id"], kind="stable")
        .drop(columns="_o")
        .reset_index(drop=True)
    )


def _metric_row(
    name: str, preds_all: pd.DataFrame, runs: list, n_boot: int, seed: int
) -> dict[str, Any]:
    """One model's metrics row (without ``rmse_vs_oracle``)."""
    p = preds_all[preds_all["model"] == name]
    per_rep = [
        summary(g["reference_mgdl"].to_numpy(), g["scored_mgdl"].to_numpy())
        for _, g in p.groupby("repeat", sort=True)
    ]
    point = {k: float(np.mean([s[k] for s in per_rep])) for k in per_rep[0]}
    ci = cluster_bootstrap_metrics(
        p["reference_mgdl"],
        p["scored_mgdl"],
        p["subject_id"],
        p["repeat"],
        n_boot=n_boot,
        seed=seed,
    )
    cov = {a: coverage_summary(p, a, n_boot=n_boot, seed=seed) for a in LEVELS}
    first = _timed(runs)
    t = first["timing"]
    raw = p["predicted_mgdl"].to_numpy()
    return {
        **point,
        **{k: v for k, v in ci.items() if "_ci_" in k},
        "model": name,
        "label": label(name),
        "privileged": row_privilege(name),
        "n_parameters": int(first["n_parameters"]),
        "latency_single_ms": t.get("latency_single_ms", np.nan),
        "latency_single_p90_ms": t.get("latency_single_p90_ms", np.nan),
        "throughput_per_s": t.get("throughput_per_s", np.nan),
        "latency_input": t.get("latency_input", ""),
        "macs_per_prediction": t.get("macs_per_prediction", np.nan),
        "macs_counted": t.get("macs_counted", ""),
        "fit_time_s": float(np.mean([res["fit_time_s"] for _, res in runs])),
        "n_predictions": int(len(p)),
        "n_invalid_predictions": count_invalid(raw),
        "coverage90_pct": cov[0.9]["coverage"],
        "coverage90_ci_low": cov[0.9]["ci_low"],
        "coverage90_ci_high": cov[0.9]["ci_high"],
        "width90_mgdl": cov[0.9]["width"],
        "coverage80_pct": cov[0.8]["coverage"],
        "width80_mgdl": cov[0.8]["width"],
    }


def _verdict(pair: dict[str, Any], row: pd.Series | None) -> str:
    if not pair["tested"]:
        return "physics off by tuning" if pair["lambda_source"] == "tuned" else "physics off"
    if not bool(row["significant"]):
        return "no significant difference"
    return "physics helps" if row["rmse_diff_mgdl"] < 0 else "physics hurts"


def _ablation(preds, names, pairs, rmse, *, n_boot, alpha, seed) -> pd.DataFrame:
    """Each PINN against itself without physics: paired RMSE difference (with − off).

    ``pairs`` (the plan's, in ``meta["ablation_pairs"]``) say which pairs are tested:
    a PINN whose own λ is 0 is its no-physics fit, so that pair gets no difference, no
    p-value and no verdict (its RMSEs from ``rmse``, the metrics table's); Holm runs
    over the tested pairs only. Without ``pairs``
    (an older run) every ``<pinn>/no-physics`` row is paired with its PINN.
    """
    if pairs is None:
        pairs = [
            {"model": n[: -len(NO_PHYSICS)], "ablated_model": n, "lambda_phys": np.nan,
             "lambda_source": "unknown", "tested": True}
            for n in names if n.endswith(NO_PHYSICS)
        ]
    pairs = [p for p in pairs if p["model"] in names and p["ablated_model"] in names]
    if not pairs:
        return pd.DataFrame(columns=list(ABLATION_COLUMNS))
    tested = [(p["model"], p["ablated_model"]) for p in pairs if p["tested"]]
    c = pd.DataFrame()
    if tested:
        c = compare_models(
            preds, pairs=tested, pred_col="scored_mgdl", n_boot=n_boot, seed=seed, alpha=alpha
        ).set_index(["model", "reference_model"])
    rows = []
    for p in pairs:
        key = (p["model"], p["ablated_model"])
        r = c.loc[key] if p["tested"] else None
        rows.append({
            **p,
            "rmse_mgdl": r["rmse_mgdl"] if p["tested"] else rmse[p["model"]],
            "ablated_rmse_mgdl": (
                r["reference_rmse_mgdl"] if p["tested"] else rmse[p["ablated_model"]]
            ),
            **{k: (r[k] if p["tested"] else np.nan)
               for k in ("rmse_diff_mgdl", "ci_low", "ci_high", "p_value", "p_holm",
                         "p_wilcoxon")},
            "significant": bool(r["significant"]) if p["tested"] else False,
            "physics_helps": bool(r["rmse_diff_mgdl"] < 0) if p["tested"] else None,
            "verdict": _verdict(p, r),
        })
    return pd.DataFrame(rows)[list(ABLATION_COLUMNS)].reset_index(drop=True)


def _study_orderings(comparisons: pd.DataFrame) -> dict[str, Any]:
    """Which of the study's pairwise RMSE orderings hold here, and which significantly."""
    so = comparisons[comparisons["family"] == "study_order"]
    pairs = [
        {
            "better": r["reference_model"],
            "worse": r["model"],
            "holds": bool(r["study_holds"]),
            "significant": bool(r["significant"]),
            "rmse_diff_mgdl": r["rmse_diff_mgdl"],
            "ci_low": r["ci_low"],
            "ci_high": r["ci_high"],
            "p_holm": r["p_holm"],
        }
        for _, r in so.iterrows()
    ]
    return {
        "study_order": [m for m in STUDY_ORDER],
        "n_pairs": len(pairs),
        "n_hold": sum(p["holds"] for p in pairs),
        "n_hold_significant": sum(p["holds"] and p["significant"] for p in pairs),
        "n_reversed_significant": sum((not p["holds"]) and p["significant"] for p in pairs),
        "pairs": pairs,
    }


def _comparisons(preds, names, *, n_boot, alpha, seed, study: bool = True) -> pd.DataFrame:
    """Every model against the best deployable one; with ``study``, the study's orderings
    (simulated data only: on a user's device the study's claims were measured elsewhere).

    The best is chosen among the rows that read only the measured columns: the oracle
    and every other privileged row (:func:`~nirglucose.models.labels.row_privilege`) are
    references, compared with the best but never it."""
    frames = []
    if len(names) > 1:
        vs_best = compare_models(
            preds,
            pred_col="scored_mgdl",
            n_boot=n_boot,
            seed=seed,
            alpha=alpha,
            exclude_from_best=(ORACLE, *(n for n in names if row_privilege(n) is not None)),
        )
        vs_best.insert(0, "family", "vs_best")
        vs_best["study_holds"] = None
        frames.append(vs_best)
    in_study = [m for m in STUDY_ORDER if m in names] if study else []
    pairs = [(worse, better) for k, better in enumerate(in_study) for worse in in_study[k + 1 :]]
    if pairs:
        so = compare_models(
            preds, pairs=pairs, pred_col="scored_mgdl", n_boot=n_boot, seed=seed, alpha=alpha
        )
        so.insert(0, "family", "study_order")
        so["study_holds"] = so["rmse_diff_mgdl"] > 0
        frames.append(so)
    if not frames:
        return pd.DataFrame(columns=list(COMPARISON_COLUMNS))
    return pd.concat(frames, ignore_index=True)[list(COMPARISON_COLUMNS)]
