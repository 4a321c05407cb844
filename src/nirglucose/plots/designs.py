"""Device-design figures: the best achievable RMSE against the number of LEDs.

The input is the ``wavelengths`` study's design table
(:func:`~nirglucose.evaluation.sweep.wavelengths.wavelength_designs`, the sweep's
``effects.csv``); nothing here computes a bound or a metric.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pandas as pd
from matplotlib.axes import Axes

from .style import OKABE_ITO, model_label, new_axes, styled

__all__ = ["plot_design_curve"]

_DETECTOR_COLORS = ("blue", "vermillion", "bluish_green", "reddish_purple", "orange", "sky_blue")


@styled
def plot_design_curve(
    designs: pd.DataFrame,
    *,
    models: Sequence[str] = ("oracle",),
    title: str | None = None,
    ax: Axes | None = None,
) -> Axes:
    """Best RMSE against LEDs per design, one colour per detector.

    For each detector and number of LEDs: the smallest device bound (solid), the
    smallest oracle-conditioned bound of the confirmed designs (dotted) and the best
    confirmed RMSE of each model in ``models`` (markers, dashed, with its 95 %
    interval).

    Parameters
    ----------
    designs : pandas.DataFrame
        One row per design × model with ``detector``, ``n_leds``,
        ``bound_rmse_mgdl``, ``oracle_bound_rmse_mgdl``, ``model``, ``rmse_mgdl``,
        ``rmse_ci_low``, ``rmse_ci_high``. [mg/dL]
    models : sequence of str
        Confirmed models drawn (default the oracle).
    title : str, optional
        Axes title.
    ax : matplotlib.axes.Axes, optional
        Axes to draw on; a new figure's by default.

    Returns
    -------
    matplotlib.axes.Axes
    """
    ax = new_axes(ax, figsize=(6.0, 4.2))
    markers = ("o", "s", "^", "D")
    for i, (det, d) in enumerate(designs.groupby("detector", sort=False)):
        color = OKABE_ITO[_DETECTOR_COLORS[i % len(_DETECTOR_COLORS)]]
        per_k = d.groupby("n_leds")
        k = np.array(sorted(per_k.groups), dtype=float)
        ax.plot(k, per_k["bound_rmse_mgdl"].min().reindex(k).to_numpy(), "-", color=color,
                label=f"{det}: device bound")
        if "oracle_bound_rmse_mgdl" in d:
            ax.plot(k, per_k["oracle_bound_rmse_mgdl"].min().reindex(k).to_numpy(), ":",
                    color=color, label=f"{det}: oracle-conditioned bound")
        for j, m in enumerate(models):
            dm = d[d["model"] == m]
            if dm.empty:
                continue
            best = dm.loc[dm.groupby("n_leds")["rmse_mgdl"].idxmin()].sort_values("n_leds")
            y = best["rmse_mgdl"].to_numpy(float)
            err = np.vstack([y - best["rmse_ci_low"].to_numpy(float),
                             best["rmse_ci_high"].to_numpy(float) - y])
            ax.errorbar(best["n_leds"].to_numpy(float) + 0.06 * (j - (len(models) - 1) / 2),
                        y, yerr=np.where(np.isfinite(err), err, 0.0), fmt=markers[j % 4] + "--",
                        color=color, capsize=2, markersize=4, linewidth=0.8,
                        label=f"{det}: {model_label(m)} RMSE")
    ax.set_xlabel("LEDs per detector [-]")
    ax.set_ylabel("best RMSE [mg/dL]")
    ax.set_ylim(bottom=0)
    ks = sorted(designs["n_leds"].unique())
    ax.set_xticks(ks)
    ax.legend(fontsize="x-small", ncol=1 if designs["detector"].nunique() < 2 else 2)
    if title:
        ax.set_title(title)
    return ax
