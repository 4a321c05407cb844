"""The study's model-architecture, feature-engineering and performance figures.

Plain block diagrams and bar panels from numbers the report computes: layer sizes read
from fitted models, feature counts per category, metrics per model and preset.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np
import pandas as pd
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.patches import FancyBboxPatch

from .style import GREY, OKABE_ITO, model_color, model_label, plain_log_ticks, plot_style

__all__ = ["figure_architectures", "figure_feature_engineering", "figure_performance_panel"]



def _box(ax: Axes, x: float, y: float, w: float, h: float, text: str, color: str,
         fontsize: float = 8.0) -> None:
    ax.add_patch(FancyBboxPatch((x - w / 2, y - h / 2), w, h, boxstyle="round,pad=0.01",
                                fc=color, ec="black", lw=0.8))  # the colour carries its alpha
    ax.text(x, y, text, ha="center", va="center", fontsize=fontsize)


def _arrow(ax: Axes, xy_from: tuple[float, float], xy_to: tuple[float, float]) -> None:
    ax.annotate("", xy=xy_to, xytext=xy_from,
                arrowprops={"arrowstyle": "-|>", "color": GREY, "lw": 1.0})


def _rows(blocks: Sequence[tuple[str, str]]) -> list[list[int]]:
    """Block indices per row: the ``nir`` and ``pmf`` branches side by side (they run in
    parallel on the two inputs and are concatenated), every other block on its own row."""
    rows: list[list[int]] = []
    i = 0
    while i < len(blocks):
        if blocks[i][0] == "nir" and i + 1 < len(blocks) and blocks[i + 1][0] == "pmf":
            rows.append([i, i + 1])
            i += 2
        else:
            rows.append([i])
            i += 1
    return rows


def _draw_blocks(ax: Axes, blocks: Sequence[tuple[str, str]], color: str) -> int:
    """Boxes row by row, arrows between rows (split and merged at parallel branches)."""
    rows = _rows(blocks)
    for r, row in enumerate(rows):
        xs = [0.5] if len(row) == 1 else [0.26, 0.74]
        w = 0.92 if len(row) == 1 else 0.44
        for x, i in zip(xs, row, strict=True):
            name, sizes = blocks[i]
            _box(ax, x, -r, w, 0.62, f"{name}\n{sizes}",
                 "white" if i in (0, len(blocks) - 1) else color + "40",
                 fontsize=8.0 if len(row) == 1 else 7.0)
        if r:
            prev = [0.5] if len(rows[r - 1]) == 1 else [0.26, 0.74]
            for x0 in prev:
                for x1 in xs:
                    if len(prev) == len(xs) == 2 and x0 != x1:
                        continue  # parallel branches stay apart
                    _arrow(ax, (x0, -r + 0.69), (x1, -r + 0.31))
    names = [blocks[row[0]][0] for row in rows]
    for r in range(len(names) - 2):  # a block that also reads the one two rows up:
        # RTE's glucose head (trunk and optics), SDNN's stack (front and physiology)
        if names[r:r + 3] in (["trunk", "optics", "glucose"], ["inputs", "front", "stack"]):
            ax.annotate("", xy=(0.96, -r - 2), xytext=(0.96, -r),
                        arrowprops={"arrowstyle": "-|>", "color": GREY, "lw": 1.0,
                                    "connectionstyle": "arc3,rad=-0.35"})
    return len(rows)


def figure_architectures(archs: Mapping[str, tuple[Sequence[tuple[str, str]], int]],
                         *, physics: Mapping[str, str] | None = None,
                         ncols: int = 3) -> Figure:
    """One block diagram per model family, top (inputs) to bottom (glucose).

    The absorbance (``nir``) and physiology (``pmf``) branches are drawn side by side,
    split from the inputs and merged into the next block; a physics loss term, used in
    training only, is a dashed box under the output.

    Parameters
    ----------
    archs : mapping of str to (sequence of (str, str), int)
        Model -> (blocks as ``(name, sizes)``, trainable parameter count). [-]
    physics : mapping of str to str, optional
        Model -> its training loss with the physics term (e.g. ``"MSE + λ·Beer–Lambert
        residual, λ = 0.01"``); models absent have none. [-]
    ncols : int
        Panels per row. [-]

    Returns
    -------
    matplotlib.figure.Figure
        One Axes per model, with one box per block (and one for the physics loss).
    """
    models = list(archs)
    physics = physics or {}
    ncols = max(1, min(ncols, len(models)))
    nrows = -(-max(len(models), 1) // ncols)
    depth = max((len(_rows(b)) + (m in physics) for m, (b, _) in archs.items()), default=1)
    with plot_style():
        fig = Figure(figsize=(4.4 * ncols, (0.62 * depth + 0.9) * nrows), layout="constrained")
        axes = fig.subplots(nrows, ncols, squeeze=False).ravel()
        for ax, model in zip(axes, models, strict=False):
            blocks, n_params = archs[model]
            ax.set_xlim(0, 1)
            ax.set_ylim(-depth + 0.4, 0.6)
            n = _draw_blocks(ax, blocks, model_color(model))
            if model in physics:
                ax.add_patch(FancyBboxPatch((0.04, -n - 0.31), 0.92, 0.62,
                                            boxstyle="round,pad=0.01", fc="white",
                                            ec=GREY, lw=0.9, ls="--"))
                ax.text(0.5, -n, f"training loss only\n{physics[model]}", ha="center",
                        va="center", fontsize=7.0, color="#333333")
                ax.annotate("", xy=(0.5, -n + 0.31), xytext=(0.5, -n + 0.69),
                            arrowprops={"arrowstyle": "-|>", "color": GREY, "lw": 1.0,
                                        "ls": "--"})
            ax.set_title(f"{model_label(model)}\n{n_params:,} trainable parameters",
                         fontsize=9.5)
            ax.set_axis_off()
        for ax in axes[len(models):]:
            ax.set_axis_off()
    return fig


def figure_feature_engineering(n_channels: int, n_physiology: int,
                               categories: Mapping[str, Sequence[str]],
                               sources: Mapping[str, str] | None = None) -> Figure:
    """Raw intensities to absorbances to the engineered features, by category.

    Parameters
    ----------
    n_channels : int
        LED channels (raw intensities). [-]
    n_physiology : int
        Entries of the physiological vector. [-]
    categories : mapping of str to sequence of str
        Category -> the names of its features, in table order. [-]
    sources : mapping of str to str, optional
        Category -> what it is computed from: ``"absorbance"``, ``"physiology"`` or
        ``"both"`` (arrows drawn from those boxes only); both by default. [-]

    Returns
    -------
    matplotlib.figure.Figure
    """
    cats = list(categories)
    n_feat = sum(len(v) for v in categories.values())
    h = max(len(cats), 3)
    with plot_style():
        fig = Figure(figsize=(12.0, 0.55 * h + 1.2), layout="constrained")
        ax = fig.add_subplot()
        ax.set_xlim(0, 12)
        ax.set_ylim(-0.7, h - 0.3)
        mid = (h - 1) / 2
        # inputs in one column (absorbances above the physiological vector) so that no
        # arrow to a feature category crosses another box
        _box(ax, 0.95, mid + 0.8, 1.7, 1.0,
             f"raw intensities\nI_λ, reference I0_λ\n({n_channels} LEDs)", "white", 8.5)
        _box(ax, 3.2, mid + 0.8, 1.9, 1.0, f"absorbances\nA = log10(I0/I)\n({n_channels})",
             OKABE_ITO["sky_blue"] + "60", 8.5)
        _box(ax, 3.2, mid - 0.8, 1.9, 1.0,
             f"physiological\nvector\n({n_physiology} entries)", "white", 8.5)
        _arrow(ax, (1.8, mid + 0.8), (2.25, mid + 0.8))
        for i, cat in enumerate(cats):
            y = h - 1 - i
            names = list(categories[cat])
            shown = ", ".join(names[:3]) + (", …" if len(names) > 3 else "")
            _box(ax, 7.3, y, 4.6, 0.46, f"{cat} ({len(names)}): {shown}",
                 OKABE_ITO["yellow"] + "60", 7.5)
            src = (sources or {}).get(cat, "both")
            if src in ("absorbance", "both"):
                _arrow(ax, (4.15, mid + 0.8), (5.0, y))
            if src in ("physiology", "both"):
                _arrow(ax, (4.15, mid - 0.8), (5.0, y))
        _box(ax, 10.9, mid, 1.8, 1.0, f"{n_feat} features\n→ scaled\n→ ridge → glucose",
             OKABE_ITO["blue"] + "40", 8.5)
        for i in range(len(cats)):
            _arrow(ax, (9.6, h - 1 - i), (10.0, mid))
        ax.set_axis_off()
    return fig


#: Markers of the presets in the performance panel (colour stays the model's).
_PRESET_MARKERS = ("o", "s", "D")


def figure_performance_panel(table: pd.DataFrame) -> Figure:
    """Error metrics and costs side by side, one row per model and preset.

    RMSE and MARD are bars from zero (RMSE with its CI); parameters and
    multiply-accumulates per prediction are dots on log axes (a bar on a log axis has
    no meaningful length). Colour is the model's, as in every figure; the presets
    differ by marker and by a lighter bar.

    Parameters
    ----------
    table : pandas.DataFrame
        Columns ``preset``, ``model``, ``rmse_mgdl`` (optionally ``rmse_ci_low`` and
        ``rmse_ci_high``), ``mard_pct``, ``n_parameters``, ``macs_per_prediction``.
        [-, -, mg/dL, %, -, -]

    Returns
    -------
    matplotlib.figure.Figure
        Four Axes sharing the model axis; parameters and MACs on log scales.
    """
    presets = list(dict.fromkeys(table["preset"]))
    models = list(dict.fromkeys(table["model"]))
    panels = (("rmse_mgdl", "RMSE [mg/dL]", False), ("mard_pct", "MARD [%]", False),
              ("n_parameters", "trainable parameters [-]", True),
              ("macs_per_prediction", "multiply-accumulates per prediction [-]", True))
    bar_h = 0.8 / max(len(presets), 1)
    y0 = np.arange(len(models), dtype=float)
    colors = [model_color(m) for m in models]
    with plot_style():
        fig = Figure(figsize=(13.0, 0.42 * len(models) * max(len(presets), 1) ** 0.5 + 1.6),
                     layout="constrained")
        axes = fig.subplots(1, len(panels), sharey=True)
        for ax, (col, xlabel, log) in zip(axes, panels, strict=True):
            for k, preset in enumerate(presets):
                t = table[table["preset"] == preset].set_index("model").reindex(models)
                v = t[col].to_numpy(float) if col in t else np.full(len(models), np.nan)
                y = y0 - 0.4 + bar_h * (k + 0.5)
                marker = _PRESET_MARKERS[k % len(_PRESET_MARKERS)]
                if log:
                    ok = np.isfinite(v) & (v > 0)
                    ax.scatter(v[ok], y[ok], c=[c for c, o in zip(colors, ok, strict=True)
                                                if o], marker=marker, s=28, zorder=3)
                    continue
                xerr = None
                if col == "rmse_mgdl" and {"rmse_ci_low", "rmse_ci_high"} <= set(t.columns):
                    lo = t["rmse_ci_low"].to_numpy(float)
                    hi = t["rmse_ci_high"].to_numpy(float)
                    xerr = np.nan_to_num(np.vstack([v - lo, hi - v]), nan=0.0)
                ax.barh(y, np.nan_to_num(v, nan=0.0), height=bar_h * 0.9, color=colors,
                        alpha=1.0 if k == 0 else 0.45, xerr=xerr,
                        error_kw={"lw": 0.8, "capsize": 2})
                ax.scatter(np.nan_to_num(v, nan=0.0), y, color="black", marker=marker, s=10,
                           zorder=3)
            if log:
                ax.set_xscale("log")
                shown = table[col].to_numpy(float) if col in table else np.array([])
                shown = shown[np.isfinite(shown) & (shown > 0)]
                if shown.size:
                    ax.set_xlim(shown.min() / 2.0, 2.0 * shown.max())
                    plain_log_ticks(ax.xaxis, shown)
                ax.grid(axis="y", color="#EEEEEE", lw=0.6)
            else:
                ax.set_xlim(left=0)
            ax.set_xlabel(xlabel)
            ax.grid(axis="x", color="#DDDDDD", lw=0.6)
        axes[0].set_yticks(y0)
        axes[0].set_yticklabels([model_label(m) for m in models])
        axes[0].invert_yaxis()
        if len(presets) > 1:
            from matplotlib.lines import Line2D

            handles = [Line2D([], [], ls="none", marker=_PRESET_MARKERS[k % 3], color="black",
                              label=f"{p} ({'solid' if k == 0 else 'light'} bar)")
                       for k, p in enumerate(presets)]
            fig.legend(handles=handles, title="preset", fontsize=8,
                       loc="outside upper center", ncol=len(presets))
    return fig
