"""Diagnostics a reader of scikit-learn expects, as small multiples on shared axes.

* :func:`figure_agreement_scatter`: predicted against reference glucose, one panel per
  model on one pair of axes, the Clarke zone lines as an overlay, the unity and fitted
  lines, and each model's zone shares and fit in the panel (one figure instead of a
  Clarke, a Parkes and a linearity grid that drew the same points three times);
* :func:`figure_residuals`: residual (reference − prediction) against prediction;
* :func:`figure_fold_spread`: RMSE of every fold of every repeat, per model.

Every number drawn is computed by the caller (the report layer).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np
import pandas as pd
from matplotlib.figure import Figure

from .grids import CLARKE_MAX_MGDL, CLARKE_SEGMENTS
from .style import GREY, model_colors, model_label, plot_style

__all__ = ["figure_agreement_scatter", "figure_residuals", "figure_fold_spread"]


def _grid(n: int, ncols: int) -> tuple[int, int]:
    ncols = max(1, min(ncols, n))
    return -(-max(n, 1) // ncols), ncols


def _panel_text(p: Mapping[str, object]) -> str:
    """Zone shares and the fit of one panel, in the panel's corner."""
    lines = []
    zones = p.get("clarke_pct") or {}
    if zones:
        lines.append("Clarke " + " ".join(
            f"{z} {zones[z]:.0f}" if zones[z] >= 0.5 else f"{z} <1" for z in "ABCDE"
            if zones.get(z, 0) > 0) + " %")
    parkes = p.get("parkes_a_pct")
    if parkes is not None and np.isfinite(parkes):
        lines.append(f"Parkes A {parkes:.1f} %")
    slope = p.get("slope")
    if slope is not None and np.isfinite(slope):
        ci = p.get("slope_ci")
        txt = f"slope {slope:.2f}"
        if ci is not None and np.all(np.isfinite(ci)):
            txt += f" [{ci[0]:.2f}, {ci[1]:.2f}]"
        r2 = p.get("r_squared")
        lines.append(txt + (f", R² {r2:.2f}" if r2 is not None and np.isfinite(r2) else ""))
    cover = p.get("coverage_pct")
    if cover is not None and np.isfinite(cover):
        lines.append(f"90 % interval covers {cover:.0f} %")
    return "\n".join(lines)


def figure_agreement_scatter(panels: Mapping[str, Mapping[str, object]], *, ncols: int = 4,
                             lim_mgdl: float = CLARKE_MAX_MGDL) -> Figure:
    """Predicted against reference glucose, one panel per model, shared axes.

    Parameters
    ----------
    panels : mapping of str to mapping
        Model -> ``reference`` and ``predicted`` (arrays) [mg/dL]; optionally
        ``clarke_pct`` (zone -> share) [%], ``parkes_a_pct`` [%], ``slope`` [-],
        ``intercept`` [mg/dL], ``slope_ci`` [-], ``r_squared`` [-], ``coverage_pct`` [%].
    ncols : int
        Panels per row. [-]
    lim_mgdl : float
        Both axes run from 0 to this (the Clarke grid's range); points beyond are
        counted in the panel. [mg/dL]

    Returns
    -------
    matplotlib.figure.Figure
        One Axes per model (sharing x and y), each with one PathCollection of points,
        the Clarke zone lines (grey), the unity line and the least-squares line.
    """
    models = list(panels)
    nrows, ncols = _grid(len(models), ncols)
    colors = model_colors(models)
    with plot_style():
        fig = Figure(figsize=(3.1 * ncols, 3.1 * nrows + 0.4), layout="constrained")
        axes = fig.subplots(nrows, ncols, squeeze=False, sharex=True, sharey=True).ravel()
        grid = np.array([0.0, lim_mgdl])
        for ax, model in zip(axes, models, strict=False):
            p = panels[model]
            ref = np.asarray(p["reference"], float)
            pred = np.asarray(p["predicted"], float)
            for (x0, y0), (x1, y1) in CLARKE_SEGMENTS:
                ax.plot([x0, x1], [y0, y1], color="#B0B0B0", lw=0.7, zorder=1)
            ax.plot(grid, grid, color=GREY, ls=":", lw=0.9, zorder=2)
            ax.scatter(ref, pred, s=5, color=colors[model], alpha=0.5, linewidths=0,
                       zorder=3)
            if p.get("slope") is not None and np.isfinite(p["slope"]):
                ax.plot(grid, p["intercept"] + p["slope"] * grid, color="black", lw=1.0,
                        zorder=4)
            beyond = int(np.count_nonzero((ref > lim_mgdl) | (pred > lim_mgdl)))
            text = _panel_text(p) + (f"\n{beyond} beyond {lim_mgdl:g} not shown"
                                     if beyond else "")
            ax.text(0.03, 0.97, text, transform=ax.transAxes, ha="left", va="top",
                    fontsize=6.5, zorder=5,
                    bbox={"boxstyle": "round,pad=0.25", "fc": "white", "ec": "none",
                          "alpha": 0.85})
            ax.set_title(f"{model_label(model)} (n = {ref.size})", fontsize=8.5)
            ax.set_xlim(0, lim_mgdl)
            ax.set_ylim(0, lim_mgdl)
            ax.set_aspect("equal")
        for ax in axes[len(models):]:
            ax.set_axis_off()
        fig.supxlabel("reference glucose [mg/dL]", fontsize=9)
        fig.supylabel("predicted glucose [mg/dL]", fontsize=9)
    return fig


