"""What the benchmark writes: its columns, :class:`BenchmarkResult` and ``table.md``.

The column tuples name every output table of
:func:`~nirglucose.evaluation.benchmark.run_benchmark`; :class:`BenchmarkResult`
holds the tables and writes them (:data:`OUTPUT_FILES`, each atomically);
``table.md`` sets our values (95 % CIs) beside the reference study's Table 1.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Final

import numpy as np
import pandas as pd

from ...calibration.personal import CALIBRATION_COLUMNS
from ...dataset import Dataset, atomic_write
from ...metrics.resampling import PAIRED_COLUMNS
from ...models.labels import LAMBDA_ROW, NO_PHYSICS, ablation_base, lambda_row, row_privilege
from ..engine.tasks import prepare_out
from ..reference import STUDY_TABLE
from .inverse import INVERSE_COLUMNS

__all__ = [
    "BenchmarkResult",
    "METRIC_COLUMNS",
    "PREDICTION_COLUMNS",
    "COMPARISON_COLUMNS",
    "DROP_ONE_COLUMNS",
    "OUTPUT_FILES",
    "STALE_FILES",
    "ORACLE",
    "REFERENCE_MODELS",
    "PINN_MODELS",
    "NO_PHYSICS",
    "LAMBDA_ROW",
    "ABLATION_COLUMNS",
    "lambda_row",
    "ablation_base",
]

#: Columns of ``BenchmarkResult.drop_one`` / ``drop_one.csv``.
DROP_ONE_COLUMNS: Final = (
    "model",
    "dropped_wavelength_nm",
    "rmse_all_mgdl",
    "rmse_without_mgdl",
    "delta_rmse_mgdl",
    "ci_low",
    "ci_high",
    "p_value",
    "p_holm",
    "significant",
    "n_test_subjects",
    "n_repeats",
)

#: Registry name of the oracle bound.
ORACLE = "oracle"
#: Reference learners added by ``references=True`` (no skill and off-the-shelf).
REFERENCE_MODELS = ("mean", "gp", "gbr")
#: The physics-informed networks of the study (ablated by ``ablation=True``).
PINN_MODELS = ("original-pinn", "optimized-pinn", "rte-pinn", "selective-rte-pinn")
#: Columns of ``ablation.csv``: one row per compared pair, with physics minus without.
#: ``tested`` is False where the PINN's own weight is 0 (it *is* its no-physics fit:
#: no comparison, no verdict, ``verdict`` "physics off by tuning" or "physics off");
#: ``lambda_phys`` is the with-physics row's weight; ``lambda_source`` says where it
#: came from ("tuned", "best > 0 on the tuning curve", "given").
ABLATION_COLUMNS = (
    "model",
    "ablated_model",
    "lambda_phys",
    "lambda_source",
    "tested",
    "verdict",
    "rmse_mgdl",
    "ablated_rmse_mgdl",
    "rmse_diff_mgdl",
    "ci_low",
    "ci_high",
    "p_value",
    "p_holm",
    "p_wilcoxon",
    "significant",
    "physics_helps",
)



#: Columns of ``BenchmarkResult.metrics`` / ``metrics.csv``, in order.
METRIC_COLUMNS = (
    "model",
    "label",
    "privileged",
    "rmse_mgdl",
    "rmse_ci_low",
    "rmse_ci_high",
    "mard_pct",
    "mard_ci_low",
    "mard_ci_high",
    "clarke_a_pct",
    "clarke_a_ci_low",
    "clarke_a_ci_high",
    "clarke_ab_pct",
    "parkes_a_pct",
    "parkes_ab_pct",
    "dts_a_pct",
    "within15_pct",
    "within15_ci_low",
    "within15_ci_high",
    "within20_pct",
    "iso15197_pct",
    "bias_mgdl",
    "bias_ci_low",
    "bias_ci_high",
    "loa_low_mgdl",
    "loa_high_mgdl",
    "n_parameters",
    "latency_single_ms",
    "latency_single_p90_ms",
    "throughput_per_s",
    "latency_input",
    "macs_per_prediction",
    "macs_counted",
    "rmse_vs_oracle",
    "fit_time_s",
    "n_predictions",
    "n_invalid_predictions",
    "coverage90_pct",
    "coverage90_ci_low",
    "coverage90_ci_high",
    "width90_mgdl",
    "coverage80_pct",
    "width80_mgdl",
)
#: Columns of ``predictions.parquet``.
PREDICTION_COLUMNS = (
    "model",
    "subject_id",
    "measurement_id",
    "repeat",
    "fold",
    "reference_mgdl",
    "predicted_mgdl",
    "scored_mgdl",
    "lower90_mgdl",
    "upper90_mgdl",
)
#: Columns of ``comparisons.csv``.
COMPARISON_COLUMNS = ("family", *PAIRED_COLUMNS, "study_holds")
#: Files :meth:`BenchmarkResult.save` writes.
OUTPUT_FILES = (
    "metrics.csv",
    "metrics.json",
    "table.md",
    "predictions.parquet",
    "comparisons.csv",
    "histories.json",
    "drop_one.csv",
    "ablation.csv",
    "calibration.csv",
    "inverse.csv",
    "dataset.parquet",
    "meta.json",
)

#: What a new run into an existing directory removes before it computes: the previous
#: run's results (:data:`OUTPUT_FILES`) and the report drawn from them, which would
#: otherwise look like this run's were it stopped half-way. Not ``dataset.parquet``:
#: it may be the very file this run reads (``--data OUT/dataset.parquet``).
STALE_FILES = (*(f for f in OUTPUT_FILES if f != "dataset.parquet"), "report.html")


# --------------------------------------------------------------------------- result
@dataclass
class BenchmarkResult:
    """What :func:`run_benchmark` computed.

    Attributes
    ----------
    metrics : pandas.DataFrame
        One row per model (:data:`METRIC_COLUMNS`), best RMSE first.
    predictions : pandas.DataFrame
        Every out-of-fold prediction (:data:`PREDICTION_COLUMNS`).
    comparisons : pandas.DataFrame
        Paired tests (:data:`COMPARISON_COLUMNS`): family ``"vs_best"`` (every model
        against the best non-oracle model) and ``"study_order"`` (every pair the study
        ranked, worse minus better; ``study_holds`` says whether our ranking agrees).
    histories : dict
        Model -> per-epoch dicts of the first fold of the first repeat (empty list for
        models without training history).
    meta : dict
        Protocol, seeds, dataset hash and config, versions, task counts, methods;
        ``study_orderings`` says which of the study's pairwise orderings hold here.
    ablation : pandas.DataFrame
        Physics ablation (:data:`ABLATION_COLUMNS`); empty without ``ablation=True``.
    dataset : Dataset, optional
        The dataset benchmarked (written to ``dataset.parquet``).
    calibration : pandas.DataFrame
        Personal calibration (:data:`~nirglucose.calibration.personal.CALIBRATION_COLUMNS`);
        empty without ``calibration=k``.
    inverse : pandas.DataFrame
        The inverse task (:data:`~nirglucose.evaluation.benchmark.inverse.INVERSE_COLUMNS`): each
        state-predicting model's tissue-state error against the truth; empty when no
        model predicts state or the data has no ``true_*`` columns.
    drop_one : pandas.DataFrame
        Drop-one-LED refits (:data:`DROP_ONE_COLUMNS`,
        ``drop_one.csv``): per model and LED, the RMSE refitted without that LED's
        columns minus the RMSE with every LED (same folds, seeds and held-out
        subjects; first repeat), with its paired cluster-bootstrap 95 % CI
        (:mod:`~nirglucose.evaluation.benchmark.drop_one`); empty with ``drop_one_models="none"``.
    """

    metrics: pd.DataFrame
    predictions: pd.DataFrame
    comparisons: pd.DataFrame
    histories: dict[str, list[dict[str, Any]]]
    meta: dict[str, Any]
    dataset: Dataset | None = field(default=None, repr=False)
    ablation: pd.DataFrame = field(default_factory=lambda: pd.DataFrame(columns=ABLATION_COLUMNS))
    calibration: pd.DataFrame = field(
        default_factory=lambda: pd.DataFrame(columns=CALIBRATION_COLUMNS)
    )
    inverse: pd.DataFrame = field(default_factory=lambda: pd.DataFrame(columns=INVERSE_COLUMNS))
    drop_one: pd.DataFrame = field(
        default_factory=lambda: pd.DataFrame(columns=DROP_ONE_COLUMNS)
    )

    def table_markdown(self) -> str:
        """The study's Table 1 layout with our values (95 % CIs) beside the study's."""
        return _table_markdown(self)

    def save(self, out: str | Path) -> Path:
        """Write :data:`OUTPUT_FILES` into directory ``out`` (created if its parent exists)."""
        out = prepare_out(out)
        _write_csv(out / "metrics.csv", self.metrics)
        _write_text(
            out / "metrics.json",
            _dumps(
                {
                    "meta": self.meta,
                    "metrics": self.metrics.to_dict(orient="records"),
                    "ablation": self.ablation.to_dict(orient="records"),
                    "calibration": self.calibration.to_dict(orient="records"),
                }
            ),
        )
        _write_text(out / "table.md", self.table_markdown())
        atomic_write(
            out / "predictions.parquet", lambda tmp: self.predictions.to_parquet(tmp, index=False)
        )
        _write_csv(out / "comparisons.csv", self.comparisons)
        _write_text(out / "histories.json", _dumps(self.histories))
        _write_csv(out / "drop_one.csv", self.drop_one)
        _write_csv(out / "ablation.csv", self.ablation)
        _write_csv(out / "calibration.csv", self.calibration)
        _write_csv(out / "inverse.csv", self.inverse)
        if self.dataset is not None:
            self.dataset.save(out / "dataset.parquet")
        _write_text(out / "meta.json", _dumps(self.meta))
        return out


def _clean(obj: Any) -> Any:
    """JSON-safe copy: NaN/inf -> None, numpy scalars -> Python, tuples -> lists."""
    if isinstance(obj, dict):
        return {str(k): _clean(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [_clean(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return [_clean(v) for v in obj.tolist()]
    if isinstance(obj, np.bool_ | bool):
        return bool(obj)
    if isinstance(obj, np.integer):
        return int(obj)
    if isinstance(obj, float | np.floating):
        v = float(obj)
        return v if math.isfinite(v) else None
    return obj


def _dumps(obj: Any) -> str:
    return json.dumps(_clean(obj), indent=2, sort_keys=False, allow_nan=False) + "\n"


def _write_text(path: Path, text: str) -> None:
    atomic_write(path, lambda tmp: Path(tmp).write_text(text, encoding="utf-8"))


def _write_csv(path: Path, frame: pd.DataFrame) -> None:
    atomic_write(path, lambda tmp: frame.to_csv(tmp, index=False))


# --------------------------------------------------------------------------- table.md
def _fmt(v: Any, digits: int = 1) -> str:
    if v is None or (isinstance(v, float) and not math.isfinite(v)):
        return "–"
    if isinstance(v, int | np.integer):
        return f"{int(v):,}"
    return f"{float(v):.{digits}f}"


def _fmt_ms(v: Any) -> str:
    if v is None or not math.isfinite(float(v)):
        return "–"
    v = float(v)
    return f"{v:.3f}" if v < 0.1 else f"{v:.2f}" if v < 10 else f"{v:.1f}"


def _fmt_macs(v: Any) -> str:
    """A multiply-accumulate count: ``–`` when not counted, thousands separated."""
    if v is None or not math.isfinite(float(v)):
        return "–"
    return f"{float(v):,.0f}"


def _table_markdown(res: BenchmarkResult) -> str:
    """``table.md``: the metrics beside the study's Table 1 on a simulated preset; on a
    user's own data (no preset) the same metrics without the study's columns."""
    m = res.meta
    user = m.get("preset") is None
    layout = (
        "one 60/20/20 split by subject"
        if m["protocol"] == "paper-split"
        else f"grouped {m['n_splits']}-fold CV × {m['repeats']} repeats"
    )
    source = "your data" if user else f"preset `{m['preset']}`"
    study_note = "" if user else " Study: one 60/20/20 split by subject, test n = 48."
    lines = [
        "# Benchmark on your data" if user else "# Benchmark against the reference study (Table 1)",
        "",
        f"Ours: {layout} (protocol `{m['protocol']}`, seed {m['seed']}), "
        f"{m['n_subjects']} subjects, {m['n_snapshots']} snapshots, {source}, "
        f"dataset {m['dataset_hash']}; 95 % CIs from a cluster bootstrap "
        f"over subjects ({m['n_boot']:,} resamples).{study_note} Inference: our median "
        "single-sample `predict` time, median and 90th percentile over repeated calls "
        "(machine in `meta.json`, `timing_machine`); MACs: multiply-accumulates per "
        "prediction counted from the fitted model (`macs_counted` in `metrics.csv`).",
        "",
        *_table_rows(res, study=None if user else {r["model"]: r for r in STUDY_TABLE}),
        "",
    ]
    lines.extend(_significance_lines(res))
    lines.extend(_ablation_lines(res))
    return "\n".join(lines) + "\n"


def _table_rows(res: BenchmarkResult, study: dict | None) -> list[str]:
    """The metrics table's header and one row per model (study columns when given)."""
    cols = ["RMSE mg/dL", "MARD %", "Clarke A %", "±15 %", "Params", "Inference ms"]
    head = [c for name in cols for c in ((name, "study") if study is not None else (name,))]
    head[len(head) - 1 - (study is not None)] = "Inference ms (median, p90)"
    head += ["MACs / prediction", "RMSE / oracle"]
    lines = ["| Model | " + " | ".join(head) + " |", "|---" * (len(head) + 1) + "|"]
    for _, r in res.metrics.iterrows():
        s = (study or {}).get(r["model"], {})

        def ci(stem, col, r=r):
            return f"{_fmt(r[col])} [{_fmt(r[stem + '_ci_low'])}, {_fmt(r[stem + '_ci_high'])}]"

        cells = [
            (ci("rmse", "rmse_mgdl"), _fmt(s.get("rmse_mgdl"))),
            (ci("mard", "mard_pct"), _fmt(s.get("mard_pct"))),
            (ci("clarke_a", "clarke_a_pct"), _fmt(s.get("clarke_a_pct"))),
            (ci("within15", "within15_pct"), _fmt(s.get("within15_pct"))),
            (_fmt(int(r["n_parameters"])), _fmt(s.get("n_parameters"))),
            (
                f"{_fmt_ms(r['latency_single_ms'])}, {_fmt_ms(r.get('latency_single_p90_ms'))}",
                _fmt_ms(s.get("latency_single_ms", np.nan)),
            ),
        ]
        flat = [c for pair in cells for c in (pair if study is not None else pair[:1])]
        flat += [_fmt_macs(r.get("macs_per_prediction")), _fmt(r["rmse_vs_oracle"], 2)]
        lines.append(f"| {r['label']} | " + " | ".join(flat) + " |")
    return lines


