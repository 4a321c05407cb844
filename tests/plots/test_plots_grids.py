"""Clarke and Parkes error-grid plots: artists, and grid lines that match the metrics."""

from __future__ import annotations

import numpy as np
import pytest
from matplotlib.collections import PathCollection
from matplotlib.figure import Figure

from nirglucose.metrics import PARKES_LINES, ZONE_LABELS, clarke_zones, parkes_zones
from nirglucose.plots.grids import (
    CLARKE_LABEL_POSITIONS,
    CLARKE_SEGMENTS,
    PARKES_LABEL_POSITIONS,
    figure_error_grids,
    plot_clarke_grid,
    plot_parkes_grid,
)

PCT = {"A": 70.0, "B": 20.0, "C": 5.0, "D": 5.0, "E": 0.0}


@pytest.fixture()
def pairs():
    rng = np.random.default_rng(1)
    ref = rng.uniform(40, 380, 37)
    return ref, np.clip(ref + rng.normal(0, 30, ref.size), 0, None)


def _ax():
    return Figure().add_subplot()


def test_clarke_draws_on_given_axes(pairs):
    ref, pred = pairs
    ax = _ax()
    assert plot_clarke_grid(ref, pred, zone_pct=PCT, ax=ax) is ax
    scat = [c for c in ax.collections if isinstance(c, PathCollection)]
    assert len(scat) == 1 and len(scat[0].get_offsets()) == ref.size  # one point each
    assert len(ax.lines) == len(CLARKE_SEGMENTS) + 1  # zone lines + diagonal
    letters = [t.get_text() for t in ax.texts if t.get_text() in ZONE_LABELS]
    assert len(letters) == sum(len(p) for p in CLARKE_LABEL_POSITIONS.values())
    legend = [t.get_text() for t in ax.get_legend().get_texts()]
    assert "zone A:  70.0 %" in legend and len(legend) == 6
    assert "[mg/dL]" in ax.get_xlabel() and "[mg/dL]" in ax.get_ylabel()


def test_clarke_new_axes_when_none(pairs):
    ax = plot_clarke_grid(*pairs)
    assert ax.figure is not None and ax.get_xlim() == (0.0, 400.0)


def test_clarke_rejects_mismatched_lengths():
    with pytest.raises(ValueError, match="differ in length"):
        plot_clarke_grid([100, 200], [100], ax=_ax())


def test_clarke_segments_separate_zones():
    """Points just either side of each drawn segment fall in different zones."""
    for (x0, y0), (x1, y1) in CLARKE_SEGMENTS:
        mx, my = (x0 + x1) / 2, (y0 + y1) / 2
        nx, ny = -(y1 - y0), x1 - x0
        norm = np.hypot(nx, ny)
        nx, ny = 1.5 * nx / norm, 1.5 * ny / norm
        a, b = clarke_zones([mx + nx, mx - nx], [my + ny, my - ny])
        assert a != b, ((x0, y0), (x1, y1), a, b)


def test_clarke_labels_lie_in_their_zone():
    for zone, positions in CLARKE_LABEL_POSITIONS.items():
        ref, pred = zip(*positions, strict=True)
        assert set(clarke_zones(ref, pred)) == {zone}


@pytest.mark.parametrize("dtype", [1, 2])
def test_parkes_lines_are_the_metric_vertices(pairs, dtype):
    ref, pred = pairs
    ax = _ax()
    assert plot_parkes_grid(ref, pred, zone_pct=PCT, diabetes_type=dtype, ax=ax) is ax
    assert len(ax.collections[0].get_offsets()) == ref.size
    lines = PARKES_LINES[dtype]
    assert len(ax.lines) == len(lines) + 1
    drawn = [np.column_stack(line.get_data()) for line in ax.lines[1:]]
    for got, want in zip(drawn, lines.values(), strict=True):
        np.testing.assert_array_equal(got, np.asarray(want, dtype=float))


@pytest.mark.parametrize("dtype", [1, 2])
def test_parkes_labels_lie_in_their_zone(dtype):
    for zone, positions in PARKES_LABEL_POSITIONS[dtype].items():
        ref, pred = zip(*positions, strict=True)
        assert set(parkes_zones(ref, pred, diabetes_type=dtype)) == {zone}


def test_parkes_rejects_unknown_type(pairs):
    with pytest.raises(ValueError, match="diabetes_type"):
        plot_parkes_grid(*pairs, diabetes_type=3, ax=_ax())


@pytest.mark.parametrize("kind", ["clarke", "parkes"])
def test_figure_one_panel_per_model(pairs, kind):
    ref, pred = pairs
    grids = {m: {"reference": ref, "predicted": pred, "zone_pct": PCT}
             for m in ("ebl", "pls", "sdnn", "mine", "other")}
    fig = figure_error_grids(grids, kind=kind)
    drawn = [ax for ax in fig.axes if ax.collections]
    assert len(drawn) == 5
    assert [ax.get_title() for ax in drawn][:2] == ["Enhanced Beer–Lambert", "PLS"]


def test_figure_rejects_unknown_kind():
    with pytest.raises(ValueError, match="kind"):
        figure_error_grids({}, kind="bland")
