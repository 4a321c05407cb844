"""The model-architecture, feature-engineering and performance figures agree with their sources.

Each test compares what a figure draws with an independent reading of the thing it
depicts: the Linear layers of the fitted torch modules, the fitted EBL model's
coefficient count, the benchmark's metrics table.
"""

from __future__ import annotations

import re

import matplotlib.colors
import numpy as np
import pandas as pd
import pytest
import torch.nn as nn

import nirglucose as ng
from nirglucose.models import make_model, tuned_params
from nirglucose.plots.architecture import (
    figure_architectures,
    figure_feature_engineering,
    figure_performance_panel,
)
from nirglucose.plots.style import model_color, model_label
from nirglucose.report.figures import (
    ARCHITECTURE_MODELS,
    ebl_feature_table,
    feature_categories,
    fitted_architectures,
    load_results,
    performance_table,
)

_NETWORKS = [m for m in ARCHITECTURE_MODELS if m != "ebl"]


@pytest.fixture(scope="module")
def paper_ds():
    return ng.simulate("paper", n_subjects=6, per_subject=2, seed=3)


@pytest.fixture(scope="module")
def archs(paper_ds):
    return fitted_architectures(paper_ds, "paper")


def _widths(sizes: str) -> list[int]:
    """Layer widths of a block's size text ('4→32→64, dropout 0.1' -> [4, 32, 64])."""
    return [int(w) for w in sizes.split(",")[0].split("→")]


def _module_widths(module) -> list[int]:
    """The in/out widths of every Linear layer of a module, read directly."""
    out: list[int] = []
    for lin in (m for m in module.modules() if isinstance(m, nn.Linear)):
        out += [lin.in_features, lin.out_features]
    return out


def test_architectures_have_six_families_with_the_fitted_module_sizes(archs, paper_ds):
    assert list(archs) == list(ARCHITECTURE_MODELS)
    for name in _NETWORKS:
        blocks, n_params = archs[name]
        m = make_model(name, **{**tuned_params(name, "paper"), "max_epochs": 1}).fit(paper_ds)
        inner = getattr(m.module_, "inner", m.module_)
        assert n_params == sum(p.numel() for p in m.module_.parameters() if p.requires_grad)
        shown: list[int] = []
        for block, sizes in blocks[1:-1]:  # inputs and output are not layers
            if sizes.startswith("attention"):
                att = getattr(inner, block)
                assert sizes.startswith(f"attention {att.embed_dim}-d, {att.num_heads} head")
                continue
            w = _widths(sizes)
            shown += [x for a, b in zip(w, w[1:], strict=False) for x in (a, b)]
        expected = [w for child in inner.children()
                    if not isinstance(child, nn.MultiheadAttention)
                    for w in _module_widths(child)]
        assert shown == expected, name
    n_a, n_p = len(paper_ds.wavelengths_nm), 14  # the paper device's physiological vector
    assert all(b[0] == ("inputs", f"{n_a} absorbances + {n_p} physiology")
               for b, _ in archs.values())


def test_architecture_figure_draws_every_block_and_count(archs):
    fig = figure_architectures(archs)
    axes = [ax for ax in fig.axes if ax.texts]
    assert len(axes) == 6
    for ax, (name, (blocks, n_params)) in zip(axes, archs.items(), strict=True):
        assert ax.get_title() == f"{model_label(name)}\n{n_params:,} trainable parameters"
        labels = [t.get_text() for t in ax.texts if t.get_text()]  # arrows are blank
        assert labels == [f"{b}\n{s}" for b, s in blocks]
        assert len(ax.patches) == len(blocks)
        ymin, ymax = ax.get_ylim()  # every box within the panel
        assert all(ymin <= p.get_y() and p.get_y() + p.get_height() <= ymax
                   for p in ax.patches), name


def test_architecture_blocks_follow_the_module_they_read():
    """Sizes are read from the module, not typed in: other widths, other text."""
    from nirglucose.report.figures import _module_blocks

    class Net(nn.Module):
        def __init__(self, hidden: int):
            super().__init__()
            self.front = nn.Sequential(nn.Linear(3, hidden), nn.ReLU(), nn.Dropout(0.25),
                                       nn.Linear(hidden, 2))
            self.norm = nn.LayerNorm(2)  # no widths: left out
            self.attn = nn.MultiheadAttention(8, 2)

    assert _module_blocks(Net(7)) == [("front", "3→7→2, dropout 0.25"),
                                      ("attn", "attention 8-d, 2 head(s)")]
    assert _module_blocks(Net(11))[0] == ("front", "3→11→2, dropout 0.25")


@pytest.mark.parametrize(("preset", "n_features"), [("wearable", 56), ("paper", 66)])
def test_feature_categories_sum_to_the_ebl_feature_count(preset, n_features):
    ds = ng.simulate(preset, n_subjects=6, per_subject=2, seed=1)
    table, n_ch, n_phys = ebl_feature_table(ds, preset)
    cats, src = feature_categories(table)
    m = make_model("ebl", **tuned_params("ebl", preset)).fit(ds)
    assert sum(len(v) for v in cats.values()) == np.size(m.coef_) == n_features
    assert n_ch == len(ds.wavelengths_nm) == 4
    assert set(src.values()) <= {"absorbance", "physiology", "both"}
    fig = figure_feature_engineering(n_ch, n_phys, cats, src)
    texts = [t.get_text() for t in fig.axes[0].texts]
    counts = {m.group(1): int(m.group(2)) for t in texts
              if (m := re.match(r"(\S+) \((\d+)\): ", t))}
    assert counts == {c: len(v) for c, v in cats.items()}
    assert sum(counts.values()) == n_features
    assert any(t.startswith(f"{n_features} features") for t in texts)
    assert any(f"({n_ch} LEDs)" in t for t in texts)
    assert any(f"({n_phys} entries)" in t for t in texts)


