"""Figures 8-10: trade-offs between accuracy, physics depth, size and speed.

* radar of normalised scores per model (figure 8);
* accuracy against physics depth, bubble area proportional to the parameter count
  (figure 9);
* the efficiency landscape: parameters, multiply-accumulates and latency against
  RMSE, the Pareto front marked (figure 10).

Scores, indices and Pareto fronts are computed by the report layer and passed in.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
import pandas as pd
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from numpy.typing import ArrayLike

from ..models.labels import label
from .labels import label_points, place_labels
from .style import (
    GREY,
    model_colors,
    model_label,
    model_marker,
    new_axes,
    plain_log_ticks,
    plot_style,
    styled,
)

__all__ = [
    "figure_radar_grid",
    "plot_radar",
    "plot_physics_depth",
    "plot_efficiency",
    "figure_efficiency_landscape",
    "bubble_area",
]

#: Largest bubble area of :func:`plot_physics_depth`. [pt^2]
MAX_BUBBLE_PT2 = 2200.0
#: Smallest bubble area drawn (smaller ones are enlarged to stay visible). [pt^2]
MIN_BUBBLE_PT2 = 14.0


#: Line style of each reference row drawn as a horizontal line.
_REF_STYLE = {"oracle": ":", "mean": "--"}


def _reference_lines(ax: Axes, references: Mapping[str, float] | None
                     ) -> list[tuple[str, float]]:
    """Horizontal lines for reference rows (a bound or no skill), labelled at the right."""
    out = []
    shown = sorted(((n, float(v)) for n, v in (references or {}).items()
                    if v is not None and np.isfinite(v)), key=lambda nv: nv[1])
    for k, (name, v) in enumerate(shown):
        ax.axhline(v, color=GREY, ls=_REF_STYLE.get(name, "-."), lw=1.0, zorder=1)
        # neighbours in value alternate between the right and the left end of the line,
        # so that two close references do not print over each other
        right = k % 2 == 0
        ax.annotate(f"{label(name)}: {v:.1f}", (1.0 if right else 0.0, v),
                    xycoords=("axes fraction", "data"), xytext=(-2 if right else 2, 2),
                    textcoords="offset points", ha="right" if right else "left",
                    va="bottom", fontsize=7, color=GREY)
        out.append((name, v))
    return out


def _unit(v: np.ndarray) -> np.ndarray:
    """Values rescaled to [0, 1] over their finite range (0.5 when constant)."""
    v = np.asarray(v, dtype=float)
    finite = v[np.isfinite(v)]
    if not finite.size or np.ptp(finite) == 0:
        return np.full(v.shape, 0.5)
    return (v - finite.min()) / np.ptp(finite)


def bubble_area(n_parameters: ArrayLike, max_parameters: float) -> np.ndarray:
    """Marker area proportional to the parameter count, floored at :data:`MIN_BUBBLE_PT2`.

    Examples
    --------
    >>> bubble_area([1000, 500, 1], 1000).tolist()
    [2200.0, 1100.0, 14.0]
    """
    p = np.asarray(n_parameters, dtype=float)
    area = MAX_BUBBLE_PT2 * p / float(max_parameters) if max_parameters > 0 else p * 0
    return np.maximum(area, MIN_BUBBLE_PT2)


@styled
def _radar_angles(n: int) -> tuple[np.ndarray, np.ndarray]:
    """The ``n`` spoke angles [rad], and the same closed (first repeated at the end)."""
    angles = np.linspace(0.0, 2.0 * np.pi, n, endpoint=False)
    return angles, np.append(angles, angles[:1])


def _closed_radii(row: pd.Series) -> np.ndarray:
    """One model's scores as a closed polygon's radii, NaN drawn at 0. [-]"""
    r = np.nan_to_num(row.to_numpy(float), nan=0.0)
    return np.append(r, r[:1])


def _radar_frame(ax: Axes, angles: np.ndarray, names: list[str], *, pad: float,
                 **label_kw: Any) -> None:
    """Clockwise spokes from 12 o'clock, labelled ``names``, radius 0 to just over 1."""
    ax.set_theta_offset(np.pi / 2.0)
    ax.set_theta_direction(-1)
    ax.set_xticks(angles)
    ax.set_xticklabels(names, **label_kw)
    ax.tick_params(axis="x", pad=pad)
    ax.set_ylim(0.0, 1.05)


