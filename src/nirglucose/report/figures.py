"""Per-figure inputs computed from a benchmark results directory, and the figures.

This is the computing half of the report: it reads what ``nirglucose benchmark``
wrote (:func:`load_results`), computes what each figure shows (correlations, zone
percentages, Bland–Altman limits and their confidence intervals, regression lines,
normalised scores, Pareto fronts) with :mod:`nirglucose.metrics` and numpy, and hands
plain numbers to :mod:`nirglucose.plots` (:func:`render_figures`).

Required inputs: ``metrics.csv`` (or ``metrics.json``) and ``predictions.parquet``.
Everything else (``meta.json``, ``table.md``, ``comparisons.csv``, ``histories.json``,
``importance.csv``, ``dataset.parquet``) is optional; what is missing is listed in
:attr:`Results.notes` and the figures that need it say so instead of drawing nothing.
"""

from __future__ import annotations

import json
import logging
import math
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Final

import numpy as np
import pandas as pd

from ..exceptions import DataError

__all__ = [
    "REQUIRED_METRIC_COLUMNS",
    "REQUIRED_PREDICTION_COLUMNS",
    "PHYSICS_DEPTH",
    "REFERENCE_ROWS",
    "competitors",
    "is_ablation_row",
    "reference_values",
    "pooled",
    "PHYSICS_DEPTH_LABELS",
    "NOISE_LAYER",
    "RADAR_AXES",
    "RADAR_COST_DECADES",
    "Results",
    "RenderedFigure",
    "load_results",
    "model_order",
    "first_repeat",
    "scored_column",
    "channel_correlations",
    "error_grid_inputs",
    "bland_altman_inputs",
    "linearity_inputs",
    "radar_scores",
    "pareto_front",
    "combined_cost_index",
    "efficiency_table",
    "physics_depth_table",
    "importance_matrix",
    "forest_table",
    "pipeline_columns",
    "environment_panels",
    "physiology_panels",
    "render_figures",
    "ARCHITECTURE_MODELS",
    "fitted_architectures",
    "feature_categories",
    "ebl_feature_table",
    "performance_table",
]

logger = logging.getLogger(__name__)

#: Columns ``metrics.csv`` must have.
REQUIRED_METRIC_COLUMNS: Final = ("model", "rmse_mgdl")
#: Columns ``predictions.parquet`` must have.
REQUIRED_PREDICTION_COLUMNS: Final = ("model", "reference_mgdl", "predicted_mgdl")

#: Physics depth of each registered model: how much of the forward model it uses, as
#: an ordinal level (figure 9). A presentation choice, documented here.
PHYSICS_DEPTH: Final[dict[str, int]] = {
    "sdnn": 0,
    "pls": 0,
    "gp": 0,
    "gbr": 0,
    "original-pinn": 1,
    "optimized-pinn": 1,
    "selective-rte-pinn": 2,
    "rte-pinn": 3,
    "ebl": 4,
    "oracle": 5,
}
#: Rows that are references, not competitors: drawn as horizontal lines in figures 9-10
#: and left out of the radar and the Pareto fronts (the oracle is a bound, the training
#: mean is no skill).
REFERENCE_ROWS: Final = ("oracle", "mean")

#: Tick labels of the physics-depth levels.
PHYSICS_DEPTH_LABELS: Final[dict[int, str]] = {
    0: "none\n(data-driven)",
    1: "Beer–Lambert\nloss term",
    2: "RTE loss\n(2 λ)",
    3: "RTE loss\n(all λ)",
    4: "Beer–Lambert\nfeatures",
}

#: Simulator layer in which each noise source acts (for the pipeline diagram).
NOISE_LAYER: Final[dict[str, str]] = {
    "ambient_light": "environment",
    "humidity_coupling": "environment",
    "pulsation": "physiology",
    "contact_pressure": "contact",
    "led_thermal_drift": "hardware",
    "led_ageing": "hardware",
    "led_flicker": "hardware",
    "led_wavelength_shift": "hardware",
    "dark_current": "hardware",
    "shot": "hardware",
    "johnson": "hardware",
    "adc_inl": "hardware",
    "adc_offset_drift": "hardware",
    "pmf_measurement": "measurement",
}

#: Axes of the radar chart: (label, metrics column, higher is better, log scale).
RADAR_AXES: Final[tuple[tuple[str, str, bool, bool], ...]] = (
    ("RMSE", "rmse_mgdl", False, False),
    ("MARD", "mard_pct", False, False),
    ("Clarke A", "clarke_a_pct", True, False),
    ("±15 %", "within15_pct", True, False),
    ("parameters", "n_parameters", False, True),
    ("latency", "latency_single_ms", False, True),
)

_OPTIONAL_FILES: Final = {
    "meta.json": "run metadata (taken from metrics.json where present)",
    "table.md": "the benchmark's table and significance statements",
    "comparisons.csv": "paired model comparisons",
    "histories.json": "training histories (figure 7)",
    "importance.csv": "permutation importance (figure 11)",
    "dataset.parquet": "the simulated dataset (figure 1)",
}


@dataclass
class Results:
    """What a benchmark results directory holds, loaded.

    Attributes
    ----------
    directory : pathlib.Path
        The results directory.
    metrics : pandas.DataFrame
        One row per model (``metrics.csv``).
    predictions : pandas.DataFrame
        Out-of-fold predictions (``predictions.parquet``).
    meta : dict
        Run metadata (``meta.json``, else the ``meta`` of ``metrics.json``).
    table_md : str or None
        ``table.md`` text.
    comparisons : pandas.DataFrame or None
        ``comparisons.csv``.
    histories : dict of str to pandas.DataFrame, or None
        Per-epoch histories of the networks (models with an empty history left out);
        None when ``histories.json`` is absent.
    importance : pandas.DataFrame or None
        ``importance.csv``.
    dataset : nirglucose.Dataset or None
        ``dataset.parquet``.
    notes : list of str
        What is missing or was adapted, in words, for the page.
    """

    directory: Path
    metrics: pd.DataFrame
    predictions: pd.DataFrame
    meta: dict[str, Any] = field(default_factory=dict)
    table_md: str | None = None
    comparisons: pd.DataFrame | None = None
    histories: dict[str, pd.DataFrame] | None = None
    importance: pd.DataFrame | None = None
    dataset: Any = None
    notes: list[str] = field(default_factory=list)

    @property
    def models(self) -> list[str]:
        """Models in display order (:func:`model_order`)."""
        return model_order(self.metrics["model"])

    @property
    def config(self):
        """The resolved scenario configuration (dataset's, else the metadata's), or None."""
        if self.dataset is not None and getattr(self.dataset, "config", None) is not None:
            return self.dataset.config
        cfg = self.meta.get("config")
        if isinstance(cfg, str):
            try:
                cfg = json.loads(cfg)
            except json.JSONDecodeError:
                return None
        if isinstance(cfg, dict):
            from ..config import ScenarioConfig

            try:
                return ScenarioConfig.model_validate(cfg)
            except ValueError:
                logger.warning("meta config does not validate as a ScenarioConfig")
        return None


