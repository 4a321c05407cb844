"""Tuned hyper-parameters (the packaged file and its accessor) and the collapse guard."""

from __future__ import annotations

import json

import numpy as np
import pytest

import nirglucose as ng
from nirglucose.dataset import Dataset
from nirglucose.exceptions import ConfigError
from nirglucose.models import available_models, make_model, tuned_params
from nirglucose.models.tuning import (
    LAMBDA_PHYS_GRID,
    N_CONFIGS,
    TUNED_PRESETS,
    TUNING_SEEDS,
    search_space,
    tuning_record,
)

NETWORKS = ("sdnn", "original-pinn", "optimized-pinn", "rte-pinn", "selective-rte-pinn")
PINNS = NETWORKS[1:]
REPORTED_SEEDS = range(5)


pytestmark = pytest.mark.usefixtures("torch_one_thread")  # tests/conftest.py


# ----------------------------------------------------------------- accessor and file


def test_unknown_model_or_preset_raises_config_error():
    with pytest.raises(ConfigError, match="unknown model 'gpt'"):
        tuned_params("gpt", "paper")
    with pytest.raises(ConfigError, match="unknown preset 'nope'"):
        tuned_params("sdnn", "nope")


def test_untuned_models_get_their_defaults():
    assert tuned_params("oracle", "paper") == {}  # nothing to tune
    assert tuned_params("gp", "paper") == {}  # tunes itself (marginal likelihood)


@pytest.mark.parametrize("preset", TUNED_PRESETS)
@pytest.mark.parametrize("name", ("ebl", "pls", *NETWORKS))
def test_tuned_params_build_valid_models(name, preset):
    params = tuned_params(name, preset)
    assert params, f"{name} has no tuned parameters for {preset}"
    model = make_model(name, **params)
    if name in NETWORKS:
        model._validate_params()
    else:  # the linear models check their parameters in fit
        model.fit(ng.simulate(preset, 12, 2, seed=0))
    if name in PINNS:
        assert params["lambda_phys"] in LAMBDA_PHYS_GRID
    params["mutated"] = True  # a fresh copy each call
    assert "mutated" not in tuned_params(name, preset)


def test_tuning_never_used_the_reported_seeds_and_one_budget_for_all():
    doc = tuning_record()
    budget = doc["budget"]
    assert set(budget["tuning_seeds"]) == set(TUNING_SEEDS)
    assert set(budget["tuning_seeds"]).isdisjoint(REPORTED_SEEDS)
    assert budget["configurations_per_family"] == N_CONFIGS
    for preset in TUNED_PRESETS:
        for name, score in doc["scores"][preset].items():
            assert len(score["all_configs_rmse_mgdl"]) == N_CONFIGS, (preset, name)
    for preset in TUNED_PRESETS:  # each preset tuned as the simulator defines it
        assert doc["presets"][preset] == {"simulated_as": preset}


def test_search_spaces():
    for name in PINNS:
        assert 0.0 in search_space(name)["lambda_phys"]  # the ablation is on the grid
    assert "lambda_phys" not in search_space("sdnn")
    shared = {k: v for k, v in search_space("rte-pinn").items() if k != "lambda_phys"}
    assert shared == search_space("sdnn")  # the networks' training grid is one grid
    for name in ("ebl", "pls", *NETWORKS):
        sizes = [len(v) for v in search_space(name).values()]
        assert int(np.prod(sizes)) >= N_CONFIGS
    with pytest.raises(ConfigError, match="no tuning search space"):
        search_space("oracle")
    assert set(available_models()) >= {"ebl", "pls", *NETWORKS}


# ----------------------------------------------------------------- collapse guard


@pytest.fixture(scope="module")
def quiet_split():
    """A quiet regime (``paper``: the device knows the snapshot-level nuisances),
    60 training subjects and 20 held-out subjects; a seed disjoint from the study's."""
    ds = ng.simulate("paper", 80, 3, seed=2024)
    f = ds.frame
    held_out = f.subject_id.isin(np.unique(f.subject_id)[-20:]).to_numpy()

    def rows(mask):
        return Dataset(f[mask].reset_index(drop=True), config=ds.config, seed=ds.seed)

    return rows(~held_out), rows(held_out)


