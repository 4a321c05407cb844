"""Per-figure inputs computed by the report layer."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from nirglucose.config import resolve_config
from nirglucose.metrics import bland_altman, clarke_zones, zone_percentages
from nirglucose.report.figures import (
    bland_altman_inputs,
    channel_correlations,
    drop_one_models,
    efficiency_table,
    error_grid_inputs,
    linearity_inputs,
    model_order,
    pareto_front,
    physics_depth_table,
    pipeline_columns,
    radar_scores,
)

RNG = np.random.default_rng(3)
REF = RNG.uniform(80, 300, 60)


def _preds(models=("ebl", "pls"), repeats=2):
    rows = []
    for m in models:
        for r in range(repeats):
            rows.append(pd.DataFrame({"model": m, "repeat": r, "subject_id": np.arange(60) // 3,
                                      "reference_mgdl": REF,
                                      "predicted_mgdl": REF + RNG.normal(0, 15, 60)}))
    return pd.concat(rows, ignore_index=True)


def test_error_grid_inputs_pool_repeats_and_agree_with_the_table():
    p = _preds()
    grids, clipped = error_grid_inputs(p, ["ebl", "pls"])
    assert clipped == 0 and list(grids) == ["ebl", "pls"]
    g = grids["ebl"]
    assert g["reference"].size == 120  # both repeats
    # the table averages per-repeat shares; equal repeat sizes make that the pooled share
    per_repeat = [zone_percentages(clarke_zones(q["reference_mgdl"], q["predicted_mgdl"]))["A"]
                  for _, q in p[p["model"] == "ebl"].groupby("repeat")]
    assert g["zone_pct"]["A"] == pytest.approx(np.mean(per_repeat))


def test_error_grid_inputs_keep_only_the_given_snapshots():
    p = _preds(("ebl",), 1).assign(measurement_id=np.arange(60))
    grids, _ = error_grid_inputs(p, ["ebl"], kind="parkes", diabetes_type=2,
                                 measurement_ids=range(10))
    assert grids["ebl"]["reference"].size == 10


def test_linearity_inputs_carry_prediction_intervals_when_present():
    p = _preds(("ebl",), 1)
    assert "lower" not in linearity_inputs(p, ["ebl"])["ebl"]
    p = p.assign(lower90_mgdl=p["predicted_mgdl"] - 20, upper90_mgdl=p["predicted_mgdl"] + 20)
    out = linearity_inputs(p, ["ebl"])["ebl"]
    assert np.allclose(out["upper"] - out["lower"], 40.0)
    from nirglucose.plots.agreement import figure_linearity

    fig = figure_linearity({"ebl": out})
    assert any("90 % interval" in t.get_text() for t in fig.axes[0].get_legend().get_texts())


def test_error_grid_inputs_place_negative_predictions_at_zero():
    p = _preds(("ebl",), 1)
    p.loc[0, "predicted_mgdl"] = -5.0
    grids, clipped = error_grid_inputs(p, ["ebl"], kind="parkes")
    assert clipped == 1 and grids["ebl"]["predicted"].min() == 0.0


def test_bland_altman_inputs_intervals():
    p = _preds(("ebl",), 1)
    out = bland_altman_inputs(p, ["ebl"])["ebl"]
    bias, low, high = bland_altman(p["reference_mgdl"], p["predicted_mgdl"])
    assert (out["bias"], out["loa_low"], out["loa_high"]) == (bias, low, high)
    for key, value in (("bias_ci", bias), ("loa_low_ci", low), ("loa_high_ci", high)):
        lo, hi = out[key]
        assert lo < value < hi
    # limits are less certain than the bias: sqrt(3) times wider (Bland & Altman 1986)
    width = np.diff(out["loa_low_ci"])[0] / np.diff(out["bias_ci"])[0]
    assert width == pytest.approx(np.sqrt(3))


def test_linearity_inputs_recover_a_line():
    p = pd.DataFrame({"model": "m", "reference_mgdl": REF,
                      "predicted_mgdl": 0.8 * REF + 20 + RNG.normal(0, 1e-6, REF.size)})
    out = linearity_inputs(p, ["m"])["m"]
    assert out["slope"] == pytest.approx(0.8) and out["intercept"] == pytest.approx(20.0)
    assert out["r_squared"] == pytest.approx(1.0)


def test_channel_correlations():
    adc = {850.0: np.exp(0.01 * REF), 940.0: np.full(REF.size, 2000.0)}
    r = channel_correlations(REF, adc)
    assert r[850.0] == pytest.approx(1.0) and np.isnan(r[940.0])


def test_pareto_front():
    assert pareto_front([1, 2, 3, np.nan], [3, 2, 4, 1]).tolist() == [True, True, False, False]


def test_radar_scores_orientation():
    m = pd.DataFrame({"model": ["a", "b"], "rmse_mgdl": [10.0, 20.0], "mard_pct": [5, 10],
                      "clarke_a_pct": [90.0, 45.0], "within15_pct": [80.0, 80.0],
                      "n_parameters": [10, 10_000_000], "macs_per_prediction": [100, 1000],
                      "latency_single_ms": [1.0, 10.0]})
    s = radar_scores(m, ["a", "b"])
    assert s.loc["a"].tolist() == [1.0, 1.0, 1.0, 1.0, 1.0, 1.0]
    assert s.loc["b", "RMSE"] == 0.5 and s.loc["b", "Clarke A"] == 0.5
    assert s.loc["b", "parameters"] == 0.0  # six decades above the smallest
    assert s.loc["b", "MACs"] == pytest.approx(1 - 1 / 6)
    assert "latency" not in s.columns  # it measures the machine, not the model


def test_efficiency_and_depth_tables():
    m = pd.DataFrame({"model": ["ebl", "sdnn", "oracle"], "rmse_mgdl": [14.0, 35.0, 5.0],
                      "n_parameters": [56, 3713, 0], "macs_per_prediction": [900, 100, 0],
                      "latency_single_ms": [0.01, 0.8, 0.5]})
    t = efficiency_table(m, ["ebl", "sdnn", "oracle"])
    assert list(t["model"]) == ["ebl", "sdnn"]  # the oracle is a reference line now
    assert t["front_parameters"].tolist() == [True, False]
    assert t["front_macs"].tolist() == [True, True]  # sdnn: fewer MACs, worse RMSE
    assert "combined_index" not in t.columns
    d, left_out = physics_depth_table(m, ["ebl", "sdnn", "oracle", "mine"])
    assert list(d["model"]) == ["ebl", "sdnn"] and left_out == ["mine"]  # oracle: a line


def test_drop_one_models_in_display_order():
    t = pd.DataFrame({"model": ["pls", "ebl", "ebl", "mine", "original-pinn/no-physics"],
                      "dropped_wavelength_nm": [940.0, 850.0, 940.0, 850.0, 850.0]})
    assert drop_one_models(t, model_order(["pls", "ebl"])) == ["ebl", "pls", "mine"]


def test_pipeline_reflects_the_config():
    cfg = resolve_config("paper", {"optics.model": "diffusion", "noise.shot.enabled": False,
                                   "noise.johnson.scale": 2.0})
    cols = pipeline_columns(cfg)
    boxes = {b["title"]: b for col in cols for b in col}
    assert "Optics: diffusion" in boxes
    hw = boxes["Hardware"]
    assert "shot (off)" in hw["noise_off"] and "johnson (×2)" in hw["noise_on"]
    assert "ambient light" in boxes["Environment"]["noise_on"]


def test_pipeline_noise_follows_the_device():
    """Issue 32: a noise source the device removes is not drawn as acting (paper vs wearable)."""
    from nirglucose.report.figures.descriptive import noise_states
    from nirglucose.report.figures.sections import _pipeline_caption

    def boxes(preset):
        return {b["title"]: b for col in pipeline_columns(resolve_config(preset)) for b in col}

    paper, wearable = boxes("paper"), boxes("wearable")
    assert ("pmf measurement (exact physiology: device.physiology = exact)"
            in paper["Measured outputs"]["noise_off"])
    assert "pmf measurement" in wearable["Measured outputs"]["noise_on"]
    assert any(s.startswith("contact pressure (constant-force")
               for s in paper["Physiology + contact"]["noise_off"])
    assert "contact pressure" in wearable["Physiology + contact"]["noise_on"]
    states = noise_states(resolve_config("paper"))
    n_on = sum(s == "on" for s, _ in states.values())
    cap = _pipeline_caption(resolve_config("paper"))
    assert f"{n_on} of {len(states)} noise sources act" in cap and n_on < len(states)
    assert "exact: it equals the truth" in cap and "device.physiology = exact" in cap
    assert "measured: it carries the instruments' errors" in _pipeline_caption(
        resolve_config("wearable"))


def test_pipeline_says_what_the_device_knows():
    """The measured-outputs box follows the device capabilities (paper vs wearable)."""

    def measured(preset):
        cols = pipeline_columns(resolve_config(preset))
        return next(b for col in cols for b in col if b["title"] == "Measured outputs")["details"]

    paper, wearable = measured("paper"), measured("wearable")
    assert "adc_ref_<nm>: monitor photodiode, per reading" in paper
    assert "physiological vector (14 exact values)" in paper
    assert "  humidity compensation" in paper
    assert "adc_ref_<nm>: start-up reference" in wearable
    assert "physiological vector (12 measured values)" in wearable
    assert "device capabilities:" not in wearable