@dataclass
class RenderedFigure:
    """One figure of the report.

    Attributes
    ----------
    key : str
        Stable identifier (HTML anchor, file stem).
    number : str
        Figure number as printed (``"1a"``, ``"12"``).
    title : str
        Short title.
    caption : str
        One sentence stating what the figure shows.
    png : bytes
        The figure as PNG (embedded in the page).
    files : list of pathlib.Path
        PNG/SVG files written, if a figure directory was given.
    note : str or None
        Why the figure is reduced or missing, when it is.
    """

    key: str
    number: str
    title: str
    caption: str
    png: bytes = b""
    files: list[Path] = field(default_factory=list)
    note: str | None = None


# --------------------------------------------------------------------------- loading


def _read_json(path: Path) -> Any:
    try:
        return json.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise DataError(f"{path.name} in {str(path.parent)!r} is not valid JSON: {exc}") from exc


def _read_csv(path: Path) -> pd.DataFrame:
    try:
        if path.stat().st_size == 0 or not path.read_text(encoding="utf-8").strip():
            return pd.DataFrame()  # e.g. no comparisons in a one-model run
        return pd.read_csv(path)
    except (OSError, ValueError, pd.errors.ParserError) as exc:
        raise DataError(
            f"{path.name} in {str(path.parent)!r} is not a readable CSV: {exc}") from exc


def _require_columns(frame: pd.DataFrame, required: Iterable[str], what: str) -> None:
    missing = [c for c in required if c not in frame.columns]
    if missing:
        raise DataError(f"{what} lacks column(s) {missing}; it has {list(frame.columns)}")


def load_results(results_dir: str | Path) -> Results:
    """Load a benchmark results directory.

    Parameters
    ----------
    results_dir : str or path
        Directory written by ``nirglucose benchmark --out``.

    Returns
    -------
    Results

    Raises
    ------
    DataError
        If the directory is missing, or lacks ``metrics.csv``/``metrics.json`` or
        ``predictions.parquet``, or one of them is unreadable or lacks required columns.
    """
    d = Path(results_dir)
    if not d.is_dir():
        raise DataError(f"results directory {str(d)!r} does not exist; run `nirglucose "
                        f"benchmark --out {d}` first")
    notes: list[str] = []
    meta: dict[str, Any] = {}
    metrics: pd.DataFrame | None = None
    if (d / "metrics.json").is_file():
        data = _read_json(d / "metrics.json")
        if isinstance(data, dict):
            meta = dict(data.get("meta") or {})
            if isinstance(data.get("metrics"), list):
                metrics = pd.DataFrame(data["metrics"])
        elif isinstance(data, list):
            metrics = pd.DataFrame(data)
    if (d / "metrics.csv").is_file():
        metrics = _read_csv(d / "metrics.csv")
    if metrics is None:
        raise DataError(f"results directory {str(d)!r} is incomplete: no metrics.csv or "
                        f"metrics.json (rerun `nirglucose benchmark --out {d}`)")
    _require_columns(metrics, REQUIRED_METRIC_COLUMNS, "metrics.csv")
    if metrics.empty:
        raise DataError(f"metrics.csv in {str(d)!r} has no rows")
    metrics = metrics.assign(model=metrics["model"].astype(str))

    pred_path = d / "predictions.parquet"
    if not pred_path.is_file():
        raise DataError(f"results directory {str(d)!r} is incomplete: no predictions.parquet "
                        f"(rerun `nirglucose benchmark --out {d}`)")
    try:
        predictions = pd.read_parquet(pred_path)
    except (OSError, ValueError) as exc:
        raise DataError(f"predictions.parquet in {str(d)!r} is unreadable: {exc}") from exc
    _require_columns(predictions, REQUIRED_PREDICTION_COLUMNS, "predictions.parquet")
    predictions = predictions.assign(model=predictions["model"].astype(str))

    if (d / "meta.json").is_file():
        doc = _read_json(d / "meta.json") or {}
        if not isinstance(doc, dict):  # issue 20: one line, not a TypeError
            raise DataError(f"meta.json in {str(d)!r} must hold an object, not a list or value")
        meta = {**meta, **doc}
    elif not meta:
        notes.append("No run metadata (meta.json, or meta in metrics.json): configuration, "
                     "seed, dataset hash and version are unknown.")

    res = Results(directory=d, metrics=metrics, predictions=predictions, meta=meta, notes=notes)
    if (d / "table.md").is_file():
        res.table_md = (d / "table.md").read_text(encoding="utf-8")
    else:
        notes.append("No table.md: the significance statements are derived from "
                     "comparisons.csv.")
    if (d / "comparisons.csv").is_file():
        res.comparisons = _read_csv(d / "comparisons.csv")
    else:
        notes.append("No comparisons.csv: no paired model comparisons to report.")
    if (d / "histories.json").is_file():
        raw = _read_json(d / "histories.json")
        if raw is not None and not isinstance(raw, dict):  # issue 20
            raise DataError(f"histories.json in {str(d)!r} must map model names to lists")
        res.histories = {
            str(m): pd.DataFrame(h) for m, h in (raw or {}).items()
            if isinstance(h, list) and h
        }
    else:
        notes.append("No histories.json: the training-dynamics figure is left out.")
    if (d / "importance.csv").is_file():
        imp = _read_csv(d / "importance.csv")
        _require_columns(imp, ("model", "wavelength_nm", "rmse_increase_mgdl"), "importance.csv")
        res.importance = imp
    else:
        notes.append("No importance.csv: the wavelength-utilisation figure is left out.")
    if (d / "dataset.parquet").is_file():
        from ..dataset import load_dataset

        res.dataset = load_dataset(d / "dataset.parquet")
    else:
        notes.append("No dataset.parquet: the data-characteristics figures are left out.")
    missing_pred = sorted(set(metrics["model"]) - set(predictions["model"]))
    if missing_pred:
        notes.append(f"No predictions for {', '.join(missing_pred)}: they are left out of the "
                     f"per-prediction figures (3-6).")
    return res


# --------------------------------------------------------------------------- helpers

#: Model families of the architecture figure, in the study's order.
ARCHITECTURE_MODELS: Final = ("ebl", "original-pinn", "optimized-pinn", "rte-pinn",
                              "selective-rte-pinn", "sdnn")


