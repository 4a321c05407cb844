"""Constructor-parameter constraints of the estimators, checked by one mechanism.

Every registered estimator declares ``_parameter_constraints``: a dict of parameter
name -> list of accepted constraints, the table scikit-learn's own estimators carry
(e.g. ``sklearn.linear_model.Ridge``) [1]_. :class:`ValidatedParamsMixin` checks it
with scikit-learn's ``validate_parameter_constraints`` at the start of ``fit`` (and of
``predict`` where a parameter drives prediction), so a bad value is refused in one line
that names the parameter, the estimator, the valid values and the value given::

    The 'cv' parameter of EnhancedBeerLambert must be an int in the range [2, inf).
    Got 1 instead.

The error is a :class:`ParameterError`: a :class:`~nirglucose.exceptions.ConfigError`
(the CLI's one-line exit 2) that is also scikit-learn's ``InvalidParameterError``, so
scikit-learn's ``check_param_validation`` runs on our estimators unchanged.

Two additions to scikit-learn's constraints:

* :class:`Interval` refuses booleans (``True`` is not a count nor a rate; scikit-learn's
  accepts it as 1). Its ``Real`` ranges exclude NaN, and an open upper end excludes
  infinity, as scikit-learn's do.
* :class:`IntervalArray`: a non-empty 1-D sequence whose every element lies in the
  interval (a grid of ridge penalties).

Rules between parameters (``n_heads`` divides ``d_model``) stay in
:meth:`ValidatedParamsMixin._check_param_relations`, run after the table.

References
----------
.. [1] F. Pedregosa et al., "Scikit-learn: Machine Learning in Python", JMLR 12,
   2825-2830 (2011); ``sklearn.utils._param_validation`` (scikit-learn >= 1.2).
"""

from __future__ import annotations

from numbers import Integral, Real
from typing import Any, ClassVar

import numpy as np
from sklearn.utils._param_validation import Interval as _SklearnInterval
from sklearn.utils._param_validation import (
    InvalidParameterError,
    StrOptions,
    validate_parameter_constraints,
)

from ..exceptions import ConfigError

__all__ = [
    "Integral",
    "Interval",
    "IntervalArray",
    "ParameterError",
    "Real",
    "StrOptions",
    "ValidatedParamsMixin",
    "check_parameters",
]


class ParameterError(ConfigError, InvalidParameterError):
    """A constructor parameter outside its constraints (a ConfigError, one line)."""


class Interval(_SklearnInterval):
    """scikit-learn's ``Interval`` that refuses booleans.

    Examples
    --------
    >>> Interval(Integral, 1, None, closed="left").is_satisfied_by(True)
    False
    >>> Interval(Real, 0, None, closed="neither").is_satisfied_by(float("inf"))
    False
    """

    def is_satisfied_by(self, val: Any) -> bool:
        if isinstance(val, bool | np.bool_):
            return False
        return bool(super().is_satisfied_by(val))


class IntervalArray(Interval):
    """A non-empty 1-D sequence of numbers (not strings), each inside the interval.

    Examples
    --------
    >>> c = IntervalArray(Real, 0, None, closed="neither")
    >>> c.is_satisfied_by((0.1, 1.0)), c.is_satisfied_by((1.0, -1.0)), c.is_satisfied_by(1.0)
    (True, False, False)
    """

    def is_satisfied_by(self, val: Any) -> bool:
        if isinstance(val, str | bytes):
            return False
        try:  # a ragged or otherwise odd sequence is not a sequence of numbers
            values = np.asarray(val).tolist() if np.ndim(val) == 1 and len(val) else None
        except (TypeError, ValueError):
            return False
        return values is not None and all(Interval.is_satisfied_by(self, v) for v in values)

    def __str__(self) -> str:
        return f"a non-empty sequence of numbers each {super().__str__()[2:]}"


def check_parameters(constraints: dict[str, Any], params: dict[str, Any], owner: str) -> None:
    """Check ``params`` against ``constraints`` (scikit-learn's table format).

    Parameters
    ----------
    constraints : dict
        Parameter name -> list of constraints (``None``, a type, ``"boolean"``,
        ``"random_state"``, :class:`Interval`, ``StrOptions``, ...) or
        ``"no_validation"``.
    params : dict
        Parameter name -> value.
    owner : str
        The estimator's (or function's) name, for the message.

    Raises
    ------
    ParameterError
        The first parameter that meets none of its constraints, in one line.

    Examples
    --------
    >>> check_parameters({"cv": [Interval(Integral, 2, None, closed="left")]}, {"cv": 1}, "M")
    Traceback (most recent call last):
    ...
    nirglucose.models._params.ParameterError: The 'cv' parameter of M must be an int in \
the range [2, inf). Got 1 instead.
    """
    try:
        validate_parameter_constraints(constraints, params, caller_name=owner)
    except InvalidParameterError as exc:
        raise ParameterError(str(exc)) from None


class ValidatedParamsMixin:
    """``_validate_params`` over the class's ``_parameter_constraints`` table.

    Placed before ``BaseEstimator`` in the bases; subclasses declare the table (one
    entry per constructor parameter) and may add :meth:`_check_param_relations`.
    """

    _parameter_constraints: ClassVar[dict[str, Any]] = {}

    def _validate_params(self) -> None:
        """Refuse (one-line :class:`ParameterError`) any parameter out of its constraints."""
        params = self.get_params(deep=False)  # type: ignore[attr-defined]
        check_parameters(self._parameter_constraints, params, type(self).__name__)
        self._check_param_relations()

    def _check_param_relations(self) -> None:
        """Rules between parameters (raise :class:`ParameterError`); none by default."""
