"""The deployable forward-model inversion (device-inversion, issue 39): the device's
parts and published tables only, glucose's response learned."""

from __future__ import annotations

import json

import numpy as np
import pytest

import nirglucose as ng
from nirglucose.config import resolve_config
from nirglucose.config.parts import LED_PARTS
from nirglucose.dataset import load_dataset
from nirglucose.dataset.schema import DeviceSchema
from nirglucose.exceptions import ConfigError, DataError
from nirglucose.models import load_model, make_model
from nirglucose.models._inversion_solver import NUISANCES, ForwardModel
from nirglucose.models.device_inversion import (
    DEFAULT_LED_FWHM_NM,
    POPULATION_PRIOR,
    DeviceInversion,
    calibrate_with_glucose,
    device_prior_start,
    device_scenario,
    skill_weight,
)
from nirglucose.models.inversion import PhysicsInversion, prior_start
from nirglucose.models.registry import privileged_knowledge

FAST = {"n_em": 3}


def _rmse(pred, y) -> float:
    return float(np.sqrt(np.mean((np.asarray(pred) - np.asarray(y)) ** 2)))


@pytest.fixture(scope="module")
def paper():
    return ng.simulate("paper", 30, 3, seed=1), ng.simulate("paper", 10, 3, seed=2)


@pytest.fixture(scope="module")
def fitted(paper):
    return DeviceInversion(**FAST).fit(paper[0])


def test_is_registered_and_deployable():
    assert isinstance(make_model("device-inversion"), DeviceInversion)
    assert privileged_knowledge("device-inversion") is None
    assert DeviceInversion.__doc__.splitlines()[0].startswith(
        "Physics inversion (device parts only)")


def test_a_dataset_its_frame_and_its_csv_fit_the_same_model(paper, fitted, tmp_path):
    """No scenario is read: the Dataset, its bare frame, its CSV and the same rows under
    another scenario (physical: glucose gain 1 instead of 11) give one model."""
    train, test = paper
    csv = load_dataset(train.save(tmp_path / "train.csv"))
    assert csv.config is None
    other = ng.Dataset(train.frame, config=resolve_config("physical"))
    base = fitted.predict(test)
    for data in (train.frame, csv, other):
        m = DeviceInversion(**FAST).fit(data)
        np.testing.assert_array_equal(m.predict(test.frame), base)
        np.testing.assert_array_equal(m.glucose_response_, fitted.glucose_response_)
        assert m.skill_weight_ == fitted.skill_weight_
    # the privileged inversion reads that scenario: the same rows, another model
    priv = PhysicsInversion(**FAST)
    assert not np.allclose(priv.fit(train).predict(test), priv.fit(other).predict(test))


def test_beats_no_skill_on_paper(paper, fitted):
    """Deployable and still far better than the training mean where glucose's signal is
    the study's (an estimator no better than the mean here would be a defect)."""
    train, test = paper
    y = test.frame["glucose_mgdl"].to_numpy()
    no_skill = _rmse(np.full_like(y, train.frame["glucose_mgdl"].mean()), y)
    assert _rmse(fitted.predict(test), y) < 0.5 * no_skill  # the privileged test's bar
    assert 0.8 < fitted.skill_weight_ <= 1.0


def test_learns_the_glucose_response_it_is_not_told(paper, fitted):
    """The same subjects with half the gain: the learned response halves (the model
    file holds no gain, so it can only have come from the rows)."""
    half = ng.simulate("paper", 30, 3, seed=1, overrides={"glucose.signal_gain": 5.5})
    m = DeviceInversion(**FAST).fit(half)
    full_resp = fitted.gain_ * fitted.glucose_response_  # measured units, per mg/dL
    half_resp = m.gain_ * m.glucose_response_
    assert np.all(full_resp > 0)
    ratio = float(np.sum(full_resp * half_resp) / np.sum(half_resp**2))
    assert 1.6 < ratio < 2.5, (full_resp, half_resp)


def test_never_reads_truth(paper, fitted):
    train, test = paper
    truth = [c for c in train.frame.columns if c.startswith("true_")]
    assert truth
    rng = np.random.default_rng(0)
    frame = train.frame.copy()
    for c in truth:
        frame[c] = rng.permutation(frame[c].to_numpy())
    m = DeviceInversion(**FAST).fit(frame.drop(columns=truth[:3]))
    np.testing.assert_array_equal(m.predict(test), fitted.predict(test))