def _module_blocks(module) -> list[tuple[str, str]]:
    """Blocks of a fitted torch module: each top-level child with its layer widths."""
    import torch.nn as nn

    inner = getattr(module, "inner", module)
    blocks: list[tuple[str, str]] = []
    for name, child in inner.named_children():
        if isinstance(child, nn.MultiheadAttention):
            blocks.append((name, f"attention {child.embed_dim}-d, {child.num_heads} head(s)"))
            continue
        linears = [m for m in child.modules() if isinstance(m, nn.Linear)]
        if not linears:
            continue  # norms, dropout: no widths to show
        widths = [linears[0].in_features] + [m.out_features for m in linears]
        drop = [m.p for m in child.modules() if isinstance(m, nn.Dropout) and m.p > 0]
        blocks.append((name, "→".join(str(w) for w in widths)
                       + (f", dropout {drop[0]:g}" if drop else "")))
    return blocks


def fitted_architectures(dataset, preset: str | None,
                         models: Sequence[str] = ARCHITECTURE_MODELS
                         ) -> dict[str, tuple[list[tuple[str, str]], int]]:
    """Layer sizes of each model family, read from models fitted for one epoch.

    Each model is built with the run's tuned parameters
    (:func:`nirglucose.models.tuned_params`) and fitted on ``dataset`` for one epoch
    (the sizes do not depend on training), so the diagram shows the widths that ran.
    """
    from ..models import make_model, tuned_params

    out: dict[str, tuple[list[tuple[str, str]], int]] = {}
    for name in models:
        params = dict(tuned_params(name, preset)) if preset else {}
        if name != "ebl":
            params["max_epochs"] = 1
        m = make_model(name, **params).fit(dataset)
        schema = m.schema_
        n_a, n_p = len(schema.labels), len(schema.physiology)
        if name == "ebl":
            blocks = [("inputs", f"{n_a} absorbances + {n_p} physiology"),
                      ("features", f"{len(m.table_)} engineered (Beer–Lambert)"),
                      ("standardise", f"{len(m.table_)}"),
                      ("ridge", f"{len(m.table_)}→1, α = {m.alpha_:.0e}"),
                      ("output", "glucose [mg/dL]")]
        else:
            blocks = [("inputs", f"{n_a} absorbances + {n_p} physiology")] \
                + _module_blocks(m.module_) \
                + [("output", "glucose [mg/dL]")]
        out[name] = (blocks, int(m.n_parameters))
    return out


def ebl_feature_table(dataset, preset: str | None) -> tuple[tuple, int, int]:
    """The Enhanced Beer–Lambert features of ``dataset``'s device, from a fitted model.

    Returns
    -------
    tuple
        (feature table of :func:`nirglucose.features.feature_table`, LED channels,
        physiological entries).
    """
    from ..models import make_model, tuned_params

    m = make_model("ebl", **(tuned_params("ebl", preset) if preset else {})).fit(dataset)
    return tuple(m.table_), len(m.schema_.labels), len(m.schema_.physiology)


#: What each feature operation (:attr:`nirglucose.features.FeatureSpec.op`) reads.
_OP_SOURCE: Final = {"A": "absorbance", "lin": "absorbance", "AA": "absorbance",
                     "w": "both", "envA": "both", "pmf": "physiology", "env2": "physiology"}


def feature_categories(table) -> tuple[dict[str, list[str]], dict[str, str]]:
    """Feature names by category (table order), and what each category is computed from.

    The source is ``"absorbance"``, ``"physiology"`` or ``"both"``, from the operations
    of the category's features (``"both"`` when unknown or mixed).
    """
    cats: dict[str, list[str]] = {}
    src: dict[str, set[str]] = {}
    for spec in table:
        cats.setdefault(spec.category, []).append(spec.name)
        op = spec.op[0] if spec.op else None
        src.setdefault(spec.category, set()).add(_OP_SOURCE.get(op, "both"))
    return cats, {c: next(iter(s)) if len(s) == 1 else "both" for c, s in src.items()}


def performance_table(metrics_by_preset: Mapping[str, pd.DataFrame],
                      models: Sequence[str]) -> pd.DataFrame:
    """Long table of the performance panel: one row per preset and model."""
    cols = ("rmse_mgdl", "rmse_ci_low", "rmse_ci_high", "mard_pct", "n_parameters",
            "latency_single_ms")
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
    from ..plots.style import MODEL_COLORS

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


