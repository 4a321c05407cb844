"""Wavelength utilisation: what each model loses when one LED is left out.

One panel per model: for each LED, the paired RMSE difference of the model refitted
without that LED minus the model with every LED, with its 95 % CI (``drop_one.csv``,
computed by :mod:`nirglucose.evaluation.benchmark.drop_one`). Above zero: the LED carries
information the others do not.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
import pandas as pd
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from .style import GREY, model_color, model_label, new_axes, plot_style, styled

__all__ = ["plot_drop_one", "figure_drop_one"]

#: Panels per row of :func:`figure_drop_one`.
_PER_ROW = 4


@styled
def plot_drop_one(
    table: pd.DataFrame,
    model: str,
    *,
    title: str | None = None,
    ax: Axes | None = None,
) -> Axes:
    """One model's RMSE lost per LED left out, with 95 % CIs.

    Parameters
    ----------
    table : pandas.DataFrame
        Rows of ``drop_one.csv``: ``model``, ``dropped_wavelength_nm`` [nm],
        ``delta_rmse_mgdl``, ``ci_low``, ``ci_high`` [mg/dL], optionally
        ``rmse_all_mgdl`` [mg/dL]; only ``model``'s rows are drawn.
    model : str
        The model whose panel this is.
    title : str, optional
        Axes title (default: the model's name and its RMSE with every LED).
    ax : matplotlib.axes.Axes, optional
        Axes to draw on; a new figure's by default.

    Returns
    -------
    matplotlib.axes.Axes
        One error bar per LED (``ax.containers``), filled where the CI excludes 0 and
        open where it does not, and a dashed line at 0.
    """
    t = table[table["model"] == model].sort_values("dropped_wavelength_nm")
    ax = new_axes(ax, figsize=(3.4, 3.0))
    x = np.arange(len(t), dtype=float)
    d = t["delta_rmse_mgdl"].to_numpy(float)
    lo, hi = t["ci_low"].to_numpy(float), t["ci_high"].to_numpy(float)
    color = model_color(model)
    excludes = (lo > 0) | (hi < 0)
    ax.axhline(0.0, color=GREY, lw=0.8, ls="--", zorder=1)
    for k in range(len(t)):
        ax.errorbar(x[k], d[k], yerr=[[d[k] - lo[k]], [hi[k] - d[k]]], fmt="o", ms=6,
                    color=color, mfc=color if excludes[k] else "white", mew=1.4,
                    capsize=3, lw=1.4, zorder=3)
    ax.set_xticks(x)
    ax.set_xticklabels([f"{w:g}" for w in t["dropped_wavelength_nm"].astype(float)])
    ax.set_xlim(-0.6, max(len(t) - 0.4, 0.6))
    ax.set_xlabel("LED left out [nm]")
    ax.set_ylabel("Δ RMSE without − with [mg/dL]")
    if title is None:
        title = model_label(model)
        if "rmse_all_mgdl" in t and len(t) and math.isfinite(float(t["rmse_all_mgdl"].iloc[0])):
            title += f"\n(all LEDs: {float(t['rmse_all_mgdl'].iloc[0]):.1f} mg/dL)"
    ax.set_title(title, fontsize=9)
    return ax


def figure_drop_one(table: pd.DataFrame, models: Sequence[str]) -> Figure:
    """Every model's :func:`plot_drop_one` panel, four per row, each on its own scale.

    Parameters
    ----------
    table : pandas.DataFrame
        ``drop_one.csv`` (see :func:`plot_drop_one`).
    models : sequence of str
        The models drawn, in panel order (those without rows are skipped).

    Returns
    -------
    matplotlib.figure.Figure
        One Axes per model drawn.
    """
    models = [m for m in models if (table["model"] == m).any()]
    n = max(len(models), 1)
    ncol = min(n, _PER_ROW)
    nrow = math.ceil(n / ncol)
    with plot_style():
        fig = Figure(figsize=(3.2 * ncol + 0.6, 2.9 * nrow + 0.4), layout="constrained")
        axes = np.atleast_1d(fig.subplots(nrow, ncol, squeeze=False)).ravel()
        for ax, m in zip(axes, models, strict=False):
            plot_drop_one(table, m, ax=ax)
        for ax in axes[len(models):]:
            ax.set_visible(False)
    return fig
