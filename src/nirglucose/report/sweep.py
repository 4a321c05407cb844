"""The sweep section of the report: figures and tables of a sweep directory.

:func:`sweep_section` returns an HTML fragment (a ``<section id="sweep">``) with the
degradation curves, the ablation or domain-shift bars and their tables, figures
embedded as base64 PNG, for the report page to include; :func:`save_sweep_figures`
writes the same figures as files. The numbers come from
:mod:`nirglucose.evaluation.sweep`; the drawing from :mod:`nirglucose.plots.sweep`.

>>> from nirglucose.report.sweep import sweep_section
>>> html = sweep_section("sweep/")  # doctest: +SKIP
"""

from __future__ import annotations

import base64
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pandas as pd
from matplotlib.figure import Figure
from pydantic import BaseModel

from ..config import ScenarioConfig, resolve_config
from ..evaluation.sweep.run import SweepResult, load_sweep, threshold_crossing
from ..exceptions import ConfigError
from ..formatting import MISSING, format_ci, format_number
from ..models.registry import privileged_knowledge
from ..plots.designs import plot_design_curve
from ..plots.fleet import figure_fleet
from ..plots.style import figure_bytes, model_label, save_figure
from ..plots.sweep import figure_ablation, figure_data_size, plot_shift_bars, plot_sweep_curve
from .markup import esc as _esc

__all__ = ["SweepFigure", "MARD_LIMIT_PCT", "sweep_figures", "save_sweep_figures",
           "sweep_section"]

#: MARD above which a model is reported as no longer usable. [%]
MARD_LIMIT_PCT = 15.0

#: Axis labels of the built-in studies' varied keys.
_KEY_LABELS = {
    "noise_scale": "noise scale, every source (× nominal) [-]",
    "noise.pmf_measurement.scale": "physiological-vector measurement error (× nominal) [-]",
}


@dataclass
class SweepFigure:
    """One rendered sweep figure.

    Attributes
    ----------
    name : str
        File stem (``"sweep_rmse"``).
    caption : str
        One sentence saying what the figure shows.
    figure : matplotlib.figure.Figure
        The figure.
    """

    name: str
    caption: str
    figure: Figure


def _key_label(key: str) -> str:
    """Axis label of a config key, with the unit from the field's description."""
    if key in _KEY_LABELS:
        return _KEY_LABELS[key]
    model: Any = ScenarioConfig
    desc = ""
    for part in key.split("."):
        fields = getattr(model, "model_fields", {})
        if part not in fields:
            break
        desc = fields[part].description or ""
        ann = fields[part].annotation
        model = ann if isinstance(ann, type) and issubclass(ann, BaseModel) else None
    unit = re.search(r"\[([^\]]*)\]\s*$", desc)
    return f"{key} [{unit.group(1)}]" if unit else key


def _numeric_key(res: SweepResult) -> str | None:
    varied = res.meta.get("varied") or []
    if len(varied) != 1 or varied[0] not in res.summary:
        return None
    vals = pd.to_numeric(res.summary[varied[0]], errors="coerce")
    return varied[0] if vals.notna().all() and vals.nunique() > 1 else None