def _finite_pairs(p: pd.DataFrame, col: str) -> tuple[np.ndarray, np.ndarray, int]:
    ref = p["reference_mgdl"].to_numpy(float)
    pred = p[col].to_numpy(float)
    ok = np.isfinite(ref) & np.isfinite(pred) & (ref > 0)
    return ref[ok], pred[ok], int(np.count_nonzero(~ok))


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
    from ..metrics import clarke_zones, parkes_zones, zone_percentages

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

    The intervals are the approximate ones of Bland & Altman (1986): standard error
    ``s / sqrt(n)`` for the bias and ``s sqrt(3 / n)`` for each limit, with a t quantile
    on ``n - 1`` degrees of freedom. Pairs from the same subject are treated as
    independent, so the intervals are somewhat narrow.

    References
    ----------
    .. [1] Bland JM, Altman DG. Statistical methods for assessing agreement between two
       methods of clinical measurement. Lancet 327(8476):307-310, 1986.
       doi:10.1016/S0140-6736(86)90837-8
    """
    from ..metrics import bland_altman

    col = scored_column(predictions)
    out: dict[str, dict[str, Any]] = {}
    for m in models:
        ref, pred, _ = _finite_pairs(pooled(predictions, m), col)
        n = ref.size
        if n < 3:
            continue
        bias, low, high = bland_altman(ref, pred)
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


def linearity_inputs(predictions: pd.DataFrame, models: Sequence[str], *,
                     level: float = 0.95) -> dict[str, dict[str, Any]]:
    """Least-squares line of predicted on reference glucose, its slope CI and R².

    When the predictions carry ``lower90_mgdl``/``upper90_mgdl`` (the benchmark's
    prediction intervals), each panel also gets ``lower`` and ``upper``.
    """
    col = scored_column(predictions)
    out: dict[str, dict[str, Any]] = {}
    for m in models:
        ref, pred, _ = _finite_pairs(pooled(predictions, m), col)
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
        p = pooled(predictions, m)
        if {"lower90_mgdl", "upper90_mgdl"} <= set(p.columns):
            r_all = p["reference_mgdl"].to_numpy(float)
            lo = p["lower90_mgdl"].to_numpy(float)
            hi = p["upper90_mgdl"].to_numpy(float)
            ok = (np.isfinite(r_all) & np.isfinite(p[col].to_numpy(float)) & (r_all > 0)
                  & np.isfinite(lo) & np.isfinite(hi))
            if ok.sum() == n:  # the same rows as the points
                out[m].update(lower=lo[ok], upper=hi[ok])
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
    (parameters, latency) lose ``1 / RADAR_COST_DECADES`` per decade above the
    cheapest model: ``1 - log10(x / best) / 6``, floored at 0 (parameter counts below 1
    and latencies below 1 µs count as 1 and 1 µs). A missing value is NaN.

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
        floor = 1.0 if col == "n_parameters" else 1e-3  # 0 parameters scores as 1
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


def combined_cost_index(n_parameters: Sequence[float], latency_ms: Sequence[float]
                        ) -> np.ndarray:
    """Mean of the min–max normalised log10 parameter count and log10 latency.

    0 is the smallest and fastest model of the set, 1 the largest and slowest (counts
    below 1 parameter and latencies below 1 µs are taken as 1 and 1 µs).

    Examples
    --------
    >>> combined_cost_index([10, 1000], [0.01, 1.0]).tolist()
    [0.0, 1.0]
    """
    parts = []
    for v, floor in ((n_parameters, 1.0), (latency_ms, 1e-3)):
        x = np.log10(np.maximum(np.asarray(v, dtype=float), floor))
        finite = x[np.isfinite(x)]
        if finite.size and np.ptp(finite) > 0:
            parts.append((x - finite.min()) / np.ptp(finite))
        else:
            parts.append(np.where(np.isfinite(x), 0.0, np.nan))
    return np.nanmean(np.vstack(parts), axis=0) if parts else np.array([])


def efficiency_table(metrics: pd.DataFrame, models: Sequence[str]) -> pd.DataFrame:
    """Inputs of figure 10: costs, the combined index and the three Pareto fronts.

    Only competitors (:func:`competitors`); the references are drawn as lines.
    """
    models = competitors(models)
    t = pd.DataFrame({
        "model": list(models),
        "rmse_mgdl": _metric(metrics, models, "rmse_mgdl"),
        "n_parameters": _metric(metrics, models, "n_parameters"),
        "latency_single_ms": _metric(metrics, models, "latency_single_ms"),
    })
    t["combined_index"] = combined_cost_index(t["n_parameters"], t["latency_single_ms"])
    for col, front, log in (("n_parameters", "front_parameters", True),
                            ("latency_single_ms", "front_latency", True),
                            ("combined_index", "front_combined", False)):
        cost = t[col].to_numpy(float)
        if log:  # a log axis cannot show zero cost: the front is among what is drawn
            cost = np.where(cost > 0, cost, np.nan)
        t[front] = pareto_front(cost, t["rmse_mgdl"])
    return t


def is_ablation_row(model: str) -> bool:
    """Whether ``model`` is an ablation row (``<pinn>/no-physics``), shown in its own table."""
    return "/" in str(model)


def competitors(models: Iterable[str]) -> list[str]:
    """Models that compete: neither a reference row (:data:`REFERENCE_ROWS`) nor an ablation."""
    return [m for m in models if m not in REFERENCE_ROWS and not is_ablation_row(m)]


def reference_values(metrics: pd.DataFrame, models: Sequence[str]) -> dict[str, float]:
    """RMSE of the reference rows present (oracle bound, no-skill mean). [mg/dL]"""
    refs = [m for m in REFERENCE_ROWS if m in models]
    return {m: float(v) for m, v in zip(refs, _metric(metrics, refs, "rmse_mgdl"), strict=True)
            if np.isfinite(v)}


def physics_depth_table(metrics: pd.DataFrame, models: Sequence[str]) -> tuple[pd.DataFrame,
                                                                                list[str]]:
    """Inputs of figure 9 and the models left out (no known physics depth).

    Reference rows (:data:`REFERENCE_ROWS`) and ablation rows are not competitors and
    are neither drawn as bubbles nor listed as left out.
    """
    models = competitors(models)
    known = [m for m in models if m in PHYSICS_DEPTH]
    t = pd.DataFrame({
        "model": known,
        "physics_depth": [PHYSICS_DEPTH[m] for m in known],
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


def importance_matrix(importance: pd.DataFrame, models: Sequence[str]) -> pd.DataFrame:
    """Models × wavelengths matrix of the mean RMSE increase (rows in display order).

    Ablation rows (``<pinn>/no-physics``) are left out; they have their own table.
    """
    mat = importance.pivot_table(index="model", columns="wavelength_nm",
                                 values="rmse_increase_mgdl", aggfunc="mean")
    rows = [m for m in models if m in mat.index] + [m for m in mat.index if m not in models
                                                     and not is_ablation_row(m)]
    return mat.reindex(rows).sort_index(axis=1)


def _study_rows() -> dict[str, dict[str, Any]]:
    from ..evaluation.reference import STUDY_TABLE

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


def _fmt_range(v: Sequence[float], unit: str) -> str:
    return f"{v[0]:g}–{v[1]:g} {unit}"


def pipeline_columns(config) -> list[list[dict[str, Any]]]:
    """Boxes of the pipeline diagram (figure 2), from a resolved ScenarioConfig.

    Each box lists settings of its layer and the noise sources acting in it
    (:data:`NOISE_LAYER`), on (with their effective factor, enabled × scale ×
    ``noise_scale``) or off.
    """
    from ..config import NOISE_SOURCES

    noise: dict[str, tuple[list[str], list[str]]] = {}
    for src in NOISE_SOURCES:
        layer = NOISE_LAYER.get(src, "hardware")
        on, off = noise.setdefault(layer, ([], []))
        f = config.noise_factor(src)
        (on if f > 0 else off).append(f"{src.replace('_', ' ')}" + (f" ×{f:g}" if f > 0 and f != 1
                                                                       else ""))

    def box(title: str, layers: Sequence[str], details: list[str], kind: str) -> dict[str, Any]:
        on = [s for layer in layers for s in noise.get(layer, ([], []))[0]]
        off = [s for layer in layers for s in noise.get(layer, ([], []))[1]]
        return {"title": title, "details": details, "noise_on": on, "noise_off": off,
                "kind": kind}

    env, phys, glu, hw, opt = (config.environment, config.physiology, config.glucose,
                               config.hardware, config.optics)
    wl = ", ".join(f"{w:g}" for w in config.leds.wavelengths_nm)
    status = [f"  {k} {v:.0%}" for k, v in glu.status_probs.items()]
    return [
        [
            box("Environment", ("environment",), [
                f"ambient {_fmt_range(env.temperature_c, '°C')}",
                f"RH {_fmt_range(env.humidity_pct, '%')}",
                f"light {_fmt_range(env.ambient_lux, 'lx')}",
            ], "input"),
            box("Glucose", (), [
                f"signal gain ×{glu.signal_gain:g}",
                "diabetes status mix:",
                *status,
            ], "input"),
            box("Physiology + contact", ("physiology", "contact"), [
                f"age {_fmt_range(phys.age_yr, 'yr')}",
                f"variation scale ×{phys.variation_scale:g}",
                f"coupling SD {config.contact.coupling_sd:g}",
            ], "input"),
        ],
        [
            box(f"Optics: {opt.model}", (), [
                f"LEDs {wl} nm",
                f"source–detector {opt.source_detector_mm:g} mm",
                f"water spectrum: {opt.water_source}",
                "μa: water, Hb, HbO2, lipid, melanin, glucose; μs′: power law, "
                "lowered by glucose",
            ], "optics"),
        ],
        [
            box("Hardware", ("hardware",), [
                f"LED power {', '.join(f'{p:g}' for p in config.leds.power_mw)} mW",
                f"TIA gain {hw.tia_gain_ohm:.0e} Ω",
                f"ADC {hw.adc_bits} bit, {hw.adc_vref_v:g} V",
            ], "hardware"),
        ],
        [
            box("Measured outputs", ("measurement",), _measured_lines(config), "output"),
        ],
    ]


def _measured_lines(config) -> list[str]:
    """What the device records and knows, from its capabilities (``device.*``)."""
    from ..config import device_capabilities
    from ..simulate.measurement import PMF_COLUMNS, PPG_COLUMNS

    caps = device_capabilities(config)
    n_phys = len(PMF_COLUMNS) + (len(PPG_COLUMNS) if "ppg_perfusion_spo2" in caps else 0)
    ref = ("monitor photodiode, per reading" if "monitor_photodiode" in caps
           else "start-up reference")
    how = "exact" if "exact_physiology" in caps else "measured"
    lines = ["adc_<nm>: codes per LED", f"adc_ref_<nm>: {ref}",
             f"physiological vector ({n_phys} {how} values)"]
    if caps:
        lines += ["device capabilities:", *(f"  {c.replace('_', ' ')}" for c in caps)]
    return lines


def _panel(frame: pd.DataFrame, cols: Sequence[str], xlabel: str, log: bool = False
           ) -> dict[str, Any] | None:
    for c in cols:
        if c in frame.columns:
            return {"values": frame[c].to_numpy(float), "xlabel": xlabel, "log": log}
    return None


def environment_panels(frame: pd.DataFrame) -> list[dict[str, Any]]:
    """Panels of the environment figure (true ambient conditions where recorded)."""
    panels = [
        _panel(frame, ["true_ambient_temperature_c"], "ambient temperature [°C]"),
        _panel(frame, ["true_humidity_pct", "humidity_pct"], "relative humidity [%]"),
        _panel(frame, ["true_pressure_mbar", "pressure_mbar"], "barometric pressure [mbar]"),
        _panel(frame, ["true_ambient_lux", "ambient_lux"], "ambient illuminance [lx]", log=True),
    ]
    out = [p for p in panels if p is not None]
    if "true_light_source" in frame.columns:
        counts = frame["true_light_source"].astype(str).value_counts()
        out.append({"counts": counts.sort_index(), "xlabel": "ambient light source"})
    return out


_PHYSIOLOGY: Final = (
    ("age_yr", "age [yr]"),
    ("bmi_kgm2", "BMI [kg/m²]"),
    ("melanin_fraction", "melanin [volume fraction]"),
    ("skin_thickness_mm", "skin thickness [mm]"),
    ("hydration_pct", "hydration [% of nominal]"),
    ("systolic_bp_mmhg", "systolic BP [mmHg]"),
    ("heart_rate_bpm", "heart rate [1/min]"),
    ("resp_rate_bpm", "respiration rate [1/min]"),
    ("skin_temp_c", "skin temperature [°C]"),
)


def physiology_panels(frame: pd.DataFrame) -> list[dict[str, Any]]:
    """Panels of the physiology figure (the measured physiological vector)."""
    out: list[dict[str, Any]] = []
    if "fitzpatrick_type" in frame.columns:
        counts = frame["fitzpatrick_type"].astype(int).value_counts().sort_index()
        out.append({"counts": {f"{k}": int(v) for k, v in counts.items()},
                    "xlabel": "Fitzpatrick skin type [I–VI as 1–6]"})
    for col, label in _PHYSIOLOGY:
        p = _panel(frame, [col], label)
        if p is not None:
            out.append(p)
    return out


# --------------------------------------------------------------------------- rendering


def _adc_by_wavelength(frame: pd.DataFrame, wavelengths: Sequence[float]
                       ) -> dict[float, np.ndarray]:
    out = {}
    for w in wavelengths:
        col = f"adc_{w:g}"
        if col in frame.columns:
            out[float(w)] = frame[col].to_numpy(float)
    return out


@dataclass
class _Page:
    """What every section builder of :func:`render_figures` reads, and the figures so far.

    ``add`` numbers every figure in page order (so the contents and the captions
    agree), draws the wanted ones and keeps them in :attr:`rendered`.
    """

    results: Results
    out_dir: Path | None
    formats: Sequence[str]
    wanted: set[str] | None
    compare: Mapping[str, pd.DataFrame] | None
    rendered: list[RenderedFigure] = field(default_factory=list)
    count: int = 0

    @property
    def models(self) -> list[str]:
        return self.results.models

    @property
    def preds(self) -> pd.DataFrame:
        return self.results.predictions

    @property
    def pred_models(self) -> list[str]:
        have = set(self.preds["model"])
        return [m for m in self.models if m in have and not is_ablation_row(m)]

    @property
    def user_data(self) -> bool:
        """A user's measurements: no simulation configuration and no preset recorded."""
        return self.results.config is None and not self.results.meta.get("preset")

    @property
    def rep_note(self) -> str:
        p = self.preds
        n_rep = int(p["repeat"].nunique()) if "repeat" in p.columns else 1
        return (f"every out-of-fold prediction of all {n_rep} repeats pooled, so the zone "
                f"shares equal the table's" if n_rep > 1 else "every out-of-fold prediction")

    def wants(self, *keys: str) -> bool:
        """Whether any of ``keys`` is to be drawn."""
        return self.wanted is None or bool(self.wanted & set(keys))

    def add(self, key: str, title: str, caption: str, build: Callable[[], Any] | None,
            note: str | None = None) -> None:
        """Number the next figure; draw it (``build``) if it is wanted."""
        from ..plots.style import figure_bytes, save_figure

        self.count += 1
        number = str(self.count)
        if not self.wants(key):
            return
        out = RenderedFigure(key=key, number=number, title=title, caption=caption, note=note)
        fig = None
        if build is not None:
            try:
                fig = build()
            except (ValueError, KeyError, TypeError, IndexError) as exc:
                logger.exception("figure %s could not be drawn", number)
                out.note = f"Figure {number} could not be drawn: {exc}"
        if fig is not None:
            out.png = figure_bytes(fig, "png")
            if self.out_dir is not None:
                out.files = save_figure(fig, self.out_dir / f"fig{number}_{key}", self.formats)
            else:
                fig.clear()
        self.rendered.append(out)


