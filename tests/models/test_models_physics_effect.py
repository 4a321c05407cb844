"""The physics term, measured (issue 39 D): the training loop's gradient probes
(models/_training.py, _torch_base.py) and the verdict read from a history
(models/physics_effect.py)."""

from __future__ import annotations

from unittest import mock

import numpy as np
import pandas as pd
import pytest
import torch

import nirglucose as ng
from nirglucose.evaluation.estimators import fit_history
from nirglucose.models import RTEPINN, SDNN, OriginalPINN, _torch_base
from nirglucose.models._training import gradient_norms
from nirglucose.models.physics_effect import (
    GRADIENT_KEYS,
    GRADIENT_PROBES,
    PULL_INERT_SD,
    is_probe_epoch,
    physics_verdict,
)
from nirglucose.models.physics_losses import glucose_absorptivity_per_cm_per_mgdl

pytestmark = pytest.mark.usefixtures("torch_one_thread")  # tests/conftest.py

FAST = {"max_epochs": 40, "random_state": 0, "weight_decay": 0.03}


@pytest.fixture(scope="module")
def paper():
    return ng.simulate("paper", n_subjects=16, per_subject=3, seed=5)


@pytest.fixture(scope="module")
def study_fit(paper):
    return OriginalPINN(lambda_phys=1.0, **FAST).fit(paper)


def _probed(model):
    return [r for r in model.history_ if r["grad_norm_data"] is not None]


# ----------------------------------------------------------------- the probe itself


def test_gradient_norms_against_hand_computed_values():
    """z = (w0, w1), M = mean((z - t)^2), P = z0^2 + 3 w2 (w2 outside z) at lambda 2."""
    w = torch.tensor([1.0, 2.0, 5.0], requires_grad=True)
    z = w[:2] * 1.0
    t = torch.tensor([0.0, 4.0])
    data = ((z - t) ** 2).mean()
    physics = z[0] ** 2 + 3.0 * w[2]
    out = gradient_norms([w], data, physics, 2.0, z)
    # dM/dw = (z - t) = (1, -2, 0); dP/dw = (2 z0, 0, 3) = (2, 0, 3)
    assert out["grad_norm_data"] == pytest.approx(np.sqrt(5.0))
    assert out["grad_norm_physics_unit"] == pytest.approx(np.sqrt(13.0))
    assert out["grad_norm_physics"] == pytest.approx(2 * np.sqrt(13.0))
    assert out["grad_ratio"] == pytest.approx(2 * np.sqrt(13.0) / np.sqrt(5.0))
    # pull: lambda * (n/2) * RMS(dP/dz) = 2 * 1 * sqrt((2^2 + 0) / 2)
    assert out["pull_sd"] == pytest.approx(2 * np.sqrt(2.0))
    # the part not through z: (0, 0, 3), weighted 2, over |dM/dw|
    assert out["indirect_ratio"] == pytest.approx(6.0 / np.sqrt(5.0))


def test_gradient_norms_of_a_term_outside_the_graph_are_none():
    w = torch.tensor([1.0, 2.0], requires_grad=True)
    out = gradient_norms([w], (w ** 2).mean(), torch.zeros(()), 1.0, w)
    assert out["grad_norm_data"] > 0
    assert all(out[k] is None for k in GRADIENT_KEYS if k != "grad_norm_data")


def test_probe_epochs():
    epochs = [e for e in range(1, 201) if is_probe_epoch(e, 200)]
    assert epochs[0] == 1 and epochs[-1] == 200 and len(epochs) == GRADIENT_PROBES + 1
    assert all(is_probe_epoch(e, 3) for e in (1, 2, 3))
    assert sum(is_probe_epoch(e, 37) for e in range(1, 38)) <= GRADIENT_PROBES + 2


def test_probes_leave_the_fit_bit_identical(paper, study_fit):
    with mock.patch.object(_torch_base, "is_probe_epoch", lambda epoch, n: False):
        plain = OriginalPINN(lambda_phys=1.0, **FAST).fit(paper)
    np.testing.assert_array_equal(plain.predict(paper), study_fit.predict(paper))
    assert all(r["grad_norm_data"] is None for r in plain.history_)


def test_history_rows_carry_the_probes(study_fit, paper):
    rows = study_fit.history_
    assert all(set(GRADIENT_KEYS) <= set(r) for r in rows)
    probed = [r["epoch"] for r in _probed(study_fit)]
    assert probed == [e for e in range(1, FAST["max_epochs"] + 1)
                      if is_probe_epoch(e, FAST["max_epochs"])]
    # not losses: the training-dynamics figure draws only train_* / val_* columns
    assert not any(k.startswith(("train_", "val_")) for k in GRADIENT_KEYS)
    # the benchmark's histories.json takes the rows as they are
    assert fit_history(study_fit)[0]["pull_sd"] == rows[0]["pull_sd"]
    sdnn = SDNN(max_epochs=3, random_state=0).fit(paper)
    assert not any(k in sdnn.history_[0] for k in GRADIENT_KEYS)
    assert physics_verdict(sdnn.history_)["verdict"] == "unmeasured"


# ----------------------------------------------------------------- the study's term


