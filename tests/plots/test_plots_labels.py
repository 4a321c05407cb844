"""Figures 9 and 10: no two text labels overlap (matplotlib's window extents)."""

from __future__ import annotations

import pandas as pd

from nirglucose.plots.labels import overlapping_texts
from nirglucose.plots.tradeoffs import figure_efficiency_landscape, plot_physics_depth
from nirglucose.report.figures import (
    PHYSICS_DEPTH_LABELS,
    _figure_one,
    efficiency_table,
    physics_depth_table,
    reference_values,
)

# A crowded run like the one that clumped: five networks within 1.5 mg/dL and a factor
# of three in latency, plus references and an ablation row.
METRICS = pd.DataFrame({
    "model": ["ebl", "pls", "oracle", "original-pinn", "optimized-pinn", "rte-pinn",
              "selective-rte-pinn", "sdnn", "gp", "gbr", "mean", "rte-pinn/no-physics"],
    "rmse_mgdl": [35.4, 41.0, 0.8, 34.1, 33.9, 33.7, 33.6, 35.2, 21.0, 55.8, 58.8, 33.8],
    "n_parameters": [59, 19, 16, 20257, 76353, 187977, 187461, 3809, 1378, 1317, 1, 187977],
    "macs_per_prediction": [58, 18, float("nan"), 19872, 108224, 186816, 186304, 3688,
                            1520, 300, 0, 186816],
    "latency_single_ms": [1.6, 1.7, 5.7, 2.1, 2.2, 2.6, 2.3, 1.9, 0.02, 0.04, 0.01, 2.6],
})
MODELS = list(METRICS["model"])


def test_efficiency_labels_do_not_overlap_and_references_are_lines():
    from nirglucose.plots.style import model_label

    fig = figure_efficiency_landscape(efficiency_table(METRICS, MODELS),
                                      reference_values(METRICS, MODELS))
    assert overlapping_texts(fig) == []
    texts = [t.get_text() for t in fig.axes[0].texts]
    assert model_label("optimized-pinn") in texts and model_label("sdnn") in texts
    assert model_label("oracle") not in texts  # a reference line, not a point label
    assert any(t.startswith(model_label("oracle")) for t in texts)
    assert all(ax.get_ylim()[0] == 0.0 for ax in fig.axes[:3])  # RMSE axes from zero


def test_physics_depth_labels_do_not_overlap():
    import matplotlib as mpl

    from nirglucose.plots.style import plot_style

    depth, left_out = physics_depth_table(METRICS, MODELS)
    assert "oracle" not in set(depth["model"]) and "mean" not in left_out
    fig = _figure_one(lambda ax: plot_physics_depth(
        depth, depth_labels=PHYSICS_DEPTH_LABELS, references=reference_values(METRICS, MODELS),
        ax=ax), (11.0, 5.2), plot_style)
    assert overlapping_texts(fig) == []
    assert fig.axes[0].get_ylim()[0] == 0.0
    assert len([c for c in fig.axes[0].collections
                if isinstance(c, mpl.collections.PathCollection)]) >= len(depth)


def test_overlap_check_can_fail():
    from matplotlib.figure import Figure

    fig = Figure()
    ax = fig.add_subplot()
    ax.text(0.5, 0.5, "Original PINN")
    ax.text(0.52, 0.5, "Optimized PINN")
    assert overlapping_texts(fig) == [("Original PINN", "Optimized PINN")]


def test_labels_keep_off_reference_lines_and_their_texts():
    # Points just under a horizontal reference line with its value printed at the
    # right edge (the no-skill line of Figs 14-15): no label may cross either.
    from matplotlib.figure import Figure
    from matplotlib.text import Text

    from nirglucose.plots.labels import _renderer, label_points, place_labels

    fig = Figure(figsize=(4, 3))
    ax = fig.add_subplot()
    ax.set_xlim(0, 10)
    ax.set_ylim(0, 60)
    line = ax.axhline(56.5, ls="--")
    note = ax.text(9.9, 57, "No skill (training mean): 56.5", ha="right", va="bottom")
    xs = [1.0, 3.0, 5.0, 7.0, 9.0]
    label_points(ax, xs, [54.0] * 5, [f"model {i}" for i in range(5)])
    place_labels(fig)
    renderer = _renderer(fig)
    fixed = [line.get_window_extent(renderer), Text.get_window_extent(note, renderer)]
    for t in ax.texts:
        if t is note:
            continue
        box = Text.get_window_extent(t, renderer)
        assert not any(box.overlaps(f) for f in fixed), t.get_text()
