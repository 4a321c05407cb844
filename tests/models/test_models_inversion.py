"""The forward-model estimator (physics-inversion) and the hybrids (issue 29)."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest

import nirglucose as ng
from nirglucose.dataset import load_dataset
from nirglucose.exceptions import ConfigError, DataError
from nirglucose.models import Oracle, load_model, make_model
from nirglucose.models._base import predict_input
from nirglucose.models._inversion_solver import NUISANCES
from nirglucose.models.hybrid import EBLGP, PhysicsInversionGP
from nirglucose.models.inversion import PhysicsInversion

NOISE_FREE = {"noise_scale": 0.0}


def _rmse(pred, y) -> float:
    return float(np.sqrt(np.mean((np.asarray(pred) - np.asarray(y)) ** 2)))


@pytest.fixture(scope="module")
def paper():
    return ng.simulate("paper", 30, 3, seed=1), ng.simulate("paper", 10, 3, seed=2)


def test_never_reads_truth(paper):
    """Deleting or permuting every true_* column changes no prediction."""
    train, test = paper
    base = PhysicsInversion(n_em=3).fit(train).predict(test)
    rng = np.random.default_rng(0)
    truth = [c for c in train.frame.columns if c.startswith("true_")]
    assert truth  # the simulator wrote ground truth the estimator could have read
    dropped = [ng.Dataset(d.frame.drop(columns=truth), config=d.config) for d in (train, test)]
    permuted = []
    for d in (train, test):
        f = d.frame.copy()
        for c in truth:
            f[c] = rng.permutation(f[c].to_numpy())
        permuted.append(ng.Dataset(f, config=d.config))
    for tr, te in (dropped, permuted):
        np.testing.assert_array_equal(PhysicsInversion(n_em=3).fit(tr).predict(te), base)


def test_recovers_glucose_on_noise_free_data_within_the_oracles_error():
    train = ng.simulate("paper", 30, 3, seed=1, overrides=NOISE_FREE)
    test = ng.simulate("paper", 10, 3, seed=2, overrides=NOISE_FREE)
    y = test.frame["glucose_mgdl"]
    oracle = _rmse(Oracle().fit(train).predict(test), y)
    inv = _rmse(PhysicsInversion().fit(train).predict(test), y)
    assert inv <= oracle + 1.0, (inv, oracle)  # within 1 mg/dL of the bound
    assert inv < 0.05 * float(np.std(y))


def test_beats_no_skill_and_recovers_the_state(paper):
    train, test = paper
    y = test.frame["glucose_mgdl"].to_numpy()
    m = PhysicsInversion().fit(train)
    state = m.estimate_state(test)
    no_skill = _rmse(np.full_like(y, train.frame["glucose_mgdl"].mean()), y)
    assert _rmse(state["glucose_mgdl"], y) < 0.5 * no_skill
    assert list(state.columns[:1]) == ["glucose_mgdl"] and len(state.columns) == 1 + len(NUISANCES)
    # the state is checked against the truth here, in the test: the estimator never saw it
    truth = test.frame["true_blood_fraction_detected"].to_numpy()
    assert np.corrcoef(state["blood_fraction"], truth)[0, 1] > 0.9


@pytest.mark.parametrize("assumed", ["diffusion"])
def test_any_assumed_forward_model_fits(paper, assumed):
    """The assumed model is a parameter; data made by beer-lambert, read as diffusion."""
    train, test = paper
    pred = PhysicsInversion(forward_model=assumed, n_em=2).fit(train).predict(test)
    assert pred.shape == (len(test),) and np.isfinite(pred).all()


def test_save_load_round_trip(paper, tmp_path):
    train, test = paper
    m = PhysicsInversion(n_em=3, prior_scale=2.0).fit(train)
    path = m.save(tmp_path / "inv.json")
    assert json.loads(path.read_text())["model"] == "physics-inversion"
    back = load_model(path)
    assert isinstance(back, PhysicsInversion) and back.get_params() == m.get_params()
    np.testing.assert_allclose(back.predict(test), m.predict(test), rtol=1e-9)
    assert back.n_parameters == m.n_parameters > 0


def test_bad_input_one_line(paper):
    train, test = paper
    bad_form = "'forward_model' parameter of PhysicsInversion.*'beer-lambert'.*Got 'mie'"
    with pytest.raises(ConfigError, match=bad_form):
        PhysicsInversion(forward_model="mie").fit(train)
    with pytest.raises(ConfigError, match=r"'prior_scale' .* range \(0\.0, inf\)\. Got 0 inst"):
        PhysicsInversion(prior_scale=0).fit(train)
    with pytest.raises(ConfigError, match=r"'n_em' .* int in the range \[0, inf\)\. Got -1 inst"):
        PhysicsInversion(n_em=-1).fit(train)
    with pytest.raises(DataError, match="not a plain array"):
        PhysicsInversion().fit(np.ones((30, 4)), np.full(30, 100.0))
    with pytest.raises(DataError, match="missing columns"):
        PhysicsInversion(n_em=1).fit(train).predict(test.frame.drop(columns="adc_940"))
    from sklearn.exceptions import NotFittedError

    with pytest.raises(NotFittedError):
        PhysicsInversion().predict(test)


def test_data_without_a_scenario_is_refused_never_read_as_a_preset(paper, tmp_path):
    """A frame or CSV carries no scenario: one line naming the deployable estimator,
    never the paper preset's optics and gain (issue 39)."""
    train, _ = paper
    csv = load_dataset(train.save(tmp_path / "train.csv"))
    assert csv.config is None  # a CSV keeps the columns only
    for data in (train.frame, csv):
        with pytest.raises(DataError, match="reads the generating scenario.*'device-inversion'"):
            PhysicsInversion(n_em=1).fit(data)
        with pytest.raises(DataError, match="reads the generating scenario"):
            PhysicsInversionGP(backbone_params={"n_em": 1}, cv=0).fit(data)
    from device_data import simulate_device

    other = simulate_device(3, 12)  # the scenario's LEDs are not the columns'
    with pytest.raises(DataError, match="pass the Dataset"):
        PhysicsInversion(n_em=1).fit(ng.Dataset(other.frame, config=train.config))


