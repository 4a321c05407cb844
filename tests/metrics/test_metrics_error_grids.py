"""Clarke and Parkes error grids and zone percentages.

Expected zones are derived by hand from the published definitions:

* Clarke et al., Diabetes Care 10:622-628, 1987 (doi:10.2337/diacare.10.5.622):
  A = within 20 % or both <= 70; C upper above y = x + 110 (70 <= x <= 290), C lower
  below y = 1.4 x - 182 (130 <= x <= 180); D upper left x < 70, 70 < y <= 180 outside A;
  D lower right x > 240, 70 <= y < 180; E x < 70 & y > 180 or x > 180 & y < 70.
* Parkes et al., Diabetes Care 23:1143-1148, 2000, with the coordinates published by
  Pfützner et al., J Diabetes Sci Technol 7:1275-1281, 2013
  (doi:10.1177/193229681300700517), transcribed independently below.

Boundary convention under test: a point exactly on a line gets the less severe zone.
"""

from __future__ import annotations

import numpy as np
import pytest

from nirglucose.exceptions import DataError
from nirglucose.metrics import (
    PARKES_TYPE1_LINES,
    PARKES_TYPE2_LINES,
    clarke_zones,
    parkes_zones,
    zone_percentages,
)

EPS = 1e-6


def clarke(ref: float, pred: float) -> str:
    return str(clarke_zones([ref], [pred])[0])


def parkes(ref: float, pred: float, diabetes_type: int) -> str:
    return str(parkes_zones([ref], [pred], diabetes_type=diabetes_type)[0])


# --- Clarke ------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("ref", "pred", "zone"),
    [
        (100, 100, "A"),  # perfect agreement
        (300, 330, "A"),  # +10 %
        (50, 20, "A"),  # both hypoglycaemic (<= 70)
        (100, 150, "B"),  # +50 %, below the C line y = x + 110 = 210
        (200, 120, "B"),  # -40 %, ref > 180 but pred >= 70, ref <= 240
        (300, 200, "B"),  # -33 %, pred >= 180 so not lower D
        (100, 300, "C"),  # 300 > 100 + 110
        (200, 350, "C"),  # 350 > 200 + 110
        (170, 20, "C"),  # 20 < 1.4 * 170 - 182 = 56, ref <= 180
        (30, 120, "D"),  # ref < 70, 70 < pred <= 180, pred > 1.2 * 30
        (300, 120, "D"),  # ref > 240, 70 <= pred < 180
        (400, 100, "D"),
        (30, 300, "E"),  # ref < 70, pred > 180
        (300, 30, "E"),  # ref > 180, pred < 70
    ],
)
def test_clarke_well_inside_each_zone(ref: float, pred: float, zone: str) -> None:
    assert clarke(ref, pred) == zone


