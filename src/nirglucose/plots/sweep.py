"""Sweep figures: degradation curves, noise-source ablation bars, domain-shift bars.

The inputs are the tables of :mod:`nirglucose.evaluation.sweep` (``summarize_sweep``,
``ablation_effects``, ``shift_effects``); nothing here computes a metric.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pandas as pd
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from .style import GREY, model_colors, model_label, model_marker, new_axes, plot_style, styled

__all__ = [
    "METRIC_LABELS",
    "plot_sweep_curve",
    "plot_ablation_bars",
    "plot_shift_bars",
    "figure_ablation",
    "figure_data_size",
]

#: Axis label (with unit) of each metric a sweep figure can show.
METRIC_LABELS: dict[str, str] = {
    "rmse_mgdl": "RMSE [mg/dL]",
    "mard_pct": "MARD [%]",
    "clarke_a_pct": "Clarke zone A [%]",
    "within15_pct": "within ±15 % [%]",
    "bias_mgdl": "bias [mg/dL]",
    "rmse_vs_oracle": "RMSE / oracle RMSE [-]",
}


def _models(frame: pd.DataFrame, models: Sequence[str] | None) -> list[str]:
    present = list(dict.fromkeys(frame["model"].astype(str)))
    return [m for m in (models or present) if m in present]


@styled
def plot_sweep_curve(
    summary: pd.DataFrame,
    x: str,
    *,
    metric: str = "rmse_mgdl",
    models: Sequence[str] | None = None,
    log_x: bool | None = None,
    threshold: float | None = None,
    xlabel: str | None = None,
    title: str | None = None,
    ax: Axes | None = None,
) -> Axes:
    """A metric against a varied value, one line per model, with its band over seeds.

    Parameters
    ----------
    summary : pandas.DataFrame
        One row per scenario × model with the column ``x`` (numeric), ``model``,
        ``<metric>_mean``, ``<metric>_ci_low`` and ``<metric>_ci_high`` (the interval
        over seeds; NaN draws no band). [the metric's unit]
    x : str
        The varied column (e.g. ``"noise_scale"``).
    metric : str
        Metric stem (see :data:`METRIC_LABELS`).
    models : sequence of str, optional
        Models to draw, in legend order (default: all, in table order).
    log_x : bool, optional
        Logarithmic x axis (base 2); default when every x is positive.
    threshold : float, optional
        A horizontal reference line (e.g. 15 for a 15 % MARD limit). [the metric's unit]
    xlabel : str, optional
        x-axis label with its unit (default ``x``).
    title : str, optional
        Axes title.
    ax : matplotlib.axes.Axes, optional
        Axes to draw on; a new figure's by default.

    Returns
    -------
    matplotlib.axes.Axes
        One Line2D per model (label = the model's display name) and one
        PolyCollection band per model with a finite interval.
    """
    ax = new_axes(ax, figsize=(5.6, 4.0))
    t = summary.assign(_x=pd.to_numeric(summary[x], errors="coerce")).dropna(subset=["_x"])
    names = _models(t, models)
    colors = model_colors(names)
    xs_all = t["_x"].to_numpy(float)
    if log_x is None:
        log_x = bool(len(xs_all)) and bool(np.all(xs_all > 0))
    for m in names:
        g = t[t["model"] == m].sort_values("_x")
        xs = g["_x"].to_numpy(float)
        ys = g[f"{metric}_mean"].to_numpy(float)
        ax.plot(xs, ys, marker=model_marker(m), ms=5, lw=1.6, color=colors[m],
                label=model_label(m), zorder=3)
        lo = g.get(f"{metric}_ci_low")
        hi = g.get(f"{metric}_ci_high")
        if lo is not None and hi is not None:
            lo, hi = lo.to_numpy(float), hi.to_numpy(float)
            ok = np.isfinite(lo) & np.isfinite(hi)
            if ok.any():
                ax.fill_between(xs[ok], lo[ok], hi[ok], color=colors[m], alpha=0.18, lw=0,
                                zorder=2)
    if threshold is not None:
        unit = METRIC_LABELS.get(metric, "[]").rsplit("[", 1)[-1].rstrip("]")
        unit = "" if unit in ("", "-") else (unit if unit == "%" else f" {unit}")
        ax.axhline(threshold, color=GREY, ls="--", lw=1.0, zorder=1,
                   label=f"{threshold:g}{' ' if unit == '%' else ''}{unit} limit")
    if log_x:
        ax.set_xscale("log", base=2)
        ticks = np.unique(xs_all)
        ax.set_xticks(ticks)
        ax.set_xticklabels([f"{v:g}" for v in ticks])
        ax.minorticks_off()
    ax.set_xlabel(xlabel or x)
    ax.set_ylabel(METRIC_LABELS.get(metric, metric))
    ax.set_ylim(bottom=0.0)
    ax.grid(axis="y", color=GREY, alpha=0.25, lw=0.6)
    ax.legend(loc="upper left", fontsize=7.5)
    ax.set_title(title if title is not None else
                 f"{METRIC_LABELS.get(metric, metric).split(' [')[0]} vs {x} "
                 "(mean, 95 % CI over seeds)")
    return ax


@styled
def plot_ablation_bars(
    effects: pd.DataFrame,
    *,
    which: str = "off",
    models: Sequence[str] | None = None,
    unit: str = "mg/dL",
    title: str | None = None,
    ax: Axes | None = None,
) -> Axes:
    """ΔRMSE per noise source, one bar per model, with the interval over seeds.

    Parameters
    ----------
    effects : pandas.DataFrame
        One row per model × source with ``model``, ``source``, ``delta_<which>``,
        ``delta_<which>_ci_low``, ``delta_<which>_ci_high``. [``unit``]
    which : {"off", "only"}
        ``"off"``: metric(all on) − metric(source off), the source's cost on top of the
        others; ``"only"``: metric(source alone) − metric(all off).
    models : sequence of str, optional
        Models to draw (default: all).
    unit : str
        Unit of the deltas (for the axis label).
    title : str, optional
        Axes title.
    ax : matplotlib.axes.Axes, optional
        Axes to draw on; a new figure's by default.

    Returns
    -------
    matplotlib.axes.Axes
        One BarContainer per model (label = display name); sources on the y axis,
        largest mean effect (over the models) at the top.
    """
    if which not in ("off", "only"):
        raise ValueError(f"which must be 'off' or 'only', got {which!r}")
    col = f"delta_{which}"
    names = _models(effects, models)
    order = (effects[effects["model"].isin(names)].groupby("source", sort=False)[col].mean()
             .sort_values(ascending=True))
    sources = list(order.index)
    ax = new_axes(ax, figsize=(6.0, 0.32 * max(len(sources), 1) + 1.6))
    colors = model_colors(names)
    y = np.arange(len(sources), dtype=float)
    h = 0.8 / max(len(names), 1)
    for k, m in enumerate(names):
        g = effects[effects["model"] == m].set_index("source").reindex(sources)
        v = g[col].to_numpy(float)
        lo = g.get(f"{col}_ci_low")
        hi = g.get(f"{col}_ci_high")
        err = None
        if lo is not None and hi is not None:
            lo, hi = lo.to_numpy(float), hi.to_numpy(float)
            err = np.vstack([np.where(np.isfinite(lo), v - lo, 0.0),
                             np.where(np.isfinite(hi), hi - v, 0.0)])
            err = np.maximum(err, 0.0)
        ax.barh(y + (k - (len(names) - 1) / 2) * h, v, height=h, color=colors[m],
                label=model_label(m), xerr=err,
                error_kw={"elinewidth": 0.9, "capsize": 2, "ecolor": "#333333"})
    ax.axvline(0.0, color=GREY, lw=0.8)
    ax.set_yticks(y)
    ax.set_yticklabels([s.replace("_", " ") for s in sources])
    what = ("RMSE(all on) − RMSE(source off)" if which == "off" else
            "RMSE(source alone) − RMSE(all off)")
    ax.set_xlabel(f"ΔRMSE = {what} [{unit}]")
    ax.grid(axis="x", color=GREY, alpha=0.25, lw=0.6)
    ax.legend(loc="lower right", fontsize=7.5)
    ax.set_title(title if title is not None else
                 ("cost of each noise source on top of all others" if which == "off" else
                  "cost of each noise source on its own"))
    return ax


def figure_ablation(
    effects: pd.DataFrame, *, models: Sequence[str] | None = None, unit: str = "mg/dL"
) -> Figure:
    """Both ablation panels side by side (source switched off; source alone on)."""
    n = max(effects["source"].nunique(), 1)
    with plot_style():
        fig = Figure(figsize=(11.5, 0.32 * n + 1.8), layout="constrained")
        a, b = fig.subplots(1, 2, sharey=False)
    plot_ablation_bars(effects, which="off", models=models, unit=unit, ax=a)
    plot_ablation_bars(effects, which="only", models=models, unit=unit, ax=b)
    return fig


def figure_data_size(summary: pd.DataFrame, *, metric: str = "rmse_mgdl") -> Figure:
    """RMSE against training subjects, one panel per preset (``data-size`` study).

    Parameters
    ----------
    summary : pandas.DataFrame
        Summary of a ``data-size`` sweep: ``preset``, ``n_train_subjects``, ``model``
        and ``<metric>_mean`` / ``_ci_low`` / ``_ci_high``. [the metric's unit]
    metric : str
        Metric stem (see :data:`METRIC_LABELS`).

    Returns
    -------
    matplotlib.figure.Figure
        One Axes per preset, each with one line per model on a base-2 log x axis.
    """
    presets = list(dict.fromkeys(summary["preset"]))
    with plot_style():
        fig = Figure(figsize=(5.2 * max(len(presets), 1), 4.0), layout="constrained")
        axes = np.atleast_1d(fig.subplots(1, max(len(presets), 1), sharey=False))
    for ax, p in zip(axes, presets, strict=False):
        plot_sweep_curve(
            summary[summary["preset"] == p],
            "n_train_subjects",
            metric=metric,
            xlabel="training subjects [-]",
            title=f"preset {p}",
            ax=ax,
        )
    return fig


@styled
def plot_shift_bars(
    effects: pd.DataFrame,
    *,
    models: Sequence[str] | None = None,
    unit: str = "mg/dL",
    title: str | None = None,
    ax: Axes | None = None,
) -> Axes:
    """In-domain vs shifted test RMSE per domain shift and model.

    Parameters
    ----------
    effects : pandas.DataFrame
        One row per model × shift with ``model``, ``shift``, ``train_domain``,
        ``test_domain``, ``in_domain``, ``shifted``, ``delta_ci_low``,
        ``delta_ci_high`` (interval of shifted − in domain). [``unit``]
    models : sequence of str, optional
        Models to draw (default: all).
    unit : str
        Unit of the metric (for the axis label).
    title : str, optional
        Axes title.
    ax : matplotlib.axes.Axes, optional
        Axes to draw on; a new figure's by default.

    Returns
    -------
    matplotlib.axes.Axes
        Per model two BarContainers: in-domain (hatched, label "<model>, in domain")
        and shifted (solid, with the interval of the shift's effect added to the
        in-domain value).
    """
    names = _models(effects, models)
    shifts = list(dict.fromkeys(effects["shift"]))
    ax = new_axes(ax, figsize=(6.4, 4.6))
    colors = model_colors(names)
    x = np.arange(len(shifts), dtype=float)
    w = 0.8 / max(2 * len(names), 1)
    for k, m in enumerate(names):
        g = effects[effects["model"] == m].set_index("shift").reindex(shifts)
        ind = g["in_domain"].to_numpy(float)
        sh = g["shifted"].to_numpy(float)
        base = x + (2 * k - len(names) + 0.5) * w
        ax.bar(base, ind, width=w, color="white", edgecolor=colors[m], hatch="///",
               label=f"{model_label(m)}, in domain")
        err = None
        if "delta_ci_low" in g and "delta_ci_high" in g:
            lo = ind + g["delta_ci_low"].to_numpy(float)
            hi = ind + g["delta_ci_high"].to_numpy(float)
            err = np.maximum(np.vstack([np.nan_to_num(sh - lo), np.nan_to_num(hi - sh)]), 0.0)
        ax.bar(base + w, sh, width=w, color=colors[m], label=f"{model_label(m)}, shifted",
               yerr=err, error_kw={"elinewidth": 0.9, "capsize": 2, "ecolor": "#333333"})
    labels = []
    for s in shifts:
        row = effects[effects["shift"] == s].iloc[0]
        labels.append(f"{s}\ntrain {row['train_domain']}\ntest {row['test_domain']}"
                      .replace("degC", "°C"))
    ax.set_xticks(x)
    ax.set_xticklabels(labels, fontsize=8)
    ax.set_ylabel(f"RMSE [{unit}]")
    ax.grid(axis="y", color=GREY, alpha=0.25, lw=0.6)
    ax.set_ylim(bottom=0.0)
    ax.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.22),
              ncols=max(len(names), 1), frameon=False)
    ax.set_title(title if title is not None else "domain shift: in-domain vs shifted test")
    return ax
