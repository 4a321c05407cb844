"""Sweep figures: degradation curves with bands, ablation bars, domain-shift bars."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from matplotlib.collections import PolyCollection
from matplotlib.container import BarContainer
from matplotlib.figure import Figure

from nirglucose.plots.sweep import (
    figure_ablation,
    plot_ablation_bars,
    plot_shift_bars,
    plot_sweep_curve,
)

X = [0.25, 0.5, 1.0, 2.0, 4.0]
SUMMARY = pd.DataFrame([
    {"model": m, "noise_scale": x, "rmse_mgdl_mean": base * x ** 0.5,
     "rmse_mgdl_ci_low": base * x ** 0.5 - 2, "rmse_mgdl_ci_high": base * x ** 0.5 + 2,
     "mard_pct_mean": base * x ** 0.5 / 2, "mard_pct_ci_low": np.nan,
     "mard_pct_ci_high": np.nan}
    for m, base in (("ebl", 20.0), ("pls", 25.0), ("oracle", 5.0)) for x in X])
EFFECTS = pd.DataFrame([
    {"model": m, "source": s, "delta_off": d, "delta_off_ci_low": d - 1,
     "delta_off_ci_high": d + 1, "delta_only": 2 * d, "delta_only_ci_low": np.nan,
     "delta_only_ci_high": np.nan}
    for m in ("ebl", "pls") for s, d in (("shot", 0.1), ("led_thermal_drift", 8.0),
                                         ("contact_pressure", 5.0))])


def test_curve_lines_bands_and_axes():
    ax = Figure().add_subplot()
    assert plot_sweep_curve(SUMMARY, "noise_scale", ax=ax, xlabel="noise scale [-]") is ax
    assert len(ax.lines) == 3 and ax.lines[0].get_label() == "Enhanced Beer–Lambert"
    np.testing.assert_allclose(ax.lines[0].get_xdata(), X)
    assert sum(isinstance(c, PolyCollection) for c in ax.collections) == 3
    assert ax.get_xscale() == "log"
    assert ax.get_xlabel() == "noise scale [-]" and ax.get_ylabel() == "RMSE [mg/dL]"


def test_curve_threshold_and_missing_band():
    ax = plot_sweep_curve(SUMMARY, "noise_scale", metric="mard_pct", threshold=15.0,
                          models=["ebl"], log_x=False)
    assert len(ax.lines) == 2  # one model + the limit
    assert ax.lines[1].get_label() == "15 % limit"
    assert not any(isinstance(c, PolyCollection) for c in ax.collections)  # NaN intervals
    assert ax.get_ylabel() == "MARD [%]" and ax.get_xscale() == "linear"


def test_ablation_bars_sorted_with_units():
    ax = plot_ablation_bars(EFFECTS)
    bars = [c for c in ax.containers if isinstance(c, BarContainer)]
    assert len(bars) == 2
    labels = [t.get_text() for t in ax.get_yticklabels()]
    assert labels[-1] == "led thermal drift" and labels[0] == "shot"  # largest on top
    assert "[mg/dL]" in ax.get_xlabel()
    ax = plot_ablation_bars(EFFECTS, which="only", models=["pls"])
    assert len([c for c in ax.containers if isinstance(c, BarContainer)]) == 1
    with pytest.raises(ValueError, match="which"):
        plot_ablation_bars(EFFECTS, which="both")
    assert len(figure_ablation(EFFECTS).axes) == 2


def test_shift_bars():
    eff = pd.DataFrame([{"model": m, "shift": s, "train_domain": "I-III",
                         "test_domain": "IV-VI", "in_domain": 10.0, "shifted": 14.0,
                         "delta_ci_low": 2.0, "delta_ci_high": 6.0}
                        for m in ("ebl", "pls") for s in ("fitzpatrick", "temperature")])
    ax = plot_shift_bars(eff)
    assert len([c for c in ax.containers if isinstance(c, BarContainer)]) == 4
    assert ax.get_ylabel() == "RMSE [mg/dL]"
    assert "train I-III" in ax.get_xticklabels()[0].get_text()
