"""Figures of a device's twin: posterior intervals, posterior predictive checks and the
rank histograms of its simulation-based calibration.

The inputs are ``twin.json``'s entries and the calibration record
(``studies/records/twin_calibration.json``); nothing here computes a posterior.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from .style import GREY, OKABE_ITO, plot_style

__all__ = ["plot_posterior_intervals", "plot_ppc", "plot_rank_histogram",
           "figure_rank_histograms"]


def _axes(ax: Axes | None, size: tuple[float, float]) -> Axes:
    if ax is not None:
        return ax
    return Figure(figsize=size, layout="constrained").add_subplot()


def _unit_position(entry: dict[str, Any], value: float) -> float:
    """A value's position in its prior on the fitting scale, 0 (low) to 1 (high)."""
    prior = entry["prior"]
    lo, hi = prior["low"], prior["high"]
    if prior["scale"] == "log10":
        value, lo, hi = (np.log10(max(v, 1e-300)) for v in (value, lo, hi))
    return float((value - lo) / (hi - lo)) if hi > lo else 0.5


def plot_posterior_intervals(parameters: list[dict[str, Any]], ax: Axes | None = None) -> Axes:
    """Each parameter's 90 % posterior interval inside its prior (0 to 1 on its fitting
    scale), the median as a dot, the base scenario's value as a grey bar and the
    published magnitude as a black diamond; identified parameters in blue, the others
    (posterior ~ prior, or held at the prior) in grey.

    Parameters
    ----------
    parameters : list of dict
        ``twin.json``'s ``parameters`` entries.
    ax : matplotlib.axes.Axes, optional
        Where to draw (a new figure's when omitted).

    Returns
    -------
    matplotlib.axes.Axes
    """
    ax = _axes(ax, (7.0, 0.32 * len(parameters) + 1.2))
    with plot_style():
        for row, e in enumerate(parameters):
            y = len(parameters) - 1 - row
            colour = OKABE_ITO["blue"] if e["identified"] else GREY
            lo, mid, hi = (_unit_position(e, e[k]) for k in ("lower", "median", "upper"))
            ax.plot([lo, hi], [y, y], color=colour, lw=4, solid_capstyle="butt")
            ax.plot([mid], [y], "o", color=colour, ms=5)
            ax.plot([_unit_position(e, e["preset"])], [y], "|", color="0.3", ms=12)
            if e.get("published") is not None:
                ax.plot([_unit_position(e, e["published"])], [y], "D", color="black", ms=4)
        ax.set_yticks(range(len(parameters)))
        ax.set_yticklabels([e["key"] for e in reversed(parameters)], fontsize=7)
        ax.set_xlim(-0.02, 1.02)
        ax.set_xlabel("position in the prior (fitting scale) [-]")
        ax.set_title("posterior 90 % intervals (blue: identified)")
    return ax


def plot_ppc(ppc: dict[str, Any], ax: Axes | None = None) -> Axes:
    """The file's summaries against the twin's: each summary's file value as a dot, in
    units of the twin's central 90 % range (the band from -1 to 1); a dot outside the
    band is a feature of the file the twin does not reproduce.

    Parameters
    ----------
    ppc : dict
        ``twin.json``'s ``ppc`` entry.
    ax : matplotlib.axes.Axes, optional

    Returns
    -------
    matplotlib.axes.Axes
    """
    rows = ppc["summaries"]
    ax = _axes(ax, (7.0, 0.28 * len(rows) + 1.2))
    with plot_style():
        ax.axvspan(-1, 1, color="0.9")
        for y, s in enumerate(reversed(list(rows.values()))):
            half = max((s["twin_high"] - s["twin_low"]) / 2.0, 1e-12)
            pos = (s["file"] - (s["twin_high"] + s["twin_low"]) / 2.0) / half
            outside = abs(pos) > 1
            ax.plot([np.clip(pos, -4, 4)], [y], "o",
                    color=OKABE_ITO["vermillion"] if outside else OKABE_ITO["blue"])
        ax.set_yticks(range(len(rows)))
        ax.set_yticklabels(list(reversed(list(rows))), fontsize=7)
        ax.set_xlim(-4.2, 4.2)
        ax.set_xlabel("file's value in units of the twin's 90 % half-range [-]")
        ax.set_title("posterior predictive check")
    return ax


def plot_rank_histogram(ranks, n_draws: int, ax: Axes | None = None, *, bins: int = 10,
                        title: str = "") -> Axes:
    """Histogram of the truth's rank among ``n_draws`` posterior draws over calibration
    devices, with the uniform expectation and its 99 % band (binomial; Talts et al. 2018).

    Returns
    -------
    matplotlib.axes.Axes
    """
    from scipy.stats import binom

    ranks = np.asarray(ranks)
    ax = _axes(ax, (3.0, 2.2))
    expect = len(ranks) / bins
    lo, hi = binom.ppf([0.005, 0.995], len(ranks), 1.0 / bins)
    with plot_style():
        ax.axhspan(lo, hi, color="0.9")
        ax.axhline(expect, color="0.4", lw=1)
        ax.hist(ranks, bins=np.linspace(0, n_draws + 1, bins + 1), color=OKABE_ITO["blue"],
                alpha=0.8)
        ax.set_title(title, fontsize=7)
        ax.set_xlabel("rank of the truth [-]", fontsize=7)
    return ax


def figure_rank_histograms(record: dict[str, Any]) -> Figure:
    """One rank histogram per parameter of a calibration record."""
    params = record["parameters"]
    n = len(params)
    cols = min(n, 4)
    rows = int(np.ceil(n / cols))
    fig = Figure(figsize=(3.0 * cols, 2.4 * rows), layout="constrained")
    for i, (key, p) in enumerate(params.items()):
        ax = fig.add_subplot(rows, cols, i + 1)
        plot_rank_histogram(p["ranks"], record["n_draws"], ax,
                            title=f"{key}\ncoverage {p['coverage']:.2f}"
                                  + ("" if p["identified"] else " (not identified)"))
    return fig