def plot_radar(scores: pd.DataFrame, *, title: str | None = None, ax: Axes | None = None) -> Axes:
    """Radar (spider) chart of normalised scores, one polygon per model.

    Parameters
    ----------
    scores : pandas.DataFrame
        Index: model names; columns: the axes (e.g. ``RMSE``, ``MARD``, ``Clarke A``,
        ``±15 %``, ``parameters``, ``latency``); values in [0, 1] with 1 the best model
        on that axis, normalised by the caller. NaN values are drawn at 0. [-]
    title : str, optional
        Axes title.
    ax : matplotlib.axes.Axes, optional
        A *polar* Axes to draw on; a new figure's by default.

    Returns
    -------
    matplotlib.axes.Axes
        The polar Axes, with one outline (a Line2D) and one fill per model.
    """
    ax = new_axes(ax, figsize=(5.6, 4.6), projection="polar")
    if getattr(ax, "name", "") != "polar":
        raise ValueError("plot_radar needs a polar Axes (projection='polar')")
    axes_names = [str(c) for c in scores.columns]
    n = len(axes_names)
    angles, closed = _radar_angles(n)
    colors = model_colors(scores.index)
    for model, row in scores.iterrows():
        r = _closed_radii(row)
        ax.plot(closed, r, color=colors[model], lw=1.4, marker=model_marker(str(model)),
                ms=4, label=model_label(str(model)))
        ax.fill(closed, r, color=colors[model], alpha=0.08)
    _radar_frame(ax, angles, axes_names, pad=11)
    ax.set_yticks([0.25, 0.5, 0.75, 1.0])
    ax.set_yticklabels(["0.25", "0.5", "0.75", "1"], fontsize=7, color=GREY)
    ax.set_rlabel_position(90.0 / max(n, 1))
    ax.legend(loc="upper left", bbox_to_anchor=(1.08, 1.02), fontsize=7.5)
    ax.set_title(title if title is not None else "Normalised scores (1 = best on each axis)",
                 pad=18)
    return ax


#: Outline colour of the other models in a radar small multiple (context, not data ink).
_OTHERS_GREY = "#C8C8C8"


