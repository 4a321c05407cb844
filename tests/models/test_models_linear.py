"""Enhanced Beer–Lambert ridge and the PLS baseline."""

from __future__ import annotations

import json
import pickle

import numpy as np
import pandas as pd
import pytest
from sklearn.base import clone
from sklearn.cross_decomposition import PLSRegression
from sklearn.linear_model import Ridge
from sklearn.model_selection import GroupKFold, cross_val_predict
from sklearn.pipeline import make_pipeline
from sklearn.preprocessing import StandardScaler
from sklearn.utils.estimator_checks import parametrize_with_checks

import nirglucose as ng
from nirglucose.dataset import measured_columns
from nirglucose.exceptions import ConfigError, DataError, NotFittedError
from nirglucose.features import ebl_feature_matrix
from nirglucose.models import EnhancedBeerLambert, PLSBaseline, load_model, make_model
from nirglucose.models.linear import _group_kfold_ids, _pls_inputs

COLS = measured_columns()

#: Checks that fit or predict on random arrays of 1-10 columns (or reshape them): our
#: models take exactly the 20 measured columns (4 ADC codes, 4 reference codes, 12
#: physiological entries) and reject any other width with a DataError, so these checks
#: cannot apply. ``test_sklearn_contract_on_valid_measurements`` below re-checks what
#: each of them checks, on valid measurements.
WIDTH = "fits on random arrays whose width is not the 20 measured columns"
EXPECTED_FAILED = {
    "check_fit_score_takes_y": WIDTH + " (score(X, y) is checked below)",
    "check_estimators_overwrite_params": WIDTH + " (params unchanged by fit: below)",
    "check_dont_overwrite_parameters": WIDTH + " (no public attribute set by fit: below)",
    "check_estimators_fit_returns_self": WIDTH + " (fit returns self: below)",
    "check_readonly_memmap_input": WIDTH + " (read-only input: below)",
    "check_n_features_in_after_fitting": WIDTH + " (wrong width at predict raises: below)",
    "check_positive_only_tag_during_fit": WIDTH + " (ADC codes must be positive: below)",
    "check_estimators_dtypes": WIDTH + " (float32/int64 input: below)",
    "check_dtype_object": WIDTH + " (object arrays of numbers: below)",
    "check_pipeline_consistency": WIDTH + " (Pipeline gives the same result: below)",
    "check_estimators_nan_inf": WIDTH + " (NaN/inf rejected in fit and predict: below)",
    "check_estimators_pickle": WIDTH + " (pickle round trip: below)",
    "check_estimators_pickle(readonly_memmap=True)": WIDTH + " (pickle round trip: below)",
    "check_f_contiguous_array_estimator": WIDTH + " (C and F order agree: below)",
    "check_regressors_train": WIDTH + " (learning on noise-free data: test_real_learning)",
    "check_regressors_train(readonly_memmap=True)": WIDTH + " (as above)",
    "check_regressors_train(readonly_memmap=True,X_dtype=float32)": WIDTH + " (as above)",
    "check_regressor_data_not_an_array": WIDTH + " (lists and DataFrames: below)",
    "check_regressors_no_decision_function": WIDTH + " (no decision_function: below)",
    "check_supervised_y_2d": WIDTH + " ((n, 1) y accepted: below)",
    "check_regressors_int": WIDTH + " (integer input: below)",
    "check_methods_sample_order_invariance": WIDTH + " (row order invariance: below)",
    "check_methods_subset_invariance": WIDTH + " (subset invariance: below)",
    "check_fit2d_1sample": WIDTH + " (one-row fit: below)",
    "check_fit2d_1feature": WIDTH + " (one column is rejected by design: below)",
    "check_dict_unchanged": WIDTH + " (predict leaves __dict__ unchanged: below)",
    "check_fit_idempotent": WIDTH + " (refit gives identical predictions: below)",
    "check_fit_check_is_fitted": WIDTH + " (check_is_fitted after fit: below)",
    "check_n_features_in": WIDTH + " (n_features_in_ == 20: below)",
    "check_fit2d_predict1d": WIDTH + " (1-D input to predict raises: below)",
}

FAST = [
    EnhancedBeerLambert(alphas=(0.1, 1.0, 10.0), cv=3),
    PLSBaseline(max_components=3, cv=3),
]