def _section_data(page: _Page) -> None:
    """Figures 1a-1c: glucose and the NIR signal, environment, physiology."""
    from ..plots import data

    ds = page.results.dataset
    if ds is None:
        for key, title in (("data", "Glucose and NIR signal"), ("environment", "Environment"),
                           ("physiology", "Physiology")):
            page.add(key, title, "Characteristics of the simulated data.", None,
                     note="No dataset.parquet in the results directory: figure not drawn.")
        return
    what = "measured" if page.user_data else "simulated"
    frame = ds.frame
    adc = _adc_by_wavelength(frame, [float(w) for w in ds.wavelengths_nm])
    g = frame["glucose_mgdl"].to_numpy(float)
    corr = channel_correlations(g, adc)
    corr_txt = ", ".join(f"{w:g} nm r = {r:+.2f}" for w, r in corr.items())
    by_status = ("by diabetes status (left)" if "diabetes_status" in frame
                 else "(left; the diabetes status is not recorded)")
    page.add("data", "Glucose and NIR signal",
             f"Reference glucose of the {len(frame)} {what} snapshots {by_status} and the "
             f"log ADC code of each LED channel against glucose, with the Pearson "
             f"correlation ({corr_txt}).",
             lambda: data.figure_data_characteristics(
                 g, frame["diabetes_status"].astype(str).to_numpy()
                 if "diabetes_status" in frame else np.full(len(frame), "unknown"),
                 {w: np.log(v) for w, v in adc.items()}, corr))
    env = environment_panels(frame)
    if env:  # a user's data may record no ambient conditions: promise no panels
        page.add("environment", "Environment",
                 f"Distributions of the ambient conditions of the {what} snapshots "
                 "(temperature, humidity, pressure, illuminance and light source, where "
                 "recorded).",
                 lambda: data.figure_distributions(env, ncols=5))
    phys = physiology_panels(frame)
    if phys:
        page.add("physiology", "Physiology",
                 "Distributions of the measured physiological vector the models see"
                 + (" (its humidity and pressure entries are shown with the environment)."
                    if env else "."),
                 lambda: data.figure_distributions(phys, ncols=5))


