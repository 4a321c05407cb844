"""What each results figure shows, computed from the metrics and predictions.

Correlations, zone percentages, Bland–Altman limits and their confidence intervals,
regression lines, normalised scores, Pareto fronts and the tables of the trade-off,
drop-one, forest and performance figures, with :mod:`nirglucose.metrics` and numpy;
plain numbers for :mod:`nirglucose.plots`.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from typing import Any, Final

import numpy as np
import pandas as pd

from ...evaluation.reference import STUDY_TABLE
from ...formatting import format_number
from ...metrics import bland_altman, clarke_zones, parkes_zones, zone_percentages
from ...models.labels import label as model_name
from ...models.labels import row_privilege

__all__ = [
    "PHYSICS_DEPTH", "REFERENCE_ROWS", "PHYSICS_DEPTH_LABELS", "RADAR_AXES",
    "RADAR_COST_DECADES", "model_order", "scored_column", "first_repeat", "pooled",
    "channel_correlations", "error_grid_inputs", "bland_altman_inputs", "linearity_inputs",
    "radar_scores", "pareto_front", "efficiency_table",
    "is_ablation_row", "competitors", "reference_values", "physics_depth_table",
    "drop_one_models", "forest_table", "performance_table", "latency_resolution",
]

#: Physics depth of each registered model: how much of the forward model it uses, as
#: an ordinal level (figure 9). A presentation choice, documented here.
PHYSICS_DEPTH: Final[dict[str, float]] = {
    "sdnn": 0,
    "pls": 0,
    "gp": 0,
    "gbr": 0,
    "original-pinn": 1,
    "optimized-pinn": 1,
    "selective-rte-pinn": 2,
    "rte-pinn": 3,
    "ebl": 4,
    "ebl+gp": 4,  # a hybrid sits at its physics backbone's depth
    # the forward model as a loss term: more of it than the features, less than inverting it
    "original-pinn-fm": 4.5,
    "optimized-pinn-fm": 4.5,
    "rte-pinn-fm": 4.5,
    "selective-rte-pinn-fm": 4.5,
    "physics-inversion": 5,
    "device-inversion": 5,  # inverts a forward model of the declared parts and tables
    "physics-inversion+gp": 5,
    "oracle": 5,
}
#: Rows that are references, not competitors: drawn as horizontal lines in figures 9-10
#: and left out of the radar and the Pareto fronts (the oracle is a bound, the training
#: mean is no skill).
REFERENCE_ROWS: Final = ("oracle", "mean")

#: Tick labels of the physics-depth levels.
PHYSICS_DEPTH_LABELS: Final[dict[float, str]] = {
    0: "none\n(data-driven)",
    1: "Beer–Lambert\nloss term",
    2: "RTE loss\n(2 λ)",
    3: "RTE loss\n(all λ)",
    4: "Beer–Lambert\nfeatures",
    4.5: "forward-model\nloss term",
    5: "forward model\ninverted",
}

#: Axes of the radar chart: (label, metrics column, higher is better, log scale).
RADAR_AXES: Final[tuple[tuple[str, str, bool, bool], ...]] = (
    ("RMSE", "rmse_mgdl", False, False),
    ("MARD", "mard_pct", False, False),
    ("Clarke A", "clarke_a_pct", True, False),
    ("±15 %", "within15_pct", True, False),
    ("parameters", "n_parameters", False, True),
    ("MACs", "macs_per_prediction", False, True),
)


def performance_table(metrics_by_preset: Mapping[str, pd.DataFrame],
                      models: Sequence[str]) -> pd.DataFrame:
    """Long table of the performance panel: one row per preset and model."""
    cols = ("rmse_mgdl", "rmse_ci_low", "rmse_ci_high", "mard_pct", "n_parameters",
            "macs_per_prediction", "latency_single_ms")
    rows = []
    for preset, met in metrics_by_preset.items():
        m = met.drop_duplicates("model").set_index("model")
        for model in models:
            if model in m.index:
                rows.append({"preset": preset, "model": model,
                             **{c: m.at[model, c] for c in cols if c in m.columns}})
    return pd.DataFrame(rows)



def model_order(models: Iterable[str]) -> list[str]:
    """Models in display order: registered models in the study's order, then the rest.

    Examples
    --------
    >>> model_order(["sdnn", "mine", "ebl"])
    ['ebl', 'sdnn', 'mine']
    """
    from ...plots.style import MODEL_COLORS

    names = list(dict.fromkeys(str(m) for m in models))
    known = [m for m in MODEL_COLORS if m in names]
    return known + [m for m in names if m not in MODEL_COLORS]


def scored_column(predictions: pd.DataFrame) -> str:
    """Prediction column the metrics were computed on (``scored_mgdl`` if present)."""
    return "scored_mgdl" if "scored_mgdl" in predictions.columns else "predicted_mgdl"


def first_repeat(predictions: pd.DataFrame, model: str) -> pd.DataFrame:
    """One model's out-of-fold predictions of the first repeat (each snapshot once)."""
    p = predictions[predictions["model"] == model]
    if "repeat" in p.columns and len(p):
        p = p[p["repeat"] == p["repeat"].min()]
    return p