def _ablation_lines(res: BenchmarkResult) -> list[str]:
    a = res.ablation
    if a is None or not len(a):
        return []
    label = {r["model"]: r["label"] for _, r in res.metrics.iterrows()}
    tested = a["tested"].astype(bool) if "tested" in a else np.ones(len(a), bool)
    out = [
        "",
        "## Physics ablation",
        "",
        "Each PINN refitted with its physics term off (`lambda_phys = 0`), everything else "
        "identical (same splits, seeds and parameters). Δ RMSE = with physics − without "
        "(negative: the physics term helps); paired cluster bootstrap over subjects, "
        f"Holm over the {int(tested.sum())} tested pairs, α = {res.meta['alpha']}. Where "
        "tuning chose λ = 0 the PINN *is* its no-physics fit: no verdict; it is also "
        "refitted at the best λ > 0 of the tuning's validation curve (`/lambda=` rows).",
        "",
        "| PINN | λ | RMSE with physics | RMSE without | Δ RMSE mg/dL [95 % CI] | p_holm "
        "| verdict |",
        "|---|---|---|---|---|---|---|",
    ]
    for (_, r), t in zip(a.iterrows(), tested, strict=True):
        verdict = r["verdict"] if "verdict" in r else ""
        diff = (
            f"{r['rmse_diff_mgdl']:+.2f} [{r['ci_low']:+.2f}, {r['ci_high']:+.2f}]" if t else "—"
        )
        p = f"{r['p_holm']:.3g}" if t else "—"
        lam = r.get("lambda_phys", float("nan"))
        out.append(
            f"| {label.get(r['model'], r['model'])} | {lam:g} | {_fmt(r['rmse_mgdl'])} "
            f"| {_fmt(r['ablated_rmse_mgdl'])} | {diff} | {p} | {verdict} |"
        )
    return out


