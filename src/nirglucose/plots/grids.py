"""Figures 3 and 4: Clarke and Parkes (consensus) error grids.

The Parkes boundary lines are drawn from the vertex lists of
:mod:`nirglucose.metrics.error_grids` (:data:`~nirglucose.metrics.PARKES_LINES`), so
the picture and the zone counts cannot disagree. The Clarke grid has no vertex list
there (its zones are inequalities); :data:`CLARKE_SEGMENTS` draws the lines that
:func:`~nirglucose.metrics.clarke_zones` documents, and the tests check each segment
against that function (points just either side fall in different zones).

Zone percentages are computed by the caller (the report layer, with
:func:`~nirglucose.metrics.zone_percentages`) and passed in for the legend.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Final

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.transforms import offset_copy
from numpy.typing import ArrayLike

from ..metrics import PARKES_LINES, ZONE_LABELS
from .style import GREY, OKABE_ITO, model_colors, model_label, new_axes, plot_style, styled

__all__ = [
    "CLARKE_MAX_MGDL",
    "PARKES_MAX_MGDL",
    "CLARKE_SEGMENTS",
    "CLARKE_LABEL_POSITIONS",
    "PARKES_LABEL_POSITIONS",
    "plot_clarke_grid",
    "plot_parkes_grid",
    "figure_error_grids",
]

#: Axis range of the Clarke grid as published. [mg/dL]
CLARKE_MAX_MGDL: Final = 400.0
#: Axis range of the Parkes grid as published. [mg/dL]
PARKES_MAX_MGDL: Final = 550.0

#: Clarke et al. (1987) zone boundaries as (reference, predicted) segments in mg/dL,
#: following the inequalities of :func:`nirglucose.metrics.clarke_zones`. The
#: diagonal (perfect agreement) is drawn separately.
CLARKE_SEGMENTS: Final[tuple[tuple[tuple[float, float], tuple[float, float]], ...]] = (
    ((0.0, 70.0), (70.0 / 1.2, 70.0)),  # A: both <= 70 (upper edge)
    ((70.0 / 1.2, 70.0), (CLARKE_MAX_MGDL / 1.2, CLARKE_MAX_MGDL)),  # A/B upper: p = 1.2 r
    ((70.0, 0.0), (70.0, 56.0)),  # A: both <= 70 (right edge)
    ((70.0, 56.0), (CLARKE_MAX_MGDL, 0.8 * CLARKE_MAX_MGDL)),  # A/B lower: p = 0.8 r
    ((70.0, 84.0), (70.0, CLARKE_MAX_MGDL)),  # D, E upper left: r = 70
    ((0.0, 180.0), (70.0, 180.0)),  # D/E upper left: p = 180
    ((70.0, 180.0), (290.0, CLARKE_MAX_MGDL)),  # B/C upper: p = r + 110
    ((130.0, 0.0), (180.0, 70.0)),  # B/C lower: p = 7/5 r - 182
    ((180.0, 0.0), (180.0, 70.0)),  # E lower right: r = 180
    ((180.0, 70.0), (CLARKE_MAX_MGDL, 70.0)),  # D, E lower right: p = 70
    ((240.0, 70.0), (240.0, 180.0)),  # D lower right: r = 240
    ((240.0, 180.0), (CLARKE_MAX_MGDL, 180.0)),  # D lower right: p = 180
)

#: Where the zone letters are written on the Clarke grid, (reference, predicted) in
#: mg/dL; the tests check each lies in its zone.
CLARKE_LABEL_POSITIONS: Final[dict[str, tuple[tuple[float, float], ...]]] = {
    "A": ((30.0, 18.0), (330.0, 345.0)),
    "B": ((300.0, 380.0), (370.0, 255.0)),
    "C": ((130.0, 370.0), (165.0, 15.0)),
    "D": ((25.0, 125.0), (370.0, 122.0)),
    "E": ((25.0, 370.0), (370.0, 22.0)),
}

#: Where the zone letters are written on the Parkes grids, by diabetes type. [mg/dL]
PARKES_LABEL_POSITIONS: Final[dict[int, dict[str, tuple[tuple[float, float], ...]]]] = {
    1: {
        "A": ((460.0, 480.0),),
        "B": ((260.0, 420.0), (440.0, 280.0)),
        "C": ((150.0, 480.0), (470.0, 160.0)),
        "D": ((72.0, 500.0), (480.0, 50.0)),
        "E": ((18.0, 500.0),),
    },
    2: {
        "A": ((460.0, 480.0),),
        "B": ((300.0, 470.0), (440.0, 280.0)),
        "C": ((160.0, 480.0), (470.0, 170.0)),
        "D": ((75.0, 500.0), (480.0, 55.0)),
        "E": ((18.0, 500.0),),
    },
}

_ZONE_TEXT = {"fontsize": 11, "fontweight": "bold", "color": GREY, "ha": "center",
              "va": "center"}


def _pairs(reference: ArrayLike, predicted: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    ref = np.asarray(reference, dtype=float).ravel()
    pred = np.asarray(predicted, dtype=float).ravel()
    if ref.shape != pred.shape:
        raise ValueError(f"reference and predicted differ in length: {ref.size} vs {pred.size}")
    return ref, pred


def _zone_legend(ax: Axes, scatter_label: str, zone_pct: Mapping[str, float] | None,
                 color: str, note: str = "") -> None:
    handles = [Line2D([], [], ls="none", marker="o", ms=5, color=color, alpha=0.8)]
    labels = [scatter_label]
    if zone_pct:
        for z in ZONE_LABELS:
            if z in zone_pct:
                handles.append(Line2D([], [], ls="none"))
                labels.append(f"zone {z}: {zone_pct[z]:5.1f} %")
    # below the grid (so that no zone and no point is hidden behind it), a fixed distance
    # under the x label whatever the panel size, two columns so that it stays within the
    # panel's width and clear of its neighbours
    below = offset_copy(ax.transAxes, fig=ax.figure, y=-30, units="points")
    ax.legend(handles, labels, loc="upper center", bbox_to_anchor=(0.5, 0.0),
              bbox_transform=below, ncol=2, handlelength=0.8, handletextpad=0.4,
              columnspacing=1.0, borderaxespad=0.0, fontsize=8.5, frameon=False,
              title=note or None, title_fontsize=7.5)


def _scatter(ax: Axes, ref: np.ndarray, pred: np.ndarray, lim: float, color: str,
             point_size: float) -> str:
    """Draw the points; return the legend's note on points beyond the axes ('' if none)."""
    ax.scatter(ref, pred, s=point_size, color=color, alpha=0.6, linewidths=0, zorder=3)
    outside = int(np.count_nonzero((ref > lim) | (pred > lim)))
    ax.set_xlim(0, lim)
    ax.set_ylim(0, lim)
    ax.set_aspect("equal")
    ax.set_xlabel("reference glucose [mg/dL]")
    ax.set_ylabel("predicted glucose [mg/dL]")
    # said in the legend: a note inside the grid would sit on a zone label
    return f"{outside} beyond {lim:g} mg/dL not shown" if outside else ""


