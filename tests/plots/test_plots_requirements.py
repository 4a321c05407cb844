"""plots.requirements: the averaging curve and the minimal-designs table."""

from __future__ import annotations

import pandas as pd
from matplotlib.axes import Axes

from nirglucose.plots.requirements import plot_averaging_curve, plot_minimal_designs


def _curve():
    rows = []
    for design, scale in (("study's device", 56.0), ("BPW34: least", 40.0)):
        for w in (0.0, 1.0, 60.0, 300.0):
            bound = scale / (1 + w) ** 0.3
            rows.append({"design": design, "window_s": w, "state_rmse_mgdl": bound,
                         "total_rmse_mgdl": bound + 0.01 * w})
    return pd.DataFrame(rows)


def test_averaging_curve_draws_one_line_per_design_and_the_target():
    ax = plot_averaging_curve(_curve(), target_rmse_mgdl=15.0)
    assert isinstance(ax, Axes)
    labels = [line.get_label() for line in ax.lines]
    assert "study's device" in labels and "BPW34: least" in labels
    assert "target 15 mg/dL" in labels
    assert ax.get_xscale() == "symlog"
    solid = next(line for line in ax.lines if line.get_label() == "BPW34: least")
    assert list(solid.get_xdata()) == [0.0, 1.0, 60.0, 300.0]


def test_minimal_designs_table_has_a_column_per_detector():
    designs = pd.DataFrame({"detector_label": ["Si (BPW34)", "InGaAs (G17190-010K)"],
                            "reached": [True, False], "n_leds": [8, 20],
                            "leds_nm": ["800,850", "850,900"], "capabilities": ["", "x"],
                            "adc_bits": [16, 24], "total_rmse_mgdl": [13.4, 17.0]})
    ax = plot_minimal_designs(designs)
    table = ax.tables[0]
    cells = table.get_celld()
    assert cells[(0, 0)].get_text().get_text() == "Si (BPW34)"
    assert cells[(1, 1)].get_text().get_text() == "no"  # row 1: "reaches the target"
    texts = {c.get_text().get_text() for c in cells.values()}
    assert "13.4" in texts and "24" in texts
