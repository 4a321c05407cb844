"""Training-dynamics plots."""

from __future__ import annotations

import numpy as np
import pandas as pd
from matplotlib.figure import Figure

from nirglucose.plots.training import (
    NO_NETWORKS_TEXT,
    figure_training_dynamics,
    loss_term_columns,
    plot_training_history,
)

EPOCHS = np.arange(1, 11)
PINN = pd.DataFrame({"epoch": EPOCHS, "train_loss": 1 / EPOCHS, "val_loss": 1.2 / EPOCHS,
                     "train_mse": 0.9 / EPOCHS, "train_physics": 0.1 / EPOCHS})
SDNN = PINN[["epoch", "train_loss", "val_loss"]]


def test_one_line_per_loss_column():
    ax = Figure().add_subplot()
    assert plot_training_history(PINN, ax=ax) is ax
    assert len(ax.lines) == 4
    assert all(len(line.get_xdata()) == EPOCHS.size for line in ax.lines)
    assert ax.get_yscale() == "log"
    assert ax.get_xlabel() == "epoch [-]"


def test_loss_terms_exclude_totals():
    assert loss_term_columns(PINN) == ["train_mse", "train_physics"]
    assert loss_term_columns(SDNN) == []


def test_figure_one_panel_per_network():
    fig = figure_training_dynamics({"original-pinn": PINN, "sdnn": SDNN})
    drawn = [ax for ax in fig.axes if ax.lines]
    assert [len(ax.lines) for ax in drawn] == [4, 2]


def test_figure_without_networks_says_so():
    fig = figure_training_dynamics({})
    texts = [t.get_text() for ax in fig.axes for t in ax.texts]
    assert texts == [NO_NETWORKS_TEXT]


def test_a_loss_term_has_one_colour_in_every_panel():
    """'train mse' and 'train physics' look the same whatever the model's colour."""
    other = PINN.assign(train_reflectance=0.3 / EPOCHS)[
        ["epoch", "train_loss", "train_reflectance", "train_mse", "train_physics"]]
    fig = figure_training_dynamics({"original-pinn": PINN, "optimized-pinn": other,
                                    "rte-pinn": PINN})
    colours: dict[str, set] = {}
    for ax in fig.axes:
        for line in ax.lines:
            name = line.get_label()
            if "(total" not in name:
                colours.setdefault(name, set()).add(line.get_color())
    assert {"train mse", "train physics", "train reflectance"} <= set(colours)
    assert all(len(c) == 1 for c in colours.values()), colours
    assert len({next(iter(c)) for c in colours.values()}) == len(colours)  # distinct terms