@pytest.mark.parametrize("cls", [EBLGP, PhysicsInversionGP])
def test_hybrids_round_trip_and_learn_a_residual(paper, cls, tmp_path):
    train, test = paper
    params = {"backbone_params": {"n_em": 3}} if cls is PhysicsInversionGP else {}
    m = cls(random_state=0, **params).fit(train)
    pred = m.predict(test)
    backbone = m.backbone_.predict(test)
    gp = m.residual_.predict(np.column_stack([m.schema_.stacked(predict_input(m, test)),
                                              backbone]))
    assert np.isfinite(pred).all() and not np.allclose(gp, 0.0)  # the GP learned a residual
    # the prediction is the stack of the two (issue 29; weights in test_models_hybrid.py)
    stack = m.y_mean_ + m.backbone_weight_ * (backbone - m.y_mean_) + m.shrinkage_ * gp
    np.testing.assert_allclose(pred, stack, rtol=1e-12)
    back = load_model(m.save(tmp_path / "h.json"))
    np.testing.assert_allclose(back.predict(test), pred, rtol=1e-9)
    assert back.n_parameters == m.n_parameters
    with pytest.raises(ConfigError, match=r"'cv' parameter .* an int in the range \[0, inf\)"):
        cls(cv=-1).fit(train)


def test_hybrids_are_registered():
    assert isinstance(make_model("ebl+gp"), EBLGP)
    assert isinstance(make_model("physics-inversion+gp"), PhysicsInversionGP)
    assert isinstance(make_model("physics-inversion"), PhysicsInversion)


def test_inversion_hybrid_reports_its_backbones_state(paper):
    train, test = paper
    m = PhysicsInversionGP(backbone_params={"n_em": 3}, cv=0, random_state=0).fit(train)
    state = m.estimate_state(test)
    back = m.backbone_.estimate_state(test)
    pd.testing.assert_frame_equal(state.drop(columns="glucose_mgdl"),
                                  back.drop(columns="glucose_mgdl"))
    np.testing.assert_allclose(state["glucose_mgdl"], m.predict(test))
    assert not np.allclose(state["glucose_mgdl"], back["glucose_mgdl"])  # the GP corrects


def test_the_variance_floor_follows_the_declared_adc_bits():
    # the data's declared bits (the scenario's, which averaging raises) set the floor
    from nirglucose.models._inversion_solver import residual_var_floor

    ov = {"hardware.adc_bits": 16, "device.monitor_photodiode": True}
    train = ng.simulate("physical", 20, 3, seed=1, overrides=ov)
    est = PhysicsInversion(n_em=2).fit(train)
    assert est.schema_.adc_bits == 16
    assert est._var_floor() == residual_var_floor(16) == 2e-8 / 256
    twelve = PhysicsInversion(n_em=2).fit(ng.simulate("physical", 20, 3, seed=1))
    assert twelve._var_floor() == 2e-8  # 12-bit results stay byte-identical


def test_an_ill_conditioned_residual_covariance_still_whitens():
    # residuals of about 1e-4 in two directions of four (the modes absorb the rest) and
    # a 24-bit quantisation floor (2e-8 / 4^12) in the others: the inverse's Cholesky
    # factor fails in floating point, the eigen-decomposition does not
    from nirglucose.models._inversion_solver import residual_var_floor

    est = PhysicsInversion(n_em=2).fit(ng.simulate("physical", 20, 3, seed=1))
    floor = residual_var_floor(24)
    a = np.random.default_rng(0).standard_normal((4, 2)) * 1e-2
    est.noise_cov_ = a @ a.T + floor * np.eye(4)
    est._var_floor = lambda: floor
    with pytest.raises(np.linalg.LinAlgError):
        np.linalg.cholesky(np.linalg.inv(est.noise_cov_))
    r = est._root_w()
    np.testing.assert_allclose(r @ est.noise_cov_ @ r.T, np.eye(4), atol=1e-4)  # cond ~1e11
