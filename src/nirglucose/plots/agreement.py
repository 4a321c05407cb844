"""Figures 5 and 6: agreement with the reference (Bland–Altman) and linearity.

Both take precomputed numbers: the Bland–Altman bias, limits of agreement and their
confidence intervals, and the fitted regression line, all from the report layer.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from numpy.typing import ArrayLike

from .style import GREY, OKABE_ITO, model_colors, model_label, new_axes, plot_style, styled

__all__ = [
    "plot_bland_altman",
    "plot_linearity",
    "figure_bland_altman",
    "figure_linearity",
]

Interval = tuple[float, float]


def _xy(x: ArrayLike, y: ArrayLike, names: str) -> tuple[np.ndarray, np.ndarray]:
    a = np.asarray(x, dtype=float).ravel()
    b = np.asarray(y, dtype=float).ravel()
    if a.shape != b.shape:
        raise ValueError(f"{names} differ in length: {a.size} vs {b.size}")
    return a, b


@styled
def _ba_span(loa_low: float, loa_high: float, difference_mgdl: ArrayLike) -> float:
    """Largest absolute limit of agreement or difference (1 with no differences). [mg/dL]"""
    d = np.asarray(difference_mgdl, float)
    return max(abs(float(loa_low)), abs(float(loa_high)),
               float(np.nanmax(np.abs(d))) if d.size else 1.0)


def plot_bland_altman(
    mean_mgdl: ArrayLike,
    difference_mgdl: ArrayLike,
    *,
    bias: float,
    loa_low: float,
    loa_high: float,
    bias_ci: Interval | None = None,
    loa_low_ci: Interval | None = None,
    loa_high_ci: Interval | None = None,
    color: str | None = None,
    ylim_mgdl: float | None = None,
    title: str | None = None,
    ax: Axes | None = None,
) -> Axes:
    """Bland–Altman plot: difference against mean, bias and 95 % limits of agreement.

    Parameters
    ----------
    mean_mgdl : array_like
        Mean of reference and prediction of each pair, ``(ref + pred) / 2``. [mg/dL]
    difference_mgdl : array_like
        Difference of each pair, ``pred - ref``. [mg/dL]
    bias, loa_low, loa_high : float
        Mean difference and the 95 % limits of agreement (bias ∓ 1.96 SD). [mg/dL]
    bias_ci, loa_low_ci, loa_high_ci : (float, float), optional
        95 % confidence intervals of the three lines, drawn as shaded bands. [mg/dL]
    color : str, optional
        Point colour.
    ylim_mgdl : float, optional
        Half-height of the y range (the same for every panel of a figure); by default
        1.2 times the largest of the limits and the differences. [mg/dL]
    title : str, optional
        Axes title; the bias and limits with their intervals are set under it, not
        over the lines.
    ax : matplotlib.axes.Axes, optional
        Axes to draw on; a new figure's by default.

    Returns
    -------
    matplotlib.axes.Axes
        The Axes: one PathCollection (one point per pair), the zero line, the bias
        and both limits (four lines) and one band per interval given.

    References
    ----------
    .. [1] Bland JM, Altman DG. Statistical methods for assessing agreement between two
       methods of clinical measurement. Lancet 327(8476):307-310, 1986.
       doi:10.1016/S0140-6736(86)90837-8
    """
    ax = new_axes(ax, figsize=(5.0, 3.6))
    m, d = _xy(mean_mgdl, difference_mgdl, "mean_mgdl and difference_mgdl")
    color = color or OKABE_ITO["blue"]
    ax.scatter(m, d, s=8, color=color, alpha=0.55, linewidths=0, zorder=3)
    ax.axhline(0.0, color=GREY, lw=0.7, ls=":")
    lines = (
        ("bias", bias, bias_ci, "-"),
        ("+1.96 SD", loa_high, loa_high_ci, "--"),
        ("−1.96 SD", loa_low, loa_low_ci, "--"),
    )
    parts = []
    for name, value, ci, ls in lines:
        ax.axhline(value, color="black", lw=1.0, ls=ls)
        txt = f"{value:+.1f}"
        if ci is not None and np.all(np.isfinite(ci)):
            ax.axhspan(ci[0], ci[1], color=color, alpha=0.15, lw=0)
            txt += f" [{ci[0]:+.0f}, {ci[1]:+.0f}]"
        parts.append((name, txt))
    half = ylim_mgdl if ylim_mgdl is not None else 1.2 * _ba_span(loa_low, loa_high, d)
    if np.isfinite(half) and half > 0:
        ax.set_ylim(-half, half)
    stats = (f"bias {parts[0][1]}\nLoA {parts[2][1]} / {parts[1][1]}")
    ax.set_xlabel("mean of reference and prediction [mg/dL]")
    ax.set_ylabel("prediction − reference [mg/dL]")
    ax.set_title(f"{title if title is not None else 'Bland–Altman'}\n{stats}",
                 fontsize=8.5)
    return ax


@styled
def plot_linearity(
    reference: ArrayLike,
    predicted: ArrayLike,
    *,
    slope: float,
    intercept: float,
    r_squared: float | None = None,
    slope_ci: Interval | None = None,
    lower: ArrayLike | None = None,
    upper: ArrayLike | None = None,
    interval_level: str = "90 %",
    color: str | None = None,
    title: str | None = None,
    ax: Axes | None = None,
) -> Axes:
    """Predicted against reference glucose, the unity line and the fitted line.

    Parameters
    ----------
    reference, predicted : array_like
        Reference and predicted glucose, same length. [mg/dL]
    slope : float
        Slope of the regression of predicted on reference, fitted by the caller. [-]
    intercept : float
        Its intercept. [mg/dL]
    r_squared : float, optional
        Coefficient of determination of that fit. [-]
    slope_ci : (float, float), optional
        95 % confidence interval of the slope. [-]
    lower, upper : array_like, optional
        Prediction interval of each point (e.g. ``lower90_mgdl``/``upper90_mgdl``),
        drawn as thin vertical bars. [mg/dL]
    interval_level : str
        Nominal level of those intervals, for the legend.
    color : str, optional
        Point and line colour.
    title : str, optional
        Axes title.
    ax : matplotlib.axes.Axes, optional
        Axes to draw on; a new figure's by default.

    Returns
    -------
    matplotlib.axes.Axes
        The Axes: one PathCollection (one point per pair), the unity line and the
        regression line.
    """
    ax = new_axes(ax, figsize=(4.4, 4.2))
    ref, pred = _xy(reference, predicted, "reference and predicted")
    color = color or OKABE_ITO["blue"]
    ax.scatter(ref, pred, s=8, color=color, alpha=0.55, linewidths=0, zorder=3)
    if lower is not None and upper is not None:
        lo_i, hi_i = _xy(lower, upper, "lower and upper")
        if lo_i.size != ref.size:
            raise ValueError(f"lower/upper have {lo_i.size} values, reference {ref.size}")
        covered = (ref >= lo_i) & (ref <= hi_i)
        ax.vlines(ref, lo_i, hi_i, color=color, alpha=0.18, lw=0.8, zorder=2,
                  label=f"{interval_level} interval ({100 * covered.mean():.0f} % cover)")
    both = np.concatenate([ref, pred])
    both = both[np.isfinite(both)]
    lo = float(np.floor(min(both.min(), 0.9 * ref.min()) / 25) * 25) if both.size else 0.0
    hi = float(np.ceil(1.03 * both.max() / 25) * 25) if both.size else 400.0
    lo = max(lo, 0.0) if both.size and both.min() >= 0 else lo
    grid = np.array([lo, hi])
    ax.plot(grid, grid, color=GREY, ls=":", lw=1.0, label="unity (y = x)")
    ax.plot(grid, intercept + slope * grid, color="black", lw=1.2,
            label="least-squares fit")
    text = f"slope {slope:.2f}"
    if slope_ci is not None and np.all(np.isfinite(slope_ci)):
        text += f" [{slope_ci[0]:.2f}, {slope_ci[1]:.2f}]"
    text += f"\nintercept {intercept:+.1f} mg/dL"
    if r_squared is not None and np.isfinite(r_squared):
        text += f"\nR² = {r_squared:.2f}"
    ax.text(0.97, 0.03, text, transform=ax.transAxes, ha="right", va="bottom", fontsize=7.5,
            bbox={"boxstyle": "round,pad=0.3", "fc": "white", "ec": GREY, "lw": 0.5})
    ax.set_xlim(lo, hi)
    ax.set_ylim(lo, hi)
    ax.set_aspect("equal")
    ax.legend(loc="upper left", fontsize=7.5)
    ax.set_xlabel("reference glucose [mg/dL]")
    ax.set_ylabel("predicted glucose [mg/dL]")
    ax.set_title(title if title is not None else "Linearity")
    return ax


def _per_model_figure(
    panels: Mapping[str, Mapping[str, object]],
    draw: Callable[..., Axes],
    panel_size: tuple[float, float],
    ncols: int,
    layout: str = "constrained",
) -> Figure:
    models = list(panels)
    n = max(1, len(models))
    ncols = min(ncols, n)
    nrows = -(-n // ncols)
    colors = model_colors(models)
    with plot_style():
        fig = Figure(figsize=(panel_size[0] * ncols, panel_size[1] * nrows), layout=layout)
        fig.get_layout_engine().set(h_pad=0.1)  # room between a title and the row above
        axes = fig.subplots(nrows, ncols, squeeze=False).ravel()
        for ax, model in zip(axes, models, strict=False):
            draw(ax, dict(panels[model]), colors[model], model_label(model))
        for k, ax in enumerate(axes):
            if k >= len(models):
                ax.set_axis_off()
            elif k < len(models) - ncols:
                ax.set_xlabel("")
        if not models:
            axes[0].text(0.5, 0.5, "no predictions", ha="center", va="center",
                         transform=axes[0].transAxes)
    return fig


def figure_bland_altman(panels: Mapping[str, Mapping[str, object]], *, ncols: int = 4) -> Figure:
    """One Bland–Altman panel per model, each on its own y range.

    A shared range is set by the worst model (the no-skill one spans ±250 mg/dL) and
    flattens every other panel's limits and intervals to a few pixels; each panel is
    therefore scaled to its own limits and differences.

    Parameters
    ----------
    panels : mapping of str to mapping
        Model -> keyword arguments of :func:`plot_bland_altman` (``mean_mgdl``,
        ``difference_mgdl``, ``bias``, ``loa_low``, ``loa_high`` and the optional
        intervals).
    ncols : int
        Panels per row. [-]

    Returns
    -------
    matplotlib.figure.Figure
    """

    def draw(ax: Axes, p: dict, color: str, title: str) -> Axes:
        return plot_bland_altman(p.pop("mean_mgdl"), p.pop("difference_mgdl"), color=color,
                                 title=title, ax=ax, **p)

    return _per_model_figure(panels, draw, (3.7, 3.3), ncols)


def figure_linearity(panels: Mapping[str, Mapping[str, object]], *, ncols: int = 4) -> Figure:
    """One linearity panel per model.

    Parameters
    ----------
    panels : mapping of str to mapping
        Model -> keyword arguments of :func:`plot_linearity` (``reference``,
        ``predicted``, ``slope``, ``intercept`` and optionally ``r_squared``,
        ``slope_ci``).
    ncols : int
        Panels per row. [-]

    Returns
    -------
    matplotlib.figure.Figure
    """

    def draw(ax: Axes, p: dict, color: str, title: str) -> Axes:
        return plot_linearity(p.pop("reference"), p.pop("predicted"), color=color,
                              title=title, ax=ax, **p)

    # "compressed" keeps equal-aspect panels packed without overlaps
    return _per_model_figure(panels, draw, (3.5, 3.5), ncols, layout="compressed")
