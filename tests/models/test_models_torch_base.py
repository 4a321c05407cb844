"""The shared training loop: scaling, splits, determinism, history, save/load, checks."""

from __future__ import annotations

import json
import pickle

import numpy as np
import pytest
import torch
from sklearn.base import clone
from sklearn.exceptions import NotFittedError as SklearnNotFittedError

import nirglucose as ng
from nirglucose.exceptions import ConfigError, DataError, NotFittedError
from nirglucose.models import (
    RTEPINN,
    SDNN,
    OptimizedPINN,
    OriginalPINN,
    SelectiveRTEPINN,
    load_model,
)
from nirglucose.models._base import MEASURED_COLUMNS
from nirglucose.models._torch_base import (
    NUMPY_ROWS,
    WHITENING_KEY,
    TorchRegressor,
    nir_pmf_features,
    zca_whitening,
)
from nirglucose.models._training import start_at_mean
from nirglucose.models.networks import (
    OptimizedPINNNet,
    OriginalPINNNet,
    RTEPINNNet,
    SDNNNet,
    mlp,
    numpy_mlp,
)

FAST = {"max_epochs": 3, "batch_size": 16, "random_state": 0}
#: Early stopping on an internal subject split (no longer the default: full batch,
#: fixed tuned epochs, no split).
ES = {"val_fraction": 0.2}


pytestmark = pytest.mark.usefixtures("torch_one_thread")  # tests/conftest.py


@pytest.fixture(scope="module")
def small():
    return ng.simulate("wearable", n_subjects=16, per_subject=3, seed=3)


@pytest.fixture(scope="module")
def fitted(small):
    return OriginalPINN(max_epochs=6, batch_size=16, patience=None, random_state=0, **ES).fit(small)


def _weights(model):
    return {k: v.clone() for k, v in model.module_.state_dict().items()}


# ----------------------------------------------------------------- features and scaling


def test_absorbance_features_by_hand():
    X = np.zeros((1, 20))
    X[0, :4] = [1000, 2000, 100, 4000]
    X[0, 4:8] = [10000, 2000, 1000, 4000]
    X[0, 8:] = np.arange(12)
    a, pmf = nir_pmf_features(X)
    np.testing.assert_allclose(a, [[1.0, 0.0, 1.0, 0.0]])
    np.testing.assert_array_equal(pmf, np.arange(12)[None])


def test_scaler_standardises_training_inputs(fitted, small):
    s = fitted.scaler_
    assert s["y_scale"] > 0 and np.all(s["nir_scale"] > 0) and np.all(s["pmf_scale"] > 0)
    # Training rows are a subset (validation held out), so the means are close to the
    # full-data means but fitted on the training part only.
    a, _ = nir_pmf_features(small.frame[list(MEASURED_COLUMNS)].to_numpy(float))
    assert np.all(np.abs(s["nir_mean"] - a.mean(axis=0)) < 2 * a.std(axis=0))


# ----------------------------------------------------------------- training loop


def test_fit_returns_self_and_sets_state(small):
    m = SDNN(**FAST)
    assert m.fit(small) is m
    assert m.n_features_in_ == 20
    assert m.n_epochs_ == 3 and 1 <= m.best_epoch_ <= 3
    assert not m.module_.training


def test_history_records_every_epoch_and_term(fitted):
    h = fitted.history_
    assert [r["epoch"] for r in h] == list(range(1, 7))
    for r in h:
        for key in (
            "train_loss",
            "val_loss",
            "train_mse",
            "val_mse",
            "train_physics",
            "val_physics",
            "lr",
            "val_rmse_mgdl",
        ):
            assert isinstance(r[key], float), key
        expected = r["train_mse"] + 0.01 * r["train_physics"]
        assert r["train_loss"] == pytest.approx(expected, rel=1e-5)