def sweep_figures(sweep_dir: str | Path | SweepResult) -> list[SweepFigure]:
    """The figures of a sweep: curves for a one-key grid, bars for ablation / cohort.

    Parameters
    ----------
    sweep_dir : str, Path or SweepResult
        A directory written by :func:`~nirglucose.evaluation.sweep.run_sweep`.

    Returns
    -------
    list of SweepFigure
    """
    res = sweep_dir if isinstance(sweep_dir, SweepResult) else load_sweep(sweep_dir)
    n_seeds = len(res.meta.get("seeds", []))
    out: list[SweepFigure] = []
    key = _numeric_key(res)
    if key is not None:
        xl = _key_label(key)
        ax = plot_sweep_curve(res.summary, key, metric="rmse_mgdl", xlabel=xl)
        out.append(SweepFigure(
            "sweep_rmse", f"RMSE of each model against {key}: mean over {n_seeds} seeds, "
            "band = 95 % t-interval over seeds.", ax.figure))
        ax = plot_sweep_curve(res.summary, key, metric="mard_pct", xlabel=xl,
                              threshold=MARD_LIMIT_PCT)
        out.append(SweepFigure(
            "sweep_mard", f"MARD of each model against {key}, with the "
            f"{format_number(MARD_LIMIT_PCT, style='general')} % line; band = 95 % t-interval "
            "over seeds.", ax.figure))
    if res.effects is not None and "source" in res.effects:
        out.append(SweepFigure(
            "sweep_ablation", "Noise-source ablation: ΔRMSE when a source is switched off "
            "with all others on (left) and when it is the only one on (right); error bars: "
            f"95 % paired t-interval over {n_seeds} seeds.", figure_ablation(res.effects)))
    if res.meta.get("study") == "data-size" and "n_train_subjects" in res.summary:
        out.append(SweepFigure(
            "sweep_data_size", "RMSE on an independent test draw against the number of "
            f"training subjects, one panel per preset: mean over {n_seeds} seeds.",
            figure_data_size(res.summary)))
    if res.effects is not None and "oracle_bound_rmse_mgdl" in res.effects:
        out.append(_design_figure(res.effects))
    if res.effects is not None and "shift" in res.effects:
        ax = plot_shift_bars(res.effects)
        out.append(SweepFigure(
            "sweep_shift", "Domain shift: test RMSE in the training domain (hatched) and "
            "in the shifted domain (solid); error bars: 95 % paired t-interval of the "
            "shift's effect over seeds.", ax.figure))
    if res.effects is not None and "rmse_vs_same_unit" in res.effects:

        out.append(SweepFigure(
            "sweep_fleet", "Unit-to-unit tolerance: RMSE on the test units' subjects "
            "against the tolerance scale (1 = the stated part tolerances), for a model "
            "trained on the same unit, on other units without transfer, and with a "
            f"per-unit factory reference (bias or slope/bias per channel); {n_seeds} "
            "seed(s), error bars: 95 % interval.", figure_fleet(res.effects)))
    return out


def _design_figure(designs: pd.DataFrame) -> SweepFigure:
    """The ``wavelengths`` study's curve: best RMSE against LEDs per detector."""
    ax = plot_design_curve(designs)
    return SweepFigure(
        "sweep_designs", "Best achievable glucose RMSE against the number of LEDs, one "
        "colour per detector: the smallest device bound over every LED subset (solid), "
        "the oracle-conditioned bound of the confirmed design (dotted) and the oracle's "
        "RMSE on its simulated data (markers, 95 % interval).", ax.figure)


def save_sweep_figures(
    sweep_dir: str | Path, formats: tuple[str, ...] = ("png", "svg")
) -> list[Path]:
    """Write every sweep figure to ``<sweep_dir>/figures/<name>.<fmt>``.

    Returns
    -------
    list of pathlib.Path
        The files written.
    """
    d = Path(sweep_dir)
    figs = sweep_figures(d)
    (d / "figures").mkdir(exist_ok=True)
    paths: list[Path] = []
    for f in figs:
        paths += save_figure(f.figure, d / "figures" / f.name, formats)
    return paths


def _num(v: Any, digits: int = 1) -> str:
    return format_number(v, digits, text=_esc)


def _table(head: list[str], rows: list[list[str]], table_id: str) -> str:
    th = "".join(f"<th>{h}</th>" for h in head)
    body = "".join("<tr>" + "".join(f"<td>{c}</td>" for c in r) + "</tr>" for r in rows)
    return (f'<div class="scroll"><table id="{table_id}"><thead><tr>{th}</tr></thead>'
            f"<tbody>{body}</tbody></table></div>")


def _ci(row: pd.Series, stem: str) -> str:
    return format_ci(row[f"{stem}_mean"], row.get(f"{stem}_ci_low"), row.get(f"{stem}_ci_high"),
                     text=_esc)


def _label(model: str) -> str:
    return _esc(model_label(model))


def _figure_html(f: SweepFigure) -> str:
    data = base64.b64encode(figure_bytes(f.figure, "png", close=True)).decode("ascii")
    return (f'<figure id="fig-{f.name}"><img src="data:image/png;base64,{data}" '
            f'alt="{_esc(f.caption)}"><figcaption><b>{_esc(f.name)}.</b> '
            f"{_esc(f.caption)}</figcaption></figure>")


def sweep_section(sweep_dir: str | Path) -> str:
    """An HTML fragment presenting a sweep directory, for the report page.

    Parameters
    ----------
    sweep_dir : str or Path
        A directory written by ``nirglucose sweep`` / :func:`run_sweep`.

    Returns
    -------
    str
        ``<section id="sweep">…</section>``: a description of the sweep, its tables
        (MARD-limit crossings and RMSE per scenario; ablation or shift effects) and its
        figures as base64 PNG. Self-contained (no script, nothing loaded).

    Raises
    ------
    DataError
        ``sweep_dir`` is not a sweep directory.
    """
    res = load_sweep(sweep_dir)
    key = _numeric_key(res)
    parts = ['<section id="sweep">', *_intro(res.meta)]
    if key is not None:
        parts += _crossing(res.summary, key)
    if "rmse_mgdl_mean" in res.summary:
        parts.append(_summary_table(res.summary, res.meta, key))
    if res.meta.get("study") == "mismatch":
        parts += _mismatch_tables(res.effects, res.meta)
    else:
        parts += _effects_tables(res.effects)
    for f in sweep_figures(res):
        parts.append(_figure_html(f))
    parts.append("</section>")
    return "\n".join(parts) + "\n"


