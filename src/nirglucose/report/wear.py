"""The report of a worn run (``nirglucose wear-benchmark``): findings first, then the
traces, the error by days since calibration, the schedules and the CGM standards.

Reads the files of :class:`~nirglucose.evaluation.wear.WearResult`; computes
no metric except the schedule applied to the drawn traces
(:func:`~nirglucose.calibration.schedules.apply_schedule`, the same function the
benchmark scored).
"""

from __future__ import annotations

import base64
import html
import json
from pathlib import Path

import pandas as pd

from ..calibration.schedules import apply_schedule
from ..dataset import atomic_write
from ..exceptions import DataError
from ..formatting import format_number
from ..plots.style import figure_bytes, model_label
from ..plots.wear import figure_wear_traces, plot_error_by_day

__all__ = ["is_wear_results", "build_wear_report"]

_NEEDED = ("wear_schedules.csv", "wear_by_day.csv", "wear_standards.csv", "wear_icgm.csv",
           "wear_predictions.csv", "wear_meta.json")
_CSS = ("body{font-family:system-ui,sans-serif;max-width:1100px;margin:2em auto;padding:0 1em;"
        "line-height:1.45}table{border-collapse:collapse;margin:1em 0;font-size:0.9em}"
        "th,td{border:1px solid #ccc;padding:3px 8px;text-align:right}th{background:#f3f3f3}"
        "td:first-child,th:first-child{text-align:left}img{max-width:100%}"
        ".findings li{margin:0.4em 0}@media print{body{max-width:none}}")


def is_wear_results(directory: str | Path) -> bool:
    """Whether ``directory`` holds a worn run's files (and no snapshot benchmark)."""
    d = Path(directory)
    return (d / "wear_schedules.csv").is_file() and not (d / "metrics.json").is_file()


def _img(fig, alt: str) -> str:
    data = base64.b64encode(figure_bytes(fig, "png", close=True)).decode("ascii")
    return f'<img src="data:image/png;base64,{data}" alt="{html.escape(alt)}">'


def _table(frame: pd.DataFrame) -> str:
    return frame.to_html(index=False, float_format=format_number, border=0,
                         escape=True)


#: Reference rows: a bound and no skill, never "the best model".
_REFERENCE = ("oracle", "mean")


def _findings(s: pd.DataFrame, st: pd.DataFrame) -> list[str]:
    """Every sentence computed from the tables."""
    raw = s[s["variant"] == "raw"]
    n_subj = int(raw["n_subjects"].max())
    out = []
    models = raw[~raw["model"].isin(_REFERENCE)]
    if len(models):
        best = models.loc[models["rmse_mgdl"].idxmin()]
        out.append(f"Best model and schedule: {model_label(best['model'])} with "
                   f"{best['schedule']}, "
                   f"RMSE {format_number(best['rmse_mgdl'])} mg/dL "
                   f"[{format_number(best['rmse_ci_low'])}, {format_number(best['rmse_ci_high'])}]"
                   f" ({n_subj} subjects, subject bootstrap).")
    for ref, what in (("oracle", "the oracle (true nuisances), the bound"),
                      ("mean", "no skill: the training mean, and with a schedule the last "
                       "fingerstick carried forward")):
        r = raw[raw["model"] == ref].set_index("schedule")["rmse_mgdl"]
        if len(r):
            values = ", ".join(f"{k} {format_number(v)}" for k, v in r.items())
            out.append(f"Reference, {what}: {values} mg/dL.")
    for model, g in models.groupby("model", sort=False):
        r = g.set_index("schedule")
        if "factory" in r.index and len(r) > 1:
            b = r.drop(index="factory")["rmse_mgdl"].idxmin()
            overlap = r.loc[b, "rmse_ci_high"] >= r.loc["factory", "rmse_ci_low"]
            factory = format_number(r.loc["factory", "rmse_mgdl"])
            out.append(f"{model_label(model)}: factory {factory}"
                       f", best schedule {b} {format_number(r.loc[b, 'rmse_mgdl'])} mg/dL"
                       + (" (intervals overlap: not shown to differ)." if overlap else "."))
    sm = s.pivot_table(index=["model", "schedule"], columns="variant", values="rmse_mgdl")
    if {"raw", "smoothed"} <= set(sm.columns):
        d = (sm["smoothed"] - sm["raw"])
        out.append(f"The causal smoother changes RMSE by {format_number(d.min(), sign=True)} to "
                   f"{format_number(d.max(), sign=True)} "
                   "mg/dL across models and schedules (negative: it helps).")
    passed = st[(st["variant"] == "raw") & ~st["model"].isin(_REFERENCE)]
    if len(passed):
        top = passed.loc[passed["icgm_passed"].idxmax()]
        out.append(f"iCGM criteria: at most {int(top['icgm_passed'])} of "
                   f"{int(top['icgm_criteria'])} met by a model ({model_label(top['model'])}, "
                   f"{top['schedule']}).")
    low = int(st["n_below_70"].max())
    out.append(f"{low} scored readings are below 70 mg/dL"
               + (": nothing here speaks to hypoglycaemia." if low == 0 else
                  "; the < 70 mg/dL criteria rest on them alone."))
    return out