def _significance_lines(res: BenchmarkResult) -> list[str]:
    c = res.comparisons
    label = {r["model"]: r["label"] for _, r in res.metrics.iterrows()}
    out = [f"Note: {res.meta['significance_withheld']}."] if res.meta.get(
        "significance_withheld") else []
    vb = c[c["family"] == "vs_best"]
    if len(vb):
        best = vb["reference_model"].iloc[0]
        ref = vb["model"].map(lambda m: m == ORACLE or row_privilege(str(m)) is not None)
        refs = vb[ref]
        vb = vb[~ref]
        worse = vb["significant"] & (vb["rmse_diff_mgdl"] > 0)
        better = vb["significant"] & (vb["rmse_diff_mgdl"] < 0)

        def names(rows, mask):
            return ", ".join(label[m] for m in rows.loc[mask, "model"]) or "none"

        out.append(
            f"Significant rankings (paired cluster bootstrap of the RMSE difference over "
            f"subjects, Holm-adjusted, α = {res.meta['alpha']}): best deployable model "
            f"is {label[best]}; significantly worse than it: {names(vb, worse)}; "
            f"not distinguishable from it: {names(vb, ~vb['significant'])}"
            + (f"; significantly better: {names(vb, better)}" if better.any() else "")
            + (
                "; privileged references, not competitors (they read the generating "
                f"scenario or the true nuisances): {names(refs, refs['model'].notna())}."
                if len(refs)
                else "."
            )
        )
    so = c[c["family"] == "study_order"]
    if len(so):
        n_hold = int(so["study_holds"].sum())
        n_sig = int((so["study_holds"] & so["significant"]).sum())
        out += [
            "",
            f"Study orderings (study: row model better than column model): "
            f"{n_hold} of {len(so)} hold here, {n_sig} of them significantly:",
            "",
        ]
        for _, r in so.iterrows():
            verdict = "holds" if r["study_holds"] else "reversed"
            sig = "significant" if r["significant"] else "not significant"
            out.append(
                f"- {label[r['reference_model']]} < {label[r['model']]}: {verdict} "
                f"(Δ RMSE {r['rmse_diff_mgdl']:+.1f} mg/dL [{r['ci_low']:+.1f}, "
                f"{r['ci_high']:+.1f}], p_holm = {r['p_holm']:.3g}, {sig})"
            )
    if res.meta.get("oracle_note"):
        out += ["", f"Note: {res.meta['oracle_note']}."]
    return out