def test_explicit_validation_set_is_used_and_best_weights_kept(small):
    f = small.frame
    train, val = f[f.subject_id < 12], f[f.subject_id >= 12]
    m = OriginalPINN(max_epochs=5, batch_size=16, patience=None, random_state=1)
    m.fit(train, X_val=val)
    curve = [m.start_val_mse_] + [r["val_mse"] for r in m.history_]  # epoch 0 first
    best = curve[m.best_epoch_]  # the minimum, up to the 1e-4 improvement rule
    assert min(curve) <= best <= min(curve) * (1 + 1e-4)
    pred = m.predict(val)
    y_std = (val.glucose_mgdl.to_numpy() - m.scaler_["y_mean"]) / m.scaler_["y_scale"]
    p_std = (pred - m.scaler_["y_mean"]) / m.scaler_["y_scale"]
    assert np.mean((p_std - y_std) ** 2) == pytest.approx(best, rel=1e-4)
    # All training rows were used for the scaler (no internal split).
    assert m.scaler_["y_mean"] == pytest.approx(train.glucose_mgdl.mean())


@pytest.mark.parametrize("cls", [SDNN, OriginalPINN, OptimizedPINN, RTEPINN, SelectiveRTEPINN])
def test_untrained_network_predicts_the_training_mean(small, cls):
    # The glucose output layer starts at zero: epoch 0 is the no-skill predictor.
    m = cls(max_epochs=1, lr=1e-3, whiten_inputs=False, random_state=0)
    m.fit(small)
    module = m._wrap_inputs(start_at_mean(m.build_module()), None)
    m.module_ = module.eval()
    m._build_fast_path()
    y_mean = small.frame.glucose_mgdl.mean()
    np.testing.assert_allclose(m.predict(small), y_mean, rtol=1e-6)


def test_early_stopping_returns_the_training_mean_when_nothing_is_learnable(small):
    # Glucose replaced by noise independent of the measurements: no epoch beats the
    # training mean on held-out subjects for long; the early-stopped network stays
    # near it while the same network trained for all its epochs memorises the noise.
    rng = np.random.default_rng(0)
    frame = small.frame.copy()
    frame["glucose_mgdl"] = rng.normal(130.0, 30.0, len(frame))
    train, test = frame[frame.subject_id < 12], frame[frame.subject_id >= 12]
    no_skill = np.sqrt(np.mean((test.glucose_mgdl - train.glucose_mgdl.mean()) ** 2))
    kw = {"max_epochs": 200, "lr": 1e-2, "weight_decay": 0.0, "random_state": 0}

    def rmse(model):
        return np.sqrt(np.mean((model.fit(train).predict(test) - test.glucose_mgdl) ** 2))

    stopped, plain = rmse(SDNN(val_fraction=0.25, **kw)), rmse(SDNN(**kw))
    assert stopped <= 1.05 * no_skill
    assert plain > 1.1 * no_skill  # the test can tell: without early stopping it fails


def test_validation_split_is_by_subject():
    m = SDNN(val_fraction=0.25)
    groups = np.repeat(np.arange(20), 3)
    tr, va = m._split(len(groups), groups, seed=0)
    assert set(groups[tr]).isdisjoint(groups[va])
    assert len(np.unique(groups[va])) == 5
    tr, va = m._split(60, None, seed=0)  # no subject ids: random rows
    assert len(va) == 15 and len(set(tr) | set(va)) == 60
    with pytest.raises(ConfigError, match="val_fraction=0.9 leaves nothing to train on out "
                                          "of 6 subjects; lower it"):
        SDNN(val_fraction=0.9)._split(12, np.repeat(np.arange(6), 2), seed=0)


def test_no_validation_trains_on_train_loss(small):
    m = SDNN(max_epochs=3, val_fraction=0.0, random_state=0).fit(small)
    assert all(r["val_loss"] is None for r in m.history_)


def test_early_stopping_stops(small):
    m = SDNN(max_epochs=200, patience=2, lr=0.05, refit=False, random_state=0, **ES).fit(small)
    assert m.n_epochs_ < 200
    assert m.n_epochs_ - m.best_epoch_ == 2
    assert m.refit_epochs_ == 0 and m.refit_history_ == []