@parametrize_with_checks(FAST, expected_failed_checks=lambda est: EXPECTED_FAILED)
def test_sklearn_checks(estimator, check, request):
    if request.node.get_closest_marker("xfail") is None:
        check(estimator)  # a real failure keeps its full traceback
        return
    try:
        check(estimator)
    except Exception as exc:  # an expected failure: a one-frame report is enough
        raise AssertionError(f"{type(exc).__name__}: {str(exc)[:300]}") from None


@pytest.fixture(scope="module")
def paper():
    return ng.simulate("paper", n_subjects=30, per_subject=3, seed=0)


@pytest.fixture(scope="module")
def arrays(paper):
    frame = paper.frame
    return (
        frame[COLS].to_numpy(float),
        frame["glucose_mgdl"].to_numpy(float),
        frame["subject_id"].to_numpy(),
    )


@pytest.fixture(scope="module")
def clean():
    """No noise and identical subjects: glucose is all that varies the optics."""
    over = {"noise_scale": 0.0, "physiology.variation_scale": 0.0}
    return (
        ng.simulate("paper", 40, 3, seed=5, overrides=over),
        ng.simulate("paper", 20, 3, seed=6, overrides=over),
    )


def _rmse(a, b):
    return float(np.sqrt(np.mean((np.asarray(a) - np.asarray(b)) ** 2)))


@pytest.mark.parametrize("est", FAST, ids=lambda e: type(e).__name__)
def test_sklearn_contract_on_valid_measurements(est, arrays, paper):
    """What the width-dependent sklearn checks check, on valid 20-column data."""
    X, y, g = arrays
    params = est.get_params()
    m = clone(est)
    assert m.fit(X, y) is m  # fit returns self
    assert m.get_params() == params  # fit does not overwrite parameters
    assert m.n_features_in_ == 20 and not hasattr(m, "feature_names_in_")
    public = {k for k in vars(m) if not k.startswith("_")}
    assert all(k.endswith("_") for k in public - set(params))
    ref = m.predict(X)
    assert ref.shape == (len(X),) and ref.dtype == np.float64
    before = {k: v for k, v in vars(m).items()}
    m.predict(X)
    assert set(vars(m)) == set(before)  # predict leaves the fitted state alone
    np.testing.assert_allclose(clone(est).fit(X, y).predict(X), ref, rtol=0, atol=1e-9)
    m2 = pickle.loads(pickle.dumps(m))
    np.testing.assert_array_equal(m2.predict(X), ref)
    perm = np.random.default_rng(0).permutation(len(X))
    np.testing.assert_allclose(m.predict(X[perm]), ref[perm], atol=1e-9)
    np.testing.assert_allclose(m.predict(X[:7]), ref[:7], atol=1e-9)
    np.testing.assert_allclose(m.predict(np.asfortranarray(X)), ref, atol=1e-9)
    ro = X.copy()
    ro.setflags(write=False)
    np.testing.assert_allclose(m.predict(ro), ref, atol=1e-9)
    np.testing.assert_allclose(m.predict(X.tolist()), ref, atol=1e-9)
    np.testing.assert_allclose(m.predict(X.astype(object)), ref, atol=1e-9)
    np.testing.assert_allclose(m.predict(pd.DataFrame(X, columns=COLS)), ref, atol=1e-9)
    np.testing.assert_allclose(m.predict(X.astype(np.float32)), ref, rtol=1e-4, atol=1e-2)
    Xi = np.rint(X).astype(np.int64)
    np.testing.assert_allclose(m.predict(Xi), m.predict(Xi.astype(float)), atol=1e-9)
    np.testing.assert_allclose(
        clone(est).fit(X, y[:, None]).predict(X),
        clone(est).fit(X, list(y)).predict(X),
        atol=1e-9,
    )
    assert np.isfinite(m.score(X, y))
    assert not hasattr(m, "decision_function")
    np.testing.assert_allclose(make_pipeline(clone(est)).fit(X, y).predict(X), ref, atol=1e-9)
    for bad in (np.nan, np.inf):
        Xb = X.copy()
        Xb[4, 11] = bad
        with pytest.raises(ValueError, match="NaN|inf"):
            clone(est).fit(Xb, y)
        with pytest.raises(ValueError, match="NaN|inf"):
            m.predict(Xb)
    Xb = X.copy()
    Xb[2, 0] = -5.0
    with pytest.raises(DataError, match="positive"):
        m.predict(Xb)
    with pytest.raises(ValueError, match="20 measured columns"):
        m.predict(X[:, :19])
    with pytest.raises(ValueError, match="20 measured columns"):
        clone(est).fit(X[:, :1], y)
    with pytest.raises(ValueError, match="2D"):
        m.predict(X[0])
    with pytest.raises(ValueError, match="requires y"):
        clone(est).fit(X)
    one = clone(est).fit(X[:1], y[:1])
    assert one.predict(X[:3]) == pytest.approx(np.full(3, y[0]))
    with pytest.raises(NotFittedError):
        clone(est).predict(X)
    # A frame's subject_id groups the inner CV: the same as passing groups.
    np.testing.assert_allclose(
        clone(est).fit(paper).predict(X), clone(est).fit(X, y, groups=g).predict(X), atol=1e-9
    )


