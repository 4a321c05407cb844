"""RMSE with its 95 % confidence interval per model: the forest plot (study values
marked) and the headline figure (models × presets, with each preset's no-skill and
oracle lines)."""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
import pandas as pd
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.transforms import offset_copy

from .style import (
    GREY,
    model_color,
    model_colors,
    model_label,
    model_marker,
    new_axes,
    plot_style,
    styled,
)

__all__ = ["plot_rmse_forest", "plot_preset_forest", "figure_headline", "HEADLINE_STATUS"]

#: Marker fill of the headline figure by status against the preset's best model.
HEADLINE_STATUS = {
    "best": "best deployable (lowest RMSE)",
    "tied": "not distinguishable from the best (paired, Holm)",
    "worse": "significantly worse than the best",
    "reference": "privileged reference, black and hollow (knows the generator; not ranked)",
}


@styled
def plot_rmse_forest(
    table: pd.DataFrame,
    *,
    title: str | None = None,
    ax: Axes | None = None,
) -> Axes:
    """Forest plot: each model's RMSE and interval, with the study's value beside it.

    Parameters
    ----------
    table : pandas.DataFrame
        One row per model, top to bottom in display order, with ``model``,
        ``rmse_mgdl``, ``rmse_ci_low``, ``rmse_ci_high`` (this run) and optionally
        ``study_rmse_mgdl`` (the study's Table 1 value; NaN where the study has none).
        [mg/dL]
    title : str, optional
        Axes title.
    ax : matplotlib.axes.Axes, optional
        Axes to draw on; a new figure's by default.

    Returns
    -------
    matplotlib.axes.Axes
        The Axes: one error bar (an ErrorbarContainer) per model and one PathCollection
        of the study's values (when any is given).
    """
    t = table.reset_index(drop=True)
    ax = new_axes(ax, figsize=(6.4, 0.42 * max(len(t), 1) + 1.4))
    colors = model_colors(t["model"])
    y = np.arange(len(t))[::-1].astype(float)
    for k, row in t.iterrows():
        m = str(row["model"])
        lo, hi = row.get("rmse_ci_low", np.nan), row.get("rmse_ci_high", np.nan)
        err = None
        if np.isfinite(lo) and np.isfinite(hi):
            err = [[max(row["rmse_mgdl"] - lo, 0.0)], [max(hi - row["rmse_mgdl"], 0.0)]]
        # a dark edge keeps pale markers (the no-skill row's light grey) visible
        ax.errorbar([row["rmse_mgdl"]], [y[k]], xerr=err, fmt=model_marker(m), ms=7,
                    color=colors[m], ecolor=colors[m], mec="black", mew=0.6, elinewidth=1.6,
                    capsize=3, zorder=3)
    handles = [Line2D([], [], color="black", marker="o", ls="-", lw=1.6,
                      label="this run: RMSE, 95 % CI")]
    if "study_rmse_mgdl" in t and t["study_rmse_mgdl"].notna().any():
        s = t["study_rmse_mgdl"].to_numpy(float)
        ok = np.isfinite(s)
        ax.scatter(s[ok], y[ok] + 0.22, marker="D", s=30, facecolors="white",
                   edgecolors="black", linewidths=1.0, zorder=4)
        handles.append(Line2D([], [], ls="none", marker="D", mfc="white", mec="black",
                              label="study (Table 1, single split, n = 48)"))
    ax.set_yticks(y)
    ax.set_yticklabels([model_label(str(m)) for m in t["model"]])
    ax.set_ylim(-0.7, len(t) - 0.3)
    shown = np.concatenate([t[c].to_numpy(float) for c in
                            ("rmse_mgdl", "rmse_ci_high", "study_rmse_mgdl") if c in t])
    shown = shown[np.isfinite(shown)]
    ax.set_xlim(0.0, 1.08 * float(shown.max()) if shown.size else None)
    ax.grid(axis="x", color=GREY, alpha=0.25, lw=0.6)
    ax.set_xlabel("RMSE [mg/dL]")
    # under the x label, a fixed distance whatever the number of rows
    below = offset_copy(ax.transAxes, fig=ax.figure, y=-30, units="points")
    ax.legend(handles=handles, loc="upper center", bbox_to_anchor=(0.5, 0.0),
              bbox_transform=below, ncol=2, fontsize=7.5, frameon=False)
    ax.set_title(title if title is not None else "RMSE with 95 % confidence interval")
    return ax