@pytest.mark.parametrize(
    ("point", "zone_on_line", "shifted", "zone_shifted"),
    [
        # (point on the line, zone on the line, zone on the far side of the line by EPS)
        # upper A line y = 1.2 x: A below / B above
        ((100, 120), "A", (100, 120 + EPS), "B"),
        # lower A line y = 0.8 x (x >= 70): A above / B below
        ((100, 80), "A", (100, 80 - EPS), "B"),
        # hypoglycaemic A edge y = 70 (x < 58.3): A below / D above
        ((30, 70), "A", (30, 70 + EPS), "D"),
        # upper A line y = 1.2 x for 58.3 < x < 70: A below / D above (1.2 * 65 = 78)
        ((65, 78), "A", (65, 78 + EPS), "D"),
        # vertical x = 70, 0 <= y <= 56: A left / B right
        ((70, 30), "A", (70 + EPS, 30), "B"),
        # vertical x = 70, 84 < y < 180: D left / B right (B is less severe)
        ((70, 120), "B", (70 - EPS, 120), "D"),
        # y = 180, x < 70: D below / E above
        ((30, 180), "D", (30, 180 + EPS), "E"),
        # vertical x = 70, y > 180: E left / C right
        ((70, 250), "C", (70 - EPS, 250), "E"),
        # upper C line y = x + 110: B below / C above
        ((150, 260), "B", (150, 260 + EPS), "C"),
        # right edge of upper C at x = 290 (y > 400): C left / B right
        ((290, 450), "B", (290 - EPS, 450), "C"),
        # lower C line y = 1.4 x - 182 (1.4 * 150 - 182 = 28): B above / C below
        ((150, 28), "B", (150, 28 - EPS), "C"),
        # vertical x = 180, y < 70: C left / E right
        ((180, 30), "C", (180 + EPS, 30), "E"),
        # y = 70, 180 < x < 240: B above / E below
        ((200, 70), "B", (200, 70 - EPS), "E"),
        # vertical x = 240, 70 < y < 180: B left / D right
        ((240, 120), "B", (240 + EPS, 120), "D"),
        # y = 70, x > 240: D above / E below
        ((300, 70), "D", (300, 70 - EPS), "E"),
        # y = 180, x > 240: B above / D below
        ((300, 180), "B", (300, 180 - EPS), "D"),
    ],
)
def test_clarke_boundary_lines(
    point: tuple[float, float], zone_on_line: str, shifted: tuple[float, float], zone_shifted: str
) -> None:
    assert clarke(*point) == zone_on_line
    assert clarke(*shifted) == zone_shifted


@pytest.mark.parametrize(
    ("ref", "pred", "zone"),
    [
        # corners: the least severe of the zones meeting at the corner
        (70, 70, "A"),  # A / B / D
        (70, 180, "B"),  # B / C / D / E
        (180, 70, "B"),  # B / C / E
        (240, 70, "B"),  # B / D / E
        (240, 180, "B"),  # B / D
        (70, 84, "A"),  # 1.2 * 70: A / B / D
        (70, 56, "A"),  # 0.8 * 70: A / B
    ],
)
def test_clarke_corners(ref: float, pred: float, zone: str) -> None:
    assert clarke(ref, pred) == zone


def test_clarke_symmetric_relative_errors_and_mirrored_e() -> None:
    # +-20 % and +-10 % around the same reference: both A; +-30 % (> 20 %): both B
    assert clarke_zones([150] * 4, [120, 180, 135, 165]).tolist() == ["A"] * 4
    assert clarke_zones([150, 150], [105, 195]).tolist() == ["B", "B"]
    # (50, 250) and its mirror (250, 50) are both E (a hypo read as hyper and back)
    assert clarke_zones([50, 250], [250, 50]).tolist() == ["E", "E"]


def test_clarke_perfect_agreement_is_always_a() -> None:
    ref = np.linspace(1.0, 1000.0, 2001)
    assert set(clarke_zones(ref, ref).tolist()) == {"A"}


def test_clarke_mmol_per_l() -> None:
    # 100 -> 150 mg/dL is B; 30 -> 300 mg/dL is E (converted with 18.016)
    ref = np.array([100.0, 30.0]) / 18.016
    pred = np.array([150.0, 300.0]) / 18.016
    assert clarke_zones(ref, pred, units="mmol/L").tolist() == ["B", "E"]
    # the same numbers read as mg/dL would be (5.55, 8.33) -> A, (1.67, 16.65) -> A
    assert clarke_zones(ref, pred).tolist() == ["A", "A"]


def test_clarke_returns_letters_array() -> None:
    zones = clarke_zones([100.0, 100.0], [100.0, 300.0])
    assert isinstance(zones, np.ndarray)
    assert zones.shape == (2,)
    assert zones.tolist() == ["A", "C"]


# --- Parkes: published vertex lists ----------------------------------------------------

