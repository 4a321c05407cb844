"""RMSE, MARD, bias, within-percent, Bland–Altman and the shared input validation.

Every expected number is computed by hand from the textbook definition (shown in the
comment next to it), never by running the code under test.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from nirglucose.exceptions import DataError
from nirglucose.metrics import (
    bland_altman,
    clarke_zones,
    iso15197_2013,
    iso15197_2013_passes,
    iso15197_2013_zone_ab,
    mard,
    mean_bias,
    parkes_zones,
    rmse,
    summary,
    within_percent,
)

EPS = 1e-6

# ref = [100, 200, 50], pred = [110, 180, 50] -> d = pred - ref = [10, -20, 0]
REF = [100.0, 200.0, 50.0]
PRED = [110.0, 180.0, 50.0]


def test_rmse_hand_computed() -> None:
    # sqrt((10^2 + 20^2 + 0^2) / 3) = sqrt(500 / 3)
    assert rmse(REF, PRED) == pytest.approx(math.sqrt(500.0 / 3.0), rel=1e-12)


def test_rmse_zero_for_perfect_prediction() -> None:
    assert rmse([80.0, 120.0], [80.0, 120.0]) == 0.0


def test_mard_hand_computed() -> None:
    # 100 * (10/100 + 20/200 + 0/50) / 3 = 100 * 0.2 / 3
    assert mard(REF, PRED) == pytest.approx(20.0 / 3.0, rel=1e-12)


def test_mard_is_relative_to_reference_not_prediction() -> None:
    # |50 - 100| / 100 = 50 % (relative to the prediction it would be 100 %)
    assert mard([100.0], [50.0]) == pytest.approx(50.0)


def test_mean_bias_sign_is_pred_minus_ref() -> None:
    # (10 - 20 + 0) / 3
    assert mean_bias(REF, PRED) == pytest.approx(-10.0 / 3.0, rel=1e-12)
    # over-reading gives a positive bias
    assert mean_bias([100.0], [105.0]) == pytest.approx(5.0)


def test_negative_predictions_allowed_for_error_statistics() -> None:
    # d = -110 -> rmse 110, bias -110: a negative estimate is a (bad) valid estimate
    assert rmse([100.0], [-10.0]) == pytest.approx(110.0)
    assert mean_bias([100.0], [-10.0]) == pytest.approx(-110.0)


@pytest.mark.parametrize(
    ("ref", "pred", "expected"),
    [
        # exactly +20 % and -20 % count as within (inclusive limit)
        (100.0, 120.0, 1.0),
        (100.0, 80.0, 1.0),
        (200.0, 240.0, 1.0),
        (200.0, 160.0, 1.0),
        # just outside by EPS
        (100.0, 120.0 + EPS, 0.0),
        (100.0, 80.0 - EPS, 0.0),
    ],
)
def test_within_percent_boundary(ref: float, pred: float, expected: float) -> None:
    assert within_percent([ref], [pred], 20) == expected


def test_within_percent_fraction() -> None:
    # |d|/ref = [0.10, 0.10, 0.0, 0.25] -> 3 of 4 within 20 %, 1 of 4 within 5 %
    ref = [100.0, 200.0, 50.0, 400.0]
    pred = [110.0, 180.0, 50.0, 300.0]
    assert within_percent(ref, pred, 20) == 0.75
    assert within_percent(ref, pred, pct=5.0) == 0.25


@pytest.mark.parametrize("pct", [-1.0, float("nan"), float("inf")])
def test_within_percent_rejects_bad_pct(pct: float) -> None:
    with pytest.raises(DataError, match="pct"):
        within_percent([100.0], [100.0], pct)


def test_bland_altman_hand_computed() -> None:
    ref = [100.0, 120.0, 140.0, 160.0]
    pred = [104.0, 118.0, 149.0, 163.0]
    # d = [4, -2, 9, 3]; bias = 14 / 4 = 3.5
    # deviations [0.5, -5.5, 5.5, -0.5]; sum of squares 61; SD (ddof=1) = sqrt(61 / 3)
    sd = math.sqrt(61.0 / 3.0)
    bias, low, high = bland_altman(ref, pred)
    assert bias == pytest.approx(3.5, rel=1e-12)
    assert low == pytest.approx(3.5 - 1.96 * sd, rel=1e-12)
    assert high == pytest.approx(3.5 + 1.96 * sd, rel=1e-12)


def test_bland_altman_named_fields_and_symmetric_case() -> None:
    # d = [-2, +2]: bias 0, SD = sqrt((4 + 4) / 1) = sqrt(8); limits symmetric about 0
    result = bland_altman([100.0, 100.0], [98.0, 102.0])
    assert result.bias == pytest.approx(0.0, abs=1e-12)
    assert result.upper_loa == pytest.approx(1.96 * math.sqrt(8.0), rel=1e-12)
    assert result.lower_loa == pytest.approx(-1.96 * math.sqrt(8.0), rel=1e-12)


def test_bland_altman_uses_sample_sd_not_population_sd() -> None:
    # d = [0, 10]: sample SD = sqrt(50) = 7.07..., population SD would be 5
    _, _, high = bland_altman([100.0, 100.0], [100.0, 110.0])
    assert high == pytest.approx(5.0 + 1.96 * math.sqrt(50.0), rel=1e-12)


def test_bland_altman_relative_hand_computed() -> None:
    ref = [100.0, 200.0]
    pred = [110.0, 180.0]
    # relative d = 100 (p - r) / ((p + r) / 2): 100 * 10 / 105 and 100 * -20 / 190
    d1 = 100.0 * 10.0 / 105.0
    d2 = 100.0 * -20.0 / 190.0
    mean = (d1 + d2) / 2.0
    sd = math.sqrt(((d1 - mean) ** 2 + (d2 - mean) ** 2) / 1.0)
    bias, low, high = bland_altman(ref, pred, relative=True)
    assert bias == pytest.approx(mean, rel=1e-12)
    assert low == pytest.approx(mean - 1.96 * sd, rel=1e-12)
    assert high == pytest.approx(mean + 1.96 * sd, rel=1e-12)


def test_bland_altman_needs_two_pairs() -> None:
    with pytest.raises(DataError, match="at least 2 pairs"):
        bland_altman([100.0], [110.0])


def test_bland_altman_relative_rejects_negative_prediction() -> None:
    with pytest.raises(DataError, match="non-negative"):
        bland_altman([100.0, 100.0], [90.0, -1.0], relative=True)


# --- shared validation: every public metric rejects the same bad inputs ---------------


def _call(name: str, ref: object, pred: object) -> object:
    functions = {
        "rmse": lambda: rmse(ref, pred),
        "mard": lambda: mard(ref, pred),
        "mean_bias": lambda: mean_bias(ref, pred),
        "within_percent": lambda: within_percent(ref, pred, 20),
        "bland_altman": lambda: bland_altman(ref, pred),
        "iso15197_2013": lambda: iso15197_2013(ref, pred),
        "iso15197_2013_zone_ab": lambda: iso15197_2013_zone_ab(ref, pred),
        "iso15197_2013_passes": lambda: iso15197_2013_passes(ref, pred),
        "clarke_zones": lambda: clarke_zones(ref, pred),
        "parkes_zones": lambda: parkes_zones(ref, pred),
        "summary": lambda: summary(ref, pred),
    }
    return functions[name]()


ALL_METRICS = [
    "rmse",
    "mard",
    "mean_bias",
    "within_percent",
    "bland_altman",
    "iso15197_2013",
    "iso15197_2013_zone_ab",
    "iso15197_2013_passes",
    "clarke_zones",
    "parkes_zones",
    "summary",
]
GRID_METRICS = [
    "iso15197_2013_zone_ab",
    "iso15197_2013_passes",
    "clarke_zones",
    "parkes_zones",
    "summary",
]


@pytest.mark.parametrize("name", ALL_METRICS)
def test_length_mismatch(name: str) -> None:
    with pytest.raises(DataError, match=r"differ in length: 3 reference values, 2 pred"):
        _call(name, [100.0, 110.0, 120.0], [100.0, 110.0])


@pytest.mark.parametrize("name", ALL_METRICS)
def test_empty(name: str) -> None:
    with pytest.raises(DataError, match="empty"):
        _call(name, [], [])


@pytest.mark.parametrize("name", ALL_METRICS)
def test_nan_in_prediction_reports_count_and_first_index(name: str) -> None:
    with pytest.raises(DataError, match=r"y_pred contains NaN: 2 values, first at index 1"):
        _call(name, [100.0, 110.0, 120.0, 130.0], [100.0, np.nan, 120.0, np.nan])


@pytest.mark.parametrize("name", ALL_METRICS)
def test_nan_in_reference(name: str) -> None:
    with pytest.raises(DataError, match=r"y_true contains NaN: 1 value, first at index 2"):
        _call(name, [100.0, 110.0, np.nan], [100.0, 110.0, 120.0])


@pytest.mark.parametrize("name", ALL_METRICS)
def test_infinite(name: str) -> None:
    with pytest.raises(DataError, match=r"y_pred contains infinite values: 1 value, first at"):
        _call(name, [100.0, 110.0], [100.0, -np.inf])


@pytest.mark.parametrize("name", ALL_METRICS)
def test_non_positive_reference(name: str) -> None:
    with pytest.raises(DataError, match=r"strictly positive.*2 values, first at index 1"):
        _call(name, [100.0, 0.0, -5.0], [100.0, 110.0, 120.0])


@pytest.mark.parametrize("name", GRID_METRICS)
def test_negative_prediction_rejected_where_a_grid_is_needed(name: str) -> None:
    with pytest.raises(DataError, match=r"non-negative.*1 value, first at index 2"):
        _call(name, [100.0, 110.0, 120.0], [100.0, 0.0, -0.5])


@pytest.mark.parametrize("name", ALL_METRICS)
def test_two_dimensional_input_rejected(name: str) -> None:
    with pytest.raises(DataError, match="one-dimensional"):
        _call(name, [[100.0, 110.0]], [[100.0, 110.0]])


@pytest.mark.parametrize("name", ALL_METRICS)
def test_non_numeric_input_rejected(name: str) -> None:
    with pytest.raises(DataError, match="numeric"):
        _call(name, ["a", "b"], [100.0, 110.0])


def test_data_error_is_a_value_error() -> None:
    with pytest.raises(ValueError):
        rmse([1.0], [1.0, 2.0])


def test_inputs_are_not_modified() -> None:
    ref = np.array([100.0, 200.0])
    pred = np.array([110.0, 190.0])
    summary(ref / 18.016, pred / 18.016, units="mmol/L")
    rmse(ref, pred)
    np.testing.assert_array_equal(ref, [100.0, 200.0])
    np.testing.assert_array_equal(pred, [110.0, 190.0])
