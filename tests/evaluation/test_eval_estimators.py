"""Estimator objects in the benchmark and the sweep (issue 33): names and objects side by
side, a clone per fold, the task seed in random_state, bad objects refused, any jobs."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from sklearn.base import BaseEstimator, RegressorMixin, clone
from sklearn.exceptions import NotFittedError
from sklearn.linear_model import Ridge
from sklearn.pipeline import Pipeline, make_pipeline
from sklearn.preprocessing import StandardScaler
from sklearn.utils.validation import check_is_fitted

import nirglucose as ng
from nirglucose.dataset import Dataset
from nirglucose.evaluation import Protocol
from nirglucose.evaluation.benchmark.run import run_benchmark
from nirglucose.evaluation.engine.tasks import derived_seed
from nirglucose.evaluation.estimators import (
    build_estimator,
    estimator_identity,
    measured_frame,
    resolve_entries,
)
from nirglucose.evaluation.splits import make_splits
from nirglucose.evaluation.sweep.run import run_sweep
from nirglucose.exceptions import ConfigError
from nirglucose.models.registry import make_model

TWO = Protocol(n_splits=2, repeats=1, resamples=30)
FAST = dict(
    timing={"n_single": 2, "min_single": 1, "warmup": 0, "batch_rows": 20, "batch_repeats": 1},
    oracle_reference=False, drop_one_models="none", protocol=TWO,
)


class SeedEcho(RegressorMixin, BaseEstimator):
    """Predicts its own random_state for every row: shows which seed reached it."""

    def __init__(self, random_state=None):
        self.random_state = random_state

    def fit(self, X, y):
        self.seen_columns_ = list(getattr(X, "columns", []))
        self.n_features_in_ = np.shape(X)[1]
        return self

    def predict(self, X):
        check_is_fitted(self, "n_features_in_")
        return np.full(len(X), float(self.random_state))


class NoFit:
    def predict(self, X):  # pragma: no cover - never called
        return X


class NoParams:
    def fit(self, X, y):  # pragma: no cover - never called
        return self

    def predict(self, X):  # pragma: no cover - never called
        return X


@pytest.fixture(scope="module")
def data():
    # a user's data (no scenario config): registered names get untuned parameters, so a
    # registered class as an object is the same estimator as its name
    return Dataset(ng.simulate("paper", n_subjects=12, per_subject=3, seed=0).frame)


def _pred(result, model):
    p = result.predictions
    return p[p["model"] == model].sort_values(["repeat", "fold", "subject_id",
                                               "measurement_id"])["predicted_mgdl"].to_numpy()


def test_names_and_objects_side_by_side(data):
    pipe = make_pipeline(StandardScaler(), Ridge(alpha=3.0))
    pls = make_model("pls")
    both = run_benchmark(data, ["pls", ("pls-object", pls), ("ridge", pipe)], **FAST)
    alone = run_benchmark(data, ["pls"], **FAST)
    m = both.metrics.set_index("model")
    assert sorted(m.index) == ["pls", "pls-object", "ridge"]
    # the same estimator by name and as an object: the same numbers, whatever else ran
    np.testing.assert_array_equal(_pred(both, "pls-object"), _pred(both, "pls"))
    np.testing.assert_array_equal(_pred(both, "pls"), _pred(alone, "pls"))
    assert m.loc["pls-object", "rmse_mgdl"] == m.loc["pls", "rmse_mgdl"]
    # the pipeline is fitted as scikit-learn would: on the measured columns, per fold
    expect = []
    groups = data.frame["subject_id"].to_numpy()
    for split in make_splits(groups, "grouped-cv", n_splits=2, repeats=1, seed=0):
        train, test = data.rows(split.train), data.rows(split.test)
        est = clone(pipe).fit(measured_frame(train), train.frame["glucose_mgdl"])
        order = np.lexsort((test.frame["measurement_id"], test.frame["subject_id"]))
        expect.append(est.predict(measured_frame(test))[order])
    np.testing.assert_allclose(_pred(both, "ridge"), np.concatenate(expect), rtol=1e-12)
    # the caller's objects stay unfitted; the metadata says they were fitted as given
    for est in (pipe, pls):
        with pytest.raises(NotFittedError):
            check_is_fitted(est[-1] if isinstance(est, Pipeline) else est)
    meta = both.meta["estimators"]
    assert set(meta) == {"pls-object", "ridge"} and meta["ridge"]["input"].startswith("measured")
    assert "fitted as given" in meta["pls-object"]["tuning"]


def test_object_of_a_registered_class_takes_its_name(data):
    res = run_benchmark(data, [make_model("ebl")], **FAST)
    ref = run_benchmark(data, ["ebl"], **FAST)  # ebl takes random_state: the same seed too
    assert list(res.metrics["model"]) == ["ebl"]
    np.testing.assert_array_equal(_pred(res, "ebl"), _pred(ref, "ebl"))


def test_task_seed_reaches_random_state(data):
    echo, nested, fixed = SeedEcho(), make_pipeline(StandardScaler(), SeedEcho()), SeedEcho(5)
    res = run_benchmark(data, [echo, ("nested", nested), ("fixed", fixed)],
                        **{**FAST, "protocol": dataclasses.replace(TWO, seed=3)})
    p = res.predictions
    for (repeat, fold), g in p.groupby(["repeat", "fold"]):
        task_seed = derived_seed(3, "SeedEcho", repeat, fold)  # as a registered model's
        got = g.set_index("model")["predicted_mgdl"]
        assert set(got.loc["SeedEcho"]) == {task_seed}
        assert set(got.loc["nested"]) == {derived_seed(
            derived_seed(3, "nested", repeat, fold), "seedecho__random_state")}
        assert set(got.loc["fixed"]) == {5.0}  # a seed the caller set is kept
    assert echo.random_state is None and not hasattr(echo, "n_features_in_")
    # the object is fed the measured columns only: no truth, ids or target
    model = build_estimator(echo, {}, 0).fit(measured_frame(data), None)
    assert model.seen_columns_ and not any(
        c.startswith("true_") or c in ("subject_id", "glucose_mgdl") for c in model.seen_columns_)


def test_jobs_and_cache(data, tmp_path):
    models = ["pls", ("ridge", make_pipeline(StandardScaler(), Ridge()))]
    one = run_benchmark(data, models, jobs=1, out=tmp_path / "a", **FAST)
    two = run_benchmark(data, models, jobs=2, **FAST)
    np.testing.assert_array_equal(_pred(one, "ridge"), _pred(two, "ridge"))
    again = run_benchmark(data, models, out=tmp_path / "a", **FAST)
    assert again.meta["tasks_computed"] == 0  # the object's tasks are found by their key
    other = ["pls", ("ridge", make_pipeline(StandardScaler(), Ridge(alpha=10.0)))]
    changed = run_benchmark(data, other, out=tmp_path / "a", **FAST)
    assert changed.meta["tasks_computed"] == 2  # other parameters: the ridge's 2 folds rerun
    assert not np.array_equal(_pred(changed, "ridge"), _pred(one, "ridge"))


def test_identity_is_deterministic_and_complete():
    a = estimator_identity(make_pipeline(StandardScaler(), Ridge(alpha=1.0)))
    b = estimator_identity(make_pipeline(StandardScaler(), Ridge(alpha=1.0)))
    c = estimator_identity(make_pipeline(StandardScaler(), Ridge(alpha=1.5)))
    assert a == b and a != c
    assert a["class"] == "sklearn.pipeline.Pipeline"
    arr = estimator_identity(Ridge(alpha=np.arange(3.0)))["params"]["alpha"]
    assert arr["shape"] == [3] and len(arr["array_sha256"]) == 64


@pytest.mark.parametrize(
    ("models", "words"),
    [
        ([NoFit()], ["NoFit", "fit/predict"]),
        ([("mine", NoFit())], ["'mine'", "fit/predict"]),
        ([NoParams()], ["NoParams", "get_params"]),
        ([Ridge], ["Ridge", "class", "Ridge()"]),
        ([Ridge(), Ridge(alpha=2.0)], ["two models share the label 'Ridge'"]),
        (["pls", ("pls", Ridge())], ["two models share the label 'pls'"]),
        ([("", Ridge())], ["label"]),
        ([("a/b", Ridge())], ["'a/b'", "'/'"]),
        (["no-such-model"], ["no-such-model"]),
    ],
)
def test_bad_entries_refused(data, models, words):
    with pytest.raises(ConfigError) as info:
        run_benchmark(data, models, **FAST)
    msg = str(info.value)
    assert "\n" not in msg and all(w in msg for w in words), msg


def test_bad_object_params_refused(data):
    with pytest.raises(ConfigError, match=r"model_params\['ridge'\]: .*no_such"):
        run_benchmark(data, [("ridge", Ridge())], model_params={"ridge": {"no_such": 1}}, **FAST)
    res = run_benchmark(data, [("ridge", Ridge())], model_params={"ridge": {"alpha": 5e4}},
                        **FAST)
    plain = run_benchmark(data, [("ridge", Ridge())], **FAST)
    assert res.meta["model_params"] == {"ridge": {"alpha": 5e4}}
    assert not np.allclose(_pred(res, "ridge"), _pred(plain, "ridge"))  # set_params applied


def test_drop_one_refits_an_object(data):
    res = run_benchmark(data, [("ridge", make_pipeline(StandardScaler(), Ridge()))],
                        **{**FAST, "drop_one_models": "all"})
    d = res.drop_one
    assert sorted(d["dropped_wavelength_nm"]) == sorted(data.wavelengths_nm)
    assert (d["model"] == "ridge").all() and np.isfinite(d["delta_rmse_mgdl"]).all()


def test_resolve_entries_forms():
    r = Ridge()
    assert [e.label for e in resolve_entries(r, [])] == ["Ridge"]  # one object
    assert [e.label for e in resolve_entries("pls,ebl,pls", [])] == ["pls", "ebl"]
    assert [e.label for e in resolve_entries(None, ["pls"])] == ["pls"]


@pytest.mark.slow  # make test-slow (CI runs it)
def test_sweep_takes_objects(tmp_path):
    kw = dict(seeds=1, n_subjects=16, per_subject=2, protocol="paper-split", n_boot=30)
    models = ["pls", ("ridge", make_pipeline(StandardScaler(), Ridge()))]
    one = run_sweep({"noise_scale": [1.0]}, models=models, jobs=1, out=tmp_path / "s", **kw)
    two = run_sweep({"noise_scale": [1.0]}, models=models, jobs=2, **kw)
    cols = ["model", "rmse_mgdl", "mard_pct"]
    assert list(one.frame["model"]) == ["pls", "ridge"]
    assert one.frame[cols].equals(two.frame[cols])
    assert set(one.meta["estimators"]) == {"ridge"}
    again = run_sweep({"noise_scale": [1.0]}, models=models, out=tmp_path / "s", **kw)
    assert again.meta["tasks_computed"] == 0
    with pytest.raises(ConfigError, match="fleet study takes registered model names"):
        run_sweep(study="fleet", models=[("ridge", Ridge())], seeds=1)


def test_measured_frame_reads_channels_as_the_schema_does(data):
    """A reference learner sees the schema's channels: every adc_<nm> (850.5 included),
    ascending whatever the file's order; a partial set of references is refused."""
    from nirglucose.dataset.schema import DeviceSchema

    frame = data.frame.rename(columns={"adc_940": "adc_940.5", "adc_ref_940": "adc_ref_940.5"})
    shuffled = frame[list(reversed(frame.columns))]
    own = Dataset(shuffled, seed=0)
    X = measured_frame(own)
    schema = DeviceSchema.infer(own, adc_bits=12)
    assert tuple(X.columns) == schema.raw_columns
    assert "adc_940.5" in X.columns and "adc_ref_940.5" in X.columns
    with pytest.raises(ng.DataError, match=r"some LEDs only: missing \['adc_ref_850'\]"):
        measured_frame(Dataset(frame.drop(columns=["adc_ref_850"]), seed=0))
    with pytest.raises(ng.DataError, match="'adc_850.0' names the 850 nm LED; spell it 'adc_850'"):
        measured_frame(Dataset(frame.assign(**{"adc_850.0": frame["adc_850"]}), seed=0))
