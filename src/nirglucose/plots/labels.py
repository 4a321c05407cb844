"""Point labels that do not overprint one another.

:func:`label_points` records labels for the points of an Axes; :func:`place_labels`
settles the figure's layout, then places each label greedily at the nearest free spot
around its point: candidate offsets on rings of growing radius, the first whose
window extent (matplotlib's ``Text.get_window_extent``) clears the labels already
placed, the Axes' other texts and horizontal/vertical reference lines, every marker of
the Axes and the Axes' edges, and that is no nearer another point than its own (else a
reader takes it for that point's label). A label set away from its point
gets a thin leader line. The layout is frozen afterwards so the places stay valid.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from matplotlib.axes import Axes
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.text import Text
from matplotlib.transforms import Bbox

from .style import GREY

__all__ = ["label_points", "place_labels", "overlapping_texts"]

#: Ring radii of the candidate label positions, nearest first. [pt]
RING_RADII_PT: tuple[float, ...] = (4.0, 9.0, 15.0, 22.0, 30.0, 40.0, 52.0, 66.0, 82.0)
#: Directions tried on each ring (0 = right, counter-clockwise). [deg]
RING_ANGLES_DEG: tuple[float, ...] = (0, 180, 90, 270, 30, 150, 330, 210, 60, 120, 300, 240)
#: Radius beyond which a leader line joins the label to its point. [pt]
LEADER_FROM_PT = 14.0
#: Clearance kept around every placed label. [px]
PAD_PX = 1.5

_PENDING = "_nirglucose_pending_labels"


def label_points(ax: Axes, x: Sequence[float], y: Sequence[float], texts: Sequence[str], *,
                 marker_radius_pt: Sequence[float] | float = 4.0, fontsize: float = 7.0,
                 color: str = "#333333") -> None:
    """Record labels for points of ``ax``; :func:`place_labels` draws them.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        Axes holding the points.
    x, y : sequence of float
        Point positions. [data units]
    texts : sequence of str
        One label per point.
    marker_radius_pt : float or sequence of float
        Radius of each point's marker, kept clear of every label. [pt]
    fontsize : float
        Label font size. [pt]
    color : str
        Label colour.
    """
    r = np.broadcast_to(np.asarray(marker_radius_pt, dtype=float), (len(texts),))
    pending = getattr(ax, _PENDING, [])
    pending.extend({"x": float(a), "y": float(b), "text": str(t), "r": float(rr),
                    "fontsize": fontsize, "color": color}
                   for a, b, t, rr in zip(x, y, texts, r, strict=True))
    setattr(ax, _PENDING, pending)


def _renderer(fig: Figure):
    if not hasattr(fig.canvas, "get_renderer"):
        FigureCanvasAgg(fig)  # a Figure made without pyplot has no renderer yet
    return fig.canvas.get_renderer()


def _overlap(a: Bbox, b: Bbox) -> float:
    w = min(a.x1, b.x1) - max(a.x0, b.x0)
    h = min(a.y1, b.y1) - max(a.y0, b.y0)
    return w * h if w > 0 and h > 0 else 0.0


def _gap(a: Bbox, x: float, y: float) -> float:
    """Distance from the point (x, y) to the box ``a`` (0 inside it). [px]"""
    return float(np.hypot(max(a.x0 - x, 0.0, x - a.x1), max(a.y0 - y, 0.0, y - a.y1)))


def _misattributed(bb: Bbox, k: int, pts: np.ndarray) -> bool:
    """Whether the label box ``bb`` of point ``k`` sits nearer another point than its own
    (a reader would read it as that point's label)."""
    own = _gap(bb, *pts[k])
    return any(_gap(bb, *pts[j]) < own for j in range(len(pts)) if j != k)


def _outside(a: Bbox, frame: Bbox) -> float:
    inner = _overlap(a, frame)
    return a.width * a.height - inner


def _fixed_obstacles(ax: Axes, renderer) -> list[Bbox]:
    """What a label must not cover besides other labels and the markers: the texts
    already in ``ax`` (e.g. a reference line's value) and its horizontal or vertical
    lines (``axhline``/``axvline`` references; a line through several points is data and
    its bounding box would block too much)."""
    boxes = [Text.get_window_extent(t, renderer).padded(PAD_PX)
             for t in ax.texts if t.get_visible() and t.get_text().strip()]
    for line in ax.lines:
        x, y = (np.asarray(v, dtype=float) for v in line.get_data())
        if line.get_visible() and len(x) >= 2 and (np.ptp(x) == 0 or np.ptp(y) == 0):
            boxes.append(line.get_window_extent(renderer).padded(PAD_PX))
    return boxes


def _best_spot(ann, p: dict, k: int, pts: np.ndarray, markers: list[Bbox],
               placed: list[Bbox], frame: Bbox, renderer) -> tuple:
    """The first free spot of label ``ann`` of point ``k`` on the rings, nearest first, else
    the least bad: ``(dx, dy, ha, va, ring)`` in points."""
    best, best_cost = None, np.inf
    for ring in RING_RADII_PT:
        radius = p["r"] + ring
        for ang in RING_ANGLES_DEG:
            dx, dy = np.cos(np.radians(ang)), np.sin(np.radians(ang))
            ha = "left" if dx > 0.3 else "right" if dx < -0.3 else "center"
            va = "bottom" if dy > 0.3 else "top" if dy < -0.3 else "center"
            ann.set_position((radius * dx, radius * dy))
            ann.set_ha(ha)
            ann.set_va(va)
            bb = ann.get_window_extent(renderer).expanded(1.0, 1.0).padded(PAD_PX)
            cost = (sum(_overlap(bb, o) for o in placed)
                    + sum(_overlap(bb, m) for m in markers)
                    + 4.0 * _outside(bb, frame)
                    # nearer another marker than its own, with no leader line to say
                    # whose it is: read as that one's
                    + (0.5 * bb.width * bb.height
                       if ring <= LEADER_FROM_PT and _misattributed(bb, k, pts) else 0.0))
            if cost < best_cost - 1e-9:
                best, best_cost = (radius * dx, radius * dy, ha, va, ring), cost
            if cost == 0.0:
                return best
    return best


def place_labels(fig: Figure) -> None:
    """Place every recorded label of ``fig`` (see the module docstring); freeze the layout."""
    axes = [ax for ax in fig.axes if getattr(ax, _PENDING, None)]
    if not axes:
        return
    renderer = _renderer(fig)
    fig.draw_without_rendering()  # settle the constrained layout first
    px_per_pt = fig.dpi / 72.0
    for ax in axes:
        pending = getattr(ax, _PENDING)
        setattr(ax, _PENDING, [])
        frame = ax.get_window_extent(renderer)
        pts = ax.transData.transform(np.array([[p["x"], p["y"]] for p in pending]))
        markers = [Bbox.from_extents(px - p["r"] * px_per_pt, py - p["r"] * px_per_pt,
                                     px + p["r"] * px_per_pt, py + p["r"] * px_per_pt)
                   for (px, py), p in zip(pts, pending, strict=True)]
        placed: list[Bbox] = _fixed_obstacles(ax, renderer)
        # most crowded points first: they have the fewest free spots
        dist = np.hypot(*(pts[:, None, :] - pts[None, :, :]).transpose(2, 0, 1))
        order = np.argsort(np.sort(dist, axis=1)[:, 1] if len(pts) > 1 else np.zeros(1))
        for k in order:
            p = pending[k]
            ann = ax.annotate(p["text"], (p["x"], p["y"]), xytext=(0, 0),
                              textcoords="offset points", fontsize=p["fontsize"],
                              color=p["color"], zorder=5, annotation_clip=False)
            best = _best_spot(ann, p, k, pts, markers, placed, frame, renderer)
            assert best is not None
            ann.set_position(best[:2])
            ann.set_ha(best[2])
            ann.set_va(best[3])
            if best[4] > LEADER_FROM_PT:
                ann_arrow = {"arrowstyle": "-", "color": GREY, "lw": 0.5,
                             "shrinkA": 1.0, "shrinkB": p["r"] + 1.0}
                ann.remove()
                ann = ax.annotate(p["text"], (p["x"], p["y"]), xytext=best[:2],
                                  textcoords="offset points", fontsize=p["fontsize"],
                                  color=p["color"], zorder=5, ha=best[2], va=best[3],
                                  annotation_clip=False, arrowprops=ann_arrow)
            ann.update_positions(renderer)  # a fresh Annotation's text is placed on draw
            placed.append(Text.get_window_extent(ann, renderer).padded(PAD_PX))
    fig.set_layout_engine("none")  # the places were computed for this layout


def overlapping_texts(fig: Figure) -> list[tuple[str, str]]:
    """Pairs of non-empty texts inside each Axes of ``fig`` whose window extents overlap.

    Examples
    --------
    >>> from matplotlib.figure import Figure
    >>> fig = Figure(); ax = fig.add_subplot()
    >>> _ = ax.text(0.5, 0.5, "one"); _ = ax.text(0.5, 0.5, "two")
    >>> overlapping_texts(fig)
    [('one', 'two')]
    """
    renderer = _renderer(fig)
    fig.draw_without_rendering()
    out = []
    for ax in fig.axes:
        texts = [t for t in ax.texts if t.get_visible() and t.get_text().strip()]
        # the text itself: an Annotation's own extent also spans its leader line
        boxes = [Text.get_window_extent(t, renderer) for t in texts]
        for i in range(len(texts)):
            for j in range(i + 1, len(texts)):
                if _overlap(boxes[i], boxes[j]) > 0:
                    out.append((texts[i].get_text(), texts[j].get_text()))
    return out