# Pfützner et al. 2013, coordinates (reference, predicted) in mg/dL.
PUBLISHED_TYPE1 = {
    "A/B upper": [(0, 50), (30, 50), (140, 170), (280, 380), (430, 550)],
    "A/B lower": [(50, 0), (50, 30), (170, 145), (385, 300), (550, 450)],
    "B/C upper": [(0, 60), (30, 60), (50, 80), (70, 110), (260, 550)],
    "B/C lower": [(120, 0), (120, 30), (260, 130), (550, 250)],
    "C/D upper": [(0, 100), (25, 100), (50, 125), (80, 215), (125, 550)],
    "C/D lower": [(250, 0), (250, 40), (550, 150)],
    "D/E upper": [(0, 150), (35, 155), (50, 550)],
}
PUBLISHED_TYPE2 = {
    "A/B upper": [(0, 50), (30, 50), (230, 330), (440, 550)],
    "A/B lower": [(50, 0), (50, 30), (90, 80), (330, 230), (550, 450)],
    "B/C upper": [(0, 60), (30, 60), (280, 550)],
    "B/C lower": [(90, 0), (260, 130), (550, 250)],
    "C/D upper": [(0, 80), (25, 80), (35, 90), (125, 550)],
    "C/D lower": [(250, 0), (250, 40), (410, 110), (550, 160)],
    "D/E upper": [(0, 200), (35, 200), (50, 550)],
}
PUBLISHED = {1: PUBLISHED_TYPE1, 2: PUBLISHED_TYPE2}


@pytest.mark.parametrize(
    ("module_lines", "published"),
    [(PARKES_TYPE1_LINES, PUBLISHED_TYPE1), (PARKES_TYPE2_LINES, PUBLISHED_TYPE2)],
)
def test_parkes_vertex_lists_match_publication(module_lines: object, published: dict) -> None:
    assert {k: [tuple(v) for v in vs] for k, vs in module_lines.items()} == published


@pytest.mark.parametrize(
    ("ref", "pred", "zone_type1", "zone_type2"),
    [
        # hand-evaluated against the lines above (value of each line at the point's x or y)
        (100, 100, "A", "A"),  # diagonal
        (300, 300, "A", "A"),
        (40, 10, "A", "A"),  # left of the vertical A/B lower start at x = 50
        # T1: A/B upper at x=100 is 50 + 70*120/110 = 126.4; B/C upper 110 + 30*440/190
        # = 179.5. T2: A/B upper at 100 is 50 + 70*280/200 = 148; B/C 60 + 70*490/250
        # = 197.2
        (100, 160, "B", "B"),
        (100, 140, "B", "A"),  # 140 > 126.4 (T1) but < 148 (T2)
        (100, 190, "C", "B"),  # 190 > 179.5 (T1) but < 197.2 (T2)
        # lower: T1 A/B lower at y=120 is x = 50 + 90*120/115 = 143.9, B/C lower x = 246;
        # T2 A/B lower x = 90 + 40*240/150 = 154, B/C lower x = 90 + 120*170/130 = 246.9
        (200, 120, "B", "B"),
        # C upper: T1 C/D upper at 100 is 215 + 20*335/45 = 363.9; T2 90 + 65*460/90 = 422
        (100, 250, "C", "C"),
        # C lower: y=100: T1 B/C x = 218, C/D x = 250 + 60*300/110 = 413.6;
        # T2 B/C x = 220.8, C/D x = 250 + 60*160/70 = 387.1
        (300, 100, "C", "C"),
        # D upper: T1 at x=40: C/D 115, D/E 155 + 5*395/15 = 286.7; T2 at x=30: C/D 85,
        # D/E 200
        (40, 140, "D", "D"),
        (30, 150, "D", "D"),
        # D lower: y=50: T1 C/D x = 250 + 10*300/110 = 277.3; T2 250 + 10*160/70 = 272.9
        (400, 50, "D", "D"),
        # E: T1 D/E at x=20 is 150 + 20*5/35 = 152.9; T2 200
        (20, 300, "E", "E"),
        (20, 180, "E", "D"),  # 180 > 152.9 (T1) but < 200 (T2)
    ],
)
def test_parkes_well_inside_each_zone(
    ref: float, pred: float, zone_type1: str, zone_type2: str
) -> None:
    assert parkes(ref, pred, 1) == zone_type1
    assert parkes(ref, pred, 2) == zone_type2


