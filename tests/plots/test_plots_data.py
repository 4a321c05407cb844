"""Data-characteristics plots (figure 1) and the pipeline diagram (figure 2)."""

from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure
from matplotlib.patches import FancyArrowPatch, FancyBboxPatch

from nirglucose.plots.data import (
    figure_data_characteristics,
    figure_distributions,
    plot_category_counts,
    plot_distribution,
    plot_glucose_by_status,
    plot_nir_vs_glucose,
)
from nirglucose.plots.pipeline import plot_pipeline

RNG = np.random.default_rng(0)
G = RNG.uniform(70, 350, 50)
STATUS = np.array(["normal", "type1", "type2", "prediabetes", "type2"] * 10)


def _ax():
    return Figure().add_subplot()


def test_glucose_by_status_one_stack_per_status():
    ax = _ax()
    assert plot_glucose_by_status(G, STATUS, ax=ax) is ax
    assert len(ax.containers) == 4
    assert sum(p.get_height() for c in ax.containers[-1:] for p in c) > 0
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert labels[0] == "normal (n = 10)"
    assert ax.get_xlabel() == "reference glucose [mg/dL]"


def test_nir_scatter_prints_given_correlation():
    ax = _ax()
    plot_nir_vs_glucose(G, np.log(3000 - G), wavelength_nm=1050.0, correlation=0.21, ax=ax)
    assert len(ax.collections[0].get_offsets()) == G.size
    assert ax.get_title() == "1050 nm  (r = +0.21)"


def test_distribution_and_counts():
    ax = plot_distribution(RNG.lognormal(4, 1, 80), xlabel="illuminance [lx]", log=True,
                           bins=10, ax=_ax())
    assert len(ax.patches) == 10 and ax.get_xscale() == "log"
    ax = plot_category_counts({"sun": 3, "led": 5}, xlabel="light source", ax=_ax())
    assert len(ax.patches) == 2


def test_figure_data_characteristics_panels():
    adc = {w: np.log(RNG.uniform(1500, 3000, G.size)) for w in (850.0, 940.0, 1050.0, 1150.0)}
    fig = figure_data_characteristics(G, STATUS, adc, dict.fromkeys(adc, 0.1))
    assert len(fig.axes) == 5


def test_figure_distributions_blank_spare_panels():
    panels = [{"values": G, "xlabel": "a [u]"}, {"counts": {"x": 1}, "xlabel": "b"},
              {"values": G, "xlabel": "c [u]"}]
    fig = figure_distributions(panels, ncols=2)
    assert len(fig.axes) == 4 and not fig.axes[3].axison


def test_pipeline_boxes_and_arrows():
    cols = [
        [{"title": "Environment", "details": ["18-30 °C"], "noise_on": ["ambient light"],
          "noise_off": ["humidity coupling"]},
         {"title": "Physiology", "details": []}],
        [{"title": "Optics: diffusion", "kind": "optics"}],
        [{"title": "Hardware", "kind": "hardware", "noise_on": ["shot"]}],
    ]
    ax = _ax()
    assert plot_pipeline(cols, ax=ax) is ax
    boxes = [p for p in ax.patches if isinstance(p, FancyBboxPatch)]
    arrows = [p for p in ax.patches if isinstance(p, FancyArrowPatch)]
    assert len(boxes) == 4 and len(arrows) == 2 + 1
    texts = [t.get_text() for t in ax.texts]
    assert "Optics: diffusion" in texts
    assert "humidity coupling (off)" in " ".join(t.strip() for t in texts)


def test_pipeline_empty():
    ax = plot_pipeline([], ax=_ax())
    assert ax.texts[0].get_text() == "no pipeline description"