def test_performance_panel_numbers_equal_the_benchmark_table(synthetic_results):
    met = load_results(synthetic_results).metrics
    other = met.assign(rmse_mgdl=met["rmse_mgdl"] * 1.5, rmse_ci_low=met["rmse_ci_low"] * 1.5,
                       rmse_ci_high=met["rmse_ci_high"] * 1.5)
    models = ["ebl", "original-pinn"]
    table = performance_table({"paper": met, "wearable": other}, models)
    assert list(table["preset"]) == ["paper", "paper", "wearable", "wearable"]
    src = {"paper": met.set_index("model"), "wearable": other.set_index("model")}
    cols = ("rmse_mgdl", "mard_pct", "n_parameters", "macs_per_prediction")
    for _, row in table.iterrows():
        for col in cols:
            assert row[col] == src[row["preset"]].at[row["model"], col], (row["model"], col)
    fig = figure_performance_panel(table)
    assert len(fig.axes) == 4
    for ax, col in zip(fig.axes, cols, strict=True):
        for k, preset in enumerate(("paper", "wearable")):
            want = [src[preset].at[m, col] for m in models]
            if ax.get_xscale() == "log":  # costs: dots, no bars on a log axis
                assert not ax.patches, col
                drawn = ax.collections[k].get_offsets()[:, 0]
            else:
                bars = [p for p in ax.patches if p.get_height() > 0]
                drawn = [b.get_width() for b in bars[2 * k: 2 * k + 2]]
            np.testing.assert_allclose(drawn, want, rtol=1e-12, err_msg=f"{col} {preset}")
        # colour is the model's in every panel, never the preset's
    bars = [p for p in fig.axes[0].patches if p.get_height() > 0]
    assert [matplotlib.colors.to_hex(b.get_facecolor()) for b in bars[:2]] == [
        model_color(m).lower() for m in models]
    assert [t.get_text() for t in fig.axes[0].get_yticklabels()] == [model_label(m)
                                                                     for m in models]
    assert fig.legends and [t.get_text().split(" ")[0] for t in fig.legends[0].get_texts()] == [
        "paper", "wearable"]


def test_performance_panel_in_the_report_uses_the_run_s_metrics(synthetic_results, monkeypatch):
    from nirglucose.plots import architecture
    from nirglucose.report.figures import render_figures

    drawn: dict[str, list] = {}

    def spy(table):  # the report's own figure builder, read before the report clears it
        out = figure_performance_panel(table)
        drawn["labels"] = [t.get_text() for t in out.axes[0].get_yticklabels()]
        drawn["widths"] = [[b.get_width() for b in ax.patches if b.get_height() > 0]
                           or list(ax.collections[0].get_offsets()[:, 0]) for ax in out.axes]
        return out

    monkeypatch.setattr(architecture, "figure_performance_panel", spy)
    res = load_results(synthetic_results)
    (fig,) = render_figures(res, include=["performance"])
    assert fig.png and fig.key == "performance"
    table = performance_table({"paper": res.metrics}, ["ebl", "original-pinn"])
    want = res.metrics.set_index("model").loc[["ebl", "original-pinn"], "rmse_mgdl"]
    pd.testing.assert_series_equal(table.set_index("model")["rmse_mgdl"], want)
    met = res.metrics.set_index("model")
    by_label = {model_label(m): m for m in met.index}
    models = [by_label[t] for t in drawn["labels"]]
    assert {"ebl", "original-pinn"} <= set(models)
    cols = ("rmse_mgdl", "mard_pct", "n_parameters", "macs_per_prediction")
    assert len(drawn["widths"]) == len(cols)
    for widths, col in zip(drawn["widths"], cols, strict=True):
        np.testing.assert_allclose(widths, [met.at[m, col] for m in models], rtol=1e-12,
                                   err_msg=col)


def test_architecture_draws_branches_side_by_side_and_the_physics_loss(paper_ds):
    from nirglucose.report.figures.descriptive import physics_loss_texts

    fitted: dict = {}
    archs = fitted_architectures(paper_ds, "paper", ["original-pinn", "sdnn"], fitted=fitted)
    physics = physics_loss_texts(fitted)
    assert set(physics) == {"original-pinn"}  # only a PINN has a physics term
    lam = fitted["original-pinn"].lambda_phys
    assert f"λ = {lam:g}" in physics["original-pinn"]
    fig = figure_architectures(archs, physics=physics)
    ax_pinn, ax_sdnn = [ax for ax in fig.axes if ax.texts]
    centre = {t.get_text().split("\n")[0]: t.get_position() for t in ax_pinn.texts
              if t.get_text()}
    assert centre["nir"][1] == centre["pmf"][1]  # one row: parallel, not a chain
    assert centre["nir"][0] < centre["pmf"][0]
    assert centre["head"][1] < centre["nir"][1]
    assert centre["training loss only"][1] < centre["output"][1]
    dashed = [p for p in ax_pinn.patches if p.get_linestyle() == "--"]
    assert len(dashed) == 1 and len(ax_pinn.patches) == len(archs["original-pinn"][0]) + 1
    assert not any(p.get_linestyle() == "--" for p in ax_sdnn.patches)
