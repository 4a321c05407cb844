"""Numbers as the report prints them: the one formatter of every report text and table.

A leaf module (it imports nothing of the package), so the report's sections, the
findings of :mod:`nirglucose.evaluation` and the tables all print a number the same
way: :func:`format_number` for one value, :func:`format_ci` for an estimate with its
interval, ``"12.3 [10.1, 14.5]"``. A missing, non-numeric or non-finite value prints as
:data:`MISSING`.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

__all__ = ["MISSING", "STYLES", "as_number", "format_ci", "format_number"]

#: What a missing or non-finite number prints as (an en dash).
MISSING = "–"

#: Valid ``style`` values of :func:`format_number`.
STYLES = ("fixed", "significant", "general", "scientific", "percent", "latency")


def _to_float(value: Any) -> float | None:
    """``float(value)`` (NaN and infinity included), None when it is not a number."""
    if value is None or isinstance(value, str) and not value.strip():
        return None
    try:
        return float(value)
    except (TypeError, ValueError):
        return None


def as_number(value: Any) -> float | None:
    """``value`` as a finite float, or None (missing, non-numeric, NaN or infinite).

    Examples
    --------
    >>> as_number("2.5"), as_number(None), as_number(float("inf")), as_number("n/a")
    (2.5, None, None, None)
    """
    f = _to_float(value)
    return f if f is not None and math.isfinite(f) else None


def format_number(
    value: Any,
    digits: int = 1,
    *,
    style: str = "fixed",
    sign: bool = False,
    thousands: bool = False,
    text: Callable[[Any], str] | None = None,
) -> str:
    """One number as the report prints it.

    Parameters
    ----------
    value : float, int, str or None
        The number (a numeric string is read as one).
    digits : int
        Decimals (``fixed``, ``scientific``, ``percent``) or significant digits
        (``significant``); unused by ``general`` and ``latency``. [-]
    style : {'fixed', 'significant', 'general', 'scientific', 'percent', 'latency'}
        ``fixed``: ``digits`` decimals; ``significant``: ``digits`` significant digits;
        ``general``: Python's shortest ``g`` form (configuration values, 1050 nm, x0.5);
        ``scientific``: ``1e-05``; ``percent``: a fraction as ``digits``-decimal
        percent (0.25 -> ``25%``); ``latency``: milliseconds from 0.001 to 100 with
        three decimals below 0.1, two below 10, else one.
    sign : bool
        Always show the sign (``+1.5``).
    thousands : bool
        Group thousands with commas (``fixed`` style). [-]
    text : callable, optional
        How to show a non-numeric, non-empty value (e.g. HTML-escaped text); by default
        it prints as :data:`MISSING`, as do None, ``""``, NaN and infinity.

    Returns
    -------
    str

    Examples
    --------
    >>> format_number(13.649), format_number(1234.5, 0, thousands=True)
    ('13.6', '1,234')
    >>> format_number(-0.0123, 2, style="significant", sign=True), format_number(None)
    ('-0.012', '–')
    >>> format_number(0.0234, style="latency"), format_number(0.25, 0, style="percent")
    ('0.023', '25%')
    """
    if style not in STYLES:  # checked first: a misspelt style shows with missing values too
        raise ValueError(f"unknown style {style!r}; valid: {', '.join(STYLES)}")
    f = _to_float(value)
    if f is None or not math.isfinite(f):
        blank = value is None or isinstance(value, str) and not value.strip()
        return text(value) if f is None and text is not None and not blank else MISSING
    plus = "+" if sign else ""
    if style == "fixed":
        return f"{f:{plus}{',' if thousands else ''}.{digits}f}"
    if style == "significant":
        return f"{f:{plus}.{digits}g}"
    if style == "general":
        return f"{f:{plus}g}"
    if style == "scientific":
        return f"{f:{plus}.{digits}e}"
    if style == "percent":
        return f"{f:{plus}.{digits}%}"
    # style == "latency"
    return f"{f:{plus}.3f}" if abs(f) < 0.1 else f"{f:{plus}.2f}" if abs(f) < 10 else (
        f"{f:{plus}.1f}")


def format_ci(value: Any, low: Any, high: Any, digits: int = 1, **options: Any) -> str:
    """An estimate and its interval, ``"12.3 [10.1, 14.5]"``, each number by
    :func:`format_number` with the same ``digits`` and options.

    Examples
    --------
    >>> format_ci(12.34, 10.06, 14.54)
    '12.3 [10.1, 14.5]'
    >>> format_ci(12.34, None, 14.55, 3, style="significant")
    '12.3 [–, 14.6]'
    """
    return (f"{format_number(value, digits, **options)} [{format_number(low, digits, **options)}"
            f", {format_number(high, digits, **options)}]")
