"""Figure 11: wavelength utilisation, a models × wavelengths heatmap.

Each cell is the permutation importance of one channel for one model: how much the
held-out RMSE rises when that channel's values are shuffled (``importance.csv``).
"""

from __future__ import annotations

import numpy as np
import pandas as pd
from matplotlib.axes import Axes

from .style import model_label, new_axes, styled

__all__ = ["plot_wavelength_heatmap"]


@styled
def plot_wavelength_heatmap(
    matrix: pd.DataFrame,
    *,
    cmap: str = "cividis",
    annotate: bool = True,
    relative: bool = True,
    title: str | None = None,
    ax: Axes | None = None,
) -> Axes:
    """Heatmap of permutation importance, models in rows, wavelengths in columns.

    Parameters
    ----------
    matrix : pandas.DataFrame
        Index: model names; columns: wavelengths (numbers); values: RMSE increase when
        that channel is permuted, computed by the benchmark. NaN cells are left blank.
        [mg/dL]
    cmap : str
        Colour map (a perceptually uniform, colour-blind-safe one by default).
    annotate : bool
        Write each cell's value (ΔRMSE in mg/dL) in it. [-]
    relative : bool
        Colour each row on its own scale (its largest rise = 1, negatives as 0), so a
        model with rises of a few mg/dL is as readable as one with hundreds. [-]
    title : str, optional
        Axes title.
    ax : matplotlib.axes.Axes, optional
        Axes to draw on; a new figure's by default.

    Returns
    -------
    matplotlib.axes.Axes
        The Axes, with one image (an AxesImage) of ``matrix.shape`` cells and a colour bar.
    """
    nrow, ncol = matrix.shape
    ax = new_axes(ax, figsize=(1.3 * max(ncol, 1) + 3.6, 0.42 * max(nrow, 1) + 1.6))
    values = matrix.to_numpy(float)
    if relative:
        # each row on its own scale: its largest rise = 1 (rows without a positive rise
        # stay at 0), negative rises clipped to 0 in colour but printed as they are
        peak = np.nanmax(np.where(np.isfinite(values), values, -np.inf), axis=1, initial=0.0)
        scale = np.where(peak > 0, peak, 1.0)[:, None]
        shown = np.clip(values / scale, 0.0, 1.0)
        vmin, vmax = 0.0, 1.0
    else:
        shown = values
        finite = values[np.isfinite(values)]
        vmin = min(0.0, float(finite.min())) if finite.size else 0.0
        vmax = float(finite.max()) if finite.size else 1.0
        if vmax <= vmin:
            vmax = vmin + 1.0
    im = ax.imshow(np.ma.masked_invalid(shown), cmap=cmap, vmin=vmin, vmax=vmax,
                   aspect="auto", interpolation="nearest")
    ax.set_xticks(range(ncol))
    ax.set_xticklabels([f"{float(c):g}" for c in matrix.columns])
    ax.set_yticks(range(nrow))
    ax.set_yticklabels([model_label(str(m)) for m in matrix.index])
    ax.set_xlabel("LED wavelength [nm]")
    for side in ("top", "right", "left", "bottom"):
        ax.spines[side].set_visible(False)
    ax.tick_params(length=0)
    if annotate:
        mid = vmin + 0.6 * (vmax - vmin)
        for i in range(nrow):
            for j in range(ncol):
                v = values[i, j]
                if np.isfinite(v):
                    txt = f"{v:.0f}" if abs(v) >= 100 else f"{v:.1f}"
                    ax.text(j, i, txt, ha="center", va="center", fontsize=7.5,
                            color="black" if shown[i, j] > mid else "white")
    cbar = ax.figure.colorbar(im, ax=ax, fraction=0.06, pad=0.02)
    cbar.set_label("ΔRMSE / row maximum [-]" if relative else "ΔRMSE [mg/dL]")
    ax.set_title(title if title is not None else
                 "Wavelength utilisation: RMSE increase [mg/dL] when a channel is permuted")
    return ax