def _section_pipeline(page: _Page) -> None:
    """Figure 2: the simulator's layers."""
    from ..plots import pipeline
    from ..plots.style import plot_style

    cfg = page.results.config
    if page.user_data:
        return  # measured, not simulated: there is no simulator pipeline to draw
    if cfg is None:
        page.add("pipeline", "Data-generation pipeline", "The simulator's layers.", None,
                 note="No resolved configuration in the results: diagram not drawn.")
        return
    n_off = sum(1 for s in NOISE_LAYER if cfg.noise_factor(s) == 0)
    page.add("pipeline", "Data-generation pipeline",
             f"The simulator's layers for this run, left to right in the order applied, with "
             f"the '{cfg.optics.model}' forward model and {len(NOISE_LAYER) - n_off} of "
             f"{len(NOISE_LAYER)} noise sources on (✓ on, with its factor when not ×1; "
             f"✗ off).",
             lambda: _figure_pipeline(pipeline, cfg, plot_style))


def _section_architecture(page: _Page) -> None:
    """The model architectures, from models fitted for one epoch."""
    from ..plots import architecture

    ds = page.results.dataset
    models = page.models
    arch_models = [m for m in ARCHITECTURE_MODELS if m in models] or list(ARCHITECTURE_MODELS)
    archs: dict[str, Any] = {}
    arch_err: str | None = "No dataset.parquet in the results: diagram not drawn."
    if ds is not None and page.wants("architecture", "features"):
        try:
            archs = fitted_architectures(ds, page.results.meta.get("preset"), arch_models)
            arch_err = None
        except (ImportError, ValueError, RuntimeError) as exc:
            archs, arch_err = {}, f"Models could not be built on this dataset: {exc}"
    page.add("architecture", "Model architectures",
             "One block diagram per model family, inputs at the top and glucose at the "
             "bottom; the layer widths (a→b→c: the Linear layers of each block) and parameter "
             "counts are read from each model built with "
             + ("the default parameters" if page.user_data else "this preset's tuned "
                "parameters")
             + " and fitted for one epoch on this run's dataset, so they are the sizes that "
             "ran.",
             (lambda: architecture.figure_architectures(archs)) if archs else None,
             note=arch_err)


def _section_features(page: _Page) -> None:
    """The Enhanced Beer–Lambert feature engineering."""
    from ..plots import architecture

    ds = page.results.dataset
    feat: dict[str, list[str]] = {}
    feat_src: dict[str, str] = {}
    n_ch = n_phys = 0
    if ds is not None and page.wants("features"):
        try:
            table, n_ch, n_phys = ebl_feature_table(ds, page.results.meta.get("preset"))
            feat, feat_src = feature_categories(table)
        except (ImportError, ValueError) as exc:
            logger.warning("feature table not built: %s", exc)
    page.add("features", "Feature engineering",
             f"How the Enhanced Beer–Lambert model turns the {n_ch} raw LED intensities and "
             f"the {n_phys}-entry physiological vector into its "
             f"{sum(len(v) for v in feat.values())} features, by category (count and first "
             "names; the full list is features.feature_table).",
             (lambda: architecture.figure_feature_engineering(
                 n_ch, n_phys, feat, feat_src)) if feat else None,
             note=None if feat else "No dataset.parquet in the results: diagram not drawn.")


def _diabetes_status(page: _Page) -> pd.Series | None:
    """Diabetes status by measurement id, when both the dataset and predictions have ids."""
    ds = page.results.dataset
    if ds is None or "diabetes_status" not in ds.frame or "measurement_id" not in ds.frame \
            or "measurement_id" not in page.preds.columns:
        return None
    return ds.frame.set_index("measurement_id")["diabetes_status"].astype(str)