def test_study_pull_matches_its_closed_form(paper, study_fit):
    """At epoch 1 the network predicts the training mean (start_at_mean), so the
    Beer-Lambert term pulls prediction i by lambda * y_scale * sum_l eps_l r_il with
    r_il = A_il - eps_l * mean(y) (in training SD): computed here from the data alone."""
    phys = study_fit.physics_  # the published glucose (gain 1), never the data's gain
    cfg = paper.config
    assert phys["signal_gain"] == 1.0 != cfg.glucose.signal_gain
    eps = glucose_absorptivity_per_cm_per_mgdl(
        cfg.leds.wavelengths_nm, phys["glucose_peak_per_cm_per_mm"], phys["signal_gain"])
    Xa, y, _ = study_fit._measurements(paper, require_target=True)
    a, _ = study_fit._nir_pmf(Xa)
    shift = 1.0 * y.std() * ((a - eps * y.mean()) * eps).sum(axis=1)
    expected = float(np.sqrt(np.mean(shift ** 2)))
    assert study_fit.history_[0]["pull_sd"] == pytest.approx(expected, rel=1e-3)
    assert expected < 1e-4  # at the published gain: under 0.01 mg/dL at a 58 mg/dL spread


def test_study_term_is_inert_and_the_forward_term_is_not(paper, study_fit):
    """At lambda = 1: the study's term pulls the predictions by orders of magnitude less
    than the data term's own residual and less than the forward-model term's; it has no
    gradient outside the glucose prediction; its value hardly moves."""
    fm = OriginalPINN(physics_form="forward", lambda_phys=1.0, **FAST).fit(paper)
    study, forward = _probed(study_fit), _probed(fm)
    residual = np.sqrt([r["train_mse"] for r in study_fit.history_])  # the data term's pull
    pull = np.array([r["pull_sd"] for r in study])
    assert np.all(pull < 1e-2 * residual.min())
    assert np.median([r["pull_sd"] for r in forward]) > 1e3 * np.median(pull)
    assert all(r["indirect_ratio"] == 0.0 for r in study + forward)  # both act via glucose
    v, w = physics_verdict(study_fit.history_), physics_verdict(fm.history_)
    assert v["verdict"] == "inert" and v["median_pull_sd"] < PULL_INERT_SD / 10
    assert v["physics_constant"] and v["physics_relative_change"] < 1e-3
    assert w["verdict"] == "active" and not w["physics_constant"]


def test_rte_study_term_acts_through_its_optics_heads(paper):
    m = RTEPINN(lambda_phys=1.0, **FAST).fit(paper)
    v = physics_verdict(m.history_)
    assert v["median_pull_sd"] == 0.0  # the term does not read the glucose prediction
    assert v["median_indirect_ratio"] > 0.1 and v["verdict"] == "active"


def test_lambda_zero_is_off_with_the_unweighted_gradient_kept(paper):
    m = OriginalPINN(lambda_phys=0.0, **FAST).fit(paper)
    rows = _probed(m)
    assert all(r["grad_norm_physics"] == 0.0 and r["grad_norm_physics_unit"] > 0 for r in rows)
    assert physics_verdict(m.history_)["verdict"] == "off"
    fm = OriginalPINN(physics_form="forward", lambda_phys=0.0, max_epochs=3,
                      random_state=0).fit(paper)
    assert all(r["grad_norm_physics"] is None for r in _probed(fm))
    assert physics_verdict(fm.history_)["verdict"] == "off"


# ----------------------------------------------------------------- the verdict's rule


def _row(epoch, **kw):
    base = {"epoch": epoch, "train_physics": 1.0, "grad_norm_data": 1.0,
            "grad_norm_physics": 0.1, "grad_norm_physics_unit": 0.1, "grad_ratio": 0.1,
            "pull_sd": 1e-4, "indirect_ratio": 0.0}
    return {**base, **kw}


@pytest.mark.parametrize(
    ("rows", "verdict"),
    [
        ([{"epoch": 1, "train_mse": 1.0}], "unmeasured"),
        ([_row(1), _row(2)], "inert"),
        ([_row(1, pull_sd=0.02), _row(2, pull_sd=0.02)], "active"),
        ([_row(1, indirect_ratio=0.002), _row(2, indirect_ratio=0.002)], "active"),
        ([_row(1, grad_norm_physics=0.0), _row(2, grad_norm_physics=0.0)], "off"),
        ([_row(1, **dict.fromkeys(("grad_norm_physics", "grad_norm_physics_unit",
                                   "grad_ratio", "pull_sd", "indirect_ratio")))], "off"),
        # the median decides: one loud probe of three does not make the term active
        ([_row(1, pull_sd=5.0), _row(2), _row(3)], "inert"),
    ],
)
def test_verdict_rule(rows, verdict):
    out = physics_verdict(rows)
    assert out["verdict"] == verdict and out["reason"]
    assert physics_verdict(pd.DataFrame(rows))["verdict"] == verdict  # the report's form


def test_verdict_reports_the_physics_change():
    rows = [_row(1, train_physics=2.0), {"epoch": 2, "train_physics": 1.0}]
    out = physics_verdict(rows)
    assert out["physics_relative_change"] == pytest.approx(0.5)
    assert out["physics_constant"] is False and out["probes"] == 1
    assert physics_verdict(rows, pull_inert_sd=1e-5)["verdict"] == "active"
