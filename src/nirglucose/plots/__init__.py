"""Figures of the study, one module per figure family.

Every ``plot_*`` function draws on a given Axes (``ax=None`` makes a new figure) and
returns it; every ``figure_*`` function builds a Figure from several of them. They take
precomputed numbers (plain arrays and DataFrames) and never compute a metric: the
report layer (:mod:`nirglucose.report.figures`) does that. Matplotlib runs on the
non-interactive Agg backend; figures are built without pyplot state.
"""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")

from .style import (  # noqa: E402
    MODEL_COLORS,
    OKABE_ITO,
    figure_bytes,
    model_color,
    model_label,
    save_figure,
)

__all__ = [
    "OKABE_ITO",
    "MODEL_COLORS",
    "model_color",
    "model_label",
    "save_figure",
    "figure_bytes",
]
