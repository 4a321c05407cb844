"""The Beer-Lambert PINNs' 'forward' physics term: the readings' glucose likelihood
under the package's forward model (models/pinn.py, physics_losses.py, inversion.py)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import torch

import nirglucose as ng
from nirglucose.evaluation.benchmark.inverse import task_state
from nirglucose.exceptions import ConfigError
from nirglucose.models import (
    RTEPINN,
    OriginalPINN,
    SelectiveRTEPINN,
    available_models,
    get_model_class,
    load_model,
    make_model,
    tuned_params,
)
from nirglucose.models._inversion_solver import NUISANCES
from nirglucose.models.inversion import PhysicsInversion
from nirglucose.models.physics_losses import forward_likelihood_loss
from nirglucose.models.pinn import (
    FORWARD_MODEL_KNOWLEDGE,
    OptimizedPINNForward,
    OriginalPINNForward,
)
from nirglucose.models.registry import describe_model, get_variant, register_variant

pytestmark = pytest.mark.usefixtures("torch_one_thread")  # tests/models/conftest.py

FAST = {"max_epochs": 15, "random_state": 0, "weight_decay": 0.03}


@pytest.fixture(scope="module")
def paper():
    return ng.simulate("paper", n_subjects=12, per_subject=3, seed=3)


@pytest.fixture(scope="module")
def inversion(paper):
    return PhysicsInversion().fit(paper)


# ----------------------------------------------------------------- the likelihood


def test_likelihood_mode_is_the_joint_map_with_a_flat_glucose_prior(paper, inversion):
    """Independent route: the linearised marginal's mode (Laplace over the nuisances)
    against the nonlinear joint MAP of glucose and nuisances by Levenberg-Marquardt with
    a flat glucose prior. For a linear-Gaussian model the two coincide exactly."""
    y = paper.frame["glucose_mgdl"].to_numpy()
    mode, info = inversion.glucose_likelihood(paper, y)
    flat = PhysicsInversion(**inversion.get_params())
    flat.__dict__.update(inversion.__dict__)
    flat.glucose_var_ = 1e8  # (1e4 mg/dL)^2: flat against the likelihood's ~1 mg/dL
    joint = flat.predict(paper)
    sd = 1.0 / np.sqrt(info)
    assert np.all(info > 0)
    assert np.max(np.abs(mode - joint) / sd) < 0.05
    # the mode is a fixed point: linearising there again returns it
    again, _ = inversion.glucose_likelihood(paper, mode)
    assert np.max(np.abs(again - mode) / sd) < 0.05


def test_likelihood_reads_the_absorbances(paper, inversion):
    """Shifting one LED's codes moves the likelihood's mode (it is not the reference)."""
    y = paper.frame["glucose_mgdl"].to_numpy()
    mode, _ = inversion.glucose_likelihood(paper, y)
    frame = paper.frame.copy()
    frame["adc_1150"] = np.round(frame["adc_1150"] * 1.002)
    moved, _ = inversion.glucose_likelihood(ng.Dataset(frame, paper.config), y)
    assert np.median(np.abs(moved - mode)) > 0.5


def test_forward_loss_is_zero_at_the_mode_and_positive_elsewhere():
    mode = torch.tensor([90.0, 140.0, 200.0])
    info = torch.tensor([0.5, 0.02, 0.0])
    assert float(forward_likelihood_loss(mode, mode, info)) == 0.0
    off = mode + torch.tensor([3.0, 0.0, 0.0])
    assert float(forward_likelihood_loss(off, mode, info)) == pytest.approx(0.5 * 9 / 3)
    # a row without information contributes nothing
    assert float(forward_likelihood_loss(mode + torch.tensor([0, 0, 50.0]), mode, info)) == 0.0


def test_pinn_physics_term_is_zero_at_the_linearised_map(paper, inversion):
    """Through the estimator: predicting each training row's likelihood mode zeroes the
    term; any other prediction makes it positive."""
    m = OriginalPINNForward(max_epochs=2, random_state=0).fit(paper)
    Xa, y, _ = m._measurements(paper, require_target=True)
    m.__dict__["_fm_inversion"] = inversion
    m.__dict__["_fm_draws"] = (y, np.random.default_rng(0))
    try:
        batch = m._tensors({**m._training_rows(Xa, y), "y": m._scale_y(y)})
    finally:
        m.__dict__.pop("_fm_inversion")
    at_mode = (batch["fm_glucose_mgdl"] - m.scaler_["y_mean"]) / m.scaler_["y_scale"]
    _, terms = m.get_loss(at_mode, batch["y"], batch)
    assert float(terms["physics"]) == pytest.approx(0.0, abs=1e-6)
    _, terms = m.get_loss(at_mode + 0.1, batch["y"], batch)
    assert float(terms["physics"]) > 1.0


# ----------------------------------------------------------------- the estimators


def test_forward_term_changes_the_fit_and_lambda_zero_is_the_plain_network(paper):
    on = OriginalPINN(physics_form="forward", lambda_phys=0.1, **FAST).fit(paper)
    off = OriginalPINN(physics_form="forward", lambda_phys=0.0, **FAST).fit(paper)
    plain = OriginalPINN(physics_form="study", lambda_phys=0.0, **FAST).fit(paper)
    assert on.physics_["enabled"] and on.physics_["forward_model"] == "beer-lambert"
    assert 0.1 < on.physics_["likelihood_sd_median_mgdl"] < 50
    assert np.abs(on.predict(paper) - off.predict(paper)).max() > 0.1
    np.testing.assert_array_equal(off.predict(paper), plain.predict(paper))
    assert on.history_[-1]["train_physics"] > 0


def test_collocation_changes_the_fit_reproducibly(paper):
    a = OriginalPINNForward(collocation=2, **FAST).fit(paper)
    b = OriginalPINNForward(collocation=2, **FAST).fit(paper)
    c = OriginalPINNForward(collocation=0, **FAST).fit(paper)
    np.testing.assert_array_equal(a.predict(paper), b.predict(paper))
    assert np.abs(a.predict(paper) - c.predict(paper)).max() > 0.01
    assert a.history_[-1]["train_collocation"] > 0


def test_forward_term_never_reads_truth(paper):
    """Shuffling every true_* column across rows changes nothing (fit and predictions)."""
    frame = paper.frame.copy()
    truth = [c for c in frame.columns if c.startswith("true_")]
    assert truth
    rng = np.random.default_rng(0)
    frame[truth] = frame[truth].to_numpy()[rng.permutation(len(frame))]
    shuffled = ng.Dataset(frame, paper.config)
    a = OriginalPINNForward(collocation=1, **FAST).fit(paper)
    b = OriginalPINNForward(collocation=1, **FAST).fit(shuffled)
    np.testing.assert_array_equal(a.predict(paper), b.predict(shuffled))
    assert a.physics_ == b.physics_


def test_study_is_the_default_and_absolute_its_alias(paper):
    assert OriginalPINN().physics_form == "study"
    a = OriginalPINN(physics_form="study", **FAST).fit(paper)
    b = OriginalPINN(physics_form="absolute", **FAST).fit(paper)
    np.testing.assert_array_equal(a.predict(paper), b.predict(paper))


def test_forward_term_is_off_without_a_device(paper):
    X = np.random.default_rng(0).normal(size=(30, 5))
    y = np.linspace(80, 200, 30)
    m = OriginalPINNForward(max_epochs=2, random_state=0).fit(X, y)
    assert not m.physics_["enabled"]
    assert "plain array" in m.physics_["constants_from"]
    assert m.history_[-1]["train_physics"] == 0.0


@pytest.mark.parametrize(
    "params",
    [{"collocation": -1}, {"collocation": 1.5}, {"forward_model": "monte-carlo"}],
)
def test_bad_forward_parameters_raise_one_clear_error(paper, params):
    with pytest.raises(ConfigError, match=next(iter(params))):
        OriginalPINNForward(**params).fit(paper)


def test_registered_with_their_twins_training(paper, tmp_path):
    m = make_model("optimized-pinn-fm")
    assert isinstance(m, OptimizedPINNForward) and m.physics_form == "forward"
    # where the forward-model PINN was not tuned itself (lab), its twin's training
    # settings without the twin's physics weight ...
    twin = tuned_params("original-pinn", "lab")
    fm = tuned_params("original-pinn-fm", "lab")
    assert "lambda_phys" not in fm
    assert fm == {k: v for k, v in twin.items() if k != "lambda_phys"}
    # ... and where it was (paper, wearable), its own, physics weight included
    own = tuned_params("original-pinn-fm", "paper")
    assert "lambda_phys" in own and set(own) >= set(fm)
    fitted = OriginalPINNForward(max_epochs=2, random_state=0).fit(paper)
    fitted.save(tmp_path / "m.json")
    back = load_model(tmp_path / "m.json")
    np.testing.assert_array_equal(back.predict(paper), fitted.predict(paper))
    assert back.physics_ == fitted.physics_


# ----------------------------------------------------------------- the RTE PINNs


RTE_FIT = {**FAST, "max_epochs": 100, "lr": 1e-2}


@pytest.fixture(scope="module")
def rte_forward(paper):
    return RTEPINN(physics_form="forward", lambda_phys=1.0, **RTE_FIT).fit(paper)


def test_rte_forward_state_head_tracks_the_forward_models_modes(paper, rte_forward):
    """The state head learns the forward model's posterior modes of the training rows
    (its target), better than their mean; the study form has no state columns."""
    y = paper.frame["glucose_mgdl"].to_numpy()
    modes = PhysicsInversion().fit(paper).linearise(paper, y)["theta"][:, 1:]
    st = rte_forward.estimate_state(paper)
    assert {"glucose_mgdl", "blood_fraction", "water_fraction", "melanin_fraction",
            "skin_thickness_mm", "coupling"} <= set(st.columns)
    melanin = modes[:, NUISANCES.index("melanin_fraction")]
    assert np.mean((st["melanin_fraction"] - melanin) ** 2) < 0.5 * melanin.var()
    np.testing.assert_allclose(st["glucose_mgdl"], rte_forward.predict(paper))
    study = RTEPINN(max_epochs=2, random_state=0).fit(paper)
    assert list(study.estimate_state(paper).columns) == ["glucose_mgdl"]
    assert task_state(study, paper) is None
    assert set(task_state(rte_forward, paper)) >= {"blood_fraction", "skin_thickness_mm"}


def test_rte_forward_never_reads_truth_and_round_trips(paper, rte_forward, tmp_path):
    frame = paper.frame.copy()
    truth = [c for c in frame.columns if c.startswith("true_")]
    frame[truth] = frame[truth].to_numpy()[::-1]
    shuffled = ng.Dataset(frame, paper.config)
    again = RTEPINN(physics_form="forward", lambda_phys=1.0, **RTE_FIT).fit(shuffled)
    np.testing.assert_array_equal(again.predict(paper), rte_forward.predict(paper))
    rte_forward.save(tmp_path / "rte.json")
    back = load_model(tmp_path / "rte.json")
    pd.testing.assert_frame_equal(back.estimate_state(paper), rte_forward.estimate_state(paper))
    assert back.predict_one(*_one_reading(back, paper)) == pytest.approx(
        float(back.predict(paper)[0]), abs=1e-3)


def test_rte_forward_at_lambda_zero_is_its_plain_network(paper):
    """λ = 0 leaves the term out of the graph: the state head trains on nothing, and
    glucose equals the forward form's plain network (the ablation's pair)."""
    a = RTEPINN(physics_form="forward", lambda_phys=0.0, **FAST).fit(paper)
    b = RTEPINN(physics_form="forward", lambda_phys=0.0, **FAST).fit(paper)
    c = RTEPINN(physics_form="forward", lambda_phys=1.0, **FAST).fit(paper)
    np.testing.assert_array_equal(a.predict(paper), b.predict(paper))
    assert np.abs(a.predict(paper) - c.predict(paper)).max() > 0.1


def test_rte_bad_physics_form_raises(paper):
    with pytest.raises(ConfigError, match="physics_form"):
        SelectiveRTEPINN(physics_form="relative").fit(paper)


def _one_reading(model, ds):
    row = ds.frame.iloc[0]
    sch = model.schema_
    return ([row[f"adc_{w}"] for w in sch.labels], [row[f"adc_ref_{w}"] for w in sch.labels],
            [row[c] for c in sch.physiology])


# ----------------------------------------------------------------- registered variants


FM_TWINS = {"original-pinn-fm": ("original-pinn", 0.1),
            "optimized-pinn-fm": ("optimized-pinn", 0.1),
            "rte-pinn-fm": ("rte-pinn", 1.0),
            "selective-rte-pinn-fm": ("selective-rte-pinn", 1.0)}
DATA = Path(__file__).parent / "data"


@pytest.mark.parametrize("name", list(FM_TWINS))
def test_fm_models_are_registered_variants_of_their_twins(name):
    """Issue 42: one class per network; each -fm name is its twin with two defaults."""
    twin_name, lam = FM_TWINS[name]
    cls, twin = get_model_class(name), get_model_class(twin_name)
    assert cls.__bases__ == (twin,) and cls.registry_name == name
    assert cls.variant_of == twin_name and get_variant(twin_name) is None
    v = get_variant(name)
    assert v.base == twin_name and dict(v.defaults) == {"physics_form": "forward",
                                                         "lambda_phys": lam}
    assert v.privileged == cls.privileged == FORWARD_MODEL_KNOWLEDGE
    # nothing of its own but the defaults (and the privileged note); scikit-learn adds
    # its metadata-request methods to every estimator class
    own = {k for k in vars(cls) if not k.endswith("_request")}
    assert own <= {"__doc__", "__module__", "__qualname__", "__init__", "own_params",
                   "training_defaults", "variant_of", "privileged", "registry_name"}
    fm_params = make_model(name).get_params()
    twin_params = make_model(twin_name).get_params()
    assert {k for k in fm_params if fm_params[k] != twin_params[k]} == {"physics_form",
                                                                      "lambda_phys"}
    assert describe_model(name).startswith(f"{twin_name} with physics_form='forward', ")


def test_variant_fits_as_its_twin_with_those_parameters(paper):
    a = OriginalPINNForward(**FAST).fit(paper)
    b = OriginalPINN(physics_form="forward", lambda_phys=0.1, **FAST).fit(paper)
    np.testing.assert_array_equal(a.predict(paper), b.predict(paper))
    assert a.physics_ == b.physics_ and a.history_ == b.history_


def test_a_file_saved_by_the_class_of_its_own_still_loads():
    """A model file written by the pre-variant code (commit 8eb8f05, when
    OriginalPINNForward was a class of its own) loads as the variant and predicts the
    same numbers: to float32 rounding, since torch's float32 kernels round differently
    on CPUs with and without AVX-512 (seen: 3e-6 relative on an AMD EPYC without it)."""
    check = json.loads((DATA / "original-pinn-fm_8eb8f05_check.json").read_text())
    model = load_model(DATA / "original-pinn-fm_8eb8f05.json")
    assert type(model) is OriginalPINNForward and model.physics_form == "forward"
    rows = pd.DataFrame(check["rows"])
    np.testing.assert_allclose(model.predict(rows), np.array(check["predicted_mgdl"]),
                               rtol=2e-5, atol=0)


@pytest.mark.parametrize(
    ("base", "defaults", "name", "match"),
    [
        ("original-pinn", {"nope": 1}, "x-variant", "'nope' is not a parameter"),
        ("original-pinn", {"lambda_phys": 1.0}, "original-pinn-fm", "registered already"),
        ("ebl", {"alphas": (1.0,)}, "x-variant", "own_params"),
    ],
)
def test_register_variant_refuses_bad_declarations(base, defaults, name, match):
    with pytest.raises(TypeError, match=match):
        register_variant(name, get_model_class(base), defaults=defaults, summary="x",
                         class_name="X")
    assert "x-variant" not in available_models()


def test_unregistered_base_is_refused():
    class Loose(OriginalPINN):
        pass

    Loose.registry_name = "nowhere"
    with pytest.raises(TypeError, match="not a registered class"):
        register_variant("x-loose", Loose, defaults={}, summary="x", class_name="X")


def test_hybrid_summaries_name_no_private_class():
    for name in ("ebl+gp", "physics-inversion+gp"):
        assert "_ResidualHybrid" not in describe_model(name)
