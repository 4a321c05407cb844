"""Enhanced Beer–Lambert ridge and the PLS baseline."""

from __future__ import annotations

import json
import pickle

import numpy as np
import pytest
from sklearn.base import clone
from sklearn.cross_decomposition import PLSRegression
from sklearn.linear_model import Ridge
from sklearn.model_selection import GroupKFold, cross_val_predict
from sklearn.pipeline import make_pipeline
from sklearn.preprocessing import StandardScaler

import nirglucose as ng
from nirglucose.dataset import measured_columns
from nirglucose.exceptions import ConfigError, DataError, NotFittedError
from nirglucose.features import ebl_feature_matrix
from nirglucose.models import EnhancedBeerLambert, PLSBaseline, load_model, make_model
from nirglucose.models.linear import _group_kfold_ids

COLS = measured_columns()

@pytest.fixture(scope="module")
def paper():
    return ng.simulate("wearable", n_subjects=30, per_subject=3, seed=0)


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
        ng.simulate("wearable", 40, 3, seed=5, overrides=over),
        ng.simulate("wearable", 20, 3, seed=6, overrides=over),
    )


def _rmse(a, b):
    return float(np.sqrt(np.mean((np.asarray(a) - np.asarray(b)) ** 2)))


#: Fast settings of the two linear models.
FAST = [
    EnhancedBeerLambert(alphas=(0.1, 1.0, 10.0), cv=3),
    PLSBaseline(max_components=3, cv=3),
]