def test_refit_on_all_rows_for_the_selected_epochs(small):
    kw = {"max_epochs": 12, "patience": None, "random_state": 0, **ES}
    m = OriginalPINN(**kw).fit(small)
    assert m.refit_epochs_ == m.best_epoch_ == len(m.refit_history_)
    assert [r["lr"] for r in m.refit_history_] == [r["lr"] for r in m.history_[: m.best_epoch_]]
    assert all(r["val_loss"] is None for r in m.refit_history_)
    no_refit = OriginalPINN(refit=False, **kw).fit(small)
    assert no_refit.history_ == m.history_  # same selection run
    assert not np.array_equal(no_refit.predict(small), m.predict(small))
    # An explicit validation set means no refit (the study's 60/20/20 protocol).
    f = small.frame
    explicit = OriginalPINN(**kw).fit(f[f.subject_id < 12], X_val=f[f.subject_id >= 12])
    assert explicit.refit_epochs_ == 0


def test_smoothed_selection_ignores_a_lucky_epoch():
    from nirglucose.models._training import smoothed_argmin

    curve = [1.0, 0.5, 0.9, 0.8, 0.7, 0.6, 0.6, 0.65, 0.7, 0.8, 0.9]
    assert int(np.argmin(curve)) + 1 == 2  # the raw minimum is a lucky epoch
    assert smoothed_argmin(curve, 5) == 7
    assert smoothed_argmin([3.0, 2.0, 1.0], 1) == 3


@pytest.mark.parametrize("schedule", ["plateau", "cosine", "none"])
def test_lr_schedules(small, schedule):
    m = SDNN(max_epochs=4, lr=1e-3, lr_schedule=schedule, patience=None, random_state=0, **ES)
    m.fit(small)
    lrs = [r["lr"] for r in m.history_]
    assert lrs[0] == pytest.approx(1e-3)
    if schedule == "cosine":
        assert lrs[-1] < lrs[0]
    if schedule == "none":
        assert len(set(lrs)) == 1


def test_training_lowers_the_loss_on_a_learnable_problem():
    # The lab preset (one nominal 'subject', quiet instrument) with the noise off:
    # glucose is the main thing that moves the absorbance.
    ds = ng.simulate("lab", n_subjects=20, per_subject=4, seed=0, overrides={"noise_scale": 0.0})
    m = OriginalPINN(max_epochs=60, patience=None, lr=3e-3, random_state=0, **ES).fit(ds)
    h = m.history_
    assert h[-1]["train_mse"] < 0.5 * h[0]["train_mse"]
    assert m.best_epoch_ > 0 and h[m.best_epoch_ - 1]["val_mse"] < 0.5 * m.start_val_mse_


def test_full_batch_is_the_default_and_one_step_per_epoch(small):
    m = SDNN(max_epochs=4, random_state=0)
    assert m.batch_size is None and m.val_fraction == 0 and m.patience is None
    steps = []
    original = m.train_step
    m.train_step = lambda batch: steps.append(len(batch["y"])) or original(batch)
    m.fit(small)
    assert steps == [len(small)] * 4  # every row, once per epoch
    assert m.best_epoch_ == m.n_epochs_ == 4  # no split: the last weights are kept
    # A batch size at least the row count is the same full-batch training.
    big = SDNN(max_epochs=4, batch_size=10_000, random_state=0).fit(small)
    np.testing.assert_array_equal(
        big.predict(small), SDNN(max_epochs=4, random_state=0).fit(small).predict(small)
    )


def test_zca_whitening_decorrelates():
    rng = np.random.default_rng(0)
    z = rng.normal(size=(500, 3)) @ np.array([[1.0, 0.9, 0.0], [0.0, 0.1, 0.0], [0.0, 0.0, 2.0]])
    w = zca_whitening(z)
    np.testing.assert_allclose(w, w.T)
    np.testing.assert_allclose(np.cov(z @ w, rowvar=False), np.eye(3), atol=1e-10)
    # A constant column maps to 0 instead of dividing by 0.
    w0 = zca_whitening(np.column_stack((z[:, 0], np.zeros(500))))
    assert np.isfinite(w0).all() and np.all(w0[1] == 0) and np.all(w0[:, 1] == 0)