@styled
def plot_clarke_grid(
    reference: ArrayLike,
    predicted: ArrayLike,
    *,
    zone_pct: Mapping[str, float] | None = None,
    label: str = "predictions",
    color: str | None = None,
    title: str | None = None,
    point_size: float = 10.0,
    ax: Axes | None = None,
) -> Axes:
    """Clarke error grid: the predictions over the zone lines, zones labelled.

    Parameters
    ----------
    reference, predicted : array_like
        Reference and predicted glucose, same length. [mg/dL]
    zone_pct : mapping of str to float, optional
        Share of points in each zone, computed by the caller
        (:func:`nirglucose.metrics.zone_percentages`), shown in the legend. [%]
    label : str
        Legend label of the points (a model name, say).
    color : str, optional
        Point colour.
    title : str, optional
        Axes title.
    point_size : float
        Marker area. [pt^2]
    ax : matplotlib.axes.Axes, optional
        Axes to draw on; a new figure's by default.

    Returns
    -------
    matplotlib.axes.Axes
        The Axes: one PathCollection with one point per pair, the diagonal and one
        line per entry of :data:`CLARKE_SEGMENTS`, ten zone letters.

    References
    ----------
    .. [1] Clarke WL et al. Evaluating clinical accuracy of systems for self-monitoring
       of blood glucose. Diabetes Care 10(5):622-628, 1987. doi:10.2337/diacare.10.5.622
    """
    ax = new_axes(ax, figsize=(4.6, 4.6))
    ref, pred = _pairs(reference, predicted)
    lim = CLARKE_MAX_MGDL
    ax.plot([0, lim], [0, lim], ls=":", color=GREY, lw=0.9)
    for (x0, y0), (x1, y1) in CLARKE_SEGMENTS:
        ax.plot([x0, x1], [y0, y1], color="black", lw=0.9)
    for zone, positions in CLARKE_LABEL_POSITIONS.items():
        for x, y in positions:
            ax.text(x, y, zone, **_ZONE_TEXT)
    color = color or OKABE_ITO["blue"]
    beyond = _scatter(ax, ref, pred, lim, color, point_size)
    _zone_legend(ax, f"{label} (n = {ref.size})", zone_pct, color, note=beyond)
    ax.set_title(title if title is not None else "Clarke error grid")
    return ax


