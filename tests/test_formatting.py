"""The report's one number formatter: worked examples, missing values and properties."""

from __future__ import annotations

import html
import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from nirglucose.formatting import MISSING, STYLES, as_number, format_ci, format_number

FINITE = st.floats(allow_nan=False, allow_infinity=False, min_value=-1e9, max_value=1e9)


@pytest.mark.parametrize(
    ("value", "kwargs", "text"),
    [
        (13.649, {}, "13.6"),
        (13.65, {"digits": 2}, "13.65"),
        (1234.5, {"digits": 0, "thousands": True}, "1,234"),  # round half to even
        (1234.56, {"thousands": True}, "1,234.6"),
        (2.0, {"sign": True}, "+2.0"),
        (-0.0123, {"digits": 2, "style": "significant", "sign": True}, "-0.012"),
        (0.000123456, {"digits": 3, "style": "significant"}, "0.000123"),
        (1050.0, {"style": "general"}, "1050"),
        (1e-5, {"digits": 0, "style": "scientific"}, "1e-05"),
        (0.254, {"digits": 0, "style": "percent"}, "25%"),
        (0.01234, {"style": "latency"}, "0.012"),
        (1.234, {"style": "latency"}, "1.23"),
        (12.34, {"style": "latency"}, "12.3"),
        ("2.5", {}, "2.5"),
        (np.float32(0.5), {"digits": 2}, "0.50"),
        (np.int64(7), {"digits": 0}, "7"),
    ],
)
def test_worked_examples(value, kwargs, text):
    assert format_number(value, **kwargs) == text


@pytest.mark.parametrize("value", [None, "", " ", float("nan"), float("inf"), -np.inf,
                                   np.float32("nan"), "nan", "n/a", object()])
def test_missing_non_finite_and_text_print_as_missing(value):
    assert format_number(value) == MISSING
    assert as_number(value) is None
    assert format_ci(value, value, value) == f"{MISSING} [{MISSING}, {MISSING}]"


def test_text_is_shown_by_the_callers_rule_but_blanks_and_nan_stay_missing():
    esc = html.escape
    assert format_number("<b>", text=esc) == "&lt;b&gt;"
    assert format_number(None, text=esc) == format_number("", text=esc) == MISSING
    assert format_number(float("nan"), text=esc) == MISSING


def test_unknown_style_is_refused_with_the_valid_ones():
    with pytest.raises(ValueError, match="unknown style 'sci'; valid: fixed"):
        format_number(1.0, style="sci")
    assert STYLES[0] == "fixed"


@given(FINITE, st.integers(0, 4))
def test_fixed_reads_back_within_half_a_unit_of_the_last_digit(x, digits):
    text = format_number(x, digits, thousands=True)
    half_unit = 0.5 * 10.0**-digits
    assert abs(float(text.replace(",", "")) - x) <= half_unit * (1 + 1e-9) + 1e-9 * abs(x)


@given(FINITE, FINITE, FINITE)
def test_ci_is_its_three_numbers(m, lo, hi):
    assert format_ci(m, lo, hi) == f"{format_number(m)} [{format_number(lo)}, {format_number(hi)}]"


@given(FINITE)
def test_sign_only_adds_a_plus_to_non_negative_numbers(x):
    plain, signed = format_number(x, 2), format_number(x, 2, sign=True)
    assert signed == (plain if plain.startswith("-") else "+" + plain)


@given(st.floats(min_value=0.0, max_value=1e3))
def test_latency_decimals_follow_the_magnitude(ms):
    text = format_number(ms, style="latency")
    decimals = 3 if ms < 0.1 else 2 if ms < 10 else 1
    assert len(text.split(".")[1]) == decimals
    assert math.isclose(float(text), ms, abs_tol=0.5 * 10.0**-decimals * (1 + 1e-9))


@pytest.mark.parametrize("value", [1.0, None, math.nan])
def test_a_misspelt_style_is_refused_whatever_the_value(value):
    with pytest.raises(ValueError, match="unknown style 'percnt'"):
        format_number(value, style="percnt")
