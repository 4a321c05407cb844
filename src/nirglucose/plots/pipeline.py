"""Figure 2: the data-generation pipeline as a block diagram.

The diagram is drawn from a description of the run's configuration (built by the
report layer from the resolved :class:`~nirglucose.config.ScenarioConfig`): columns of
boxes, left to right in the order the simulator applies its layers, each box listing
its settings and the noise sources it adds, with the switched-off ones struck out.
"""

from __future__ import annotations

import textwrap
from collections.abc import Mapping, Sequence

from matplotlib.axes import Axes
from matplotlib.patches import FancyArrowPatch, FancyBboxPatch

from .style import GREY, OKABE_ITO, new_axes, styled

__all__ = ["plot_pipeline", "pipeline_height_in", "STAGE_COLORS"]

#: Fill colour of each kind of stage box (light tints of the Okabe–Ito palette).
STAGE_COLORS: dict[str, str] = {
    "input": "#DCEEF9",  # sky blue tint
    "optics": "#D6EFE6",  # bluish green tint
    "hardware": "#FBE7C6",  # orange tint
    "output": "#EFEFEF",
}



def _box_lines(box: Mapping[str, object]) -> list[tuple[str, str, bool]]:
    """(text, colour, bold) of each line of a box."""
    lines: list[tuple[str, str, bool]] = [(str(box["title"]), "black", True)]
    for d in box.get("details", ()) or ():
        lines.append((str(d), "#222222", False))
    on = list(box.get("noise_on", ()) or ())
    off = list(box.get("noise_off", ()) or ())
    if on or off:
        lines.append(("noise sources:", "#222222", False))
        lines.extend((f"  \u2713 {name}", "#222222", False) for name in on)
        lines.extend((f"  \u2717 {name}" if name.endswith(")") else f"  \u2717 {name} (off)",
                      GREY, False) for name in off)
    return lines


def _wrap(lines: list[tuple[str, str, bool]], width: int) -> list[tuple[str, str, bool]]:
    out = []
    for text, color, bold in lines:
        indent = len(text) - len(text.lstrip(" "))
        parts = textwrap.wrap(text.strip(), width=width - indent) or [""]
        out.append((" " * indent + parts[0], color, bold))
        out.extend((" " * (indent + 4) + p, color, bold) for p in parts[1:])
    return out


def pipeline_height_in(columns: Sequence[Sequence[Mapping[str, object]]]) -> float:
    """Figure height (inches) that fits the tallest column at 8 pt text."""
    rows = max((sum(len(_box_lines(b)) + 2.2 for b in col) for col in columns), default=8)
    return 0.16 * rows + 0.7


#: Horizontal gap between columns. [% of the width]
_COLUMN_GAP = 5.0
#: Text size of the box lines (titles 0.8 pt larger). [pt]
_FONT_PT = 8.0


def _column_width(ncol: int) -> float:
    """Width of one column of boxes. [% of the width]"""
    return (100.0 - _COLUMN_GAP * (ncol - 1)) / ncol


def _chars_per_box(ax: Axes, width: float, fontsize: float) -> int:
    """Characters that fit in a box: its width in points over an average glyph width."""
    frac = ax.get_position().width
    if ax.figure.get_layout_engine() is not None:  # the layout will widen a lone Axes
        frac = max(frac, 0.95)
    box_pt = ax.figure.get_figwidth() * frac * 72.0 * width / 100.0
    return max(12, int(box_pt / (0.52 * fontsize)) - 2)


def _draw_boxes(ax: Axes, columns: Sequence[Sequence[Mapping[str, object]]],
                wrapped: list[list[list[tuple[str, str, bool]]]], width: float, gap: float,
                fontsize: float) -> list[list[tuple[float, float, float, float]]]:
    """Draw each column's boxes, centred vertically; (x, y, width, height) of each box.

    The vertical layout is in text-line units; the y limits fit the tallest column.
    """
    pad, vgap = 0.6, 1.0
    heights = [[len(lines) + 2 * pad for lines in col] for col in wrapped]
    totals = [sum(h) + vgap * (len(h) - 1) for h in heights]
    tallest = max(totals)
    ax.set_xlim(0, 100)
    ax.set_ylim(-tallest / 2 - 0.3, tallest / 2 + 0.3)
    extents: list[list[tuple[float, float, float, float]]] = []
    for c, col in enumerate(columns):
        x0 = c * (width + gap)
        y = totals[c] / 2.0
        col_ext = []
        for box, lines, h in zip(col, wrapped[c], heights[c], strict=True):
            y0 = y - h
            face = STAGE_COLORS.get(str(box.get("kind", "input")), STAGE_COLORS["input"])
            ax.add_patch(FancyBboxPatch((x0, y0), width, h,
                                        boxstyle="round,pad=0,rounding_size=0.5",
                                        fc=face, ec=GREY, lw=0.8, mutation_aspect=0.15))
            for k, (text, color, bold) in enumerate(lines):
                ax.text(x0 + 1.0, y - pad - (k + 0.5), text, ha="left", va="center",
                        fontsize=fontsize + (0.8 if bold else 0), color=color,
                        fontweight="bold" if bold else "normal")
            col_ext.append((x0, y0, width, h))
            y = y0 - vgap
        extents.append(col_ext)
    return extents


def _draw_arrows(ax: Axes, extents: list[list[tuple[float, float, float, float]]]) -> None:
    """An arrow from every box of a column to every box of the next."""
    for left, right in zip(extents[:-1], extents[1:], strict=True):
        for x0, y0, w, h in left:
            for x1, y1, _, h1 in right:
                ax.add_patch(FancyArrowPatch(
                    (x0 + w, y0 + h / 2), (x1, y1 + h1 / 2), arrowstyle="-|>",
                    mutation_scale=10, color=OKABE_ITO["black"], lw=0.9, shrinkA=0, shrinkB=1,
                ))


@styled
def plot_pipeline(
    columns: Sequence[Sequence[Mapping[str, object]]],
    *,
    title: str | None = None,
    ax: Axes | None = None,
) -> Axes:
    """Draw the simulator's layers as boxes joined by arrows.

    Parameters
    ----------
    columns : sequence of sequence of mapping
        Columns of boxes, left to right. Each box is a mapping with ``title`` (str),
        optional ``details`` (list of str: settings, with units), ``noise_on`` and
        ``noise_off`` (lists of noise-source labels) and ``kind`` (a key of
        :data:`STAGE_COLORS`). Every box of a column feeds every box of the next.
    title : str, optional
        Axes title.
    ax : matplotlib.axes.Axes, optional
        Axes to draw on; a new figure's by default.

    Returns
    -------
    matplotlib.axes.Axes
        The Axes, with one FancyBboxPatch per box and one FancyArrowPatch per arrow.
    """
    ax = new_axes(ax, figsize=(11.0, 4.5))
    ax.set_axis_off()
    if not columns:
        ax.set_xlim(0, 100)
        ax.set_ylim(0, 100)
        ax.text(50, 50, "no pipeline description", ha="center", va="center")
        return ax

    width, gap, fontsize = _column_width(len(columns)), _COLUMN_GAP, _FONT_PT
    max_chars = _chars_per_box(ax, width, fontsize)
    wrapped = [[_wrap(_box_lines(b), max_chars) for b in col] for col in columns]
    extents = _draw_boxes(ax, columns, wrapped, width, gap, fontsize)
    _draw_arrows(ax, extents)
    if title:
        ax.set_title(title)
    return ax
