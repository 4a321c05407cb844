"""Per-figure inputs computed from a benchmark results directory, and the figures.

This is the computing half of the report: it reads what ``nirglucose benchmark``
wrote (:func:`load_results`), computes what each figure shows (correlations, zone
percentages, Bland–Altman limits and their confidence intervals, regression lines,
normalised scores, Pareto fronts) with :mod:`nirglucose.metrics` and numpy, and hands
plain numbers to :mod:`nirglucose.plots` (:func:`render_figures`).

Required inputs: ``metrics.csv`` (or ``metrics.json``) and ``predictions.parquet``.
Everything else (``meta.json``, ``table.md``, ``comparisons.csv``, ``histories.json``,
``drop_one.csv``, ``dataset.parquet``) is optional; what is missing is listed in
:attr:`Results.notes` and the figures that need it say so instead of drawing nothing.

The package is split by concept; every name is importable from here as before:

- :mod:`.results`: loading a results directory (:class:`Results`, :func:`load_results`);
- :mod:`.inputs`: what each results figure shows (grids, agreement, trade-offs, forest);
- :mod:`.descriptive`: the data, pipeline, architecture and feature figures' inputs;
- :mod:`.sections`: the sections in page order, their captions, :func:`render_figures`.
"""

from __future__ import annotations

from .descriptive import (
    ARCHITECTURE_MODELS,
    NOISE_LAYER,
    ebl_feature_table,
    environment_panels,
    feature_categories,
    fitted_architectures,
    physiology_panels,
    pipeline_columns,
)
from .descriptive import _module_blocks as _module_blocks  # private; the tests import it
from .inputs import (
    PHYSICS_DEPTH,
    PHYSICS_DEPTH_LABELS,
    RADAR_AXES,
    RADAR_COST_DECADES,
    REFERENCE_ROWS,
    bland_altman_inputs,
    channel_correlations,
    competitors,
    drop_one_models,
    efficiency_table,
    error_grid_inputs,
    first_repeat,
    forest_table,
    is_ablation_row,
    linearity_inputs,
    model_order,
    pareto_front,
    performance_table,
    physics_depth_table,
    pooled,
    radar_scores,
    reference_values,
    scored_column,
)
from .results import (
    REQUIRED_METRIC_COLUMNS,
    REQUIRED_PREDICTION_COLUMNS,
    RenderedFigure,
    Results,
    load_results,
)
from .sections import _figure_one as _figure_one  # private; the tests import it from here
from .sections import render_figures

__all__ = [
    "REQUIRED_METRIC_COLUMNS",
    "REQUIRED_PREDICTION_COLUMNS",
    "PHYSICS_DEPTH",
    "REFERENCE_ROWS",
    "competitors",
    "is_ablation_row",
    "reference_values",
    "pooled",
    "PHYSICS_DEPTH_LABELS",
    "NOISE_LAYER",
    "RADAR_AXES",
    "RADAR_COST_DECADES",
    "Results",
    "RenderedFigure",
    "load_results",
    "model_order",
    "first_repeat",
    "scored_column",
    "channel_correlations",
    "error_grid_inputs",
    "bland_altman_inputs",
    "linearity_inputs",
    "radar_scores",
    "pareto_front",
    "efficiency_table",
    "physics_depth_table",
    "drop_one_models",
    "forest_table",
    "pipeline_columns",
    "environment_panels",
    "physiology_panels",
    "render_figures",
    "ARCHITECTURE_MODELS",
    "fitted_architectures",
    "feature_categories",
    "ebl_feature_table",
    "performance_table",
]