def _figures(pred: pd.DataFrame, by_day: pd.DataFrame, model: str, sched: str) -> dict:
    """The two figures of the page, each with its alt text."""
    g = pred[(pred["model"] == model) & (pred["variant"] == "raw")].reset_index(drop=True)
    traces = pd.concat([g, apply_schedule(g, sched)], axis=1)
    return {
        "traces": (figure_wear_traces(traces, model=model, schedule=sched),
                   f"Reference and {model_label(model)} calibrated {sched} over the days for three "
                   "held-out subjects; fingersticks marked"),
        "by_day": (plot_error_by_day(by_day[(by_day["model"] == model)
                                            & (by_day["variant"] == "raw")]).figure,
                   f"{model_label(model)}: RMSE by whole days since the last calibration, per "
                   "schedule"),
    }


def _write_figures(figs: dict, fd: Path) -> None:
    fd.mkdir(parents=True, exist_ok=True)
    for name, (fig, _) in figs.items():
        png = figure_bytes(fig, "png")
        atomic_write(fd / f"wear_{name}.png", lambda tmp, b=png: Path(tmp).write_bytes(b))


def build_wear_report(results_dir: str | Path, out_path: str | Path, *,
                      figures_dir: str | Path | None = None) -> Path:
    """Write the HTML report of a worn run's results directory (atomically).

    Raises
    ------
    DataError
        A file of the worn run is missing, or the output directory does not exist.
    """
    d, out_path = Path(results_dir), Path(out_path)
    missing = [n for n in _NEEDED if not (d / n).is_file()]
    if missing:
        raise DataError(f"{str(d)!r} lacks {missing}; run `nirglucose wear-benchmark --out "
                        f"{d}` first")
    s = pd.read_csv(d / "wear_schedules.csv")
    by_day = pd.read_csv(d / "wear_by_day.csv")
    st = pd.read_csv(d / "wear_standards.csv")
    icgm = pd.read_csv(d / "wear_icgm.csv")
    pred = pd.read_csv(d / "wear_predictions.csv")
    meta = json.loads((d / "wear_meta.json").read_text())
    raw = s[s["variant"] == "raw"]
    models = raw[~raw["model"].isin(_REFERENCE)]
    pool = models if len(models) else raw
    best = pool.loc[pool["rmse_mgdl"].idxmin()]
    model, sched = str(best["model"]), str(best["schedule"])
    figs = _figures(pred, by_day, model, sched)
    if figures_dir is not None:
        _write_figures(figs, Path(figures_dir))
    sched_table = raw.pivot_table(index="model", columns="schedule", values="rmse_mgdl")
    crit = icgm[(icgm["model"] == model) & (icgm["variant"] == "raw")
                & (icgm["schedule"] == sched)]
    items = "".join(f"<li>{html.escape(t)}</li>" for t in _findings(s, st))
    body = (
        f"<h1>A device worn for days: {html.escape(str(meta.get('preset') or 'user data'))}</h1>"
        f"<p>{meta['n_subjects']} subjects, {meta['n_readings']} readings, "
        f"{meta['n_splits']} subject-grouped folds, seed {meta['seed']}.</p>"
        f"<h2 id='findings'>Findings</h2><ul class='findings'>{items}</ul>"
        f"<h2>Traces</h2>{_img(*figs['traces'])}"
        f"<h2>Error by days since calibration</h2>{_img(*figs['by_day'])}"
        "<h2>RMSE [mg/dL] by calibration schedule (raw predictions)</h2>"
        f"{_table(sched_table.reset_index())}"
        "<h2>Every schedule, raw and smoothed, with 95 % subject-bootstrap CIs</h2>"
        f"{_table(s)}"
        "<h2>The standards of a worn monitor</h2>"
        f"{_table(st)}"
        f"<h3>iCGM criteria: {html.escape(model_label(model))}, {html.escape(sched)}</h3>"
        f"{_table(crit.drop(columns=['model', 'variant', 'schedule']))}"
        "<p>Agreement rates are judged on their one-sided 95 % lower bound, clustered by "
        "subject (21 CFR 862.1355 special controls).</p>"
    )
    page = (f"<!DOCTYPE html>\n<html lang='en'><head><meta charset='utf-8'>"
            f"<meta name='viewport' content='width=device-width, initial-scale=1'>"
            f"<title>nirglucose: a device worn for days</title><style>{_CSS}</style></head>"
            f"<body>{body}</body></html>\n")
    if not out_path.parent.exists():
        raise DataError(f"output directory {str(out_path.parent)!r} does not exist; "
                        "create it first")
    return atomic_write(out_path, lambda tmp: Path(tmp).write_text(page, encoding="utf-8"))
