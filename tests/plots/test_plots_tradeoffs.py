"""Radar, physics-depth bubbles and the efficiency landscape."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from matplotlib.collections import PathCollection
from matplotlib.figure import Figure

from nirglucose.plots.tradeoffs import (
    MAX_BUBBLE_PT2,
    bubble_area,
    figure_efficiency_landscape,
    plot_efficiency,
    plot_physics_depth,
    plot_radar,
)

MODELS = ["ebl", "pls", "original-pinn", "sdnn"]
SCORES = pd.DataFrame(
    {"RMSE": [1.0, 0.8, 0.9, 0.4], "MARD": [1.0, 0.7, 0.9, 0.4], "Clarke A": [1, .9, .95, .8],
     "±15 %": [1, .8, .9, .7], "parameters": [1.0, 1.0, 0.2, 0.6], "latency": [1, 1, .5, .7]},
    index=MODELS)


def test_radar_one_polygon_per_model():
    ax = Figure().add_subplot(projection="polar")
    assert plot_radar(SCORES, ax=ax) is ax
    assert len(ax.lines) == len(MODELS)
    assert len(ax.patches) == len(MODELS)
    assert [t.get_text() for t in ax.get_xticklabels()] == list(SCORES.columns)
    assert len(ax.lines[0].get_xdata()) == SCORES.shape[1] + 1  # closed outline


def test_radar_needs_polar_axes():
    with pytest.raises(ValueError, match="polar"):
        plot_radar(SCORES, ax=Figure().add_subplot())
    assert plot_radar(SCORES).name == "polar"


def test_bubble_area_proportional_to_parameters():
    a = bubble_area([1_000_000, 500_000, 10], 1_000_000)
    assert a[0] == MAX_BUBBLE_PT2 and a[1] == pytest.approx(MAX_BUBBLE_PT2 / 2)
    assert a[2] > 0  # floored so that it stays visible


def test_physics_depth_one_bubble_per_model():
    t = pd.DataFrame({"model": MODELS, "physics_depth": [4, 0, 1, 0],
                      "rmse_mgdl": [13.6, 20.0, 14.6, 35.1],
                      "n_parameters": [56, 17, 163_000, 3_713],
                      "on_front": [True, True, False, False],
                      "x_offset": [0.0, -0.3, 0.0, 0.3]})
    ax = Figure().add_subplot()
    assert plot_physics_depth(t, depth_labels={0: "none", 1: "loss", 4: "features"},
                              ax=ax) is ax
    scat = [c for c in ax.collections if isinstance(c, PathCollection)]
    assert len(scat) == len(MODELS) + 2  # a bubble per model, a ring per Pareto bubble
    sizes = [c.get_sizes()[0] for c in scat]
    assert sizes[0] == max(sizes)  # drawn biggest first: the largest model's bubble
    assert ax.get_ylabel() == "RMSE [mg/dL]"


def test_physics_depth_ticks_only_the_levels_drawn():
    from nirglucose.report.figures import PHYSICS_DEPTH, PHYSICS_DEPTH_LABELS

    # the forward-model PINNs sit between the features and the inversion
    assert PHYSICS_DEPTH["ebl"] < PHYSICS_DEPTH["original-pinn-fm"] < PHYSICS_DEPTH["oracle"]
    t = pd.DataFrame({"model": ["ebl", "original-pinn-fm"], "physics_depth": [4, 4.5],
                      "rmse_mgdl": [13.6, 18.0], "n_parameters": [67, 20_000]})
    ax = Figure().add_subplot()
    plot_physics_depth(t, depth_labels=PHYSICS_DEPTH_LABELS, ax=ax)
    assert list(ax.get_xticks()) == [4.0, 4.5]
    assert [x.get_text() for x in ax.get_xticklabels()] == [
        PHYSICS_DEPTH_LABELS[4], PHYSICS_DEPTH_LABELS[4.5]]


def test_efficiency_front_line():
    ax = Figure().add_subplot()
    out = plot_efficiency([56, 17, 163_000, 3_713], [13.6, 20.0, 14.6, 35.1], MODELS,
                          on_front=[True, True, False, False], xlabel="parameters [-]",
                          log_x=True, ax=ax)
    assert out is ax
    assert len(ax.collections) == len(MODELS)
    assert len(ax.lines) == 1
    np.testing.assert_array_equal(ax.lines[0].get_xdata(), [17, 56])
    assert ax.get_xscale() == "log"


def test_efficiency_rejects_mismatch():
    with pytest.raises(ValueError, match="differ in length"):
        plot_efficiency([1, 2], [1], ["a", "b"], xlabel="x")


def test_efficiency_landscape_three_panels():
    t = pd.DataFrame({"model": MODELS, "rmse_mgdl": [13.6, 20.0, 14.6, 35.1],
                      "n_parameters": [56, 17, 163_000, 3_713],
                      "macs_per_prediction": [55, 16, 160_000, 3_600],
                      "latency_single_ms": [0.01, 0.02, 3.8, 0.8],
                      "latency_single_p90_ms": [0.02, 0.03, 4.0, 0.9],
                      "front_parameters": [True, True, False, False],
                      "front_macs": [True, True, False, False],
                      "front_latency": [True, False, False, False]})
    fig = figure_efficiency_landscape(t)
    assert len(fig.axes) == 3
    assert [ax.get_xlabel().split(" [")[0] for ax in fig.axes] == [
        "trainable parameters", "multiply-accumulates per prediction", "single-sample latency"]
    assert all(sum(type(c).__name__ == "PathCollection" for c in ax.collections) == len(MODELS)
               for ax in fig.axes)
    whiskers = [c for c in fig.axes[2].collections if type(c).__name__ == "LineCollection"]
    assert len(whiskers) == 1  # median to p90, one segment per model
    segs = whiskers[0].get_segments()
    np.testing.assert_allclose([s[1][0] for s in segs], t["latency_single_p90_ms"])


def _reference_lines_within(ax, refs):
    lo, hi = ax.get_ylim()
    drawn = [ln.get_ydata()[0] for ln in ax.lines if len(set(ln.get_ydata())) == 1
             and tuple(ln.get_xdata()) == (0, 1)]
    assert sorted(drawn) == sorted(refs.values())  # one axhline per reference
    for name, v in refs.items():
        assert lo <= v <= hi, (name, v, (lo, hi))


def test_physics_depth_reference_lines_lie_within_the_axes():
    """The no-skill line above every model must be inside the y-limits, not only in the legend."""
    t = pd.DataFrame({"model": MODELS, "physics_depth": [4, 0, 1, 0],
                      "rmse_mgdl": [13.6, 20.0, 14.6, 35.1],
                      "n_parameters": [56, 17, 163_000, 3_713]})
    refs = {"oracle": 0.8, "mean": 60.0}
    ax = plot_physics_depth(t, references=refs, ax=Figure().add_subplot())
    _reference_lines_within(ax, refs)
    assert ax.get_ylim()[0] == 0.0


def test_efficiency_reference_lines_lie_within_the_axes():
    refs = {"oracle": 0.8, "mean": 60.0}
    ax = plot_efficiency([56, 17, 163_000, 3_713], [13.6, 20.0, 14.6, 35.1], MODELS,
                         xlabel="parameters [-]", log_x=True, references=refs,
                         ax=Figure().add_subplot())
    _reference_lines_within(ax, refs)


def test_physics_depth_axis_runs_from_most_physics_to_none():
    t = pd.DataFrame({"model": ["ebl", "sdnn"], "physics_depth": [4, 0],
                      "rmse_mgdl": [14.0, 35.0], "n_parameters": [56, 3713]})
    ax = plot_physics_depth(t)
    x = {m: ax.transData.transform((d, 0))[0] for m, d in (("ebl", 4), ("sdnn", 0))}
    assert x["ebl"] < x["sdnn"]  # the study's direction: physics on the left


def test_radar_grid_says_which_axis_was_not_counted():
    from nirglucose.plots.tradeoffs import figure_radar_grid

    scores = pd.DataFrame({"RMSE": [1.0, 0.5], "MACs": [1.0, np.nan]}, index=["ebl", "gp"])
    fig = figure_radar_grid(scores)
    labels = [[t.get_text() for t in ax.get_xticklabels()] for ax in fig.axes]
    assert labels[0] == ["RMSE", "MACs"]
    assert labels[1] == ["RMSE", "MACs\n(not counted)"]