def _segment_cases() -> list[tuple[int, str, tuple[float, float]]]:
    """Midpoint of every published segment, offset by EPS to each side.

    A line "X/Y upper" has zone X below it and Y above it; "X/Y lower" has X to its
    left and Y to its right (the definition of the grid: zones are nested bands).
    """
    cases = []
    for dtype, lines in PUBLISHED.items():
        for name, vertices in lines.items():
            for (x1, y1), (x2, y2) in zip(vertices[:-1], vertices[1:], strict=True):
                xm, ym = (x1 + x2) / 2.0, (y1 + y2) / 2.0
                cases.append((dtype, name, (xm, ym)))
    return cases


@pytest.mark.parametrize(("dtype", "name", "mid"), _segment_cases())
def test_parkes_every_segment_straddled(dtype: int, name: str, mid: tuple[float, float]) -> None:
    less, more = name.split()[0].split("/")
    xm, ym = mid
    if name.endswith("upper"):
        inside, outside = (xm, ym - EPS), (xm, ym + EPS)
    else:
        inside, outside = (xm - EPS, ym), (xm + EPS, ym)
    assert parkes(*inside, dtype) == less
    assert parkes(*outside, dtype) == more


@pytest.mark.parametrize(
    ("dtype", "vertex", "zone"),
    [
        # a point exactly on a line (here a published vertex) gets the less severe zone
        (1, (30, 50), "A"),
        (1, (140, 170), "A"),
        (1, (280, 380), "A"),
        (1, (50, 30), "A"),
        (1, (385, 300), "A"),
        (1, (30, 60), "B"),
        (1, (70, 110), "B"),
        (1, (120, 30), "B"),
        (1, (260, 130), "B"),
        (1, (25, 100), "C"),
        (1, (80, 215), "C"),
        (1, (250, 40), "C"),
        (1, (35, 155), "D"),
        (2, (30, 50), "A"),
        (2, (230, 330), "A"),
        (2, (90, 80), "A"),
        (2, (330, 230), "A"),
        (2, (30, 60), "B"),
        (2, (260, 130), "B"),
        (2, (35, 90), "C"),
        (2, (410, 110), "C"),
        (2, (35, 200), "D"),
    ],
)
def test_parkes_point_on_line_gets_less_severe_zone(
    dtype: int, vertex: tuple[float, float], zone: str
) -> None:
    assert parkes(*vertex, dtype) == zone


def test_parkes_type1_ab_upper_is_not_vertical_at_280() -> None:
    # Published T1 A/B upper runs (280, 380) -> (430, 550); at x = 300 it is at
    # 380 + 20 * 170 / 150 = 402.7, so (300, 420) is B (a vertical (280, 550) end
    # would leave it in A).
    assert parkes(300, 420, 1) == "B"
    assert parkes(300, 400, 1) == "A"


def test_parkes_type1_cd_lower_has_no_type2_vertex() -> None:
    # T1 C/D lower at y = 105 is x = 250 + 65 * 300 / 110 = 427.3 -> (410, 105) is C.
    # The T2 line passes through (410, 110), so there (410, 105) is D.
    assert parkes(410, 105, 1) == "C"
    assert parkes(410, 105, 2) == "D"


def test_parkes_lines_extend_past_550() -> None:
    # last T1 A/B upper segment slope 170 / 150: at x = 700 the line is at
    # 550 + 270 * 170 / 150 = 856; the diagonal point is A, well above is B
    assert parkes(700, 700, 1) == "A"
    assert parkes(700, 850, 1) == "A"
    assert parkes(700, 860, 1) == "B"


@pytest.mark.parametrize("dtype", [1, 2])
def test_parkes_perfect_agreement_is_always_a(dtype: int) -> None:
    ref = np.linspace(1.0, 1000.0, 2001)
    assert set(parkes_zones(ref, ref, diabetes_type=dtype).tolist()) == {"A"}


