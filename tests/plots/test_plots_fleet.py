"""The fleet study's figure: one panel per model, one line per variant."""

from __future__ import annotations

import numpy as np
import pandas as pd

from nirglucose.plots.fleet import VARIANT_STYLES, figure_fleet


def _table():
    rows = []
    for m in ("ebl", "oracle"):
        for v in ("same-unit", "no-transfer", "slope-bias"):
            for s in (0.0, 1.0, 2.0):
                y = 10.0 + (s * 50 if v == "no-transfer" else s)
                rows.append({"tolerance_scale": s, "variant": v, "model": m, "rmse_mgdl": y,
                             "rmse_ci_low": y - 30.0, "rmse_ci_high": y + 2.0})
    return pd.DataFrame(rows)


def test_panels_lines_and_log_axis():
    fig = figure_fleet(_table())
    axes = fig.axes
    assert len(axes) == 2 and [a.get_title() for a in axes][0] != ""
    labels = [t.get_text() for t in axes[0].get_legend().get_texts()]
    assert labels == [VARIANT_STYLES[v][2] for v in ("same-unit", "no-transfer", "slope-bias")]
    assert axes[0].get_yscale() == "log"
    # the no-transfer line climbs with the scale; an interval below zero ends at the floor
    line = axes[0].get_lines()
    ys = [ln.get_ydata() for ln in line if len(ln.get_xdata()) == 3]
    assert any(np.allclose(y, [10, 60, 110]) for y in ys)
    assert axes[0].get_ylim()[0] > 0