def test_without_a_glucose_signal_it_falls_back_to_the_mean(paper):
    """Reference glucose shuffled across subjects: the response it learns in-sample is
    noise, and the held-out folds say so (skill weight near 0)."""
    train, test = paper
    frame = train.frame.copy()
    subjects = frame["subject_id"].unique()
    rng = np.random.default_rng(3)
    new = dict(zip(subjects, rng.permutation(subjects), strict=True))
    by_subject = frame.groupby("subject_id")["glucose_mgdl"].apply(list)
    frame["glucose_mgdl"] = np.concatenate([by_subject[new[s]] for s in subjects])
    m = DeviceInversion(**FAST).fit(frame)
    assert m.skill_weight_ < 0.3
    no_fold = DeviceInversion(**FAST, cv=0).fit(frame)
    assert no_fold.skill_weight_ == 1.0
    mean = frame["glucose_mgdl"].mean()
    spread = np.abs(m.predict(test) - mean).max()
    assert spread < np.abs(no_fold.predict(test) - mean).max()


def test_save_load_round_trip_without_a_scenario(paper, fitted, tmp_path):
    _, test = paper
    path = fitted.save(tmp_path / "dev.json")
    doc = json.loads(path.read_text())
    assert doc["model"] == "device-inversion" and "config_" not in doc["state"]
    assert "signal_gain" not in path.read_text()
    back = load_model(path)
    assert isinstance(back, DeviceInversion) and back.get_params() == fitted.get_params()
    np.testing.assert_allclose(back.predict(test), fitted.predict(test), rtol=1e-9)
    assert back.n_parameters == fitted.n_parameters
    doc["state"]["skill_weight_"] = 1.5
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps(doc))
    with pytest.raises(DataError, match="skill_weight_ 1.5 is outside"):
        load_model(bad)


def test_declared_led_widths_are_used(paper, fitted):
    train, test = paper
    assert np.all(fitted.led_fwhm_nm_ == DEFAULT_LED_FWHM_NM)
    wide = DeviceInversion(**FAST, led_fwhm_nm=[40.0, 45.0, 50.0, 60.0]).fit(train)
    assert wide.led_fwhm_nm_.tolist() == [40.0, 45.0, 50.0, 60.0]
    assert not np.allclose(wide.predict(test), fitted.predict(test))


def test_default_led_width_is_the_catalogues():
    certain = [p.fwhm_nm for p in LED_PARTS.values() if not p.uncertain]
    assert DEFAULT_LED_FWHM_NM == float(np.median(certain))


def test_bad_input_one_line(paper):
    train, _ = paper
    with pytest.raises(DataError, match="led_fwhm_nm gives 2 widths for 4 LEDs"):
        DeviceInversion(**FAST, led_fwhm_nm=[40.0, 50.0]).fit(train)
    with pytest.raises(ConfigError, match="'led_fwhm_nm' parameter of DeviceInversion"):
        DeviceInversion(led_fwhm_nm=0.0).fit(train)
    with pytest.raises(ConfigError, match=r"'cv' parameter .* int in the range \[0, inf\)"):
        DeviceInversion(cv=-1).fit(train)
    with pytest.raises(DataError, match="not a plain array"):
        DeviceInversion().fit(np.ones((30, 4)), np.full(30, 100.0))
    with pytest.raises(DataError, match="cannot model this device's LEDs.*700-1700"):
        device_scenario([1800.0], [40.0])


def test_device_scenario_reads_no_preset():
    cfg = device_scenario([850.0, 1150.0], [30.0, 60.0])
    assert cfg.preset == "device" and cfg.glucose.signal_gain == 1.0
    assert cfg.leds.wavelengths_nm == (850.0, 1150.0) and cfg.leds.fwhm_nm == (30.0, 60.0)
    # power and responsivity fill the LED records only: the log ratio never reads them
    theta = np.array([[np.log(0.02), 0.7, 0.6, 0.8, 0.05, 1.5, 0.0, 0.0]])
    base = ForwardModel(cfg, "beer-lambert").log_ratio(np.array([100.0]), theta)
    leds = [e.model_copy(update={"power_mw": 20.0, "responsivity_a_per_w": 0.3})
            for e in cfg.leds.emitters]
    other = cfg.model_copy(update={"leds": cfg.leds.model_copy(update={"emitters": leds})})
    np.testing.assert_array_equal(
        ForwardModel(other, "beer-lambert").log_ratio(np.array([100.0]), theta), base)