@styled
def plot_preset_forest(
    table: pd.DataFrame,
    references: Mapping[str, float],
    order: list[str],
    *,
    title: str | None = None,
    xmax: float | None = None,
    ax: Axes | None = None,
    labels: Mapping[str, str] | None = None,
) -> Axes:
    """One preset's panel of the headline figure.

    Parameters
    ----------
    table : pandas.DataFrame
        The preset's rows: ``model``, ``rmse_mgdl``, ``rmse_ci_low``, ``rmse_ci_high``
        and ``status`` (``"best"``, ``"tied"``, ``"worse"`` or ``""``). [mg/dL]
    references : mapping of str to float
        ``"mean"`` (no skill) and ``"oracle"`` RMSE, drawn as vertical lines. [mg/dL]
    order : list of str
        Models top to bottom (a model missing from ``table`` leaves its row empty).
    title : str, optional
        Axes title.
    xmax : float, optional
        Upper x limit. [mg/dL]
    ax : matplotlib.axes.Axes, optional
        Axes to draw on.
    labels : mapping of str to str, optional
        Row labels (default: each model's label), e.g. marking a PINN's physics off.

    Returns
    -------
    matplotlib.axes.Axes
        One ErrorbarContainer per model drawn; one Line2D per reference line.
    """
    ax = new_axes(ax, figsize=(5.0, 0.42 * max(len(order), 1) + 1.4))
    t = table.set_index("model")
    y = {m: float(len(order) - 1 - k) for k, m in enumerate(order)}
    best = t.index[t["status"] == "best"] if "status" in t else []
    if len(best):
        b = t.loc[best[0]]
        ax.axvspan(b["rmse_ci_low"], b["rmse_ci_high"], color=model_color(best[0]),
                   alpha=0.12, lw=0, zorder=0)
    refs = [m for m in order if m in t.index and t.at[m, "status"] == "reference"] \
        if "status" in t else []
    if refs:  # the privileged references apart, under a grey rule
        ax.axhline(max(y[m] for m in refs) + 0.5, color=GREY, lw=0.8, zorder=1)
    for m in [m for m in order if m in t.index]:
        r = t.loc[m]
        lo, hi, v = r["rmse_ci_low"], r["rmse_ci_high"], r["rmse_mgdl"]
        err = ([[max(v - lo, 0.0)], [max(hi - v, 0.0)]]
               if np.isfinite(lo) and np.isfinite(hi) else None)
        if m in refs:  # drawn like the oracle: black, hollow, its CI dotted
            bars = ax.errorbar([v], [y[m]], xerr=err, fmt=model_marker(m), ms=7,
                               color="black", ecolor="black", mfc="white", mec="black",
                               mew=1.2, elinewidth=1.0, capsize=3, zorder=3)
            for line in bars[2]:
                line.set_linestyle(":")
            continue
        c = model_color(m)
        open_ = r.get("status", "") == "worse"
        ax.errorbar([v], [y[m]], xerr=err, fmt=model_marker(m), ms=8 if r.get("status") ==
                    "best" else 6.5, color=c, ecolor=c, mfc="white" if open_ else c,
                    mec=c if open_ else "black", mew=1.3 if open_ else 0.6, elinewidth=1.6,
                    capsize=3, zorder=3)
    styles = {"mean": ("--", GREY, "no skill"), "oracle": (":", "black", "oracle")}
    for ref, x in references.items():
        ls, col, name = styles.get(ref, ("-.", GREY, ref))
        ax.axvline(x, ls=ls, color=col, lw=1.2, zorder=1)
        ax.annotate(f"{name} {x:.1f}", (x, 1.0), xycoords=("data", "axes fraction"),
                    xytext=(2, 2), textcoords="offset points", fontsize=7.5, color=col,
                    ha="left" if ref == "oracle" else "right", va="bottom")
    ax.set_yticks([y[m] for m in order])
    ax.set_yticklabels([(labels or {}).get(m, model_label(m))
                        + (" (reference)" if m in refs else "") for m in order])
    ax.set_ylim(-0.7, len(order) - 0.3)
    ax.set_xlim(0.0, xmax)
    ax.grid(axis="x", color=GREY, alpha=0.25, lw=0.6)
    ax.set_xlabel("RMSE [mg/dL], 95 % CI")
    if title:
        ax.set_title(title, pad=14)
    return ax