@pytest.mark.parametrize(
    "grid",
    [
        lambda r, p: clarke_zones(r, p),
        lambda r, p: parkes_zones(r, p, diabetes_type=1),
        lambda r, p: parkes_zones(r, p, diabetes_type=2),
    ],
    ids=["clarke", "parkes1", "parkes2"],
)
def test_severity_never_decreases_moving_away_from_the_diagonal(grid: object) -> None:
    # Both grids are nested risk bands: along a vertical line (fixed reference), the
    # zone letter can only get worse as the prediction moves away from the reference.
    refs = np.arange(2.0, 700.0, 7.0)
    preds = np.arange(0.0, 900.0, 3.0)
    rr, pp = np.meshgrid(refs, preds, indexing="ij")
    zones = grid(rr.ravel(), pp.ravel()).reshape(rr.shape)
    severity = zones.view(np.uint32).astype(int) - ord("A")
    above = np.where(pp >= rr, severity, -1)
    below = np.where(pp <= rr, severity, -1)
    assert np.all(np.diff(above, axis=1)[pp[:, 1:] > rr[:, 1:]] >= 0)
    assert np.all(np.diff(below[:, ::-1], axis=1)[(pp <= rr)[:, ::-1][:, 1:]] >= 0)


def test_parkes_mmol_per_l() -> None:
    ref = np.array([100.0, 20.0]) / 18.016
    pred = np.array([250.0, 300.0]) / 18.016
    assert parkes_zones(ref, pred, units="mmol/L").tolist() == ["C", "E"]


@pytest.mark.parametrize("bad", [0, 3, "1", 1.5, True])
def test_parkes_bad_diabetes_type(bad: object) -> None:
    with pytest.raises(DataError, match="diabetes_type must be 1 or 2"):
        parkes_zones([100.0], [100.0], diabetes_type=bad)


@pytest.mark.parametrize("func", [clarke_zones, parkes_zones])
def test_unknown_units_lists_valid_units(func: object) -> None:
    with pytest.raises(ValueError, match=r"'mg/dL', 'mmol/L'"):
        func([100.0], [100.0], units="g/L")


def test_units_are_case_insensitive() -> None:
    assert clarke_zones([100.0], [100.0], units="MG/DL").tolist() == ["A"]


# --- zone_percentages ------------------------------------------------------------------


def test_zone_percentages_all_keys_present() -> None:
    # 2 A, 1 B, 1 E of 4 -> 50, 25, 0, 0, 25
    assert zone_percentages(["A", "A", "B", "E"]) == {
        "A": 50.0,
        "B": 25.0,
        "C": 0.0,
        "D": 0.0,
        "E": 25.0,
    }


def test_zone_percentages_accepts_grid_output_and_object_arrays() -> None:
    zones = clarke_zones([100.0, 100.0, 30.0], [100.0, 300.0, 300.0])  # A, C, E
    expected = {"A": 100 / 3, "B": 0.0, "C": 100 / 3, "D": 0.0, "E": 100 / 3}
    assert zone_percentages(zones) == pytest.approx(expected)
    assert zone_percentages(np.array(zones.tolist(), dtype=object)) == pytest.approx(expected)


def test_zone_percentages_values_are_python_floats() -> None:
    result = zone_percentages(["C"])
    assert all(type(v) is float for v in result.values())
    assert result["C"] == 100.0


@pytest.mark.parametrize(
    ("zones", "match"),
    [
        ([], "empty"),
        (["A", "F", "B", "a"], r"2 invalid labels, first at index 1 \('F'\)"),
        (["A", "AB"], "first at index 1"),
        (["A", ""], "first at index 1"),
        ([1, 2], "letters"),
        ([["A"]], "one-dimensional"),
    ],
)
def test_zone_percentages_bad_input(zones: object, match: str) -> None:
    with pytest.raises(DataError, match=match):
        zone_percentages(zones)