def figure_radar_grid(scores: pd.DataFrame, *, ncols: int = 3) -> Figure:
    """Radar small multiples: one polar panel per model, the others in thin grey.

    Parameters
    ----------
    scores : pandas.DataFrame
        As for :func:`plot_radar`. [-]
    ncols : int
        Panels per row. [-]

    Returns
    -------
    matplotlib.figure.Figure
        One polar Axes per model: its polygon filled in its colour, every other model's
        outline thin and grey for comparison. No mean score: averaging accuracy and cost
        axes weighs them by an arbitrary scale.
    """
    models = [str(m) for m in scores.index]
    ncols = max(1, min(ncols, len(models)))
    nrows = -(-len(models) // ncols)
    names = [str(c) for c in scores.columns]
    angles, closed = _radar_angles(len(names))
    colors = model_colors(scores.index)
    radii = {m: _closed_radii(scores.loc[m]) for m in models}
    with plot_style():
        fig = Figure(figsize=(3.3 * ncols, 3.1 * nrows), layout="constrained")
        for i, model in enumerate(models):
            ax = fig.add_subplot(nrows, ncols, i + 1, projection="polar")
            for other in models:
                if other != model:
                    ax.plot(closed, radii[other], color=_OTHERS_GREY, lw=0.7, zorder=1)
            ax.plot(closed, radii[model], color=colors[model], lw=1.8, zorder=3,
                    marker=model_marker(model), ms=3.5)
            ax.fill(closed, radii[model], color=colors[model], alpha=0.25, zorder=2)
            missing = scores.loc[model].isna().to_numpy()  # drawn at 0: say it is missing
            _radar_frame(ax, angles, [f"{n}\n(not counted)" if miss else n
                                      for n, miss in zip(names, missing, strict=True)],
                         pad=1, fontsize=7.5)
            ax.set_yticks([0.5, 1.0])
            ax.set_yticklabels([])
            ax.set_title(model_label(model), fontsize=9, pad=10)
    return fig


@styled
def plot_physics_depth(
    table: pd.DataFrame,
    *,
    depth_labels: Mapping[float, str] | None = None,
    references: Mapping[str, float] | None = None,
    title: str | None = None,
    ax: Axes | None = None,
) -> Axes:
    """Accuracy against physics depth, bubble area proportional to parameters.

    Parameters
    ----------
    table : pandas.DataFrame
        One row per model with ``model``, ``physics_depth`` (ordinal level, int),
        ``rmse_mgdl`` and ``n_parameters``; optionally ``on_front`` (bool: on the
        parameters–RMSE Pareto front, computed by the caller) and ``x_offset`` (a
        horizontal nudge separating models of the same depth). [-, -, mg/dL, -]
    depth_labels : mapping of float to str, optional
        Tick label of each depth level.
    references : mapping of str to float, optional
        Reference rows (the oracle's bound, the no-skill mean) drawn as horizontal
        lines, not as competitors. [mg/dL]
    title : str, optional
        Axes title.
    ax : matplotlib.axes.Axes, optional
        Axes to draw on; a new figure's by default.

    Returns
    -------
    matplotlib.axes.Axes
        The Axes, with one PathCollection (a bubble) per model. Labels are placed by
        :func:`~nirglucose.plots.labels.place_labels` (by the caller when it passed
        ``ax``).
    """
    own = ax is None
    ax = new_axes(ax, figsize=(7.0, 4.4))
    t = table.reset_index(drop=True)
    pmax = float(np.nanmax(t["n_parameters"].to_numpy(float))) if len(t) else 1.0
    front = t["on_front"].to_numpy(bool) if "on_front" in t else np.zeros(len(t), bool)
    _draw_bubbles(ax, t, pmax, front)
    present = set(t["physics_depth"])  # a level no drawn model has gets no tick
    levels = sorted(v for v in (depth_labels or present) if v in present)
    ax.set_xticks(levels)
    ax.set_xticklabels([(depth_labels or {}).get(v, str(v)) for v in levels], fontsize=7.5)
    if levels:  # most physics on the left, as the study orders its methods
        ax.set_xlim(max(levels) + 0.8, min(levels) - 0.8)
    y = t["rmse_mgdl"].to_numpy(float)
    lines = _reference_lines(ax, references)
    # the reference lines too: a no-skill line above the data must not fall off the axes
    top = max(([float(np.nanmax(y))] if y.size else [1.0]) + [v for _, v in lines])
    ax.set_ylim(0.0, 1.25 * top)  # from zero: differences keep their true proportion
    _bubble_legend(ax, pmax, bool(front.any()), [name for name, _ in lines])
    ax.set_xlabel("physics depth: how much of the forward model a method uses "
                  "(most on the left, none on the right)")
    ax.set_ylabel("RMSE [mg/dL]")
    ax.set_title(title if title is not None else "Accuracy vs physics depth")
    if own:
        place_labels(ax.figure)
    return ax


def _draw_bubbles(ax: Axes, t: pd.DataFrame, pmax: float, front: np.ndarray) -> None:
    """One bubble per model at its depth (nudged by ``x_offset``), Pareto ones ringed, labelled."""
    colors = model_colors(t["model"])
    areas = bubble_area(t["n_parameters"].to_numpy(float), pmax)
    offset = t["x_offset"].to_numpy(float) if "x_offset" in t else np.zeros(len(t))
    x = t["physics_depth"].to_numpy(float) + offset
    # biggest first, so small bubbles stay on top and visible
    for k in np.argsort(-areas, kind="stable"):
        row = t.iloc[k]
        ax.scatter([x[k]], [row["rmse_mgdl"]], s=areas[k], color=colors[row["model"]],
                   alpha=0.55, edgecolors=colors[row["model"]], linewidths=0.8, zorder=3)
        if front[k]:  # a black ring around the bubble, clear of its translucent fill
            ax.scatter([x[k]], [row["rmse_mgdl"]], s=max(1.6 * areas[k], 110.0),
                       facecolors="none", edgecolors="black", linewidths=1.5, zorder=4)
    label_points(ax, x, t["rmse_mgdl"].to_numpy(float),
                 [f"{lab}\n{int(p):,} params"
                  for lab, p in zip(t["label"] if "label" in t else map(model_label, t["model"]),
                                    t["n_parameters"], strict=True)],
                 marker_radius_pt=np.sqrt(np.where(front, np.maximum(1.6 * areas, 110.0),
                                                   areas)) / 2.0)


def _bubble_legend(ax: Axes, pmax: float, any_front: bool, references: Sequence[str]) -> None:
    """Legend right of the Axes: bubble sizes, the Pareto ring and the reference lines."""
    refs = [v for v in (1e2, 1e4, 1e6) if v <= 1.5 * pmax] or [pmax]
    handles = [Line2D([], [], ls="none", marker="o", ms=np.sqrt(bubble_area([v], pmax)[0]),
                      mfc="none", mec=GREY) for v in refs]
    labels = [f"{v:,.0f} parameters" for v in refs]
    if any_front:
        handles.append(Line2D([], [], ls="none", marker="o", ms=10, mfc="none", mec="black",
                              mew=1.5))
        labels.append("Pareto-optimal\n(parameters vs RMSE)")
    for name in references:
        handles.append(Line2D([], [], color=GREY, ls=_REF_STYLE.get(name, "-."), lw=1.0))
        labels.append(f"{label(name)}\n(reference, not a competitor)")
    biggest = float(np.sqrt(bubble_area([max(refs)], pmax)[0]))
    ax.legend(handles, labels, loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8,
              labelspacing=max(1.0, biggest / 14.0), borderpad=0.9,
              handlelength=max(2.0, biggest / 7.0), handletextpad=0.8,
              title="bubble area ∝ parameters", title_fontsize=8, frameon=False)


@styled
def plot_efficiency(
    x: ArrayLike,
    rmse_mgdl: ArrayLike,
    models: Sequence[str],
    *,
    on_front: ArrayLike | None = None,
    xlabel: str,
    log_x: bool = False,
    references: Mapping[str, float] | None = None,
    title: str | None = None,
    ax: Axes | None = None,
) -> Axes:
    """RMSE against a cost (parameters, latency, ...), the Pareto front marked.

    Parameters
    ----------
    x : array_like
        The cost of each model (lower is better). [unit in ``xlabel``]
    rmse_mgdl : array_like
        RMSE of each model. [mg/dL]
    models : sequence of str
        Model names, same order. [-]
    on_front : array_like of bool, optional
        Whether each model is on the Pareto front (no other model has both lower
        cost and lower RMSE), computed by the caller; those are joined by a step line.
    xlabel : str
        Axis label with unit.
    log_x : bool
        Logarithmic cost axis. [-]
    references : mapping of str to float, optional
        Reference rows drawn as horizontal lines, not as points. [mg/dL]
    title : str, optional
        Axes title.
    ax : matplotlib.axes.Axes, optional
        Axes to draw on; a new figure's by default.

    Returns
    -------
    matplotlib.axes.Axes
        The Axes, with one PathCollection per model and, when a front is given, one
        line through it. The y axis starts at 0. Labels are placed by
        :func:`~nirglucose.plots.labels.place_labels` (by the caller when it passed
        ``ax``).
    """
    own = ax is None
    ax = new_axes(ax, figsize=(4.4, 3.6))
    xv = np.asarray(x, dtype=float)
    yv = np.asarray(rmse_mgdl, dtype=float)
    names = list(models)
    if not (xv.shape == yv.shape == (len(names),)):
        raise ValueError(f"x, rmse_mgdl and models differ in length: {xv.size}, {yv.size}, "
                         f"{len(names)}")
    colors = model_colors(names)
    front = np.zeros(len(names), bool) if on_front is None else np.asarray(on_front, bool)
    for k, m in enumerate(names):
        ax.scatter([xv[k]], [yv[k]], s=55 if front[k] else 40, color=colors[m],
                   marker=model_marker(m), edgecolors="black" if front[k] else "none",
                   linewidths=1.2, zorder=3, label=model_label(m))
    if front.any():
        order = np.argsort(xv[front])
        fx, fy = xv[front][order], yv[front][order]
        ax.step(fx, fy, where="post", color="black", lw=0.9, ls="--", zorder=2,
                label="Pareto front")
    label_points(ax, xv, yv, [model_label(m) for m in names], marker_radius_pt=4.5,
                 fontsize=7.0)
    if log_x:
        ax.set_xscale("log")
        plain_log_ticks(ax.xaxis, xv)
    ax.margins(x=0.15)
    lines = _reference_lines(ax, references)
    top = max(([float(np.nanmax(yv))] if yv.size else [1.0]) + [v for _, v in lines])
    ax.set_ylim(0.0, 1.2 * top)  # from zero: a 5 mg/dL gap keeps its true proportion
    ax.set_xlabel(xlabel)
    ax.set_ylabel("RMSE [mg/dL]")
    ax.set_title(title if title is not None else "Efficiency")
    if own:
        place_labels(ax.figure)
    return ax


def figure_efficiency_landscape(table: pd.DataFrame,
                                references: Mapping[str, float] | None = None) -> Figure:
    """Parameters, multiply-accumulates and latency against RMSE, fronts marked.

    Parameters
    ----------
    table : pandas.DataFrame
        One row per model with ``model``, ``rmse_mgdl``, ``n_parameters``,
        ``macs_per_prediction``, ``latency_single_ms`` (optionally
        ``latency_single_p90_ms``, drawn as a whisker to the right) and the boolean fronts
        ``front_parameters``, ``front_macs``, ``front_latency``, all computed by the caller.
    references : mapping of str to float, optional
        Reference rows (oracle bound, no-skill mean) drawn as horizontal lines. [mg/dL]

    Returns
    -------
    matplotlib.figure.Figure
    """
    panels = (
        ("n_parameters", "front_parameters", "trainable parameters [-]", True,
         "Size vs accuracy"),
        ("macs_per_prediction", "front_macs", "multiply-accumulates per prediction [-]", True,
         "Arithmetic vs accuracy"),
        ("latency_single_ms", "front_latency", "single-sample latency [ms] (median–p90)", True,
         "Time on this machine vs accuracy"),
    )
    with plot_style():
        fig = Figure(figsize=(14.0, 4.6), layout="constrained")
        axes = fig.subplots(1, 3)
        models = list(table["model"])
        for ax, (col, front, xlabel, log_x, title) in zip(axes, panels, strict=True):
            x = table[col].to_numpy(float)
            ok = np.isfinite(x) & (x > 0 if log_x else True)
            plot_efficiency(x[ok], table["rmse_mgdl"].to_numpy(float)[ok],
                            [m for m, o in zip(models, ok, strict=True) if o],
                            on_front=table[front].to_numpy(bool)[ok] if front in table else None,
                            xlabel=xlabel, log_x=log_x, references=references,
                            title=title, ax=ax)
            if col == "latency_single_ms" and "latency_single_p90_ms" in table:
                p90 = table["latency_single_p90_ms"].to_numpy(float)[ok]
                ax.hlines(table["rmse_mgdl"].to_numpy(float)[ok], x[ok], p90, color=GREY,
                          lw=1.0, zorder=1)
            if not ok.any():  # results written before this cost was recorded
                ax.text(0.5, 0.5, f"{xlabel.split(' [')[0]}:\nnot in these results",
                        transform=ax.transAxes, ha="center", va="center", fontsize=8,
                        color=GREY)
            elif not ok.all():
                ax.text(0.98, 0.98, f"{int((~ok).sum())} model(s) without {xlabel.split(' [')[0]}",
                        transform=ax.transAxes, ha="right", va="top", fontsize=7, color=GREY)
        seen: dict[str, object] = {}
        for ax in axes:
            for h, lab in zip(*ax.get_legend_handles_labels(), strict=True):
                seen.setdefault(lab, h)
        labels = [lab for lab in seen if lab != "Pareto front"]
        labels += ["Pareto front"] if "Pareto front" in seen else []
        handles = [seen[lab] for lab in labels]
        if handles:
            fig.legend(handles, labels, loc="outside right center", fontsize=8)
        place_labels(fig)
    return fig
