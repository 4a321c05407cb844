"""The oracle bound: the forward model inverted with the true nuisance state."""

from __future__ import annotations

import json

import numpy as np
import pytest

import nirglucose as ng
from nirglucose.dataset import measured_columns
from nirglucose.exceptions import ConfigError, DataError, NotFittedError
from nirglucose.models import EnhancedBeerLambert, Oracle, load_model


def _rmse(a, b):
    return float(np.sqrt(np.mean((np.asarray(a) - np.asarray(b)) ** 2)))


@pytest.fixture(scope="module")
def noise_free():
    over = {"noise_scale": 0.0}
    return (
        ng.simulate("wearable", 30, 3, seed=1, overrides=over),
        ng.simulate("wearable", 15, 3, seed=2, overrides=over),
    )


@pytest.fixture(scope="module")
def paper():
    return ng.simulate("wearable", 40, 3, seed=3), ng.simulate("wearable", 20, 3, seed=4)


# The data-driven scikit-learn checks cannot apply (the oracle reads true_* columns and
# the scenario config, which no array carries); the checks that need no data run in
# test_models_sklearn_checks.py, those behaviours are tested here.


def test_noise_free_error_is_quantisation_only(noise_free):
    train, test = noise_free
    y = test.frame["glucose_mgdl"].to_numpy()
    for prior in (True, False):
        pred = Oracle(prior=prior).fit(train).predict(test)
        assert _rmse(pred, y) < 1.0, prior  # 12-bit quantisation: about 0.3 mg/dL


def test_round_trip_forward_inverse_over_a_glucose_grid(noise_free):
    """Simulate at a grid of glucose values through the same nuisance state; invert."""
    from nirglucose.simulation.simulator import detected_fraction_given_glucose

    train, test = noise_free
    o = Oracle(prior=False, tol=1e-6).fit(train)
    frame = test.frame.iloc[:8]
    cfg = test.config
    for g in (60.0, 150.0, 390.0):
        glucose = np.full(len(frame), g)
        frac = detected_fraction_given_glucose(cfg, frame, glucose)
        ratio = frac / cfg.hardware.reference_transmission * np.exp(o.offset_)
        synth = frame.copy()
        ref = 3000.0
        for k, wl in enumerate(("850", "940", "1050", "1150")):
            synth[f"adc_ref_{wl}"] = ref
            synth[f"adc_{wl}"] = ref * ratio[:, k]  # unquantised codes
        est = o.predict(ng.Dataset(synth, config=cfg))
        np.testing.assert_allclose(est, glucose, atol=1e-3)


def test_bounds_the_linear_model_on_the_paper_preset(paper):
    train, test = paper
    y = test.frame["glucose_mgdl"].to_numpy()
    oracle = _rmse(Oracle().fit(train).predict(test), y)
    ebl = _rmse(EnhancedBeerLambert().fit(train).predict(test), y)
    assert oracle < ebl
    assert oracle < np.std(y)


def test_what_it_learns(paper):
    train, _ = paper
    o = Oracle().fit(train)
    assert o.offset_.shape == (4,) and o.noise_cov_.shape == (4, 4)
    np.testing.assert_allclose(o.noise_cov_, o.noise_cov_.T)
    assert np.all(np.linalg.eigvalsh(o.noise_cov_) > 0)
    assert o.prior_mean_ == pytest.approx(train.frame["glucose_mgdl"].mean())
    assert o.n_parameters == 4 + 10 + 2


def test_needs_the_dataset_and_its_truth(paper):
    train, test = paper
    with pytest.raises(DataError, match="scenario config"):
        Oracle().fit(train.frame)
    with pytest.raises(DataError, match="needs a Dataset"):
        Oracle().fit(train.frame[measured_columns()].to_numpy())
    user = ng.Dataset(train.frame[measured_columns() + ["glucose_mgdl"]], config=train.config)
    with pytest.raises(DataError, match="ground-truth columns; missing"):
        Oracle().fit(user)
    o = Oracle().fit(train)
    # A plain frame is read with the training scenario.
    np.testing.assert_array_equal(o.predict(test.frame), o.predict(test))
    with pytest.raises(NotFittedError):
        Oracle().predict(test)
    with pytest.raises(ConfigError, match="max_iter"):
        Oracle(max_iter=0).fit(train)


def test_save_load(paper, tmp_path):
    train, test = paper
    o = Oracle().fit(train)
    path = o.save(tmp_path / "oracle.json")
    assert json.loads(path.read_text())["model"] == "oracle"
    back = load_model(path)
    assert isinstance(back, Oracle)
    np.testing.assert_array_equal(back.predict(test), o.predict(test))


def test_the_variance_floor_follows_the_datas_adc_bits(monkeypatch):
    # a quiet design (monitor photodiode, 16-bit ADC) at published magnitudes: the
    # residual noise is far below a 12-bit code's quantisation (2e-8 in ln units), and
    # a floor fixed at 12 bits would drown it; the floor of 16 bits is 2e-8 / 4^4
    import nirglucose.models.oracle as oracle_module
    from nirglucose.models._inversion_solver import VAR_FLOOR_12BIT, residual_var_floor

    assert residual_var_floor(12) == VAR_FLOOR_12BIT == 2e-8  # 12-bit results unchanged
    assert residual_var_floor(16) == 2e-8 / 256 and residual_var_floor(10) == 2e-8 * 16
    ov = {"hardware.adc_bits": 16, "device.monitor_photodiode": True}
    train = ng.simulate("physical", 30, 3, seed=1, overrides=ov)
    test = ng.simulate("physical", 15, 3, seed=2, overrides=ov)
    y = test.frame["glucose_mgdl"].to_numpy()
    o = Oracle().fit(train)
    assert np.all(np.diag(o.noise_cov_) < 1e-9)  # the residual, not the 12-bit floor
    quiet = _rmse(o.predict(test), y)
    monkeypatch.setattr(oracle_module, "residual_var_floor", lambda bits: VAR_FLOOR_12BIT)
    fixed = _rmse(Oracle().fit(train).predict(test), y)
    assert quiet < 0.8 * fixed  # measured: 0.54 against 0.83 mg/dL