def test_whitened_inputs_are_a_buffer_saved_with_the_weights(small, tmp_path):
    m = SDNN(max_epochs=3, random_state=0).fit(small)
    state = m.module_.state_dict()
    assert WHITENING_KEY in state and state[WHITENING_KEY].shape == (16, 16)
    assert m.n_parameters == SDNN(whiten_inputs=False).n_parameters == 3713
    back = SDNN.load(m.save(tmp_path / "m.json"))
    np.testing.assert_array_equal(back.predict(small), m.predict(small))
    row = small.frame.iloc[0]
    one = back.predict_one(
        row[["adc_850", "adc_940", "adc_1050", "adc_1150"]].to_numpy(float),
        row[["adc_ref_850", "adc_ref_940", "adc_ref_1050", "adc_ref_1150"]].to_numpy(float),
        row[list(MEASURED_COLUMNS[8:])].to_numpy(float),
    )
    assert one == pytest.approx(m.predict(small)[0], rel=1e-5)
    plain = SDNN(max_epochs=3, whiten_inputs=False, random_state=0).fit(small)
    assert WHITENING_KEY not in plain.module_.state_dict()
    assert not np.allclose(plain.predict(small), m.predict(small))


# ----------------------------------------------------------------- determinism


def test_same_seed_identical_weights_and_predictions(small):
    a = OptimizedPINN(**FAST).fit(small)  # has dropout: exercises the seeded RNG
    b = OptimizedPINN(**FAST).fit(small)
    wa, wb = _weights(a), _weights(b)
    assert all(torch.equal(wa[k], wb[k]) for k in wa)
    np.testing.assert_array_equal(a.predict(small), b.predict(small))


def test_other_seed_differs(small):
    a = SDNN(**FAST).fit(small)
    b = SDNN(**{**FAST, "random_state": 1}).fit(small)
    assert not np.array_equal(a.predict(small), b.predict(small))


def test_fit_leaves_global_torch_rng_alone(small):
    torch.manual_seed(123)
    expected = torch.rand(3)
    torch.manual_seed(123)
    SDNN(**FAST).fit(small)
    assert torch.equal(torch.rand(3), expected)


def test_refit_is_idempotent(small):
    m = SDNN(**FAST)
    p1 = m.fit(small).predict(small)
    p2 = m.fit(small).predict(small)
    np.testing.assert_array_equal(p1, p2)


# ----------------------------------------------------------------- prediction paths


def test_predict_one_matches_predict(fitted, small):
    f = small.frame.iloc[:5]
    batch = fitted.predict(f)
    for i in range(5):
        row = f.iloc[i]
        one = fitted.predict_one(
            row[["adc_850", "adc_940", "adc_1050", "adc_1150"]].to_numpy(float),
            row[["adc_ref_850", "adc_ref_940", "adc_ref_1050", "adc_ref_1150"]].to_numpy(float),
            row[list(MEASURED_COLUMNS[8:])].to_numpy(float),
        )
        assert one == pytest.approx(batch[i], rel=1e-5)


@pytest.mark.parametrize(
    "net",
    [
        SDNNNet(),
        OriginalPINNNet(),
        OptimizedPINNNet(d_model=32, n_heads=4),
        RTEPINNNet([0.3, 0.4, 0.5, 1.0], [15.0, 13.0, 11.0, 10.0]),
        RTEPINNNet([0.5], [11.0]),
    ],
    ids=lambda n: type(n).__name__,
)
@pytest.mark.parametrize("n", [1, 5])
def test_numpy_forward_matches_the_module(net, n):
    net.eval()
    rng = np.random.default_rng(n)
    a = rng.normal(size=(n, 4)).astype(np.float32)
    b = rng.normal(size=(n, 12)).astype(np.float32)
    with torch.inference_mode():
        expected = net(torch.from_numpy(a), torch.from_numpy(b))
    got = net.numpy_forward()(np.concatenate((a, b), axis=1))
    expected = expected if isinstance(expected, tuple) else (expected,)
    got = got if isinstance(got, tuple) else (got,)
    for e, g in zip(expected, got, strict=True):
        assert g.dtype == np.float32 and g.shape == tuple(e.shape)
        np.testing.assert_allclose(g, e.numpy(), rtol=1e-5, atol=1e-6)


