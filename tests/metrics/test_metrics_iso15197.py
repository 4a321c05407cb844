"""ISO 15197:2013, clause 6.3.3: accuracy limits and the consensus-grid criterion.

Definition used for the expected values: within means |pred - ref| <= 15 mg/dL when
ref < 100 mg/dL and |pred - ref| <= 15 % of ref when ref >= 100 mg/dL (limits
inclusive); criterion a) >= 95 % within, criterion b) >= 99 % in zones A + B of the type 1
consensus (Parkes) error grid.
"""

from __future__ import annotations

import numpy as np
import pytest

from nirglucose.metrics import iso15197_2013, iso15197_2013_passes, iso15197_2013_zone_ab

EPS = 1e-6


def within(ref: float, pred: float) -> bool:
    return iso15197_2013([ref], [pred]) == 1.0


@pytest.mark.parametrize(
    ("ref", "pred", "expected"),
    [
        # below 100 mg/dL: absolute +-15 mg/dL, limit inclusive
        (80, 95, True),
        (80, 65, True),
        (80, 95 + EPS, False),
        (80, 65 - EPS, False),
        # 99 mg/dL still uses +-15 mg/dL: 114 is within although 15 % of 99 is 14.85
        (99, 114, True),
        (99, 114 + EPS, False),
        # exactly 100 mg/dL uses the +-15 % rule: 15 % of 100 = 15
        (100, 115, True),
        (100, 85, True),
        (100, 115 + EPS, False),
        (100, 85 - EPS, False),
        # above: +-15 % of the reference; 15 % of 200 = 30 exactly
        (200, 230, True),
        (200, 170, True),
        (200, 230 + EPS, False),
        (200, 170 - EPS, False),
        # 15 % of 150 = 22.5
        (150, 172, True),
        (150, 173, False),
        # 15 % of 300 = 45: a 40 mg/dL error is within although > 15 mg/dL
        (300, 340, True),
        (300, 346, False),
        # at 50 mg/dL a 14 mg/dL error (28 %) is within
        (50, 64, True),
    ],
)
def test_iso_limits(ref: float, pred: float, expected: bool) -> None:
    assert within(ref, pred) is expected


def test_iso_symmetric_around_reference() -> None:
    # +-15 at 60 and +-15 % at 200: all four within, one step further all out
    assert iso15197_2013([60, 60, 200, 200], [75, 45, 230, 170]) == 1.0
    assert iso15197_2013([60, 60, 200, 200], [76, 44, 231, 169]) == 0.0


def test_iso_fraction() -> None:
    # 80->95 in, 80->96 out, 200->230 in, 200->231 out
    assert iso15197_2013([80, 80, 200, 200], [95, 96, 230, 231]) == 0.5


def test_iso_mmol_per_l() -> None:
    # 5 mmol/L = 90.08 mg/dL (< 100): limit 15 mg/dL = 0.8326 mmol/L
    assert iso15197_2013([5.0], [5.8], units="mmol/L") == 1.0  # 14.4 mg/dL off
    assert iso15197_2013([5.0], [5.9], units="mmol/L") == 0.0  # 16.2 mg/dL off
    # 10 mmol/L (180 mg/dL): +-15 % = +-1.5 mmol/L
    assert iso15197_2013([10.0], [11.4], units="mmol/L") == 1.0
    assert iso15197_2013([10.0], [11.6], units="mmol/L") == 0.0


def test_zone_ab_uses_type1_parkes() -> None:
    # T1 Parkes (Pfützner 2013): (100,110) A, (100,160) B, (100,190) C
    # (T1 B/C upper at x=100 is 110 + 30*440/190 = 179.5; in T2 it would be 197.2 -> B)
    assert iso15197_2013_zone_ab([100, 100], [110, 160]) == 1.0
    assert iso15197_2013_zone_ab([100, 100], [110, 190]) == 0.5
    # (20, 300) is E, (400, 50) is D
    assert iso15197_2013_zone_ab([20, 400, 100, 100], [300, 50, 100, 100]) == 0.5


def _pairs(n_good: int, n_bad: int, bad_pred: float) -> tuple[np.ndarray, np.ndarray]:
    ref = np.full(n_good + n_bad, 100.0)
    pred = np.concatenate([np.full(n_good, 100.0), np.full(n_bad, bad_pred)])
    return ref, pred


def test_passes_exactly_95_percent_within() -> None:
    # (100, 120): 20 % off -> not within 15 %, but T1 Parkes A (A/B upper at 100 = 126.4)
    ref, pred = _pairs(19, 1, 120.0)  # 19 / 20 = 95 % within, 100 % A+B
    assert iso15197_2013(ref, pred) == pytest.approx(0.95)
    assert iso15197_2013_passes(ref, pred) is True
    ref, pred = _pairs(18, 2, 120.0)  # 90 % within
    assert iso15197_2013_passes(ref, pred) is False


def test_passes_exactly_99_percent_zone_ab() -> None:
    # (100, 190) is T1 zone C and also outside +-15 %
    ref, pred = _pairs(99, 1, 190.0)  # 99 % within, 99 % A+B
    assert iso15197_2013_passes(ref, pred) is True
    ref, pred = _pairs(98, 2, 190.0)  # 98 % within (passes a), 98 % A+B (fails b)
    assert iso15197_2013(ref, pred) >= 0.95
    assert iso15197_2013_passes(ref, pred) is False


def test_passes_returns_python_bool() -> None:
    assert type(iso15197_2013_passes([100.0], [100.0])) is bool


def test_iso_unknown_units() -> None:
    with pytest.raises(ValueError, match="mmol/L"):
        iso15197_2013([100.0], [100.0], units="mM")
