"""The one-call summary: keys, types, hand-computed values, units, diabetes type."""

from __future__ import annotations

import math

import numpy as np
import pytest

from nirglucose.exceptions import DataError
from nirglucose.metrics import summary

EXPECTED_KEYS = [
    "n",
    "rmse_mgdl",
    "mard_pct",
    "bias_mgdl",
    "clarke_a_pct",
    "clarke_ab_pct",
    "clarke_b_pct",
    "clarke_c_pct",
    "clarke_d_pct",
    "clarke_e_pct",
    "parkes_a_pct",
    "parkes_ab_pct",
    "within15_pct",
    "within20_pct",
    "iso15197_pct",
    "iso15197_zone_ab_pct",
    "loa_low_mgdl",
    "loa_high_mgdl",
    "dts_a_pct",
]

# Five pairs, every value worked out by hand from the definitions:
#   (100, 110): d = +10, 10 %   Clarke A, Parkes T1 A (A/B upper at 100 = 126.4)
#   (200, 180): d = -20, 10 %   Clarke A, Parkes T1 A (A/B lower at y=180: x = 218.5)
#   ( 50,  50): d =   0,  0 %   A, A
#   (300, 240): d = -60, 20 %   Clarke A (exactly 0.8 * 300), Parkes T1 A (x = 301.8)
#   (250,  50): d = -200, 80 %  Clarke E (ref > 180, pred < 70),
#                               Parkes T1 C (B/C lower x = 148 < 250 < C/D lower 277.3)
REF = [100.0, 200.0, 50.0, 300.0, 250.0]
PRED = [110.0, 180.0, 50.0, 240.0, 50.0]
D = [10.0, -20.0, 0.0, -60.0, -200.0]


def test_keys_in_order_and_plain_floats() -> None:
    result = summary(REF, PRED)
    assert list(result) == EXPECTED_KEYS
    assert all(type(v) is float for v in result.values())


def test_hand_computed_values() -> None:
    result = summary(REF, PRED)
    bias = sum(D) / 5  # -54
    sd = math.sqrt(sum((d - bias) ** 2 for d in D) / 4)  # sqrt(29520 / 4)
    expected = {
        "n": 5.0,
        "rmse_mgdl": math.sqrt((100 + 400 + 0 + 3600 + 40000) / 5),
        "mard_pct": 100 * (0.1 + 0.1 + 0.0 + 0.2 + 0.8) / 5,  # 24
        "bias_mgdl": bias,
        "clarke_a_pct": 80.0,
        "clarke_ab_pct": 80.0,
        "clarke_b_pct": 0.0,
        "clarke_c_pct": 0.0,
        "clarke_d_pct": 0.0,
        "clarke_e_pct": 20.0,
        "parkes_a_pct": 80.0,
        "parkes_ab_pct": 80.0,
        "within15_pct": 60.0,  # 10 %, 10 %, 0 % (20 % and 80 % are out)
        "within20_pct": 80.0,  # the 20 % pair is on the inclusive limit
        "iso15197_pct": 60.0,  # (300, 240): 60 > 45 out; (50, 50) in
        "iso15197_zone_ab_pct": 80.0,
        "loa_low_mgdl": bias - 1.96 * sd,
        "loa_high_mgdl": bias + 1.96 * sd,
        # DTS (Table A1): (200, 180) left of the A/B lower line (x = 225 at y = 180);
        # (300, 240) exactly on it (x = 62.5 + 190 * 537.5 / 430 = 300) -> A;
        # (250, 50) right of the vertical D/E lower run at x = 238 -> E.
        "dts_a_pct": 80.0,
    }
    assert result == pytest.approx(expected, rel=1e-12, abs=1e-12)


def test_mmol_per_l_inputs_reported_in_mgdl() -> None:
    rng = np.random.default_rng(0)
    ref = rng.uniform(40.0, 400.0, 200)
    pred = ref * rng.uniform(0.6, 1.5, 200)
    in_mgdl = summary(ref, pred)
    in_mmol = summary(ref / 18.016, pred / 18.016, units="mmol/L")
    assert in_mmol == pytest.approx(in_mgdl, rel=1e-9, abs=1e-9)


def test_diabetes_type_changes_parkes_keys_but_not_iso_zone_ab() -> None:
    # (100, 190): T1 C (B/C upper 179.5), T2 B (B/C upper 197.2); (100, 100) A
    type1 = summary([100.0, 100.0], [100.0, 190.0], diabetes_type=1)
    type2 = summary([100.0, 100.0], [100.0, 190.0], diabetes_type=2)
    assert type1["parkes_ab_pct"] == 50.0
    assert type2["parkes_ab_pct"] == 100.0
    # ISO 15197 criterion b) always uses the type 1 grid
    assert type1["iso15197_zone_ab_pct"] == 50.0
    assert type2["iso15197_zone_ab_pct"] == 50.0


def test_parkes_a_differs_by_type() -> None:
    # (100, 140): T1 B (A/B upper 126.4), T2 A (A/B upper 148)
    assert summary([100.0, 100.0], [100.0, 140.0])["parkes_a_pct"] == 50.0
    assert summary([100.0, 100.0], [100.0, 140.0], diabetes_type=2)["parkes_a_pct"] == 100.0


def test_single_pair_has_nan_limits_of_agreement() -> None:
    result = summary([100.0], [110.0])
    assert result["n"] == 1.0
    assert result["bias_mgdl"] == 10.0
    assert math.isnan(result["loa_low_mgdl"])
    assert math.isnan(result["loa_high_mgdl"])


def test_bad_units_and_type() -> None:
    with pytest.raises(DataError, match=r"\['mg/dL', 'mmol/L'\]"):
        summary([100.0], [100.0], units="mg/L")
    with pytest.raises(DataError, match="diabetes_type"):
        summary([100.0], [100.0], diabetes_type=3)


def test_large_input_is_vectorised() -> None:
    # 200 000 pairs finish quickly (a Python loop over samples would take seconds)
    rng = np.random.default_rng(1)
    ref = rng.uniform(40.0, 400.0, 200_000)
    pred = np.abs(ref + rng.normal(0.0, 20.0, ref.shape))
    result = summary(ref, pred)
    assert result["n"] == 200_000.0
    total = sum(result[f"clarke_{z}_pct"] for z in "bcde") + result["clarke_a_pct"]
    assert total == pytest.approx(100.0)