def _intro(m: dict[str, Any]) -> list[str]:
    """The heading, what was swept on what, and the shared overrides if any."""
    layout = (f"{m.get('protocol')} ({m.get('n_splits')} folds × {m.get('repeats')} repeats)"
              if m.get("protocol") == "grouped-cv" else str(m.get("protocol")))
    parts = [
        f"<h2>Sweep: {_esc(m.get('study'))}</h2>",
        f"<p>{len(m.get('scenarios', []))} scenarios × {len(m.get('seeds', []))} seeds × "
        f"{len(m.get('models', []))} models ({', '.join(_label(x) for x in m.get('models', []))})"
        f" on preset <code>{_esc(m.get('preset'))}</code>, {m.get('n_subjects')} subjects × "
        f"{m.get('per_subject')} snapshots per dataset, {_esc(layout)} per task; "
        f"nirglucose {_esc(m.get('version'))}. Values are means over seeds with 95 % "
        "t-intervals over seeds.</p>",
    ]
    if m.get("base_overrides"):
        sets = ", ".join(f"<code>{_esc(k)}={_esc(v)}</code>"
                         for k, v in m["base_overrides"].items())
        parts.append(f"<p>Shared overrides: {sets}.</p>")
    return parts


def _crossing(s: pd.DataFrame, key: str) -> list[str]:
    """Where each model's MARD crosses :data:`MARD_LIMIT_PCT` along the numeric ``key``."""
    cross = threshold_crossing(s, key, "mard_pct", MARD_LIMIT_PCT)
    rows = [[_label(r["model"]),
             _num(r["crossing"], 2) if r["status"] == "crosses" else _esc(r["status"])]
            for _, r in cross.iterrows()]
    return [f"<h3>Where MARD crosses {format_number(MARD_LIMIT_PCT, style='general')} %</h3>",
            _table(["model", f"{_esc(key)} at the crossing"], rows, "sweep-crossing")]


def _summary_table(s: pd.DataFrame, m: dict[str, Any], key: str | None) -> str:
    """RMSE and MARD per scenario and model, collapsed."""
    label_cols = [c for c in m.get("label_columns", []) if c in s]
    head = ["scenario", "model", "RMSE mg/dL [95 % CI]", "MARD % [95 % CI]",
            "Clarke A %"]
    if "rmse_vs_oracle_mean" in s and s["rmse_vs_oracle_mean"].notna().any():
        head.append("RMSE / oracle")
    rows = []
    for _, r in s.iterrows():
        name = (", ".join(f"{c}={r[c]}" for c in label_cols) if key is not None
                else r["scenario"])
        row = [_esc(name), _label(r["model"]), _ci(r, "rmse_mgdl"), _ci(r, "mard_pct"),
               _num(r.get("clarke_a_pct_mean"))]
        if len(head) == 6:
            row.append(_num(r.get("rmse_vs_oracle_mean"), 2))
        rows.append(row)
    return ("<details><summary>RMSE and MARD per scenario and model "
            f"({len(rows)} rows)</summary>"
            + _table(head, rows, "sweep-summary") + "</details>")


