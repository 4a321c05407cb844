"""Figure 1: characteristics of the simulated data.

Glucose by diabetes status, the NIR signal (log ADC code) against glucose per channel
with its correlation, and the distributions of the environment and of physiology. The
correlations are computed by the caller (the report layer) and passed in.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np
import pandas as pd
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from numpy.typing import ArrayLike

from .style import DATA_COLOR, GREY, STATUS_COLORS, new_axes, plot_style, styled

__all__ = [
    "plot_glucose_by_status",
    "plot_nir_vs_glucose",
    "plot_distribution",
    "plot_category_counts",
    "figure_data_characteristics",
    "figure_distributions",
]



@styled
def plot_glucose_by_status(
    glucose_mgdl: ArrayLike,
    status: ArrayLike,
    *,
    bins: int | Sequence[float] = 25,
    ax: Axes | None = None,
) -> Axes:
    """Stacked histogram of reference glucose, one colour per diabetes status.

    Parameters
    ----------
    glucose_mgdl : array_like
        Reference glucose of each snapshot. [mg/dL]
    status : array_like of str
        Diabetes status of each snapshot (e.g. ``normal``, ``type2``). [-]
    bins : int or sequence of float
        Histogram bins (count, or edges in mg/dL). [-]
    ax : matplotlib.axes.Axes, optional
        Axes to draw on; a new figure's by default.

    Returns
    -------
    matplotlib.axes.Axes
        The Axes, with one bar container per status.
    """
    ax = new_axes(ax)
    g = np.asarray(glucose_mgdl, dtype=float)
    s = np.asarray(status).astype(str)
    if g.shape != s.shape:
        raise ValueError(f"glucose and status differ in length: {g.shape} vs {s.shape}")
    order = [k for k in STATUS_COLORS if k in set(s)] + sorted(set(s) - set(STATUS_COLORS))
    fallback = iter(["#BDBDBD", "#8A8A8A", "#2B2B2B"])
    data = [g[s == k] for k in order]
    colors = [STATUS_COLORS.get(k) or next(fallback, GREY) for k in order]
    labels = [f"{k} (n = {len(d)})" for k, d in zip(order, data, strict=True)]
    if isinstance(bins, int) and g.size:
        bins = np.linspace(np.floor(g.min() / 10) * 10, np.ceil(g.max() / 10) * 10, bins + 1)
    ax.hist(data, bins=bins, stacked=True, color=colors, label=labels, edgecolor="white",
            linewidth=0.4)
    ax.set_xlabel("reference glucose [mg/dL]")
    ax.set_ylabel("snapshots [count]")
    ax.set_title("Glucose by diabetes status")
    ax.legend(title="status", loc="upper right")
    return ax


@styled
def plot_nir_vs_glucose(
    glucose_mgdl: ArrayLike,
    log_adc: ArrayLike,
    *,
    wavelength_nm: float,
    correlation: float | None = None,
    color: str | None = None,
    ax: Axes | None = None,
) -> Axes:
    """Scatter of one channel's log ADC code against reference glucose.

    Parameters
    ----------
    glucose_mgdl : array_like
        Reference glucose. [mg/dL]
    log_adc : array_like
        Natural log of the channel's ADC code, same length. [ln(code)]
    wavelength_nm : float
        The channel's LED wavelength, for the title. [nm]
    correlation : float, optional
        Pearson correlation of the two, computed by the caller, printed on the panel. [-]
    color : str, optional
        Marker colour.
    ax : matplotlib.axes.Axes, optional
        Axes to draw on; a new figure's by default.

    Returns
    -------
    matplotlib.axes.Axes
        The Axes, with one point per snapshot (one PathCollection).
    """
    ax = new_axes(ax)
    g = np.asarray(glucose_mgdl, dtype=float)
    y = np.asarray(log_adc, dtype=float)
    if g.shape != y.shape:
        raise ValueError(f"glucose and log_adc differ in length: {g.shape} vs {y.shape}")
    ax.scatter(g, y, s=9, alpha=0.55, color=color or DATA_COLOR, linewidths=0)
    ax.set_xlabel("glucose [mg/dL]")
    ax.set_ylabel("ln(ADC code) [-]")
    title = f"{wavelength_nm:g} nm"
    if correlation is not None and np.isfinite(correlation):
        title += f"  (r = {correlation:+.2f})"
    ax.set_title(title)
    return ax


@styled
def plot_distribution(
    values: ArrayLike,
    *,
    xlabel: str,
    bins: int = 25,
    log: bool = False,
    color: str | None = None,
    ax: Axes | None = None,
) -> Axes:
    """Histogram of one numeric variable.

    Parameters
    ----------
    values : array_like
        The values; NaNs are left out. [unit given in ``xlabel``]
    xlabel : str
        Axis label, with the unit in brackets (``"skin temperature [°C]"``).
    bins : int
        Number of bins. [-]
    log : bool
        Logarithmic bins and x axis (for illuminance, say). [-]
    color : str, optional
        Bar colour.
    ax : matplotlib.axes.Axes, optional
        Axes to draw on; a new figure's by default.

    Returns
    -------
    matplotlib.axes.Axes
        The Axes, with one bar per bin.
    """
    ax = new_axes(ax, figsize=(3.2, 2.6))
    v = np.asarray(values, dtype=float)
    v = v[np.isfinite(v)]
    if log:
        v = v[v > 0]
    edges: int | np.ndarray = bins
    if log and v.size:
        lo, hi = np.log10(v.min()), np.log10(v.max())
        edges = np.logspace(lo, hi if hi > lo else lo + 1, bins + 1)
    ax.hist(v, bins=edges, color=color or DATA_COLOR, edgecolor="white", linewidth=0.4)
    if log:
        ax.set_xscale("log")
    ax.set_xlabel(xlabel)
    ax.set_ylabel("count")
    return ax


@styled
def plot_category_counts(
    counts: Mapping[str, int] | pd.Series,
    *,
    xlabel: str,
    color: str | None = None,
    ax: Axes | None = None,
) -> Axes:
    """Bar chart of category counts (light source, Fitzpatrick type, ...).

    Parameters
    ----------
    counts : mapping of str to int
        Category -> count, in display order. [count]
    xlabel : str
        Axis label.
    color : str, optional
        Bar colour.
    ax : matplotlib.axes.Axes, optional
        Axes to draw on; a new figure's by default.

    Returns
    -------
    matplotlib.axes.Axes
        The Axes, with one bar per category.
    """
    ax = new_axes(ax, figsize=(3.2, 2.6))
    items = list(dict(counts).items())
    labels = [str(k) for k, _ in items]
    ax.bar(labels, [v for _, v in items], color=color or DATA_COLOR,
           edgecolor="white")
    ax.set_xlabel(xlabel)
    ax.set_ylabel("count")
    return ax


def figure_data_characteristics(
    glucose_mgdl: ArrayLike,
    status: ArrayLike,
    log_adc: Mapping[float, ArrayLike],
    correlations: Mapping[float, float],
) -> Figure:
    """Glucose by status and the log ADC of every channel against glucose.

    Parameters
    ----------
    glucose_mgdl : array_like
        Reference glucose. [mg/dL]
    status : array_like of str
        Diabetes status of each snapshot. [-]
    log_adc : mapping of float to array_like
        Wavelength -> ln(ADC code) of each snapshot. [nm -> ln(code)]
    correlations : mapping of float to float
        Wavelength -> Pearson r of glucose and ln(ADC code). [nm -> -]

    Returns
    -------
    matplotlib.figure.Figure
    """
    wls = list(log_adc)
    n = len(wls)
    with plot_style():
        fig = Figure(figsize=(11.0, 3.4 if n <= 4 else 6.2), layout="constrained")
        ncols = max(1, min(n, 4)) + 2
        nrows = 1 if n <= 4 else 2
        gs = fig.add_gridspec(nrows, ncols)
        plot_glucose_by_status(glucose_mgdl, status, ax=fig.add_subplot(gs[:, :2]))
        for k, wl in enumerate(wls):
            ax = fig.add_subplot(gs[k // (ncols - 2), 2 + k % (ncols - 2)])
            plot_nir_vs_glucose(glucose_mgdl, log_adc[wl], wavelength_nm=wl,
                                correlation=correlations.get(wl),
                                color=DATA_COLOR, ax=ax)
            if k % (ncols - 2):
                ax.set_ylabel("")
    return fig


def figure_distributions(
    panels: Sequence[Mapping[str, object]],
    *,
    title: str | None = None,
    ncols: int = 4,
) -> Figure:
    """A grid of distributions, one panel per variable.

    Parameters
    ----------
    panels : sequence of mapping
        One mapping per panel, either ``{"values": array, "xlabel": str, "log": bool}``
        (a histogram, :func:`plot_distribution`) or ``{"counts": mapping, "xlabel": str}``
        (a bar chart, :func:`plot_category_counts`).
    title : str, optional
        Figure title.
    ncols : int
        Panels per row. [-]

    Returns
    -------
    matplotlib.figure.Figure
    """
    n = max(1, len(panels))
    ncols = min(ncols, n)
    nrows = -(-n // ncols)
    with plot_style():
        fig = Figure(figsize=(2.75 * ncols, 2.3 * nrows + (0.3 if title else 0)),
                     layout="constrained")
        axes = fig.subplots(nrows, ncols, squeeze=False).ravel()
        for ax, panel in zip(axes, panels, strict=False):
            if "counts" in panel:
                plot_category_counts(panel["counts"], xlabel=str(panel["xlabel"]), ax=ax)
            else:
                plot_distribution(panel["values"], xlabel=str(panel["xlabel"]),
                                  log=bool(panel.get("log", False)), ax=ax)
        for ax in axes[len(panels):]:
            ax.set_axis_off()
        if not panels:
            axes[0].text(0.5, 0.5, "no variables to show", ha="center", va="center",
                         transform=axes[0].transAxes)
        if title:
            fig.suptitle(title)
    return fig