def _section_grids(page: _Page) -> None:
    """Figures 3-4: the Clarke and Parkes error grids."""
    from ..plots import grids

    preds, pred_models, rep_note = page.preds, page.pred_models, page.rep_note
    n_first = len(pooled(preds, pred_models[0])) if pred_models else 0
    cg, clipped = error_grid_inputs(preds, pred_models, kind="clarke")
    clip_txt = f" ({clipped} negative predictions placed at 0 mg/dL)" if clipped else ""
    page.add("clarke", "Clarke error grids",
             f"Clarke error grid of each model ({rep_note}, n = {n_first} per model)"
             f"{clip_txt}, with the share of points in each zone in the legend.",
             lambda: grids.figure_error_grids(cg, kind="clarke") if cg else None,
             note=None if cg else "No predictions: figure not drawn.")
    status = _diabetes_status(page)
    if status is None:
        pg, _ = error_grid_inputs(preds, pred_models, kind="parkes", diabetes_type=1)
        page.add("parkes", "Parkes error grids",
                 f"Parkes (consensus) error grid for type 1 diabetes of each model "
                 f"({rep_note}); the diabetes status of each snapshot is not recorded here, "
                 f"so the type-1 grid is applied to all.",
                 lambda: grids.figure_error_grids(pg, kind="parkes") if pg else None,
                 note=None if pg else "No predictions: figure not drawn.")
        return
    t2, other = status.index[status == "type2"], status.index[status != "type2"]
    for dtype, ids, who in ((1, other, "type-1, prediabetes and normal"), (2, t2, "type-2")):
        pg, _ = error_grid_inputs(preds, pred_models, kind="parkes", diabetes_type=dtype,
                                  measurement_ids=ids)
        page.add(f"parkes_type{dtype}", f"Parkes error grids, type {dtype}",
                 f"Parkes (consensus) error grid for type {dtype} diabetes, applied to the "
                 f"{len(ids)} {who} snapshots only ({rep_note.split(',')[0]}), with the "
                 f"share of points in each zone in the legend. The table's Parkes A column "
                 f"uses the type-1 grid for every snapshot.",
                 (lambda pg=pg, dtype=dtype: grids.figure_error_grids(
                     pg, kind="parkes", diabetes_type=dtype)) if pg else None,
                 note=None if pg else f"No {who} snapshots: figure not drawn.")


def _section_agreement(page: _Page) -> None:
    """Figures 5-6: Bland–Altman and linearity."""
    from ..plots import agreement

    preds, rep_note = page.preds, page.rep_note
    ba = bland_altman_inputs(preds, page.pred_models)
    page.add("bland_altman", "Bland–Altman",
             f"Prediction minus reference against their mean for each model ({rep_note}), on "
             f"one y range for all panels, with the bias (solid) and 95 % limits of agreement "
             f"(dashed), their values and 95 % confidence intervals (shaded) under each title "
             f"(Bland & Altman 1986).",
             lambda: agreement.figure_bland_altman(ba) if ba else None,
             note=None if ba else "Too few predictions: figure not drawn.")
    lin = linearity_inputs(preds, page.pred_models)
    page.add("linearity", "Linearity",
             f"Predicted against reference glucose for each model ({rep_note}), with the "
             f"unity line and the least-squares line (slope with its 95 % CI, intercept, R²)"
             + ("; vertical bars: each prediction's 90 % interval, with the share that covers "
                "the reference." if {"lower90_mgdl", "upper90_mgdl"} <= set(preds.columns)
                else "."),
             lambda: agreement.figure_linearity(lin) if lin else None,
             note=None if lin else "Too few predictions: figure not drawn.")


def _section_training(page: _Page) -> None:
    """Figure 7: training dynamics of the networks."""
    from ..plots import training

    histories = page.results.histories
    if histories is None:
        page.add("training", "Training dynamics", "Training and validation loss per epoch.",
                 None, note="No histories.json in the results directory: figure not drawn.")
        return
    hist = {m: histories[m] for m in model_order(histories) if not is_ablation_row(m)}
    has_val = any("val_loss" in h and h["val_loss"].notna().any() for h in hist.values())
    caption = ((f"Training (solid){' and validation (dashed)' if has_val else ''} loss per "
                "epoch of each network, thick the total and thin each term of the "
                "physics-informed ones (a term equal to another curve is named in that "
                "curve's legend entry rather than drawn under it). Losses are mean squared "
                "errors of glucose standardised on the training rows, so 1 is the training "
                "mean's loss; physics terms are in their own squared residual units. "
                + ("" if has_val else "These fits used no validation split, so there are no "
                   "validation curves. ")
                + "The physics-ablation refits are left out: their physics weight is 0, so "
                "their total is their MSE.") if hist else
               "No networks in this run, so there are no training curves to show.")
    page.add("training", "Training dynamics", caption,
             lambda: training.figure_training_dynamics(hist),
             note=None if hist else "No networks in this run.")


def _reference_text(refs: Mapping[str, float]) -> str:
    """Caption sentence naming the reference rows drawn as horizontal lines."""
    if not refs:
        return ""
    names = [("oracle (a bound, not a competitor)" if r == "oracle" else
              "training mean (no skill)") for r in refs]
    return (" The " + " and ".join(names)
            + (" are drawn as horizontal reference lines." if len(names) > 1 else
               " is drawn as a horizontal reference line."))


def _section_radar(page: _Page) -> None:
    """Figure 8: normalised scores."""
    from ..plots import tradeoffs

    scores = radar_scores(page.results.metrics, competitors(page.models))
    page.add("radar", "Normalised scores",
             "One panel per model (its polygon in colour, the other models' outlines in grey "
             "for comparison), with its mean score in the title: each model's RMSE, MARD, "
             "Clarke zone A and share within ±15 % as a ratio to the best model shown "
             "(1 = best), and its parameter count and latency scored 1 for the "
             "smallest and fastest, minus 1/6 per decade above it (the oracle, a bound, and "
             "the training mean, no skill, are references rather than competitors and are "
             "left out; so are the ablation rows).",
             lambda: tradeoffs.figure_radar_grid(scores) if len(scores) else None,
             note=None if len(scores) else "No model besides the oracle.")