def test_numpy_mlp_runs_branches_side_by_side():
    a = mlp((4, 8, 3))
    b = mlp((2, 5, 6))
    f = numpy_mlp(a, b)
    x = np.random.default_rng(0).normal(size=(3, 6)).astype(np.float32)
    with torch.no_grad():
        expected = torch.cat((a(torch.from_numpy(x[:, :4])), b(torch.from_numpy(x[:, 4:]))), 1)
    np.testing.assert_allclose(f(x), expected.numpy(), rtol=1e-6, atol=1e-7)
    with pytest.raises(ValueError, match="same layer pattern"):
        numpy_mlp(a, mlp((2, 5, 6, 7)))


def test_small_and_large_batches_agree(fitted, small):
    full = fitted.predict(small)  # torch path
    for k in (1, 3, NUMPY_ROWS):
        np.testing.assert_allclose(fitted.predict(small.frame.iloc[:k]), full[:k], rtol=1e-5)


def test_refit_rebuilds_the_fast_path(small):
    m = SDNN(**FAST).fit(small)
    row = small.frame.iloc[:1]
    before = m.predict(row)
    m.set_params(random_state=5).fit(small)
    np.testing.assert_allclose(m.predict(row), m.predict(small)[:1], rtol=1e-5)
    assert not np.allclose(m.predict(row), before)


def test_predict_one_rejects_bad_input(fitted):
    with pytest.raises(DataError, match="4 ADC codes"):
        fitted.predict_one([1, 2, 3], [1, 2, 3], np.ones(12))
    with pytest.raises(DataError, match="> 0"):
        fitted.predict_one([0, 2, 3, 4], [1, 2, 3, 4], np.ones(12))
    X = np.ones((1, 20))
    X[0, 5] = -1.0
    with pytest.raises(DataError, match="adc_ref_940.*outside 1-4095"):
        fitted.predict(X)  # the one-row (NumPy) path checks the codes too
    X[0, 5] = np.nan
    with pytest.raises(DataError, match="NaN"):
        fitted.predict(X)


def test_predict_accepts_dataset_frame_and_array(fitted, small):
    p1 = fitted.predict(small)
    p2 = fitted.predict(small.frame)
    p3 = fitted.predict(small.frame[list(MEASURED_COLUMNS)].to_numpy(float))
    np.testing.assert_array_equal(p1, p2)
    np.testing.assert_array_equal(p1, p3)
    assert p1.dtype == np.float64 and p1.shape == (len(small),)


def test_never_reads_true_columns(fitted, small):
    f = small.frame.copy()
    for c in [c for c in f.columns if c.startswith("true_")]:
        f[c] = np.nan
    np.testing.assert_array_equal(fitted.predict(f), fitted.predict(small))


def test_n_parameters_is_counted(fitted):
    assert fitted.n_parameters == sum(p.numel() for p in fitted.module_.parameters())
    assert OriginalPINN().n_parameters == fitted.n_parameters  # unfitted: fresh module


# ----------------------------------------------------------------- bad input and params


def test_unfitted_predict_raises_both_not_fitted_errors():
    with pytest.raises(NotFittedError, match="not fitted"):
        SDNN().predict(np.ones((2, 20)))
    with pytest.raises(SklearnNotFittedError):
        SDNN().predict(np.ones((2, 20)))


def test_nan_raises(small):
    f = small.frame.copy()
    f.loc[3, "adc_940"] = np.nan
    with pytest.raises(DataError):
        SDNN(**FAST).fit(f)
    X = f[list(MEASURED_COLUMNS)].to_numpy(float)
    with pytest.raises(ValueError, match="NaN"):
        SDNN(**FAST).fit(X, f.glucose_mgdl)


