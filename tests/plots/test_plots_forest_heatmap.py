"""Forest plot of RMSE (figure 12) and the wavelength heatmap (figure 11)."""

from __future__ import annotations

import numpy as np
import pandas as pd
from matplotlib.figure import Figure
from matplotlib.image import AxesImage

from nirglucose.plots.forest import plot_rmse_forest
from nirglucose.plots.wavelengths import plot_wavelength_heatmap


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


def test_heatmap_cells_and_annotations():
    mat = pd.DataFrame([[1.0, 2.0, 3.0, 4.0], [0.5, np.nan, 1.5, 2.5]],
                       index=["ebl", "pls"], columns=[850.0, 940.0, 1050.0, 1150.0])
    ax = Figure().add_subplot()
    assert plot_wavelength_heatmap(mat, ax=ax) is ax
    images = [a for a in ax.get_children() if isinstance(a, AxesImage)]
    assert len(images) == 1 and images[0].get_array().shape == (2, 4)
    assert len(ax.texts) == 7  # finite cells only
    assert [t.get_text() for t in ax.get_xticklabels()] == ["850", "940", "1050", "1150"]
    assert ax.get_xlabel() == "LED wavelength [nm]"


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
    from nirglucose.evaluation.findings import headline_table  # noqa: F401 (the producer)

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
