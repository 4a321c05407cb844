"""Forest plot of RMSE and the drop-one-LED dot plot (wavelength utilisation)."""

from __future__ import annotations

import numpy as np
import pandas as pd
from matplotlib.figure import Figure

from nirglucose.plots.forest import plot_rmse_forest
from nirglucose.plots.wavelengths import figure_drop_one, plot_drop_one


def test_forest_one_errorbar_per_model_and_study_marks():
    t = pd.DataFrame({"model": ["ebl", "pls", "oracle"], "rmse_mgdl": [14.0, 18.0, 5.0],
                      "rmse_ci_low": [12.0, 16.0, 4.0], "rmse_ci_high": [16.0, 20.0, 6.0],
                      "study_rmse_mgdl": [13.6, np.nan, np.nan]})
    ax = Figure().add_subplot()
    assert plot_rmse_forest(t, ax=ax) is ax
    assert len(ax.containers) == 3
    assert len(ax.collections[-1].get_offsets()) == 1  # only EBL has a study value
    assert [t.get_text() for t in ax.get_yticklabels()][0] == "Enhanced Beer–Lambert"
    assert ax.get_xlabel() == "RMSE [mg/dL]"


def test_forest_without_study_values():
    t = pd.DataFrame({"model": ["mine"], "rmse_mgdl": [10.0], "rmse_ci_low": [np.nan],
                      "rmse_ci_high": [np.nan]})
    ax = plot_rmse_forest(t)
    assert len(ax.containers) == 1 and len(ax.get_legend().get_texts()) == 1


def _drop_table():
    return pd.DataFrame({
        "model": ["ebl"] * 4 + ["pls"] * 2,
        "dropped_wavelength_nm": [1150.0, 850.0, 940.0, 1050.0, 850.0, 940.0],
        "rmse_all_mgdl": [14.0] * 4 + [20.0] * 2,
        "delta_rmse_mgdl": [0.5, 3.0, -0.2, 9.0, 1.0, 2.0],
        "ci_low": [-0.5, 1.0, -1.0, 6.0, -2.0, 0.5],
        "ci_high": [1.5, 5.0, 0.6, 12.0, 4.0, 3.5],
    })


def test_drop_one_dots_with_cis_filled_where_the_ci_excludes_zero():
    ax = Figure().add_subplot()
    assert plot_drop_one(_drop_table(), "ebl", ax=ax) is ax
    assert len(ax.containers) == 4  # one error bar per LED
    assert [t.get_text() for t in ax.get_xticklabels()] == ["850", "940", "1050", "1150"]
    # sorted by wavelength: 850 (CI 1..5) and 1050 (6..12) exclude 0, filled
    faces = [c.lines[0].get_markerfacecolor() for c in ax.containers]
    filled = [f != "white" for f in faces]
    assert filled == [True, False, True, False]
    ys = [float(c.lines[0].get_ydata()[0]) for c in ax.containers]
    assert ys == [3.0, -0.2, 9.0, 0.5]
    assert "14.0 mg/dL" in ax.get_title() and ax.get_xlabel() == "LED left out [nm]"


def test_drop_one_figure_one_panel_per_model():
    fig = figure_drop_one(_drop_table(), ["pls", "ebl", "absent"])
    shown = [a for a in fig.axes if a.get_visible()]
    assert len(shown) == 2 and [len(a.containers) for a in shown] == [2, 4]


def test_forest_every_row_has_a_visible_marker():
    """The no-skill row too: a line marker ('_') would vanish into its error bar."""
    from matplotlib.lines import Line2D

    models = ["ebl", "oracle", "gbr", "mean"]
    t = pd.DataFrame({"model": models, "rmse_mgdl": [14.0, 5.0, 16.0, 40.0],
                      "rmse_ci_low": [12.0, 4.0, 14.0, 35.0],
                      "rmse_ci_high": [16.0, 6.0, 18.0, 45.0]})
    ax = plot_rmse_forest(t)
    assert len(ax.containers) == len(models)
    for model, cont in zip(models, ax.containers, strict=True):
        line = cont.lines[0]  # the data marker of the error bar
        assert line.get_marker() in Line2D.filled_markers, (model, line.get_marker())
        assert line.get_markersize() >= 5, model
        assert line.get_markeredgecolor() != line.get_markerfacecolor(), model


def _headline_table():
    from nirglucose.evaluation.benchmark.findings import headline_table  # noqa: F401 (the producer)

    rows = []
    for preset, vals in (("paper", {"gp": 4.0, "ebl": 13.6, "pls": 25.0}),
                         ("wearable", {"gp": 48.7, "ebl": 45.5, "pls": 50.8})):
        best = min(vals, key=vals.get)
        for m, v in vals.items():
            rows.append({"preset": preset, "model": m, "rmse_mgdl": v, "rmse_ci_low": v - 2,
                         "rmse_ci_high": v + 2, "status": "best" if m == best else
                         ("tied" if preset == "wearable" else "worse")})
    return pd.DataFrame(rows), {"paper": {"mean": 56.5, "oracle": 0.8},
                                "wearable": {"mean": 56.5, "oracle": 11.0}}


def test_headline_one_panel_per_preset_with_reference_lines():
    from nirglucose.plots.forest import figure_headline
    from nirglucose.plots.style import model_color

    table, refs = _headline_table()
    fig = figure_headline(table, refs)
    axes = [a for a in fig.axes if a.containers]
    assert [a.get_title() for a in axes] == ["preset: paper", "preset: wearable"]
    for ax, preset in zip(axes, ("paper", "wearable"), strict=True):
        assert len(ax.containers) == 3  # one error bar per model
        xs = sorted(line.get_xdata()[0] for line in ax.lines if line.get_linestyle() in
                    ("--", ":"))
        assert xs == sorted(refs[preset].values())  # no skill and oracle of this preset
    # rows sorted by the first preset's RMSE, shared by both panels
    assert [t.get_text() for t in axes[0].get_yticklabels()][0] == "Gaussian process (ARD)"
    # colour per model as everywhere; open markers for the significantly worse
    paper = axes[0]
    for cont, model in zip(paper.containers, ["gp", "ebl", "pls"], strict=True):
        line = cont.lines[0]
        assert line.get_color() == model_color(model)
        assert (line.get_markerfacecolor() == "white") == (model != "gp")
    assert all(c.lines[0].get_markerfacecolor() != "white" for c in axes[1].containers)