def pooled(predictions: pd.DataFrame, model: str) -> pd.DataFrame:
    """One model's out-of-fold predictions of every repeat, pooled.

    Each repeat predicts every snapshot once, so the zone shares of the pooled points
    equal the table's (per-repeat shares averaged over repeats, all repeats the same size).
    """
    return predictions[predictions["model"] == model]


def _finite_pairs(p: pd.DataFrame, col: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Finite reference/prediction pairs with a positive reference, and the row mask kept."""
    ref = p["reference_mgdl"].to_numpy(float)
    pred = p[col].to_numpy(float)
    ok = np.isfinite(ref) & np.isfinite(pred) & (ref > 0)
    return ref[ok], pred[ok], ok


def channel_correlations(glucose_mgdl: np.ndarray, adc: Mapping[float, np.ndarray]
                         ) -> dict[float, float]:
    """Pearson r between glucose and ln(ADC code) of each channel.

    Examples
    --------
    >>> g = np.array([80.0, 120.0, 160.0]); a = {850.0: np.array([100, 90, 80])}
    >>> round(channel_correlations(g, a)[850.0], 3)
    -0.999
    """
    out = {}
    for wl, codes in adc.items():
        x = np.log(np.asarray(codes, dtype=float))
        ok = np.isfinite(x) & np.isfinite(glucose_mgdl)
        if ok.sum() > 2 and np.ptp(x[ok]) > 0 and np.ptp(glucose_mgdl[ok]) > 0:
            out[wl] = float(np.corrcoef(glucose_mgdl[ok], x[ok])[0, 1])
        else:
            out[wl] = float("nan")
    return out


def error_grid_inputs(predictions: pd.DataFrame, models: Sequence[str], *, kind: str = "clarke",
                      diabetes_type: int = 1, measurement_ids: Iterable[Any] | None = None
                      ) -> tuple[dict[str, dict[str, Any]], int]:
    """Points and zone percentages of the Clarke or Parkes grid of each model.

    Uses every repeat's predictions pooled (:func:`pooled`) and the scored predictions (negative
    ones are placed at 0 mg/dL by the benchmark, as the grids require; if only raw
    predictions exist, negatives are placed at 0 here and counted).

    ``measurement_ids`` keeps only those snapshots (e.g. the type-2 ones for the
    type-2 Parkes grid).

    Returns
    -------
    grids : dict
        Model -> ``{"reference", "predicted", "zone_pct"}``.
    n_clipped : int
        Raw predictions below 0 placed at 0 here.
    """
    col = scored_column(predictions)
    grids: dict[str, dict[str, Any]] = {}
    clipped = 0
    keep = None if measurement_ids is None else set(measurement_ids)
    for m in models:
        p = pooled(predictions, m)
        if keep is not None:
            p = p[p["measurement_id"].isin(keep)]
        ref, pred, _ = _finite_pairs(p, col)
        if ref.size == 0:
            continue
        neg = pred < 0
        clipped += int(neg.sum())
        pred = np.where(neg, 0.0, pred)
        zones = (clarke_zones(ref, pred) if kind == "clarke"
                 else parkes_zones(ref, pred, diabetes_type=diabetes_type))
        grids[m] = {"reference": ref, "predicted": pred, "zone_pct": zone_percentages(zones)}
    return grids, clipped


def _t_quantile(level: float, dof: int) -> float:
    from scipy.stats import t

    return float(t.ppf(0.5 + level / 2.0, dof))


def bland_altman_inputs(predictions: pd.DataFrame, models: Sequence[str], *,
                        level: float = 0.95) -> dict[str, dict[str, Any]]:
    """Bland–Altman points, bias, limits of agreement and their confidence intervals.

    The points are every repeat's predictions pooled; the bias and limits are computed
    per repeat and averaged over repeats, as the table's ``bias_mgdl``,
    ``loa_low_mgdl`` and ``loa_high_mgdl`` are (one definition for both). The
    intervals are the approximate ones of Bland & Altman (1986): standard error
    ``s / sqrt(n)`` for the bias and ``s sqrt(3 / n)`` for each limit, with a t quantile
    on ``n - 1`` degrees of freedom, ``n`` the snapshots of one repeat. Pairs from the
    same subject are treated as independent, so the intervals are somewhat narrow.

    References
    ----------
    .. [1] Bland JM, Altman DG. Statistical methods for assessing agreement between two
       methods of clinical measurement. Lancet 327(8476):307-310, 1986.
       doi:10.1016/S0140-6736(86)90837-8
    """
    col = scored_column(predictions)
    out: dict[str, dict[str, Any]] = {}
    for m in models:
        p = pooled(predictions, m)
        ref, pred, ok = _finite_pairs(p, col)
        if ref.size < 3:
            continue
        rep = p["repeat"].to_numpy()[ok] if "repeat" in p.columns else np.zeros(ref.size)
        bias, low, high, n = _per_repeat_limits(ref, pred, rep)
        s = (high - bias) / 1.96
        tq = _t_quantile(level, n - 1)
        se_b, se_l = s / math.sqrt(n), s * math.sqrt(3.0 / n)
        out[m] = {
            "mean_mgdl": 0.5 * (ref + pred),
            "difference_mgdl": pred - ref,
            "bias": bias, "loa_low": low, "loa_high": high,
            "bias_ci": (bias - tq * se_b, bias + tq * se_b),
            "loa_low_ci": (low - tq * se_l, low + tq * se_l),
            "loa_high_ci": (high - tq * se_l, high + tq * se_l),
        }
    return out


def _per_repeat_limits(ref: np.ndarray, pred: np.ndarray, rep: np.ndarray
                       ) -> tuple[float, float, float, int]:
    """Bias and limits of agreement per repeat, averaged over repeats (the table's).

    Each repeat predicts every snapshot once; the benchmark computes every metric per
    repeat and averages (:mod:`nirglucose.metrics.resampling`), so the figure does too.
    Returns (bias, lower, upper, snapshots per repeat, the smallest).
    """
    per = [bland_altman(ref[rep == r], pred[rep == r]) for r in np.unique(rep)
           if (rep == r).sum() >= 3]
    if not per:
        per = [bland_altman(ref, pred)]
    arr = np.asarray(per, dtype=float)
    n = int(min((rep == r).sum() for r in np.unique(rep)))
    return float(arr[:, 0].mean()), float(arr[:, 1].mean()), float(arr[:, 2].mean()), n


def linearity_inputs(predictions: pd.DataFrame, models: Sequence[str], *,
                     level: float = 0.95) -> dict[str, dict[str, Any]]:
    """Least-squares line of predicted on reference glucose, its slope CI and R².

    When the predictions carry ``lower90_mgdl``/``upper90_mgdl`` (the benchmark's
    prediction intervals), each panel also gets ``lower`` and ``upper``.
    """
    col = scored_column(predictions)
    out: dict[str, dict[str, Any]] = {}
    for m in models:
        p = pooled(predictions, m)
        ref, pred, ok = _finite_pairs(p, col)
        n = ref.size
        if n < 3 or np.ptp(ref) == 0:
            continue
        slope, intercept = np.polyfit(ref, pred, 1)
        resid = pred - (intercept + slope * ref)
        sxx = float(np.sum((ref - ref.mean()) ** 2))
        se = math.sqrt(float(resid @ resid) / (n - 2) / sxx)
        tq = _t_quantile(level, n - 2)
        sst = float(np.sum((pred - pred.mean()) ** 2))
        r2 = 1.0 - float(resid @ resid) / sst if sst > 0 else float("nan")
        out[m] = {"reference": ref, "predicted": pred, "slope": float(slope),
                  "intercept": float(intercept), "r_squared": r2,
                  "slope_ci": (float(slope - tq * se), float(slope + tq * se))}
        if {"lower90_mgdl", "upper90_mgdl"} <= set(p.columns):
            lo = p["lower90_mgdl"].to_numpy(float)[ok]  # the same rows as the points
            hi = p["upper90_mgdl"].to_numpy(float)[ok]
            if np.isfinite(lo).all() and np.isfinite(hi).all():
                out[m].update(lower=lo, upper=hi)
    return out


def _metric(metrics: pd.DataFrame, models: Sequence[str], col: str) -> np.ndarray:
    if col not in metrics.columns:
        return np.full(len(models), np.nan)
    s = metrics.drop_duplicates("model").set_index("model")[col]
    return pd.to_numeric(s.reindex(list(models)), errors="coerce").to_numpy(float)


#: Decades of parameters or latency above the smallest model's that score 0 on the radar.
RADAR_COST_DECADES: Final = 6.0


def radar_scores(metrics: pd.DataFrame, models: Sequence[str]) -> pd.DataFrame:
    """Scores in [0, 1] per model and radar axis, 1 = best of these models.

    Accuracy axes are ratios to the best model (``best / x`` for RMSE and MARD,
    ``x / best`` for Clarke A and ±15 %), so that close models look close. Cost axes
    (parameters, multiply-accumulates per prediction) lose ``1 / RADAR_COST_DECADES``
    per decade above the cheapest model: ``1 - log10(x / best) / 6``, floored at 0
    (counts below 1 count as 1). A missing value is NaN. Latency is not an axis: it
    measures the machine and Python's call overhead more than the model (the MACs
    are its machine-independent stand-in). No composite is formed: a mean over these
    axes weighs accuracy against cost by the arbitrary 1/6 per decade.

    Examples
    --------
    >>> m = pd.DataFrame({"model": ["a", "b"], "rmse_mgdl": [10.0, 20.0],
    ...                   "n_parameters": [100, 100_000]})
    >>> s = radar_scores(m, ["a", "b"])
    >>> s["RMSE"].tolist(), s["parameters"].tolist()
    ([1.0, 0.5], [1.0, 0.5])
    """
    cols = {}
    for label, col, higher, log in RADAR_AXES:
        v = _metric(metrics, models, col)
        floor = 1.0  # 0 parameters or MACs score as 1
        ok = np.isfinite(v) & (v > 0 if not (log or higher) else v >= 0)
        score = np.full(v.shape, np.nan)
        if ok.any():
            if log:
                x = np.log10(np.maximum(v[ok], floor))
                score[ok] = np.clip(1.0 - (x - x.min()) / RADAR_COST_DECADES, 0.0, 1.0)
            elif higher:
                best = v[ok].max()
                score[ok] = v[ok] / best if best > 0 else 1.0
            else:
                score[ok] = v[ok].min() / v[ok]
        cols[label] = score
    return pd.DataFrame(cols, index=pd.Index(list(models), name="model"))


def pareto_front(cost: Sequence[float], rmse: Sequence[float]) -> np.ndarray:
    """Mask of points no other point dominates (both lower-or-equal, one strictly lower).

    Examples
    --------
    >>> pareto_front([1, 2, 3, 4], [10, 5, 7, 4]).tolist()
    [True, True, False, True]
    """
    c = np.asarray(cost, dtype=float)
    r = np.asarray(rmse, dtype=float)
    ok = np.isfinite(c) & np.isfinite(r)
    le = (c[:, None] <= c[None, :]) & (r[:, None] <= r[None, :])
    lt = (c[:, None] < c[None, :]) | (r[:, None] < r[None, :])
    dominated = (le & lt & ok[:, None]).any(axis=0)
    return ok & ~dominated


def efficiency_table(metrics: pd.DataFrame, models: Sequence[str], *, latency: bool = True
                     ) -> pd.DataFrame:
    """Inputs of the efficiency figure: costs and the Pareto fronts, one per cost.

    Only competitors (:func:`competitors`); the references are drawn as lines. The
    costs are the trainable parameters, the multiply-accumulates per prediction
    (machine-independent) and the median single-sample latency with its 90th
    percentile. No combined index: how parameters, arithmetic and time should weigh
    against each other depends on the device, so each keeps its own front. With
    ``latency=False`` (differences inside timing noise, :func:`latency_resolution`)
    every latency counts as equal: the latency front is the most accurate model only.
    """
    models = competitors(models)
    t = pd.DataFrame({
        "model": list(models),
        "rmse_mgdl": _metric(metrics, models, "rmse_mgdl"),
        "n_parameters": _metric(metrics, models, "n_parameters"),
        "macs_per_prediction": _metric(metrics, models, "macs_per_prediction"),
        "latency_single_ms": _metric(metrics, models, "latency_single_ms"),
        "latency_single_p90_ms": _metric(metrics, models, "latency_single_p90_ms"),
    })
    for col, front in (("n_parameters", "front_parameters"),
                       ("macs_per_prediction", "front_macs"),
                       ("latency_single_ms", "front_latency")):
        cost = t[col].to_numpy(float)
        if col == "latency_single_ms" and not latency:
            cost = np.where(np.isfinite(cost), 1.0, np.nan)
        cost = np.where(cost > 0, cost, np.nan)  # a log axis cannot show zero cost
        t[front] = pareto_front(cost, t["rmse_mgdl"])
    return t


def is_ablation_row(model: str) -> bool:
    """Whether ``model`` is an ablation row (``<pinn>/no-physics``), shown in its own table."""
    return "/" in str(model)


def competitors(models: Iterable[str]) -> list[str]:
    """Models that compete: neither a reference row (:data:`REFERENCE_ROWS`), nor a
    privileged estimator (it reads the generating scenario: a reference, like the
    oracle; :func:`~nirglucose.models.labels.row_privilege`), nor an ablation."""
    return [m for m in models if m not in REFERENCE_ROWS and not is_ablation_row(m)
            and row_privilege(str(m)) is None]


def reference_values(metrics: pd.DataFrame, models: Sequence[str]) -> dict[str, float]:
    """RMSE of the reference rows present (oracle bound, no-skill mean) and of the
    privileged estimators, drawn like the oracle. [mg/dL]"""
    refs = [m for m in REFERENCE_ROWS if m in models]
    refs += [m for m in models if m not in refs and not is_ablation_row(m)
             and row_privilege(str(m)) is not None]
    return {m: float(v) for m, v in zip(refs, _metric(metrics, refs, "rmse_mgdl"), strict=True)
            if np.isfinite(v)}


def physics_depth_table(metrics: pd.DataFrame, models: Sequence[str], *,
                        lambdas: Mapping[str, float] | None = None
                        ) -> tuple[pd.DataFrame, list[str]]:
    """Inputs of the physics-depth figure and the models left out (no known depth).

    Reference rows (:data:`REFERENCE_ROWS`) and ablation rows are not competitors and
    are neither drawn as bubbles nor listed as left out. A PINN whose tuned physics
    weight (``lambdas``, from ``meta.json``) is 0 trained without its physics term: it
    sits at depth 0 (no physics) and its ``label`` says ``physics off``. Privileged
    rows are not competitors (:func:`competitors`): they are drawn as reference lines.
    """

    models = competitors(models)
    known = [m for m in models if m in PHYSICS_DEPTH]
    off = {m for m in known if (lambdas or {}).get(m) == 0.0}
    t = pd.DataFrame({
        "model": known,
        "label": [model_name(m) + (" (physics off: λ = 0)" if m in off else "")
                  for m in known],
        "physics_depth": [0.0 if m in off else PHYSICS_DEPTH[m] for m in known],
        "rmse_mgdl": _metric(metrics, known, "rmse_mgdl"),
        "n_parameters": _metric(metrics, known, "n_parameters"),
    })
    t = t[np.isfinite(t["rmse_mgdl"]) & np.isfinite(t["n_parameters"])].reset_index(drop=True)
    t["on_front"] = pareto_front(t["n_parameters"], t["rmse_mgdl"])
    # spread models sharing a level
    t["x_offset"] = 0.0
    for _, idx in t.groupby("physics_depth").groups.items():
        k = len(idx)
        if k > 1:
            t.loc[idx, "x_offset"] = np.linspace(-0.3, 0.3, k)
    left_out = [m for m in models if m not in set(t["model"])]
    return t, left_out


def drop_one_models(drop_one: pd.DataFrame, models: Sequence[str]) -> list[str]:
    """The models of ``drop_one.csv`` in display order (``models`` first, then the rest).

    Ablation rows (``<pinn>/no-physics``) are left out; they have their own table.
    """
    have = list(dict.fromkeys(str(m) for m in drop_one["model"]))
    rows = [m for m in models if m in have] + [m for m in have if m not in models]
    return [m for m in rows if not is_ablation_row(m)]


def _study_rows() -> dict[str, dict[str, Any]]:
    return {str(r["model"]): dict(r) for r in STUDY_TABLE}


def forest_table(metrics: pd.DataFrame, models: Sequence[str], *,
                 with_study: bool = True) -> pd.DataFrame:
    """Inputs of the forest plot: RMSE, its interval, and the study's RMSE where it has one.

    ``with_study=False`` (a user's data, measured on another device) leaves the study's
    values out (all NaN).
    """
    study = _study_rows() if with_study else {}
    return pd.DataFrame({
        "model": list(models),
        "rmse_mgdl": _metric(metrics, models, "rmse_mgdl"),
        "rmse_ci_low": _metric(metrics, models, "rmse_ci_low"),
        "rmse_ci_high": _metric(metrics, models, "rmse_ci_high"),
        "study_rmse_mgdl": [float(study[m]["rmse_mgdl"]) if m in study else np.nan
                            for m in models],
    })


# --------------------------------------------------------------------------- data figures


def latency_resolution(metrics: pd.DataFrame, peers: Sequence[pd.DataFrame] = ()
                       ) -> dict[str, Any] | None:
    """Whether the competitors' latencies differ by more than the timing noise.

    The noise is measured, not assumed: the largest ratio between one model's median
    single-sample latencies on the runs given (``metrics`` and each of ``peers``: the
    other presets of one benchmark, timed on the same machine), and at least each
    model's p90 / median ratio within a run. Latencies are *resolved* when the
    competitors' spread (slowest / fastest) exceeds that noise; otherwise no figure or
    table may rank models on latency.

    Returns
    -------
    dict or None
        ``noise`` (ratio), ``spread`` (ratio), ``resolved`` (bool), ``low``/``high``
        (fastest and slowest median latency) [ms] and ``text`` (a sentence); None
        without latencies.

    Examples
    --------
    >>> a = pd.DataFrame({"model": ["ebl", "pls"], "latency_single_ms": [0.1, 0.06]})
    >>> b = pd.DataFrame({"model": ["ebl", "pls"], "latency_single_ms": [0.04, 0.05]})
    >>> r = latency_resolution(a, [b]); round(r["noise"], 1), r["resolved"]
    (2.5, False)
    """
    def lat(m: pd.DataFrame, col: str = "latency_single_ms") -> pd.Series:
        if col not in m.columns:
            return pd.Series(dtype=float)
        s = pd.to_numeric(m.drop_duplicates("model").set_index("model")[col], errors="coerce")
        return s[[x for x in s.index if x in set(competitors(s.index))]].dropna()

    own = lat(metrics)
    own = own[own > 0]
    if len(own) < 2:
        return None
    ratios = [float((lat(metrics, "latency_single_p90_ms") / own).max())] \
        if "latency_single_p90_ms" in metrics.columns else []
    for peer in peers:
        other = lat(peer).reindex(own.index)
        ok = other.notna() & (other > 0)
        if ok.any():
            r = np.maximum(own[ok] / other[ok], other[ok] / own[ok])
            ratios.append(float(r.max()))
    noise = max([x for x in ratios if np.isfinite(x)] or [1.0])
    spread = float(own.max() / own.min())
    resolved = spread > noise
    across = " between this benchmark's presets" if peers else " (p90 / median)"
    text = (f"Latency: median single-sample prediction time on the benchmark's machine; "
            f"the competitors span {format_number(own.min(), 3)}–{format_number(own.max(), 3)} ms "
            f"({format_number(spread)}×) and the same model's timing varies up to "
            f"{format_number(noise)}×{across}. ")
    text += ("The differences exceed that noise." if resolved else
             "The differences are inside that noise, so no table or figure here ranks the "
             "models on latency (Python call overhead, not the models' arithmetic).")
    return {"noise": noise, "spread": spread, "resolved": resolved,
            "low": float(own.min()), "high": float(own.max()), "text": text}