def figure_residuals(panels: Mapping[str, Mapping[str, object]], *, ncols: int = 4
                     ) -> Figure:
    """Residual (reference − prediction) against prediction, one panel per model.

    Parameters
    ----------
    panels : mapping of str to mapping
        Model -> ``predicted`` and ``residual`` (arrays) [mg/dL], and optionally
        ``bin_centre`` and ``bin_median`` (the median residual in bins of prediction,
        drawn as a line) [mg/dL].
    ncols : int
        Panels per row. [-]

    Returns
    -------
    matplotlib.figure.Figure
        One Axes per model sharing both axes: the points, the zero line and the binned
        median line.
    """
    models = list(panels)
    nrows, ncols = _grid(len(models), ncols)
    colors = model_colors(models)
    with plot_style():
        fig = Figure(figsize=(3.1 * ncols, 2.5 * nrows + 0.4), layout="constrained")
        axes = fig.subplots(nrows, ncols, squeeze=False, sharex=True, sharey=True).ravel()
        for ax, model in zip(axes, models, strict=False):
            p = panels[model]
            ax.axhline(0.0, color=GREY, lw=0.8, ls=":")
            ax.scatter(p["predicted"], p["residual"], s=5, color=colors[model], alpha=0.5,
                       linewidths=0, zorder=3)
            if "bin_centre" in p:
                ax.plot(p["bin_centre"], p["bin_median"], color="black", lw=1.1, zorder=4)
            ax.set_title(model_label(model), fontsize=8.5)
        for ax in axes[len(models):]:
            ax.set_axis_off()
        fig.supxlabel("predicted glucose [mg/dL]", fontsize=9)
        fig.supylabel("reference − prediction [mg/dL]", fontsize=9)
    return fig


def figure_fold_spread(scores: pd.DataFrame, models: Sequence[str], *,
                       references: Mapping[str, float] | None = None) -> Figure:
    """RMSE of every fold of every repeat, one row per model: box and points.

    Parameters
    ----------
    scores : pandas.DataFrame
        ``model``, ``repeat``, ``fold``, ``rmse_mgdl`` (one row per fold and repeat).
        [-, -, -, mg/dL]
    models : sequence of str
        Models in display order (top first). [-]
    references : mapping of str to float, optional
        Vertical reference lines (label -> RMSE). [mg/dL]

    Returns
    -------
    matplotlib.figure.Figure
        One Axes: a horizontal box per model and one point per fold and repeat.
    """
    models = [m for m in models if (scores["model"] == m).any()]
    colors = model_colors(models)
    with plot_style():
        fig = Figure(figsize=(7.5, 0.42 * len(models) + 1.3), layout="constrained")
        ax = fig.add_subplot()
        data = [scores.loc[scores["model"] == m, "rmse_mgdl"].to_numpy(float) for m in models]
        y = np.arange(len(models), dtype=float)
        if models:
            ax.boxplot(data, positions=y, orientation="horizontal", widths=0.55,
                       showfliers=False, medianprops={"color": "black"},
                       boxprops={"color": GREY}, whiskerprops={"color": GREY},
                       capprops={"color": GREY})
        rng = np.random.default_rng(0)  # jitter only: where a point sits across its row
        for k, (m, v) in enumerate(zip(models, data, strict=True)):
            ax.scatter(v, k + rng.uniform(-0.18, 0.18, v.size), s=12, color=colors[m],
                       alpha=0.8, linewidths=0, zorder=3)
        for label, v in (references or {}).items():
            ax.axvline(v, color=GREY, ls="--", lw=0.8)
            ax.text(v, -0.7, f" {label}", fontsize=7, color=GREY, va="bottom")
        ax.set_yticks(y)
        ax.set_yticklabels([model_label(m) for m in models])
        ax.set_ylim(len(models) - 0.5, -0.9)
        ax.set_xlim(left=0)
        ax.set_xlabel("RMSE of one fold of one repeat [mg/dL]")
        ax.grid(axis="x", color="#DDDDDD", lw=0.6)
    return fig