def figure_headline(table: pd.DataFrame, references: Mapping[str, Mapping[str, float]],
                    ) -> Figure:
    """The headline figure: one panel per preset, models on shared rows.

    Parameters
    ----------
    table : pandas.DataFrame
        ``preset``, ``model``, ``rmse_mgdl``, ``rmse_ci_low``, ``rmse_ci_high``,
        ``status`` (:func:`nirglucose.evaluation.benchmark.findings.headline_table`). [mg/dL]
    references : mapping
        Preset -> ``{"mean": ..., "oracle": ...}``. [mg/dL]

    Returns
    -------
    matplotlib.figure.Figure
        Models sorted by the first preset's RMSE; filled markers for the best model and
        those not distinguishable from it, open ones for those significantly worse; the
        best model's CI shaded.
    """
    presets = list(dict.fromkeys(table["preset"]))
    first = table[table["preset"] == presets[0]].sort_values("rmse_mgdl")
    order = list(dict.fromkeys([*first["model"], *table["model"]]))
    is_ref = set(table.loc[table["status"] == "reference", "model"]) if "status" in table \
        else set()
    order = [m for m in order if m not in is_ref] + [m for m in order if m in is_ref]
    with plot_style():
        fig = Figure(figsize=(4.6 * len(presets) + 1.6, 0.36 * len(order) + 1.9),
                     layout="constrained")
        axes = fig.subplots(1, len(presets), sharey=True, squeeze=False).ravel()
        for ax, p in zip(axes, presets, strict=True):
            part = table[table["preset"] == p]
            refs = dict(references.get(p, {}))
            xmax = 1.08 * max([*part["rmse_ci_high"].dropna(), *refs.values(), 1.0])
            plot_preset_forest(part, refs, order, title=f"preset: {p}", xmax=xmax, ax=ax,
                               labels=(dict(zip(table["model"], table["label"], strict=True))
                                       if "label" in table else None))
        handles = [Line2D([], [], ls="none", marker="o", ms=8, mfc="#444444", mec="black",
                          label=HEADLINE_STATUS["best"] + " (its CI shaded)"),
                   Line2D([], [], ls="none", marker="o", ms=6.5, mfc="#444444", mec="black",
                          label=HEADLINE_STATUS["tied"]),
                   Line2D([], [], ls="none", marker="o", ms=6.5, mfc="white", mec="#444444",
                          mew=1.3, label=HEADLINE_STATUS["worse"]),
                   Line2D([], [], ls=":", marker="8", ms=7, mfc="white", mec="black",
                          color="black", mew=1.2, label=HEADLINE_STATUS["reference"]),
                   Line2D([], [], ls="--", color=GREY, label="no skill (training mean)"),
                   Line2D([], [], ls=":", color="black", label="oracle (true nuisances, a bound)")]
        if not (table["status"].isin(("best", "tied", "worse"))).any():  # no comparisons
            handles = handles[3:]
        if not is_ref:
            handles = [h for h in handles if h.get_label() != HEADLINE_STATUS["reference"]]
        fig.legend(handles=handles, loc="outside lower center", ncol=3, fontsize=7.5,
                   frameon=False)
    return fig
