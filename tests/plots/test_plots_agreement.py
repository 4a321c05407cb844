"""Bland–Altman and linearity plots."""

from __future__ import annotations

import numpy as np
import pytest
from matplotlib.figure import Figure

from nirglucose.plots.agreement import (
    figure_bland_altman,
    figure_linearity,
    plot_bland_altman,
    plot_linearity,
)

REF = np.linspace(80, 300, 25)
PRED = REF * 0.9 + 12 + np.sin(REF)


def _ax():
    return Figure().add_subplot()


def test_bland_altman_artists():
    ax = _ax()
    mean, diff = (REF + PRED) / 2, PRED - REF
    out = plot_bland_altman(mean, diff, bias=1.0, loa_low=-20.0, loa_high=22.0,
                            bias_ci=(-1.0, 3.0), loa_low_ci=(-25.0, -15.0),
                            loa_high_ci=(17.0, 27.0), ax=ax)
    assert out is ax
    assert len(ax.collections[0].get_offsets()) == REF.size
    assert len(ax.lines) == 4  # zero, bias, two limits
    assert len(ax.patches) == 3  # one CI band per line
    ys = sorted(line.get_ydata()[0] for line in ax.lines)
    assert ys == [-20.0, 0.0, 1.0, 22.0]
    assert "bias +1.0 [-1, +3]" in ax.get_title()  # under the title, not over the lines
    assert "[mg/dL]" in ax.get_xlabel() and "[mg/dL]" in ax.get_ylabel()


def test_bland_altman_without_intervals():
    ax = plot_bland_altman([100, 110], [1, -1], bias=0.0, loa_low=-2.0, loa_high=2.0)
    assert len(ax.patches) == 0 and len(ax.lines) == 4


def test_bland_altman_rejects_mismatch():
    with pytest.raises(ValueError, match="differ in length"):
        plot_bland_altman([1, 2], [1], bias=0, loa_low=-1, loa_high=1)


def test_linearity_artists_and_line():
    ax = _ax()
    out = plot_linearity(REF, PRED, slope=0.9, intercept=12.0, r_squared=0.95,
                         slope_ci=(0.85, 0.95), ax=ax)
    assert out is ax
    assert len(ax.collections[0].get_offsets()) == REF.size
    assert len(ax.lines) == 2  # unity and fitted line
    x, y = ax.lines[1].get_data()
    np.testing.assert_allclose(y, 12.0 + 0.9 * np.asarray(x))
    text = ax.texts[0].get_text()
    assert "slope 0.90 [0.85, 0.95]" in text and "R² = 0.95" in text


def test_per_model_figures():
    ba = {m: {"mean_mgdl": REF, "difference_mgdl": PRED - REF, "bias": 0.0,
              "loa_low": -1.0, "loa_high": 1.0} for m in ("ebl", "pls", "sdnn")}
    fig = figure_bland_altman(ba)
    assert sum(1 for ax in fig.axes if ax.collections) == 3
    lin = {m: {"reference": REF, "predicted": PRED, "slope": 1.0, "intercept": 0.0}
           for m in ("ebl", "pls")}
    fig = figure_linearity(lin)
    assert [ax.get_title() for ax in fig.axes if ax.collections] == [
        "Enhanced Beer–Lambert", "PLS"]