def test_group_folds_match_sklearn():
    rng = np.random.default_rng(1)
    for groups in (
        np.repeat(np.arange(23), 3),
        rng.integers(0, 17, 90),
        rng.permutation(np.repeat(np.arange(12) * 5 + 3, 4)),
    ):
        ref = np.empty(len(groups), dtype=int)
        for f, (_, te) in enumerate(GroupKFold(5).split(groups, groups=groups)):
            ref[te] = f
        np.testing.assert_array_equal(_group_kfold_ids(groups, 5), ref)


def test_ebl_matches_sklearn_ridge_pipeline(arrays):
    X, y, g = arrays
    F = ebl_feature_matrix(X)
    alphas = (0.01, 3.0, 300.0)
    m = EnhancedBeerLambert(alphas=alphas).fit(X, y, groups=g)
    for a, mse in zip(alphas, m.cv_mse_, strict=True):
        pipe = make_pipeline(StandardScaler(), Ridge(alpha=a))
        p = cross_val_predict(pipe, F, y, groups=g, cv=GroupKFold(5))
        assert mse == pytest.approx(np.mean((p - y) ** 2), rel=1e-9)
    assert m.alpha_ == alphas[int(np.argmin(m.cv_mse_))]
    ref = make_pipeline(StandardScaler(), Ridge(alpha=m.alpha_)).fit(F, y)
    np.testing.assert_allclose(m.predict(X), ref.predict(F), atol=1e-8)
    np.testing.assert_allclose(m.predict(X), F @ m.coef_ + m.intercept_, atol=1e-9)
    assert m.n_parameters == 57


def test_pls_matches_sklearn(arrays):
    X, y, g = arrays
    U = _pls_inputs(X)
    for k in (1, 3, 8, 16):
        m = PLSBaseline(n_components=k).fit(X, y)
        ref = PLSRegression(n_components=k).fit(U, y)
        np.testing.assert_allclose(m.predict(X), ref.predict(U).ravel(), atol=1e-8)
    m = PLSBaseline(max_components=5).fit(X, y, groups=g)
    for k, mse in enumerate(m.cv_mse_, start=1):
        p = cross_val_predict(PLSRegression(k), U, y, groups=g, cv=GroupKFold(5)).ravel()
        assert mse == pytest.approx(np.mean((p - y) ** 2), rel=1e-9)
    assert m.n_components_ == int(np.argmin(m.cv_mse_)) + 1
    assert m.n_parameters == 17


def test_real_learning_on_noise_free_data(clean):
    train, test = clean
    y = test.frame["glucose_mgdl"]
    assert _rmse(EnhancedBeerLambert().fit(train).predict(test), y) < 5.0
    assert _rmse(PLSBaseline().fit(train).predict(test), y) < 20.0


def test_error_grows_with_noise():
    rmse = []
    for scale in (0.0, 1.0, 4.0):
        over = {"noise_scale": scale}
        train = ng.simulate("paper", 60, 3, seed=11, overrides=over)
        test = ng.simulate("paper", 30, 3, seed=12, overrides=over)
        rmse.append(
            _rmse(EnhancedBeerLambert().fit(train).predict(test), test.frame["glucose_mgdl"])
        )
    assert rmse[0] < rmse[1] < rmse[2], rmse