@styled
def plot_parkes_grid(
    reference: ArrayLike,
    predicted: ArrayLike,
    *,
    zone_pct: Mapping[str, float] | None = None,
    diabetes_type: int = 1,
    label: str = "predictions",
    color: str | None = None,
    title: str | None = None,
    point_size: float = 10.0,
    ax: Axes | None = None,
) -> Axes:
    """Parkes (consensus) error grid: the predictions over the zone boundary lines.

    Parameters
    ----------
    reference, predicted : array_like
        Reference and predicted glucose, same length. [mg/dL]
    zone_pct : mapping of str to float, optional
        Share of points in each zone, computed by the caller
        (:func:`nirglucose.metrics.parkes_zones` then ``zone_percentages``). [%]
    diabetes_type : {1, 2}
        Which grid's lines (:data:`nirglucose.metrics.PARKES_LINES`). [-]
    label : str
        Legend label of the points.
    color : str, optional
        Point colour.
    title : str, optional
        Axes title.
    point_size : float
        Marker area. [pt^2]
    ax : matplotlib.axes.Axes, optional
        Axes to draw on; a new figure's by default.

    Returns
    -------
    matplotlib.axes.Axes
        The Axes: one PathCollection with one point per pair, the diagonal and one
        line per boundary polyline of the grid (seven), the zone letters.

    References
    ----------
    .. [1] Parkes JL et al. A new consensus error grid to evaluate the clinical
       significance of inaccuracies in the measurement of blood glucose. Diabetes Care
       23(8):1143-1148, 2000. doi:10.2337/diacare.23.8.1143
    """
    if diabetes_type not in PARKES_LINES:
        raise ValueError(f"diabetes_type must be one of {sorted(PARKES_LINES)}, got "
                         f"{diabetes_type!r}")
    ax = new_axes(ax, figsize=(4.6, 4.6))
    ref, pred = _pairs(reference, predicted)
    lim = PARKES_MAX_MGDL
    ax.plot([0, lim], [0, lim], ls=":", color=GREY, lw=0.9)
    for vertices in PARKES_LINES[diabetes_type].values():
        pts = np.asarray(vertices, dtype=float)
        ax.plot(pts[:, 0], pts[:, 1], color="black", lw=0.9)
    for zone, positions in PARKES_LABEL_POSITIONS[diabetes_type].items():
        for x, y in positions:
            ax.text(x, y, zone, **_ZONE_TEXT)
    color = color or OKABE_ITO["blue"]
    beyond = _scatter(ax, ref, pred, lim, color, point_size)
    _zone_legend(ax, f"{label} (n = {ref.size})", zone_pct, color, note=beyond)
    ax.set_title(title if title is not None else f"Parkes error grid, type {diabetes_type}")
    return ax


def figure_error_grids(
    grids: Mapping[str, Mapping[str, object]],
    *,
    kind: str = "clarke",
    diabetes_type: int = 1,
    ncols: int = 4,
) -> Figure:
    """One error grid per model.

    Parameters
    ----------
    grids : mapping of str to mapping
        Model -> ``{"reference": array, "predicted": array, "zone_pct": dict}`` (the
        percentages computed by the caller). [mg/dL, %]
    kind : {"clarke", "parkes"}
        Which grid. [-]
    diabetes_type : {1, 2}
        Parkes grid type. [-]
    ncols : int
        Panels per row. [-]

    Returns
    -------
    matplotlib.figure.Figure
    """
    if kind not in ("clarke", "parkes"):
        raise ValueError(f"kind must be 'clarke' or 'parkes', got {kind!r}")
    models = list(grids)
    n = max(1, len(models))
    ncols = min(ncols, n)
    nrows = -(-n // ncols)
    colors = model_colors(models)
    with plot_style():
        # constrained, not compressed: the layout then makes room for the legends below
        fig = Figure(figsize=(3.6 * ncols, 4.6 * nrows), layout="constrained")
        axes = fig.subplots(nrows, ncols, squeeze=False).ravel()
        for ax, model in zip(axes, models, strict=False):
            g = grids[model]
            kw = {"zone_pct": g.get("zone_pct"), "label": "predictions",
                  "color": colors[model], "title": model_label(model), "point_size": 6.0,
                  "ax": ax}
            if kind == "clarke":
                plot_clarke_grid(g["reference"], g["predicted"], **kw)
            else:
                plot_parkes_grid(g["reference"], g["predicted"], diabetes_type=diabetes_type,
                                 **kw)
        for k, ax in enumerate(axes):
            if k >= len(models):
                ax.set_axis_off()
                continue
            if k % ncols:
                ax.set_ylabel("")
            if k < len(models) - ncols:
                ax.set_xlabel("")
        if not models:
            axes[0].text(0.5, 0.5, "no predictions", ha="center", va="center",
                         transform=axes[0].transAxes)
    return fig

