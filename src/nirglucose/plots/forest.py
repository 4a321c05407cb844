"""Figure 12: RMSE with its 95 % confidence interval per model, study values marked."""

from __future__ import annotations

import numpy as np
import pandas as pd
from matplotlib.axes import Axes
from matplotlib.lines import Line2D
from matplotlib.transforms import offset_copy

from .style import GREY, model_colors, model_label, model_marker, new_axes, styled

__all__ = ["plot_rmse_forest"]


@styled
def plot_rmse_forest(
    table: pd.DataFrame,
    *,
    title: str | None = None,
    ax: Axes | None = None,
) -> Axes:
    """Forest plot: each model's RMSE and interval, with the study's value beside it.

    Parameters
    ----------
    table : pandas.DataFrame
        One row per model, top to bottom in display order, with ``model``,
        ``rmse_mgdl``, ``rmse_ci_low``, ``rmse_ci_high`` (this run) and optionally
        ``study_rmse_mgdl`` (the study's Table 1 value; NaN where the study has none).
        [mg/dL]
    title : str, optional
        Axes title.
    ax : matplotlib.axes.Axes, optional
        Axes to draw on; a new figure's by default.

    Returns
    -------
    matplotlib.axes.Axes
        The Axes: one error bar (an ErrorbarContainer) per model and one PathCollection
        of the study's values (when any is given).
    """
    t = table.reset_index(drop=True)
    ax = new_axes(ax, figsize=(6.4, 0.42 * max(len(t), 1) + 1.4))
    colors = model_colors(t["model"])
    y = np.arange(len(t))[::-1].astype(float)
    for k, row in t.iterrows():
        m = str(row["model"])
        lo, hi = row.get("rmse_ci_low", np.nan), row.get("rmse_ci_high", np.nan)
        err = None
        if np.isfinite(lo) and np.isfinite(hi):
            err = [[max(row["rmse_mgdl"] - lo, 0.0)], [max(hi - row["rmse_mgdl"], 0.0)]]
        # a dark edge keeps pale markers (the no-skill row's light grey) visible
        ax.errorbar([row["rmse_mgdl"]], [y[k]], xerr=err, fmt=model_marker(m), ms=7,
                    color=colors[m], ecolor=colors[m], mec="black", mew=0.6, elinewidth=1.6,
                    capsize=3, zorder=3)
    handles = [Line2D([], [], color="black", marker="o", ls="-", lw=1.6,
                      label="this run: RMSE, 95 % CI")]
    if "study_rmse_mgdl" in t and t["study_rmse_mgdl"].notna().any():
        s = t["study_rmse_mgdl"].to_numpy(float)
        ok = np.isfinite(s)
        ax.scatter(s[ok], y[ok] + 0.22, marker="D", s=30, facecolors="white",
                   edgecolors="black", linewidths=1.0, zorder=4)
        handles.append(Line2D([], [], ls="none", marker="D", mfc="white", mec="black",
                              label="study (Table 1, single split, n = 48)"))
    ax.set_yticks(y)
    ax.set_yticklabels([model_label(str(m)) for m in t["model"]])
    ax.set_ylim(-0.7, len(t) - 0.3)
    shown = np.concatenate([t[c].to_numpy(float) for c in
                            ("rmse_mgdl", "rmse_ci_high", "study_rmse_mgdl") if c in t])
    shown = shown[np.isfinite(shown)]
    ax.set_xlim(0.0, 1.08 * float(shown.max()) if shown.size else None)
    ax.grid(axis="x", color=GREY, alpha=0.25, lw=0.6)
    ax.set_xlabel("RMSE [mg/dL]")
    # under the x label, a fixed distance whatever the number of rows
    below = offset_copy(ax.transAxes, fig=ax.figure, y=-30, units="points")
    ax.legend(handles=handles, loc="upper center", bbox_to_anchor=(0.5, 0.0),
              bbox_transform=below, ncol=2, fontsize=7.5, frameon=False)
    ax.set_title(title if title is not None else "RMSE with 95 % confidence interval")
    return ax
