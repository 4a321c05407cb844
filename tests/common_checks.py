"""The estimator checks every family's tests share: one copy, not one per test file.

* :func:`sklearn_checks` — scikit-learn's common checks (``parametrize_with_checks``) for
  estimators that fit plain arrays, expected failures declared per class and strict
  (an expected failure that passes fails the run), reported in one line.
* :data:`NO_DATA_CHECKS` — the checks that need no fit, for estimators that cannot fit a
  plain array (the oracle reads ``true_*`` columns, the inversions need ADC columns).
* :func:`check_parameter_validation` — every constructor parameter has a constraint in
  ``_parameter_constraints`` and a bad type or value is refused by ``fit`` in one line
  (a :class:`~nirglucose.exceptions.ConfigError`), by scikit-learn's own
  ``check_param_validation``; NaN, and infinity where the range is open, too.

Used by ``tests/models`` (every estimator family) and ``tests/test_features.py``.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from typing import Any

import numpy as np
import pytest
from sklearn.base import clone
from sklearn.utils.estimator_checks import (
    check_do_not_raise_errors_in_init_or_set_params,
    check_get_params_invariance,
    check_no_attributes_set_in_init,
    check_param_validation,
    check_parameters_default_constructible,
    check_set_params,
    parametrize_with_checks,
)

from nirglucose.exceptions import ConfigError
from nirglucose.models._params import Integral, Interval

__all__ = [
    "NO_DATA_CHECKS",
    "check_parameter_validation",
    "non_finite_cases",
    "run_check",
    "sklearn_checks",
]

#: scikit-learn checks that construct, clone and set parameters but never fit.
NO_DATA_CHECKS: tuple[Callable[[str, Any], None], ...] = (
    check_parameters_default_constructible,
    check_no_attributes_set_in_init,
    check_get_params_invariance,
    check_set_params,
    check_do_not_raise_errors_in_init_or_set_params,
)


def sklearn_checks(
    estimators: Sequence[Any], expected_failed: Mapping[str, Mapping[str, str]] | None = None
):
    """``parametrize_with_checks`` over ``estimators`` with strict expected failures.

    Parameters
    ----------
    estimators : sequence of estimator
        Instances with fast settings.
    expected_failed : mapping, optional
        Class name -> {check name: the limit that makes it fail}; none by default.

    Decorates ``test(estimator, check)``, whose body is ``run_check(check, estimator)``.
    """
    expected = expected_failed or {}
    return parametrize_with_checks(
        list(estimators),
        expected_failed_checks=lambda est: dict(expected.get(type(est).__name__, {})),
        xfail_strict=True,
    )


def run_check(check: Callable[[Any], None], estimator: Any) -> None:
    """Run one scikit-learn check; a failure reads as one line (type and message)."""
    try:
        check(estimator)
    except AssertionError as exc:
        raise AssertionError(f"{type(estimator).__name__}: {str(exc)[:300]}") from None


def check_parameter_validation(estimator: Any) -> None:
    """The constraints table covers every parameter and ``fit`` refuses bad values.

    scikit-learn's ``check_param_validation``: for every parameter an instance of an
    unknown type, then a value just outside each constraint (0 for ``[1, inf)``, a
    string that is not an option, ...) must raise its ``InvalidParameterError`` with the
    one-line message; here that error must also be a ConfigError (exit 2 in the CLI).
    """
    name = type(estimator).__name__
    params = set(estimator.get_params(deep=False))
    check_param_validation(name, estimator)  # it also asserts the table covers params
    for param in sorted(params):
        if estimator._parameter_constraints[param] == "no_validation":
            continue
        bad = clone(estimator).set_params(**{param: type("BadType", (), {})()})
        with pytest.raises(ConfigError) as info:
            bad.fit(np.ones((4, 2)), np.ones(4))
        assert "\n" not in str(info.value) and param in str(info.value), str(info.value)


def non_finite_cases(estimator: Any) -> list[tuple[str, float]]:
    """``(parameter, value)``: NaN for every parameter with a real interval, and +-inf
    where no interval of the parameter admits it (an open or finite end)."""
    cases = []
    for param, constraints in estimator._parameter_constraints.items():
        if constraints == "no_validation":
            continue
        real = [c for c in constraints if isinstance(c, Interval) and c.type is not Integral]
        if not real:
            continue
        cases.append((param, float("nan")))
        for inf in (np.inf, -np.inf):
            if not any(c.is_satisfied_by(inf) for c in real):
                cases.append((param, inf))
    return cases
