"""Palette, model colours and saving."""

from __future__ import annotations

import re

import matplotlib
from matplotlib.figure import Figure

from nirglucose.plots import style


def test_agg_backend():
    assert matplotlib.get_backend().lower() == "agg"


def test_palette_is_okabe_ito_and_models_distinct():
    assert len(style.OKABE_ITO) == 8
    assert all(re.fullmatch(r"#[0-9A-F]{6}", c) for c in style.OKABE_ITO.values())
    colors = style.model_colors(list(style.MODEL_COLORS) + ["new-model"])
    assert len(set(colors.values())) == len(colors) - 1 or len(set(colors.values())) == len(
        colors)
    assert len(set(style.MODEL_COLORS.values())) == len(style.MODEL_COLORS)


def test_unknown_models_get_distinct_colours():
    colors = style.model_colors(["a", "b", "c"])
    assert len(set(colors.values())) == 3


def test_save_figure_writes_png_and_svg(tmp_path):
    fig = Figure(figsize=(2, 2))
    fig.add_subplot().plot([0, 1], [0, 1])
    paths = style.save_figure(fig, tmp_path / "fig")
    assert [p.name for p in paths] == ["fig.png", "fig.svg"]
    assert paths[0].read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert b"<svg" in paths[1].read_bytes()[:500]
    assert not fig.axes  # closed and cleared


def test_figure_bytes_png():
    fig = Figure(figsize=(1, 1))
    assert style.figure_bytes(fig, "png").startswith(b"\x89PNG")


def test_every_registered_model_has_its_own_label_colour_and_marker():
    """No registered model falls back to a colour another model owns (issue 32)."""
    from nirglucose.models.labels import MODEL_LABELS
    from nirglucose.models.registry import MODELS
    from nirglucose.plots.style import MODEL_COLORS, MODEL_MARKERS

    names = sorted(MODELS)  # the package's own (a test may register a temporary one)
    assert set(names) <= set(MODEL_LABELS) & set(MODEL_COLORS) & set(MODEL_MARKERS)
    colours = [MODEL_COLORS[m] for m in names]
    assert len(set(colours)) == len(colours)
