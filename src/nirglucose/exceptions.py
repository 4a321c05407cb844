"""Exception hierarchy of nirglucose.

Every error the package raises on purpose derives from :class:`NirGlucoseError` and
also from the builtin type a caller would expect, so ``except ValueError`` keeps
working (the xarray / scikit-learn habit).
"""

from __future__ import annotations

import difflib
import math
import numbers
from collections.abc import Iterable

__all__ = [
    "NirGlucoseError",
    "ConfigError",
    "DataError",
    "NotFittedError",
    "unknown_name",
    "check_positive_int",
    "check_seed",
    "is_finite_number",
]


class NirGlucoseError(Exception):
    """Base class of every error raised on purpose by nirglucose."""


class ConfigError(NirGlucoseError, ValueError):
    """An invalid configuration value, preset name or override key."""


class DataError(NirGlucoseError, ValueError):
    """A malformed dataset: missing columns, NaN, non-numeric or out-of-range values."""


class NotFittedError(NirGlucoseError, AttributeError):
    """An estimator was used before ``fit``."""


def unknown_name(kind: str, name: object, valid: Iterable[str]) -> str:
    """The one message for an unknown name: echo it, suggest the closest, list the valid.

    Examples
    --------
    >>> unknown_name("preset", "papr", ["paper", "wearable"])
    "unknown preset 'papr'; did you mean 'paper'? valid: paper, wearable"
    """
    valid = list(valid)
    close = difflib.get_close_matches(str(name), valid, n=1)
    hint = f"; did you mean {close[0]!r}?" if close else ";"
    return f"unknown {kind} {name!r}{hint} valid: {', '.join(valid)}"


def is_finite_number(value: object, integer: bool = False) -> bool:
    """Whether ``value`` is a finite number as JSON or Python gives one (not a bool, not a
    string); with ``integer``, a whole one.

    Examples
    --------
    >>> is_finite_number(2.0, integer=True), is_finite_number(True), is_finite_number("1")
    (True, False, False)
    """
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        return False
    v = float(value)
    return math.isfinite(v) and (not integer or v.is_integer())


def check_seed(value: object) -> int:
    """``value`` as an ``int`` when it is a non-negative integer (not a bool): a seed.

    Raises
    ------
    ConfigError
        Anything else.

    Examples
    --------
    >>> check_seed(0)
    0
    """
    if isinstance(value, bool) or not isinstance(value, numbers.Integral) or value < 0:
        raise ConfigError(f"seed must be a non-negative integer, got {value!r}")
    return int(value)


def check_positive_int(name: str, value: object) -> int:
    """``value`` as an ``int`` when it is a positive integer (not a bool).

    Raises
    ------
    ConfigError
        Anything else, naming ``name``.

    Examples
    --------
    >>> check_positive_int("repeats", 3)
    3
    """
    if isinstance(value, bool) or not isinstance(value, numbers.Integral) or value < 1:
        raise ConfigError(f"{name} must be a positive integer, got {value!r}")
    return int(value)