def test_predict_one_equals_predict(paper, arrays):
    X, y, _ = arrays
    m = EnhancedBeerLambert().fit(paper)
    batch = m.predict(X)
    for i in (0, 5, 17, len(X) - 1):
        row = X[i]
        assert m.predict_one(row[:4], row[4:8], row[8:]) == pytest.approx(batch[i], abs=1e-9)
        assert m.predict_one(list(row[:4]), tuple(row[4:8]), list(row[8:])) == pytest.approx(
            batch[i], abs=1e-9
        )
    with pytest.raises(DataError, match="positive ADC"):
        m.predict_one([0, 1, 1, 1], X[0, 4:8], X[0, 8:])
    with pytest.raises(DataError, match="12 physiological"):
        m.predict_one(X[0, :4], X[0, 4:8], X[0, 8:15])
    with pytest.raises(NotFittedError):
        EnhancedBeerLambert().predict_one(X[0, :4], X[0, 4:8], X[0, 8:])


@pytest.mark.parametrize("cls", [EnhancedBeerLambert, PLSBaseline])
def test_save_load_round_trip(cls, paper, arrays, tmp_path):
    X, _, _ = arrays
    m = cls().fit(paper)
    path = m.save(tmp_path / "m.json")
    doc = json.loads(path.read_text())
    assert doc["format"] == "nirglucose-model" and doc["format_version"] == 1
    assert doc["model"] == cls.registry_name and "nirglucose_version" in doc
    assert set(doc["params"]) == set(m.get_params())
    for loaded in (cls.load(path), load_model(path)):
        assert type(loaded) is cls
        np.testing.assert_array_equal(loaded.predict(X), m.predict(X))
        assert loaded.get_params() == m.get_params()
    assert not list(tmp_path.glob("*.tmp"))


def test_load_rejects_bad_files(paper, tmp_path):
    m = EnhancedBeerLambert(alphas=(1.0, 10.0)).fit(paper)
    good = json.loads(m.save(tmp_path / "m.json").read_text())

    def write(doc, name="bad.json"):
        p = tmp_path / name
        p.write_text(doc if isinstance(doc, str) else json.dumps(doc))
        return p

    with pytest.raises(DataError, match="no such model file"):
        EnhancedBeerLambert.load(tmp_path / "missing.json")
    with pytest.raises(DataError, match="not JSON"):
        EnhancedBeerLambert.load(write("{nope"))
    with pytest.raises(DataError, match="format"):
        EnhancedBeerLambert.load(write({**good, "format": "other"}))
    with pytest.raises(DataError, match="format_version 2"):
        EnhancedBeerLambert.load(write({**good, "format_version": 2}))
    pls = PLSBaseline().fit(paper).save(tmp_path / "pls.json")
    with pytest.raises(DataError, match="holds a 'pls' model"):
        EnhancedBeerLambert.load(pls)
    with pytest.raises(DataError, match="unknown parameters"):
        EnhancedBeerLambert.load(write({**good, "params": {"lr": 1}}))
    state = dict(good["state"])
    del state["coef_"]
    with pytest.raises(DataError, match="lacks state 'coef_'"):
        EnhancedBeerLambert.load(write({**good, "state": state}))
    with pytest.raises(DataError, match="wrong shape"):
        EnhancedBeerLambert.load(write({**good, "state": {**good["state"], "coef_": [1.0]}}))
    with pytest.raises(DataError, match="not numeric"):
        EnhancedBeerLambert.load(write({**good, "state": {**good["state"], "coef_": ["a"]}}))
    with pytest.raises(ConfigError, match="unknown model 'zzz'"):
        load_model(write({**good, "model": "zzz"}))


def test_bad_parameters_and_inputs(paper):
    with pytest.raises(ConfigError, match="alphas"):
        EnhancedBeerLambert(alphas=(-1.0,)).fit(paper)
    with pytest.raises(ConfigError, match="cv"):
        EnhancedBeerLambert(cv=1).fit(paper)
    with pytest.raises(ConfigError, match="max_components"):
        PLSBaseline(max_components=0).fit(paper)
    frame = paper.frame.copy()
    frame.loc[5, "hydration_pct"] = np.nan
    with pytest.raises(DataError, match="hydration_pct.*rows 5"):
        EnhancedBeerLambert().fit(frame)
    with pytest.raises(DataError, match="missing columns"):
        EnhancedBeerLambert().fit(paper.frame.drop(columns=["pressure_mbar"]))
    with pytest.raises(DataError, match="glucose_mgdl"):
        PLSBaseline().fit(paper.frame.drop(columns=["glucose_mgdl"]))
    with pytest.raises(NotFittedError):
        EnhancedBeerLambert().save("never.json")


def test_registry_names():
    assert isinstance(make_model("ebl"), EnhancedBeerLambert)
    assert isinstance(make_model("pls", max_components=4), PLSBaseline)
