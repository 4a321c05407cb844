"""The common checks, over every registered estimator (``tests/common_checks.py``).

On plain arrays every learner that can fits a plain schema (the array's columns as
generic spectral inputs, no physiology, physics terms off), through the same boundary
as a device's frame, and runs scikit-learn's full ``parametrize_with_checks`` with fast
settings. The oracle, the forward-model inversion and the hybrids need a device's ADC
columns (the oracle also its ``true_*`` columns): they run the checks that need no fit.
Every estimator runs the parameter-validation check of its constraints table.
"""

from __future__ import annotations

import numpy as np
import pytest

from common_checks import (
    NO_DATA_CHECKS,
    check_parameter_validation,
    non_finite_cases,
    run_check,
    sklearn_checks,
)
from nirglucose.exceptions import ConfigError
from nirglucose.models import available_models, get_model_class, make_model
from nirglucose.models.registry import MODELS

pytestmark = pytest.mark.usefixtures("torch_one_thread")  # tests/conftest.py

#: Fast settings of the learners that fit plain arrays (registered name -> parameters).
FIT_ON_ARRAYS: dict[str, dict] = {
    "ebl": {"alphas": (0.1, 1.0, 10.0), "cv": 3},
    "pls": {"max_components": 3, "cv": 3},
    "mean": {},
    "gp": {"max_fit_rows": 200, "random_state": 0},
    "gbr": {"n_estimators": 20, "random_state": 0},
    **{
        name: {"max_epochs": 2, "batch_size": 32, "random_state": 0}
        for name in ("original-pinn", "optimized-pinn", "rte-pinn", "selective-rte-pinn", "sdnn")
    },
    # the forward-model PINNs: on a plain array (no optics) their physics term is off
    **{
        f"{name}-fm": {"max_epochs": 2, "batch_size": 32, "random_state": 0}
        for name in ("original-pinn", "optimized-pinn", "rte-pinn", "selective-rte-pinn")
    },
}
#: Estimators that cannot fit a plain array, and why.
NEED_A_DEVICE: dict[str, str] = {
    "oracle": "reads true_* columns and the scenario config",
    "physics-inversion": "inverts a forward model of a device's ADC columns",
    "device-inversion": "inverts a forward model of a device's ADC columns",
    "ebl+gp": "its backbone's residuals are learned per device (needs ADC columns)",
    "physics-inversion+gp": "inverts a forward model of a device's ADC columns",
}
#: Checks a learner is expected to fail, with the limit each one names (none today).
EXPECTED_FAILED: dict[str, dict[str, str]] = {}


def test_every_registered_estimator_is_checked():
    # the package's own models (tests may register toy models in the same session)
    assert set(FIT_ON_ARRAYS) | set(NEED_A_DEVICE) == set(MODELS)
    assert set(MODELS) <= set(available_models())
    assert not set(FIT_ON_ARRAYS) & set(NEED_A_DEVICE)


@sklearn_checks([make_model(n, **p) for n, p in FIT_ON_ARRAYS.items()], EXPECTED_FAILED)
def test_sklearn_common_checks(estimator, check):
    run_check(check, estimator)


@pytest.mark.parametrize("check", NO_DATA_CHECKS, ids=lambda c: c.__name__)
@pytest.mark.parametrize("name", sorted(NEED_A_DEVICE))
def test_sklearn_checks_that_need_no_data(name, check):
    cls = get_model_class(name)
    check(cls.__name__, cls())


@pytest.mark.parametrize("name", sorted(FIT_ON_ARRAYS | NEED_A_DEVICE))
def test_parameters_are_validated_by_their_constraints(name):
    check_parameter_validation(make_model(name))


@pytest.mark.parametrize("name", sorted(FIT_ON_ARRAYS | NEED_A_DEVICE))
def test_non_finite_parameters_are_refused_in_one_line(name):
    cases = non_finite_cases(make_model(name))
    for param, value in cases:
        with pytest.raises(ConfigError) as info:
            make_model(name, **{param: value}).fit(np.ones((4, 2)), np.ones(4))
        assert "\n" not in str(info.value) and f"'{param}'" in str(info.value)


def test_the_non_finite_cases_cover_the_real_parameters():
    # worked example: SDNN's real parameters lr (0, inf), weight_decay [0, inf),
    # dropout and val_fraction [0, 1); integers (max_epochs) have no NaN case
    cases = non_finite_cases(make_model("sdnn"))
    assert {p for p, _ in cases} == {"lr", "weight_decay", "dropout", "val_fraction"}
    assert ("lr", np.inf) in cases and ("dropout", -np.inf) in cases
    assert non_finite_cases(make_model("pls")) == []
