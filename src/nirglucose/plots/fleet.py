"""The fleet study's figure: RMSE against the tolerance scale, one line per variant.

The input is :func:`~nirglucose.evaluation.sweep.fleet.fleet_table`; nothing here computes a
metric.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
from matplotlib.figure import Figure

from .style import GREY, OKABE_ITO, model_label, plain_log_ticks, plot_style

__all__ = ["VARIANT_STYLES", "figure_fleet"]

#: Colour, marker and legend label of each fleet variant.
VARIANT_STYLES: dict[str, tuple[str, str, str]] = {
    "same-unit": (OKABE_ITO["black"], "s", "same unit (reference)"),
    "no-transfer": (OKABE_ITO["vermillion"], "o", "unseen unit, no transfer"),
    "bias": (OKABE_ITO["orange"], "^", "unseen unit, bias per channel"),
    "slope-bias": (OKABE_ITO["blue"], "D", "unseen unit, slope/bias per channel"),
}


def figure_fleet(table: pd.DataFrame, *, log_y: bool = True) -> Figure:
    """RMSE against tolerance scale, one panel per model, one line per variant.

    Parameters
    ----------
    table : pandas.DataFrame
        :func:`~nirglucose.evaluation.sweep.fleet.fleet_table`: ``tolerance_scale``,
        ``variant``, ``model``, ``rmse_mgdl``, ``rmse_ci_low``, ``rmse_ci_high``.
        [-, -, -, mg/dL, mg/dL, mg/dL]
    log_y : bool
        Logarithmic RMSE axis (the variants can differ tenfold).

    Returns
    -------
    matplotlib.figure.Figure
        One Axes per model, each with one Line2D per variant (label = the variant's
        legend label) and its 95 % interval as error bars.
    """
    models = list(dict.fromkeys(table["model"]))
    ys = table["rmse_mgdl"].to_numpy(float)
    ys = ys[np.isfinite(ys) & (ys > 0)]
    # an interval reaching below the axis (a t-interval over two seeds can) ends there
    floor = 0.5 * float(ys.min()) if log_y and ys.size else -np.inf
    with plot_style():
        fig = Figure(figsize=(4.4 * max(len(models), 1), 3.8), layout="constrained")
        axes = np.atleast_1d(fig.subplots(1, max(len(models), 1), sharey=True))
        for ax, m in zip(axes, models, strict=False):
            t = table[table["model"] == m]
            for v, g in t.groupby("variant", sort=False):
                color, marker, label = VARIANT_STYLES.get(str(v), (GREY, "x", str(v)))
                g = g.sort_values("tolerance_scale")
                x = g["tolerance_scale"].to_numpy(float)
                y = g["rmse_mgdl"].to_numpy(float)
                lo = np.clip(y - np.maximum(g["rmse_ci_low"].to_numpy(float), floor), 0, None)
                hi = np.clip(g["rmse_ci_high"].to_numpy(float) - y, 0, None)
                err = np.vstack([np.nan_to_num(lo), np.nan_to_num(hi)])
                ax.errorbar(x, y, yerr=err, color=color, marker=marker, ms=5, lw=1.5,
                            capsize=2.5, label=label, zorder=3)
            if log_y:
                ax.set_yscale("log")
                plain_log_ticks(ax.yaxis, table["rmse_mgdl"].to_numpy(float))
                ax.set_ylim(bottom=floor)
            ax.set_xlabel("tolerance scale (× stated part tolerances) [-]")
            ax.set_title(model_label(m))
            ax.grid(axis="y", color=GREY, alpha=0.25, lw=0.6)
        axes[0].set_ylabel("RMSE on the test units' subjects [mg/dL]")
        axes[0].legend(loc="upper left", fontsize=7.5)
    return fig