def test_prior_start_is_measured_or_published_never_the_simulators_relations(paper):
    train, _ = paper
    schema = DeviceSchema.infer(train)
    phys = train.frame[list(schema.physiology)].to_numpy(float)
    start = device_prior_start(schema, phys)
    col = {n: start[:, NUISANCES.index(n)] for n in NUISANCES}
    measured = train.frame
    np.testing.assert_allclose(col["skin_thickness_mm"], measured["skin_thickness_mm"])
    np.testing.assert_allclose(col["melanin_fraction"], measured["melanin_fraction"])
    np.testing.assert_allclose(np.exp(col["log_blood_fraction"]),
                               measured["blood_volume_pct"] / 100.0)
    for name in ("water_fraction", "subcutis_fat_fraction", "led_shift_nm", "log_coupling"):
        assert np.all(col[name] == POPULATION_PRIOR[name]), name
    # hydration, BMI and skin temperature move the simulator's start, not this one
    moved = phys.copy()
    for name in ("hydration_pct", "bmi_kgm2", "skin_temp_c"):
        moved[:, schema.physiology.index(name)] += 5.0
    np.testing.assert_array_equal(device_prior_start(schema, moved), start)
    cfg = train.config
    assert not np.allclose(prior_start(cfg, schema, moved), prior_start(cfg, schema, phys))


def test_calibration_recovers_a_known_response_and_handles_a_flat_model():
    rng = np.random.default_rng(0)
    dg = rng.normal(0.0, 50.0, 200)
    model = rng.normal(0.0, 0.1, (200, 3))
    obs = 0.2 + 0.9 * model + 1e-4 * dg[:, None] + rng.normal(0.0, 1e-4, (200, 3))
    a, b, beta, resid = calibrate_with_glucose(obs, model, dg)
    np.testing.assert_allclose(b, 0.9, atol=2e-3)
    np.testing.assert_allclose(beta, 1e-4, rtol=0.02)
    assert resid.std() < 2e-4
    flat = np.zeros((200, 3))  # the nuisances' optics say nothing on these channels
    obs = 0.2 + 1e-4 * dg[:, None] + rng.normal(0.0, 1e-4, (200, 3))
    _, b, beta, _ = calibrate_with_glucose(obs, flat, dg)
    assert np.all(b == 1.0)
    np.testing.assert_allclose(beta, 1e-4, rtol=0.1)


def test_skill_weight():
    y = np.array([90.0, 110.0, 100.0])
    mean = np.full(3, 100.0)
    assert skill_weight(y, y, mean) == 1.0
    assert skill_weight(y, 2 * y - mean, mean) == 0.5
    assert skill_weight(y, 2 * mean - y, mean) == 0.0  # anti-correlated: the mean
    assert skill_weight(y, mean, mean) == 0.0


def test_rte_lut_table_solver_is_the_one_named(paper, fitted, monkeypatch):
    # The mismatch study fills the rte-lut table with the diffusion solver, on the data's
    # side and on this estimator's (lut_solver): the same kind of table for both.
    import nirglucose.models.device_inversion as di

    seen = []
    monkeypatch.setattr(di, "ForwardModel", lambda cfg, model: seen.append((cfg, model)))
    monkeypatch.setattr(di, "LearnedGlucoseForward", lambda fm, mean, response: fm)
    for solver in ("diffusion", "monte-carlo"):
        m = make_model("device-inversion", forward_model="rte-lut", lut_solver=solver)
        m.schema_, m.led_fwhm_nm_ = fitted.schema_, fitted.led_fwhm_nm_
        m.glucose_mean_, m.glucose_response_ = fitted.glucose_mean_, fitted.glucose_response_
        m._build_forward()
        assert seen[-1][1] == "rte-lut" and seen[-1][0].optics.lut_solver == solver
    with pytest.raises(ConfigError, match="'lut_solver' parameter of DeviceInversion"):
        DeviceInversion(lut_solver="mc").fit(paper[0])
