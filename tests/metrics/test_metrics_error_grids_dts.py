"""DTS error grid (Klonoff et al., J Diabetes Sci Technol 18:1346-1361, 2024).

Two independent statements of the same geometry are the oracles here:

* the border vertices of the paper's Table A1 (Supplemental Appendix 2), transcribed
  again below (not imported from the module): each vertex lies on its border, so the
  pair there gets the inner zone and a pair just beyond it the outer one;
* the paper's closed-form risk (as transcribed in public implementations): with both
  glucose values clamped to 50 mg/dL, risk = 2.75 ln(monitor/reference) above the
  identity line and 2.25 ln(reference/monitor) below it, zones A-E at |risk| <= 0.5,
  1.5, 2.5, 3.5, > 3.5. Table A1 was drawn from it to within 1.2 mg/dL, so zones are
  compared away from the borders (|risk - edge| > 0.03).
"""

from __future__ import annotations

import numpy as np
import pytest

from nirglucose.exceptions import DataError
from nirglucose.metrics import DTS_LINES, dts_zones, zone_percentages

NUDGE = 1e-6

# (border, inner zone, corner vertex, far vertex) in (reference, monitor) mg/dL.
TABLE_A1 = [
    ("upper", "A", (50, 60), (500, 600)),
    ("upper", "B", (50, 86.5), (347, 600)),
    ("upper", "C", (50, 124), (241, 600)),
    ("upper", "D", (50, 179), (167, 600)),
    ("lower", "A", (62.5, 50), (600, 480)),
    ("lower", "B", (97.5, 50), (600, 307)),
    ("lower", "C", (153, 50), (600, 197)),
    ("lower", "D", (238, 50), (600, 126)),
]


def _next(zone: str) -> str:
    return "ABCDE"["ABCDE".index(zone) + 1]


@pytest.mark.parametrize(("side", "inner", "corner", "far"), TABLE_A1)
def test_table_a1_vertices_lie_on_the_borders(side, inner, corner, far) -> None:
    ref = np.array([corner[0], far[0]], dtype=float)
    mon = np.array([corner[1], far[1]], dtype=float)
    assert dts_zones(ref, mon).tolist() == [inner, inner]
    if side == "upper":  # beyond = above
        beyond = dts_zones(ref, mon * (1 + NUDGE))
    else:  # beyond = to the right
        beyond = dts_zones(ref * (1 + NUDGE), mon)
    assert beyond.tolist() == [_next(inner)] * 2


def test_borders_are_flat_or_vertical_below_the_corner() -> None:
    # Reference <= 50: upper borders are flat at the corner's monitor value.
    assert dts_zones([40, 45, 50], [86.5, 86.5 + NUDGE, 124]).tolist() == ["B", "C", "C"]
    # Monitor <= 50: lower borders are vertical at the corner's reference value.
    assert dts_zones([153, 153 + NUDGE, 238 + NUDGE], [0, 20, 10]).tolist() == [
        "C", "D", "E"]


def test_module_vertices_match_table_a1() -> None:
    for side, inner, corner, far in TABLE_A1:
        key = f"{inner}/{_next(inner)} {side}"
        assert DTS_LINES[key][1:] == (corner, far)


def test_zones_agree_with_the_closed_form_risk_away_from_borders() -> None:
    rng = np.random.default_rng(11)
    ref = rng.uniform(1.0, 700.0, 20_000)
    mon = ref * np.exp(rng.normal(0.0, 0.8, ref.size))
    rc, mc = np.maximum(ref, 50.0), np.maximum(mon, 50.0)
    risk = np.where(mc >= rc, 2.75 * np.log(mc / rc), 2.25 * np.log(rc / mc))
    edges = np.array([0.5, 1.5, 2.5, 3.5])
    expected = np.array(list("ABCDE"))[np.searchsorted(edges, risk, side="left")]
    clear = np.min(np.abs(risk[:, None] - edges), axis=1) > 0.03
    got = dts_zones(ref, mon)
    assert clear.sum() > 15_000
    np.testing.assert_array_equal(got[clear], expected[clear])
    assert set(got) == set("ABCDE")


def test_percentages_and_units() -> None:
    z = dts_zones([100, 100, 100, 100, 100], [110, 150, 190, 250, 400])
    assert zone_percentages(z) == {"A": 20.0, "B": 20.0, "C": 20.0, "D": 20.0, "E": 20.0}
    mmol = dts_zones([100 / 18.016, 200 / 18.016], [150 / 18.016, 200 / 18.016],
                     units="mmol/L")
    assert mmol.tolist() == ["B", "A"]


def test_rejects_negative_prediction() -> None:
    with pytest.raises(DataError, match="y_pred must be non-negative"):
        dts_zones([100.0], [-1.0])