def _effects_tables(e: pd.DataFrame | None) -> list[str]:
    """The noise-source ablation table and the domain-shift table, where the sweep has them."""
    parts: list[str] = []
    if e is not None and "source" in e and len(e):
        parts.append("<h3>Which noise source costs most</h3>")
        rows = [[_label(r["model"]), _esc(r["source"]),
                 f"{_num(r['delta_off'], 2)} [{_num(r['delta_off_ci_low'], 2)}, "
                 f"{_num(r['delta_off_ci_high'], 2)}]",
                 f"{_num(r['delta_only'], 2)} [{_num(r['delta_only_ci_low'], 2)}, "
                 f"{_num(r['delta_only_ci_high'], 2)}]"] for _, r in e.iterrows()]
        parts.append(_table(["model", "source", "ΔRMSE, source off (mg/dL)",
                             "ΔRMSE, source alone (mg/dL)"], rows, "sweep-ablation"))
    if e is not None and "oracle_bound_rmse_mgdl" in e and len(e):
        parts += _designs_table(e)
    if e is not None and "shift" in e and len(e):
        parts.append("<h3>Domain shift</h3>")
        rows = [[_label(r["model"]), _esc(r["shift"]), _esc(r["train_domain"]),
                 _esc(r["test_domain"]), _num(r["in_domain"]), _num(r["shifted"]),
                 f"{_num(r['delta'])} [{_num(r['delta_ci_low'])}, {_num(r['delta_ci_high'])}]"]
                for _, r in e.iterrows()]
        parts.append(_table(["model", "shift", "train", "shifted test", "RMSE in domain",
                             "RMSE shifted", "ΔRMSE [95 % CI]"], rows, "sweep-shift"))
    if e is not None and "rmse_vs_same_unit" in e and len(e):
        parts += _fleet_table(e)
    return parts


def _designs_table(e: pd.DataFrame) -> list[str]:
    """The ``wavelengths`` study's top designs: bounds and confirmed RMSE per model."""
    models = list(dict.fromkeys(e["model"]))
    head = ["detector", "LEDs", "rank", "wavelengths nm", "study LEDs kept",
            "device bound mg/dL", "oracle-cond. bound mg/dL",
            *[f"{_label(m)} RMSE [95 % CI]" for m in models]]
    keys = ["detector", "n_leds", "rank", "wavelengths_nm"]
    rows = []
    for _, d in e.groupby(keys, sort=False):
        r = d.iloc[0]
        by_model = {m: d[d["model"] == m] for m in models}
        cells = [format_ci(x["rmse_mgdl"].iloc[0], x["rmse_ci_low"].iloc[0],
                           x["rmse_ci_high"].iloc[0], text=_esc) if len(x) else MISSING
                 for x in by_model.values()]
        rows.append([_esc(r["detector"]), _esc(r["n_leds"]), _esc(r["rank"]),
                     _esc(r["wavelengths_nm"]), _esc(r["study_leds_kept"]),
                     _num(r["bound_rmse_mgdl"]), _num(r["oracle_bound_rmse_mgdl"]), *cells])
    how = ", ".join(dict.fromkeys(e["ci"].astype(str))) if "ci" in e else ""
    return ["<h3>Top LED designs</h3>",
            "<p>Every LED subset ranked by the device bound (a device that must infer "
            "the nuisances); the best designs simulated and scored. The oracle knows "
            "each reading's nuisances, so compare it with the oracle-conditioned bound. "
            f"Intervals: {_esc(how)}.</p>",
            _table(head, rows, "sweep-designs")]


def _fleet_table(e: pd.DataFrame) -> list[str]:
    """The fleet study's table: tolerance scale x variant, RMSE [CI] per model."""
    models = list(dict.fromkeys(e["model"]))
    rows = []
    for (scale, variant), g in e.groupby(["tolerance_scale", "variant"], sort=False):
        row = [_num(scale, 2), _esc(variant)]
        for m in models:
            r = g[g["model"] == m]
            if not len(r):
                row.append("")
                continue
            x = r.iloc[0]
            row.append(f"{_num(x['rmse_mgdl'])} [{_num(x['rmse_ci_low'])}, "
                       f"{_num(x['rmse_ci_high'])}]")
        rows.append(row)
    return ["<h3>Which tolerance a design can afford</h3>",
            "<p>RMSE on subjects measured by units the model never saw, mg/dL [95 % "
            "interval]; <em>same-unit</em> trains on the test unit itself.</p>",
            _table(["tolerance scale", "variant", *[f"{_label(m)} RMSE" for m in models]],
                   rows, "sweep-fleet")]


def _regime(preset: Any) -> str:
    """Which glucose regime a preset's claims hold in (its ``glucose.signal_gain``)."""
    try:
        gain = float(resolve_config(str(preset)).glucose.signal_gain)
    except ConfigError:  # a preset this version does not know: say so, claim nothing
        return f"preset <code>{_esc(preset)}</code> (glucose signal gain unknown)"
    if gain == 1.0:
        return (f"preset <code>{_esc(preset)}</code>, glucose at its published optical "
                "magnitude (physical regime)")
    return (f"preset <code>{_esc(preset)}</code>, glucose's optical effect amplified "
            f"×{format_number(gain, style='general')} over its published magnitude "
            "(amplified regime: these numbers do not hold at published magnitudes)")