@pytest.mark.slow  # make test-slow (CI runs it)
@pytest.mark.parametrize("name", NETWORKS)
def test_network_does_not_collapse_to_the_mean(quiet_split, name):
    # A network that predicts (nearly) the training mean on held-out subjects of a quiet
    # regime is a defect (init, scaling, lr, too few steps), not a finding.
    train, test = quiet_split
    y_tr, y_te = train.frame.glucose_mgdl.to_numpy(), test.frame.glucose_mgdl.to_numpy()
    model = make_model(name, **tuned_params(name, "paper"), random_state=0).fit(train)
    pred = model.predict(test)
    rmse = float(np.sqrt(np.mean((pred - y_te) ** 2)))
    no_skill = float(np.sqrt(np.mean((y_tr.mean() - y_te) ** 2)))
    spread = float(np.std(pred) / np.std(y_te))
    assert spread > 0.5, f"{name}: prediction spread {spread:.2f} of the targets'"
    assert rmse < 0.75 * no_skill, f"{name}: RMSE {rmse:.1f} vs no-skill {no_skill:.1f} mg/dL"


@pytest.mark.slow  # make test-slow (CI runs it)
def test_linear_lookups_do_not_import_torch():
    import subprocess
    import sys

    code = (
        "import sys\n"
        "from nirglucose.models import tuned_params\n"
        "from nirglucose.models.registry import is_network, is_pinn\n"
        "tuned_params('ebl', 'paper'); assert not is_network('pls') and not is_pinn('ebl')\n"
        "assert 'torch' not in sys.modules, 'torch imported'\n"
    )
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert run.returncode == 0, run.stderr[-1500:]


# ----------------------------------------------------------------- new families, λ curve

NEW_FAMILIES = ("physics-inversion", "ebl+gp", "physics-inversion+gp")


@pytest.mark.parametrize("name", NEW_FAMILIES)
def test_new_families_have_a_grid_of_the_common_size(name):
    space = search_space(name)
    assert int(np.prod([len(v) for v in space.values()])) == N_CONFIGS
    cls = type(make_model(name))
    for key in space:  # every grid key is a constructor argument
        assert key in cls().get_params(), (name, key)


@pytest.mark.parametrize("name", NEW_FAMILIES)
def test_new_families_tuned_where_recorded_build_valid_models(name):
    doc = tuning_record()
    tuned = [p for p in TUNED_PRESETS if name in doc["params"].get(p, {})]
    assert "paper" in tuned, f"{name} not tuned on paper"
    for preset in tuned:
        params = tuned_params(name, preset)
        space = search_space(name)
        for key, value in params.items():  # a grid point, as JSON stores it
            grid = [json.loads(json.dumps(v)) for v in space[key]]
            assert value in grid, (name, preset, key, value)
        assert len(doc["scores"][preset][name]["all_configs_rmse_mgdl"]) == N_CONFIGS
    ds = ng.simulate("paper", 10, 2, seed=0)
    make_model(name, **tuned_params(name, "paper")).fit(ds).predict(ds)


@pytest.mark.parametrize("preset", TUNED_PRESETS)
@pytest.mark.parametrize("name", PINNS)
def test_lambda_curve_is_recorded_and_consistent(name, preset):
    from nirglucose.models.tuning import best_positive_lambda, lambda_curve

    curve = lambda_curve(name, preset)
    assert curve is not None, f"no lambda curve for {name} on {preset}"
    assert curve["lambda_phys"] == list(LAMBDA_PHYS_GRID)
    score = tuning_record()["scores"][preset][name]
    tuned = curve["tuned_lambda_phys"]
    at_tuned = curve["slice_cv_rmse_mgdl"][curve["lambda_phys"].index(tuned)]
    assert at_tuned == pytest.approx(score["tuning_cv_rmse_mgdl"], abs=1e-3)
    # the profile is the best recorded draw per λ, and its minimum is the tuning's choice
    assert min(curve["profile_cv_rmse_mgdl"]) == pytest.approx(score["tuning_cv_rmse_mgdl"])
    best = best_positive_lambda(name, preset)
    pts = zip(curve["lambda_phys"], curve["slice_cv_rmse_mgdl"], strict=True)
    positive = {lam: r for lam, r in pts if lam > 0}
    assert best > 0 and positive[best] == min(positive.values())


def test_best_positive_lambda_without_a_curve_is_none():
    from nirglucose.models.tuning import best_positive_lambda

    assert best_positive_lambda("sdnn", "paper") is None
    assert best_positive_lambda("rte-pinn", "no-such-preset") is None