def test_missing_column_raises(small, fitted):
    with pytest.raises(DataError, match="missing columns \\['skin_temp_c'\\]"):
        fitted.predict(small.frame.drop(columns=["skin_temp_c"]))


def test_wrong_width_raises(fitted):
    with pytest.raises(ValueError, match="X has 5 features, but .* expecting 20"):
        fitted.predict(np.ones((10, 5)))


def test_nonpositive_codes_raise(small):
    f = small.frame.copy()
    f.loc[2, "adc_940"] = 0.0
    with pytest.raises(DataError, match="adc_940.*outside 1-4095.*rows 2"):
        SDNN(**FAST).fit(f)


def test_missing_target_raises(small):
    with pytest.raises(DataError, match="requires y"):
        SDNN(**FAST).fit(small.frame[list(MEASURED_COLUMNS)].to_numpy(float))
    with pytest.raises(DataError, match="glucose"):
        SDNN(**FAST).fit(small.frame.drop(columns=["glucose_mgdl"]))


def test_too_few_rows_raise(small):
    with pytest.raises(DataError, match="too few rows to fit: 2 sample"):
        SDNN(**FAST).fit(small.frame.iloc[:2])


@pytest.mark.parametrize(
    "params",
    [
        {"max_epochs": 0},
        {"batch_size": 1.5},
        {"lr": -1.0},
        {"patience": 0},
        {"val_fraction": 1.0},
        {"lr_schedule": "step"},
        {"weight_decay": -1},
        {"dropout": 1.0},
        {"dropout": -0.1},
        {"batch_size": 0},
        {"whiten_inputs": "yes"},
    ],
)
def test_bad_params_raise_config_error(small, params):
    with pytest.raises(ConfigError):
        SDNN(**params).fit(small)


def test_init_only_stores_params():
    m = OriginalPINN(lr=-5, lr_schedule="nonsense")  # validation happens in fit
    assert m.get_params()["lr"] == -5
    assert not hasattr(m, "module_")


# ----------------------------------------------------------------- save / load


def test_save_load_round_trip_identical(fitted, small, tmp_path):
    path = fitted.save(tmp_path / "model.json")
    doc = json.loads(path.read_text())
    assert doc["format"] == "nirglucose-model" and doc["format_version"] == 1
    assert doc["model"] == "original-pinn" and doc["weights_file"] == "model.safetensors"
    assert doc["params"]["random_state"] == 0 and len(doc["history"]) == fitted.n_epochs_
    assert (tmp_path / "model.safetensors").exists()
    assert not [p for p in tmp_path.iterdir() if p.name.endswith(".tmp")]
    for loaded in (OriginalPINN.load(path), load_model(path)):
        assert type(loaded) is OriginalPINN
        np.testing.assert_array_equal(loaded.predict(small), fitted.predict(small))
        assert loaded.history_ == fitted.history_
        assert loaded.get_params() == fitted.get_params()


def test_tampered_weights_raise_data_error(fitted, tmp_path):
    from safetensors.torch import load_file, save_file

    path = fitted.save(tmp_path / "m.json")
    w = tmp_path / "m.safetensors"
    state = load_file(w)
    key = next(iter(state))
    state["evil." + key] = state.pop(key)
    save_file(state, w)
    with pytest.raises(DataError, match="missing keys"):
        load_model(path)


def test_wrong_shape_and_garbage_weights_raise(fitted, tmp_path):
    from safetensors.torch import load_file, save_file

    path = fitted.save(tmp_path / "m.json")
    w = tmp_path / "m.safetensors"
    state = load_file(w)
    key = next(iter(state))
    state[key] = torch.zeros(3, 3)
    save_file(state, w)
    with pytest.raises(DataError, match="shape"):
        OriginalPINN.load(path)
    w.write_bytes(b"import os; os.system('echo pwned')")
    with pytest.raises(DataError, match="safetensors"):
        OriginalPINN.load(path)
    # integer weights would load truncated to 0: a constant prediction, no error
    fitted.save(path)
    save_file({k: v.to(torch.int32) for k, v in load_file(w).items()}, w)
    with pytest.raises(DataError, match="are torch.int32, not floating point"):
        OriginalPINN.load(path)