@pytest.mark.parametrize("est", FAST, ids=lambda e: type(e).__name__)
def test_contract_on_device_data(est, arrays, paper):
    """Fitted on a device's frame, a model reads arrays in the device's column order."""
    X, y, g = arrays
    m = clone(est).fit(paper)
    assert m.n_features_in_ == 20 and list(m.feature_names_in_) == COLS
    assert m.schema_.is_study and m.schema_.raw_columns == tuple(COLS)
    ref = m.predict(X)
    np.testing.assert_allclose(m.predict(paper), ref, atol=1e-9)
    assert ref.shape == (len(X),) and ref.dtype == np.float64
    np.testing.assert_array_equal(pickle.loads(pickle.dumps(m)).predict(X), ref)
    perm = np.random.default_rng(0).permutation(len(X))
    np.testing.assert_allclose(m.predict(X[perm]), ref[perm], atol=1e-9)
    np.testing.assert_allclose(m.predict(X[:7]), ref[:7], atol=1e-9)
    np.testing.assert_allclose(m.predict(np.asfortranarray(X)), ref, atol=1e-9)
    np.testing.assert_allclose(m.predict(X.tolist()), ref, atol=1e-9)
    shuffled = paper.frame[COLS[::-1]]  # a frame is read by name, not position
    np.testing.assert_allclose(m.predict(shuffled), ref, atol=1e-9)
    Xb = X.copy()
    Xb[2, 0] = -5.0
    with pytest.raises(DataError, match="adc_850.*outside 1-4095"):
        m.predict(Xb)
    with pytest.raises(ValueError, match="X has 19 features, but .* expecting 20"):
        m.predict(X[:, :19])
    with pytest.raises(DataError, match="missing columns \\['pressure_mbar'\\]"):
        m.predict(paper.frame.drop(columns=["pressure_mbar"]))
    with pytest.raises(DataError, match="1 sample"):
        clone(est).fit(paper.frame.iloc[:1])
    with pytest.raises(NotFittedError):
        clone(est).predict(X)
    # A frame's subject_id groups the inner CV: the same as passing groups.
    np.testing.assert_allclose(
        clone(est).fit(paper.frame.drop(columns="subject_id"), groups=g).predict(X),
        ref,
        atol=1e-9,
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


def test_ebl_matches_sklearn_ridge_pipeline(arrays, paper):
    X, y, g = arrays
    F = ebl_feature_matrix(X)
    alphas = (0.01, 3.0, 300.0)
    m = EnhancedBeerLambert(alphas=alphas).fit(paper)
    for a, mse in zip(alphas, m.cv_mse_, strict=True):
        pipe = make_pipeline(StandardScaler(), Ridge(alpha=a))
        p = cross_val_predict(pipe, F, y, groups=g, cv=GroupKFold(5))
        assert mse == pytest.approx(np.mean((p - y) ** 2), rel=1e-9)
    assert m.alpha_ == alphas[int(np.argmin(m.cv_mse_))]
    ref = make_pipeline(StandardScaler(), Ridge(alpha=m.alpha_)).fit(F, y)
    np.testing.assert_allclose(m.predict(X), ref.predict(F), atol=1e-8)
    np.testing.assert_allclose(m.predict(X), F @ m.coef_ + m.intercept_, atol=1e-9)
    assert m.n_parameters == 57


def test_pls_matches_sklearn(arrays, paper):
    X, y, g = arrays
    U = PLSBaseline().fit(paper)._features(X)
    for k in (1, 3, 8, 16):
        m = PLSBaseline(n_components=k).fit(paper.frame.drop(columns="subject_id"))
        ref = PLSRegression(n_components=k).fit(U, y)
        np.testing.assert_allclose(m.predict(X), ref.predict(U).ravel(), atol=1e-8)
    m = PLSBaseline(max_components=5).fit(paper)
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
    for scale in (0.0, 1.0, 3.0):  # x4 draws cuff readings below 50 mmHg (refused)
        over = {"noise_scale": scale}
        train = ng.simulate("wearable", 60, 3, seed=11, overrides=over)
        test = ng.simulate("wearable", 30, 3, seed=12, overrides=over)
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
    with pytest.raises(DataError, match="not JSON, or a number"):
        EnhancedBeerLambert.load(write('{"format": ' + "9" * 5000 + "}"))
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
    with pytest.raises(DataError, match="1 coefficients but its device has 56"):
        EnhancedBeerLambert.load(write({**good, "state": {**good["state"], "coef_": [1.0]}}))
    with pytest.raises(DataError, match="wrong shape"):
        EnhancedBeerLambert.load(write({**good, "state": {**good["state"], "coef_": [[1.0]]}}))
    with pytest.raises(DataError, match="malformed 'schema'"):
        EnhancedBeerLambert.load(write({**good, "state": {**good["state"], "schema_": {}}}))
    with pytest.raises(DataError, match="not numeric"):
        EnhancedBeerLambert.load(write({**good, "state": {**good["state"], "coef_": ["a"]}}))
    with pytest.raises(ConfigError, match="unknown model 'zzz'"):
        load_model(write({**good, "model": "zzz"}))
    # a value of the right shape but the wrong JSON type is refused, not coerced
    for key, value in (("intercept_", "1"), ("coef_", [True] * len(good["state"]["coef_"]))):
        with pytest.raises(DataError, match=f"state {key}' is not numeric"):
            EnhancedBeerLambert.load(write({**good, "state": {**good["state"], key: value}}))
    schema = good["state"]["schema_"]
    for bits in (99, 0, 12.5, "12", True):
        bad = {**good, "state": {**good["state"], "schema_": {**schema, "adc_bits": bits}}}
        with pytest.raises(DataError, match="adc_bits .*expected an integer from 1 to 32"):
            EnhancedBeerLambert.load(write(bad))
    for entry in ({"reference": "no"}, {"wavelengths_nm": ["850", 940]}):
        bad = {**good, "state": {**good["state"], "schema_": {**schema, **entry}}}
        with pytest.raises(DataError, match="malformed 'schema'"):
            EnhancedBeerLambert.load(write(bad))
    # stored parameters are held to the constructor's constraints
    with pytest.raises(DataError, match="'cv' parameter .*the file is corrupt"):
        EnhancedBeerLambert.load(write({**good, "params": {**good["params"], "cv": -1}}))


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
    with pytest.raises(DataError, match="no ADC columns"):
        EnhancedBeerLambert().fit(paper.frame.drop(columns=COLS[:8]))
    with pytest.raises(DataError, match="glucose_mgdl"):
        PLSBaseline().fit(paper.frame.drop(columns=["glucose_mgdl"]))
    with pytest.raises(NotFittedError):
        EnhancedBeerLambert().save("never.json")
    with pytest.raises(ConfigError, match="unknown parameter 'foo' of model 'ebl'; valid: "):
        make_model("ebl", foo=1)
    fitted = EnhancedBeerLambert(alphas=(1.0,)).fit(paper)
    for X, says in ((None, "got NoneType"), ({"adc_850": [1.0]}, "got dict"),
                    ([1.0, 2.0], "Expected 2D array")):
        with pytest.raises(DataError, match=says) as err:
            fitted.predict(X)
        assert "\n" not in str(err.value)
    twice = paper.frame.assign(extra=paper.frame["adc_850"]).rename(
        columns={"extra": "adc_850"})
    with pytest.raises(DataError, match="column 'adc_850' appears 2 times; keep one"):
        fitted.predict(twice)


def test_registry_names():
    assert isinstance(make_model("ebl"), EnhancedBeerLambert)
    assert isinstance(make_model("pls", max_components=4), PLSBaseline)
