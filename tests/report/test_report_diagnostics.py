"""Diagnostic figures: one agreement scatter, residuals, fold spread, both presets drawn."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from nirglucose.plots.agreement import figure_bland_altman
from nirglucose.plots.diagnostics import (
    figure_agreement_scatter,
    figure_fold_spread,
    figure_residuals,
)
from nirglucose.report import load_results
from nirglucose.report.figures.diagnostics import fold_scores, residual_inputs, scatter_inputs
from nirglucose.report.figures.inputs import bland_altman_inputs

#: Figures drawn once per preset (the primary's key, the peer's with ``_<preset>``).
PER_PRESET = ("data", "features", "scatter", "bland_altman", "residuals", "fold_spread", "radar",
              "physics_depth", "efficiency", "wavelengths")


def test_every_diagnostic_figure_is_drawn_for_each_preset(preset_report):
    text = preset_report.read_text(encoding="utf-8")
    for key in PER_PRESET:
        for k in (key, f"{key}_wearable"):
            assert f'<figure id="fig-{k}"><div class="zoom"><img' in text, k
        i = text.index(f'<figure id="fig-{key}_wearable">')
        assert " on wearable.</b>" in text[i:text.index("</figure>", i)], key
    # the duplicate grids are gone: one scatter per preset
    for gone in ("fig-clarke", "fig-parkes", "fig-linearity"):
        assert f'id="{gone}' not in text


def test_the_wearable_scatter_is_drawn_from_wearable_predictions(preset_results):
    paper = load_results(preset_results / "paper")
    wear = load_results(preset_results / "wearable")
    models = [m for m in wear.models if "/" not in m]
    a, _ = scatter_inputs(paper.predictions, models)
    b, _ = scatter_inputs(wear.predictions, models)
    m = models[0]
    assert not np.array_equal(a[m]["predicted"], b[m]["predicted"])
    met = wear.metrics.set_index("model")
    for model, p in b.items():  # the shares in the panels are the table's
        assert p["clarke_pct"]["A"] == pytest.approx(met.at[model, "clarke_a_pct"], abs=1e-9)
        if "parkes_a_pct" in met.columns:
            assert p["parkes_a_pct"] == pytest.approx(met.at[model, "parkes_a_pct"], abs=1e-9)


def test_agreement_scatter_shares_axes_and_draws_every_point(synthetic_results):
    res = load_results(synthetic_results)
    panels, _ = scatter_inputs(res.predictions, ["ebl", "original-pinn"])
    fig = figure_agreement_scatter(panels, ncols=2)
    axes = [ax for ax in fig.axes if ax.axison]
    assert len(axes) == 2
    assert len({ax.get_xlim() for ax in axes}) == 1 and len({ax.get_ylim() for ax in axes}) == 1
    for ax, p in zip(axes, panels.values(), strict=True):
        (points,) = ax.collections
        np.testing.assert_array_equal(points.get_offsets()[:, 1], p["predicted"])
        texts = " ".join(t.get_text() for t in ax.texts)
        assert f"Clarke A {p['clarke_pct']['A']:.0f}" in texts and "slope" in texts


def test_residuals_are_reference_minus_prediction_with_binned_medians():
    ref = np.linspace(80, 300, 200)
    pred = 0.5 * ref + 80.0  # regression to the mean: slope below 1
    p = pd.DataFrame({"model": "m", "repeat": 0, "fold": 0, "reference_mgdl": ref,
                      "scored_mgdl": pred})
    out = residual_inputs(p, ["m"])["m"]
    np.testing.assert_allclose(out["residual"], ref - pred)
    assert np.all(np.diff(out["bin_median"]) > 0)  # high predictions are too low
    fig = figure_residuals({"m": out})
    assert len(fig.axes[0].collections[0].get_offsets()) == ref.size


def test_fold_scores_and_their_spread_figure():
    rng = np.random.default_rng(0)
    rows = []
    for r in range(3):
        for f in range(5):
            e = rng.normal(0, 1 + f, 10)
            rows.append(pd.DataFrame({"model": "m", "repeat": r, "fold": f,
                                      "reference_mgdl": 100.0, "scored_mgdl": 100.0 + e}))
    p = pd.concat(rows, ignore_index=True)
    s = fold_scores(p, ["m"])
    assert len(s) == 15
    one = p[(p["repeat"] == 1) & (p["fold"] == 3)]
    want = float(np.sqrt(np.mean((one["scored_mgdl"] - 100.0) ** 2)))
    got = s.loc[(s["repeat"] == 1) & (s["fold"] == 3), "rmse_mgdl"].item()
    assert got == pytest.approx(want)
    fig = figure_fold_spread(s, ["m"])
    pts = [c for c in fig.axes[0].collections if len(c.get_offsets()) == 15]
    assert len(pts) == 1
    np.testing.assert_allclose(np.sort(pts[0].get_offsets()[:, 0]), np.sort(s["rmse_mgdl"]))


def test_bland_altman_panels_keep_their_own_range(synthetic_results):
    res = load_results(synthetic_results)
    ba = bland_altman_inputs(res.predictions, ["oracle", "original-pinn"])
    fig = figure_bland_altman(ba, ncols=2)
    lo0, hi0 = fig.axes[0].get_ylim()
    lo1, hi1 = fig.axes[1].get_ylim()
    assert hi1 > 2 * hi0  # the oracle's panel is not flattened by the network's range
    for ax, p in zip(fig.axes[:2], ba.values(), strict=True):
        lo, hi = ax.get_ylim()
        assert lo < p["loa_low_ci"][0] and p["loa_high_ci"][1] < hi  # every CI shows


def test_no_data_figure_borrows_a_model_colour(synthetic_results):
    """A colour means one model in every figure: the data figures use none of them."""
    from matplotlib.colors import to_hex

    from nirglucose.plots import data
    from nirglucose.plots.style import MODEL_COLORS

    res = load_results(synthetic_results)
    frame = res.dataset.frame
    g = frame["glucose_mgdl"].to_numpy(float)
    adc = {850.0: np.log(g + 100.0), 940.0: np.log(2 * g + 50.0)}
    fig = data.figure_data_characteristics(g, frame["diabetes_status"].astype(str), adc,
                                           {850.0: 0.5, 940.0: 0.4})
    used = set()
    for ax in fig.axes:
        for c in ax.collections:
            used |= {to_hex(x) for x in c.get_facecolors()}
        used |= {to_hex(p.get_facecolor()) for p in ax.patches}
    model = {to_hex(c) for m, c in MODEL_COLORS.items() if m != "oracle"}  # black: ink
    assert used and not used & model, used & model


def test_training_curves_carry_the_held_out_error(synthetic_results):
    from nirglucose.plots.training import figure_training_dynamics
    from nirglucose.report.figures.sections import _held_out_mse

    res = load_results(synthetic_results)
    held = _held_out_mse(res, ["original-pinn", "not-run"])
    ref = res.predictions.drop_duplicates("measurement_id")["reference_mgdl"]
    rmse = res.metrics.set_index("model").at["original-pinn", "rmse_mgdl"]
    assert held == {"original-pinn": pytest.approx(rmse ** 2 / np.var(ref))}
    hist = {"original-pinn": res.histories["original-pinn"]}
    fig = figure_training_dynamics(hist, held_out=held)
    lines = [ln for ln in fig.axes[0].lines if ln.get_linestyle() == "-."]
    assert len(lines) == 1 and lines[0].get_ydata()[0] == pytest.approx(held["original-pinn"])
    lo, hi = fig.axes[0].get_ylim()
    assert lo < held["original-pinn"] < hi