def test_load_rejects_bad_documents(fitted, tmp_path):
    path = fitted.save(tmp_path / "m.json")
    doc = json.loads(path.read_text())
    with pytest.raises(DataError, match="not 'sdnn'"):
        SDNN.load(path)
    for change, match in [
        ({"weights_file": "../m.safetensors"}, "plain file name"),
        ({"format_version": 99}, "format_version"),
        ({"params": {**doc["params"], "evil": 1}}, "unknown parameters"),
        ({"params": {**doc["params"], "dropout": 5}}, "'dropout' parameter .*corrupt"),
    ]:
        bad = tmp_path / "bad.json"
        bad.write_text(json.dumps({**doc, **change}))
        with pytest.raises(DataError, match=match):
            OriginalPINN.load(bad)
    (tmp_path / "m.safetensors").unlink()
    with pytest.raises(DataError, match="missing"):
        OriginalPINN.load(path)


def test_load_weights_only_torch_file(fitted, small, tmp_path):
    path = fitted.save(tmp_path / "m.json")
    torch.save(fitted.module_.state_dict(), tmp_path / "m.pt")
    doc = json.loads(path.read_text())
    doc["weights_file"] = "m.pt"
    path.write_text(json.dumps(doc))
    np.testing.assert_array_equal(OriginalPINN.load(path).predict(small), fitted.predict(small))
    # A pickle that is not a plain state_dict is refused by weights_only loading.
    torch.save({"x": object()}, tmp_path / "m.pt", _use_new_zipfile_serialization=True)
    with pytest.raises(DataError, match="not a weights-only torch file") as err:
        OriginalPINN.load(path)
    # one line, and no advice to turn the safety off
    assert "\n" not in str(err.value) and "False" not in str(err.value)


def test_save_needs_fitted_and_a_json_suffix(fitted, tmp_path):
    with pytest.raises(NotFittedError):
        SDNN().save(tmp_path / "x.json")
    with pytest.raises(DataError, match="suffix"):
        fitted.save(tmp_path / "x.safetensors")


def test_pickle_and_clone(fitted, small):
    again = pickle.loads(pickle.dumps(fitted))
    np.testing.assert_array_equal(again.predict(small), fitted.predict(small))
    c = clone(fitted)
    assert c.get_params() == fitted.get_params() and not hasattr(c, "module_")


# scikit-learn's common checks of the networks: tests/models/test_models_sklearn_checks.py


def test_base_class_is_abstract():
    with pytest.raises(NotImplementedError):
        TorchRegressor().build_module()


def test_training_parameters_are_declared_once():
    # Every network's constructor is generated from its own parameters plus the one
    # TRAINING_PARAMS table: no subclass re-declares the training keywords.
    import inspect

    from nirglucose.models._torch_base import TRAINING_PARAMS

    for cls in (SDNN, OriginalPINN, OptimizedPINN, RTEPINN, SelectiveRTEPINN):
        names = list(inspect.signature(cls).parameters)
        assert names[-len(TRAINING_PARAMS) :] == list(TRAINING_PARAMS), cls
        assert getattr(cls.__init__, "generated", False), cls  # no hand-written __init__
        for klass in cls.__mro__:
            assert set(vars(klass).get("own_params", {})).isdisjoint(TRAINING_PARAMS)
    assert OptimizedPINN().dropout == 0.1 and OriginalPINN().dropout == 0.0
    assert list(inspect.signature(OptimizedPINN).parameters)[:3] == [
        "d_model",
        "n_heads",
        "lambda_phys",
    ]
    with pytest.raises(TypeError, match="unexpected keyword argument 'max_epoch'"):
        SDNN(max_epoch=3)
