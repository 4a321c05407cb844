"""Figures of a worn device: traces over the days and error by days since calibration.

Inputs are the worn benchmark's tables (:mod:`nirglucose.evaluation.wear`:
``wear_predictions.csv`` with the schedule applied by the caller, ``wear_by_day.csv``);
nothing here computes a metric.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pandas as pd
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from ..constants import MINUTES_PER_DAY
from .style import (
    DATA_COLOR,
    GREY,
    OKABE_ITO,
    model_color,
    model_label,
    new_axes,
    plot_style,
    styled,
)

__all__ = ["figure_wear_traces", "plot_error_by_day"]

#: One colour per calibration schedule (Okabe–Ito; schedules are not models).
_SCHEDULE_COLORS = {
    "factory": OKABE_ITO["black"],
    "day1-1": OKABE_ITO["blue"],
    "day1-2": OKABE_ITO["sky_blue"],
    "every-24h": OKABE_ITO["vermillion"],
    "every-12h": OKABE_ITO["orange"],
}


def figure_wear_traces(traces: pd.DataFrame, *, model: str, schedule: str,
                       subjects: Sequence | None = None, ncols: int = 1) -> Figure:
    """Reference and calibrated prediction over the days, one panel per subject.

    Parameters
    ----------
    traces : pandas.DataFrame
        ``subject_id``, ``time_min``, ``glucose_mgdl`` (reference), ``calibrated_mgdl``
        (the model's prediction with ``schedule`` applied) and ``is_calibration``
        (fingersticks, marked). [-, min, mg/dL, mg/dL, -]
    model, schedule : str
        What is drawn (titles and colour).
    subjects : sequence, optional
        Subjects to draw (default the first three).

    Returns
    -------
    matplotlib.figure.Figure
    """
    subjects = list(subjects) if subjects is not None else \
        list(pd.unique(traces["subject_id"]))[:3]
    with plot_style():
        fig = Figure(figsize=(9.0, 2.2 * len(subjects)), layout="constrained")
        axes = fig.subplots(len(subjects), ncols, sharex=True, squeeze=False)[:, 0]
        for ax, sid in zip(axes, subjects, strict=True):
            g = traces[traces["subject_id"] == sid].sort_values("time_min")
            days = g["time_min"].to_numpy(float) / MINUTES_PER_DAY
            ax.axhspan(70, 180, color=GREY, alpha=0.08, lw=0)
            ax.plot(days, g["glucose_mgdl"], color=DATA_COLOR, lw=1.0, label="reference")
            ax.plot(days, g["calibrated_mgdl"], color=model_color(model), lw=1.0,
                    label=f"{model_label(model)}, {schedule}")
            cal = g["is_calibration"].to_numpy(bool)
            ax.plot(days[cal], g["glucose_mgdl"].to_numpy(float)[cal], "v", ms=6,
                    color=OKABE_ITO["vermillion"], label="fingerstick")
            ax.set_ylabel("glucose [mg/dL]")
            ax.set_title(f"subject {sid}", fontsize=9, loc="left")
        axes[-1].set_xlabel("days of wear [d]")
        axes[0].legend(loc="upper right", fontsize=7.5, ncols=3)
    return fig


@styled
def plot_error_by_day(by_day: pd.DataFrame, *, title: str | None = None,
                      ax: Axes | None = None) -> Axes:
    """RMSE against whole days since the last calibration, one line per schedule.

    Parameters
    ----------
    by_day : pandas.DataFrame
        ``schedule``, ``days_since_calibration``, ``rmse_mgdl`` and ``n_scored`` of one
        model and variant. [-, d, mg/dL, -]

    Returns
    -------
    matplotlib.axes.Axes
    """
    ax = new_axes(ax, figsize=(6.0, 3.8))
    for sched, g in by_day.groupby("schedule", sort=False):
        g = g.sort_values("days_since_calibration")
        ax.plot(g["days_since_calibration"], g["rmse_mgdl"], marker="o", ms=4,
                color=_SCHEDULE_COLORS.get(str(sched), GREY), label=str(sched))
    ax.set_xlabel("whole days since the last calibration [d]")
    ax.set_ylabel("RMSE [mg/dL]")
    r = by_day["rmse_mgdl"].to_numpy(float)
    if r.size and np.nanmin(r) > 0 and np.nanmax(r) / np.nanmin(r) > 10:
        ax.set_yscale("log")  # factory calibration can be tens of times worse
    else:
        ax.set_ylim(bottom=0)
    ax.set_xticks(np.unique(by_day["days_since_calibration"].to_numpy(int)))
    ax.legend(title="schedule", fontsize=8)
    if title:
        ax.set_title(title)
    return ax