def _who(model: str, assumed: Any) -> str:
    """A row's name: the model, what it assumes, and whether it is privileged."""
    name = _label(model)
    if isinstance(assumed, str) and assumed:
        name += f" assuming <code>{_esc(assumed)}</code>"
    try:
        priv = privileged_knowledge(model)
    except ConfigError:  # an estimator object's label: it declares nothing
        priv = None
    return f"{name} <em>(privileged reference)</em>" if priv else name


def _mismatch_tables(e: pd.DataFrame | None, m: dict[str, Any]) -> list[str]:
    """The ``mismatch`` study: per data model, every row across seeds, and what it shows.

    Built from ``effects.csv`` (:func:`~nirglucose.evaluation.sweep.analysis.mismatch_table`).
    """
    if e is None or not len(e) or "rmse_mean" not in e:
        return []
    n_seeds = len(m.get("seeds", []))
    parts = [
        "<h3>Model mismatch: the inversions against re-tuned references, across seeds</h3>",
        f"<p>Claims hold in one regime: {_regime(m.get('preset'))}. Each number is over "
        f"{n_seeds} simulated datasets (seeds), not one dataset's bootstrap: the mean "
        "RMSE, its SD and range over seeds, and the paired difference from no skill "
        "(the training mean; same seed, same folds) with a Student-t 95 % interval over "
        "seeds. <em>Privileged</em> rows read the generating scenario (or the true "
        "nuisances): references, never candidates.</p>",
    ]
    tuning = m.get("tuning") or {}
    if tuning:
        items = "".join(f"<li>{_label(k)}: {_esc(v)}</li>" for k, v in tuning.items())
        parts.append(f"<p>How each model was tuned:</p><ul>{items}</ul>")
    head = ["data made by", "model", "RMSE mg/dL, mean over seeds (SD) [min, max]",
            "Δ vs no skill mg/dL [95 % CI over seeds]", "seeds below no skill",
            "seeds worse than no skill beyond its CI"]
    rows, sentences = [], []
    for made, g in e.groupby("data_model", sort=False):
        for _, r in g.iterrows():
            rows.append([
                _esc(made), _who(r["model"], r.get("assumed_model")),
                f"{_num(r['rmse_mean'])} ({_num(r['rmse_sd'])}) "
                f"[{_num(r['rmse_min'])}, {_num(r['rmse_max'])}]",
                f"{_num(r['delta_no_skill'])} [{_num(r['delta_no_skill_ci_low'])}, "
                f"{_num(r['delta_no_skill_ci_high'])}]",
                f"{int(r['seeds_below_no_skill'])} / {int(r['n_seeds'])}",
                f"{int(r['seeds_worse_beyond_ci'])} / {int(r['n_seeds'])}",
            ])
        sentences.append(_mismatch_sentence(str(made), g))
    parts.append(_table(head, rows, "sweep-mismatch"))
    parts.append("<ul>" + "".join(f"<li>{x}</li>" for x in sentences if x) + "</ul>")
    return parts


def _mismatch_sentence(made: str, g: pd.DataFrame) -> str:
    """One data model's finding in words: each inversion matched and mismatched against
    the best deployable reference and no skill (means over seeds)."""
    def deployable(model: str) -> bool:
        try:
            return privileged_knowledge(model) is None
        except ConfigError:  # an estimator object's label: it declares nothing
            return True

    refs = g[g["assumed_model"].isna() | (g["assumed_model"].astype(str) == "")]
    no_skill = refs[refs["model"] == "mean"]
    cands = refs[[deployable(x) and x != "mean" for x in refs["model"]]]
    bits = []
    for model, h in g[~g.index.isin(refs.index)].groupby("model", sort=False):
        hit = h[h["assumed_model"] == made]
        other = h[h["assumed_model"] != made]
        kind = "deployable" if deployable(str(model)) else "privileged reference"
        if len(hit):
            txt = (f"{_label(str(model))} ({kind}) {_num(hit['rmse_mean'].iloc[0])} mg/dL "
                   "assuming the right model")
            if len(other):
                txt += (f", {_num(other['rmse_mean'].min())}-{_num(other['rmse_mean'].max())} "
                        "assuming another")
            bits.append(txt)
    if len(cands):
        best = cands.loc[cands["rmse_mean"].idxmin()]
        bits.append(f"the best re-tuned deployable reference, {_label(str(best['model']))}, "
                    f"{_num(best['rmse_mean'])}")
    if len(no_skill):
        bits.append(f"no skill {_num(no_skill['rmse_mean'].iloc[0])}")
    if not bits:
        return ""
    return f"Data made by <code>{_esc(made)}</code>: " + "; ".join(bits) + " (means over seeds)."