def _section_costs(page: _Page) -> None:
    """Figures 9-10: accuracy against physics depth and against cost."""
    from ..plots import tradeoffs
    from ..plots.style import plot_style

    metrics, models = page.results.metrics, page.models
    depth, left_out = physics_depth_table(metrics, models)
    refs = reference_values(metrics, models)
    ref_txt = _reference_text(refs)
    lo_txt = f" ({', '.join(left_out)} left out: no physics depth or metrics)" if left_out else ""
    page.add("physics_depth", "Accuracy vs physics depth",
             f"RMSE against how much of the forward model each method uses (the RMSE axis "
             f"starts at 0), bubble area proportional to the trainable parameter count; a "
             f"black ring marks the bubbles on the parameters–RMSE Pareto front."
             f"{ref_txt}{lo_txt}",
             lambda: _figure_one(lambda ax: tradeoffs.plot_physics_depth(
                 depth, depth_labels=PHYSICS_DEPTH_LABELS, references=refs, ax=ax),
                 (11.0, 5.2), plot_style)
             if len(depth) else None,
             note=None if len(depth) else "No model with a known physics depth.")
    eff = efficiency_table(metrics, models)
    page.add("efficiency", "Efficiency landscape",
             "RMSE (axis from 0) against trainable parameters, single-sample latency and a "
             "combined cost index (mean of the normalised log parameters and log latency); "
             "Pareto-optimal models (no other model both cheaper and more accurate) have a "
             f"black edge and are joined by a dashed line.{ref_txt}",
             lambda: tradeoffs.figure_efficiency_landscape(eff, refs))


def _section_performance(page: _Page) -> None:
    """The performance panel: the presets on shared axes."""
    from ..plots import architecture

    res = page.results
    by_preset = dict(page.compare) if page.compare else {
        str(res.meta.get("preset") or "this run"): res.metrics}
    perf_models = [m for m in page.models if not is_ablation_row(m) and m not in REFERENCE_ROWS]
    perf = performance_table(by_preset, perf_models)
    page.add("performance", "Performance comparison",
             "Error metrics (RMSE with its 95 % CI, MARD), trainable parameters and "
             "single-sample latency side by side"
             + (f", one bar per preset ({', '.join(by_preset)}) on shared axes"
                if len(by_preset) > 1 else "")
             + "; parameters and latency on log scales. Latency is the median single-sample "
             "prediction time measured during each run, so it depends on that machine's load.",
             (lambda: architecture.figure_performance_panel(perf)) if len(perf) else None,
             note=None if len(perf) else "No competitor models in this run.")


def _section_wavelengths(page: _Page) -> None:
    """Figure 11: permutation importance of each LED channel."""
    from ..plots import wavelengths as wl_plots
    from ..plots.style import plot_style

    imp = page.results.importance
    if imp is None or not len(imp):
        page.add("wavelengths", "Wavelength utilisation", "Permutation importance per channel.",
                 None, note="No importance.csv in the results directory: figure not drawn.")
        return
    mat = importance_matrix(imp, [m for m in page.models if not is_ablation_row(m)])
    page.add("wavelengths", "Wavelength utilisation",
             "Permutation importance of each LED channel for each model: the rise in "
             "held-out RMSE when that channel's values are shuffled, in mg/dL (the number in "
             "each cell). Colour is relative within each row (the row's largest rise = 1), "
             "so that models whose absolute rises differ by orders of magnitude can be read "
             "alike. A negative value means shuffling that channel made the model slightly "
             "better: the channel carries no usable information for it and the value is "
             "noise of the permutation; a very large one (polynomial features) means the "
             "model extrapolates when a channel leaves its training range.",
             lambda: _figure_one(lambda ax: wl_plots.plot_wavelength_heatmap(mat, ax=ax),
                                 (1.2 * mat.shape[1] + 4.2, 0.45 * mat.shape[0] + 1.6),
                                 plot_style))


def _section_forest(page: _Page) -> None:
    """Figure 12: RMSE with its confidence interval, the study's values beside it."""
    from ..plots import forest
    from ..plots.style import plot_style

    ft = forest_table(page.results.metrics, [m for m in page.models if not is_ablation_row(m)],
                      with_study=not page.user_data)
    page.add("forest", "RMSE with 95 % CI",
             "Each model's RMSE with its 95 % cluster-bootstrap confidence interval"
             + ("." if page.user_data else ", next to the value the study reported from its "
                "single 48-snapshot test set (open diamonds)."),
             lambda: _figure_one(lambda ax: forest.plot_rmse_forest(ft, ax=ax),
                                 (7.0, 0.5 * len(ft) + 1.5), plot_style))


#: The report's figures, section by section in page order (each builder adds its figures).
_SECTIONS: Final[tuple[Callable[[_Page], None], ...]] = (
    _section_data, _section_pipeline, _section_architecture, _section_features,
    _section_grids, _section_agreement, _section_training, _section_radar, _section_costs,
    _section_performance, _section_wavelengths, _section_forest,
)


def render_figures(results: Results, figures_dir: str | Path | None = None,
                   formats: Sequence[str] = ("png", "svg"), *,
                   include: Iterable[str] | None = None,
                   compare: Mapping[str, pd.DataFrame] | None = None) -> list[RenderedFigure]:
    """Build every figure of the report from loaded results.

    Parameters
    ----------
    results : Results
        From :func:`load_results`.
    figures_dir : str or path, optional
        If given, also write each figure there as ``<number>_<key>.<fmt>``; the
        directory is created if its parent exists.
    formats : sequence of str
        File formats written to ``figures_dir``. [-]
    include : iterable of str, optional
        Keys of the figures to render (``"clarke"``, ``"training"``, ...); all by default.
    compare : mapping of str to pandas.DataFrame, optional
        Metrics of each preset of a multi-preset run (the primary first): the
        performance panel then shows every preset on shared axes.

    Returns
    -------
    list of RenderedFigure
        In page order; a figure whose inputs are missing has no PNG and a ``note``.
    """
    out_dir = None
    if figures_dir is not None:
        out_dir = Path(figures_dir)
        if not out_dir.parent.exists():
            raise DataError(f"figure directory's parent {str(out_dir.parent)!r} does not exist")
        out_dir.mkdir(exist_ok=True)
    page = _Page(results=results, out_dir=out_dir, formats=formats,
                 wanted=None if include is None else set(include), compare=compare)
    for section in _SECTIONS:
        section(page)
    return page.rendered


def _figure_one(draw: Callable, figsize: tuple[float, float], plot_style, polar: bool = False):
    from matplotlib.figure import Figure

    from ..plots.labels import place_labels

    with plot_style():
        fig = Figure(figsize=figsize, layout="constrained")
        ax = fig.add_subplot(projection="polar" if polar else None)
        draw(ax)
        place_labels(fig)
    return fig


def _figure_pipeline(pipeline_mod, cfg, plot_style):
    from matplotlib.figure import Figure

    cols = pipeline_columns(cfg)
    with plot_style():
        fig = Figure(figsize=(12.0, pipeline_mod.pipeline_height_in(cols)),
                     layout="constrained")
        pipeline_mod.plot_pipeline(
            cols, ax=fig.add_subplot(),
            title=f"Simulator layers: preset '{cfg.preset}', global noise scale "
                  f"×{cfg.noise_scale:g}")
    return fig
