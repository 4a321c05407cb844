"""Figures of the "what it takes" study: error against averaging time, minimal designs.

The inputs are the tables of :class:`~nirglucose.evaluation.sweep.requirements.
RequirementsResult` (``averaging_curve.csv``, ``minimal_designs.csv``); nothing here
computes a bound.
"""

from __future__ import annotations

import textwrap

import numpy as np
import pandas as pd
from matplotlib.axes import Axes

from .style import GREY, OKABE_ITO, new_axes, styled

__all__ = ["plot_averaging_curve", "plot_minimal_designs"]

_COLORS = ("black", "blue", "vermillion", "bluish_green", "reddish_purple", "orange",
           "sky_blue")
#: Where a single reading (window 0 s) sits on the symmetric-log axis. [s]
_LINEAR_BELOW_S = 1.0


@styled
def plot_averaging_curve(
    curve: pd.DataFrame,
    *,
    target_rmse_mgdl: float | None = 15.0,
    title: str | None = None,
    ax: Axes | None = None,
) -> Axes:
    """Error against the averaging window, one colour per design.

    Solid: the total error (per-state bound and averaging lag in quadrature); dotted:
    the per-state bound alone; a grey dashed line at the target.

    Parameters
    ----------
    curve : pandas.DataFrame
        ``averaging_curve.csv``: ``design``, ``window_s`` [s], ``total_rmse_mgdl``,
        ``state_rmse_mgdl`` [mg/dL].
    target_rmse_mgdl : float or None
        The target drawn (None: none). [mg/dL]
    title : str, optional
        Axes title.
    ax : matplotlib.axes.Axes, optional
        Axes to draw on; a new figure's by default.

    Returns
    -------
    matplotlib.axes.Axes
        One solid line per design (``ax.lines``, labelled by design) and its dotted bound.
    """
    ax = new_axes(ax, figsize=(6.0, 4.2))
    for i, (name, d) in enumerate(curve.groupby("design", sort=False)):
        d = d.sort_values("window_s")
        color = OKABE_ITO[_COLORS[i % len(_COLORS)]]
        x = d["window_s"].to_numpy(float)
        ax.plot(x, d["total_rmse_mgdl"].to_numpy(float), "-o", color=color, markersize=3,
                label=str(name))
        ax.plot(x, d["state_rmse_mgdl"].to_numpy(float), ":", color=color, linewidth=0.9)
    if target_rmse_mgdl is not None:
        ax.axhline(target_rmse_mgdl, color=GREY, linestyle="--", linewidth=0.8,
                   label=f"target {target_rmse_mgdl:g} mg/dL")
    ax.set_xscale("symlog", linthresh=_LINEAR_BELOW_S)
    ax.set_xlim(left=0.0)
    ax.set_yscale("log")
    ax.set_xlabel("averaging window [s] (0: one reading)")
    ax.set_ylabel("RMSE [mg/dL] (solid: with lag; dotted: bound)")
    ax.legend(fontsize="x-small")
    if title:
        ax.set_title(title)
    return ax


#: Rows of the minimal-designs table: (column of minimal_designs.csv, row label).
_TABLE_ROWS = (
    ("reached", "reaches the target"),
    ("n_leds", "LEDs"),
    ("leds_nm", "centres [nm]"),
    ("capabilities", "capabilities"),
    ("adc_bits", "ADC [bit]"),
    ("window_label", "averaging"),
    ("power_factor", "LED power [x]"),
    ("sd_skin_thickness", "skin thickness SD [mm]"),
    ("sd_hydration", "hydration SD [%]"),
    ("sd_melanin", "melanin SD [-]"),
    ("sd_skin_temperature", "skin temperature SD [degC]"),
    ("sd_blood_volume", "blood volume SD [rel.]"),
    ("sd_spo2", "SpO2 SD [%]"),
    ("sd_humidity", "humidity SD [%RH]"),
    ("total_rmse_mgdl", "error [mg/dL]"),
    ("mard_pct", "MARD [%]"),
)


#: Display names of the capabilities in the table.
_CAPABILITY_LABELS = {"monitor_photodiode": "monitor photodiode",
                      "constant_force_probe": "constant-force probe",
                      "ppg_perfusion_spo2": "PPG perfusion/SpO2",
                      "humidity_compensation": "humidity compensation"}
#: Characters per line of a table cell. [-]
_WRAP = 26


def _cell(column: str, value) -> str:
    if isinstance(value, bool | np.bool_):
        return "yes" if value else "no"
    if isinstance(value, float | np.floating):
        return f"{value:.3g}"
    text = str(value)
    if column == "capabilities":
        names = [_CAPABILITY_LABELS.get(c, c) for c in text.split(",") if c and c != "nan"]
        return "\n".join(names) if names else "none"
    return textwrap.fill(text.replace(",", ", "), _WRAP)


@styled
def plot_minimal_designs(
    designs: pd.DataFrame,
    *,
    title: str | None = None,
    ax: Axes | None = None,
) -> Axes:
    """The least design per detector as a table (one column per detector).

    Parameters
    ----------
    designs : pandas.DataFrame
        ``minimal_designs.csv``: ``detector_label`` and the columns of the rows drawn
        (those missing are left out).
    title : str, optional
        Axes title.
    ax : matplotlib.axes.Axes, optional
        Axes to draw on; a new figure's by default.

    Returns
    -------
    matplotlib.axes.Axes
        The table is ``ax.tables[0]``; the axes' frame is off.
    """
    rows = [(col, label) for col, label in _TABLE_ROWS if col in designs.columns]
    cells = [[_cell(col, v) for v in designs[col]] for col, _ in rows]
    heads = [textwrap.fill(str(v), _WRAP) for v in designs["detector_label"]]
    lines = [max(t.count("\n") + 1 for t in row) for row in [heads, *cells]]
    ax = new_axes(ax, figsize=(2.2 + 2.0 * max(len(designs), 1), 0.2 * sum(lines) + 0.8))
    table = ax.table(cellText=cells, rowLabels=[label for _, label in rows], colLabels=heads,
                     loc="center", cellLoc="center")
    table.auto_set_font_size(False)
    table.set_fontsize(7)
    unit = 1.0 / (sum(lines) + 1)
    for (r, _c), cell in table.get_celld().items():
        cell.set_height(unit * lines[r])
    ax.axis("off")
    if title:
        ax.set_title(title)
    return ax
