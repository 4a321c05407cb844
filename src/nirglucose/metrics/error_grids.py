"""Clinical error grids: Clarke (1987), Parkes / consensus (2000), DTS (2024), zone shares.

All three grids place each (reference, predicted) pair, in mg/dL, into a risk zone 'A'
(clinically accurate) to 'E' (dangerous). Grids are evaluated without a Python loop:
the Clarke zones are a handful of vectorised inequalities and the Parkes boundary lines
are piecewise-linear curves evaluated with :func:`numpy.interp`.

Boundary convention (every grid): a pair lying exactly on a boundary line belongs to
the *less severe* (alphabetically earlier) of the zones that meet there. For example
Clarke ``(100, 120)`` (exactly +20 %) is 'A', and a Parkes pair exactly on the A/B line
is 'A'.

Predictions must be non-negative (a negative glucose has no place on a grid and is
rejected with :class:`~nirglucose.exceptions.DataError`); references must be positive.
"""

from __future__ import annotations

from types import MappingProxyType
from typing import Final

import numpy as np
from numpy.typing import ArrayLike, NDArray

from nirglucose.exceptions import DataError
from nirglucose.metrics._validation import _to_mgdl, _unit_factor, _validate_pairs

__all__ = [
    "ZONE_LABELS",
    "PARKES_TYPE1_LINES",
    "PARKES_TYPE2_LINES",
    "PARKES_LINES",
    "DTS_LINES",
    "clarke_zones",
    "parkes_zones",
    "dts_zones",
    "zone_percentages",
]

#: Zone letters in order of increasing clinical risk.
ZONE_LABELS: Final[tuple[str, ...]] = ("A", "B", "C", "D", "E")
_LABEL_ARRAY: Final[NDArray[np.str_]] = np.array(ZONE_LABELS, dtype="<U1")

# --- Parkes (consensus) error grid vertex lists ------------------------------------
#
# Vertices are (reference, predicted) in mg/dL, from Pfützner, Klonoff, Pardo & Parkes,
# "Technical aspects of the Parkes error grid", J Diabetes Sci Technol 7(5):1275-1281,
# 2013, doi:10.1177/193229681300700517 -- the paper in which the authors of the grid
# first published its exact coordinates (Parkes et al. 2000 only drew it). The grid is
# drawn on 0-550 mg/dL; beyond the last vertex each line continues along its last
# segment. "X/Y upper" separates zone X from the more severe zone Y above the
# diagonal (over-reading), "X/Y lower" below the diagonal (under-reading). Neither
# grid has an E zone below the diagonal.
#
# Note: Type 1 "A/B upper" ends (280, 380), (430, 550); "C/D lower" of type 1 has no
# (410, 110) vertex -- that vertex belongs to the type 2 grid.

#: Parkes consensus error grid, type 1 diabetes: boundary polylines. [mg/dL]
PARKES_TYPE1_LINES: Final = MappingProxyType(
    {
        "A/B upper": ((0, 50), (30, 50), (140, 170), (280, 380), (430, 550)),
        "A/B lower": ((50, 0), (50, 30), (170, 145), (385, 300), (550, 450)),
        "B/C upper": ((0, 60), (30, 60), (50, 80), (70, 110), (260, 550)),
        "B/C lower": ((120, 0), (120, 30), (260, 130), (550, 250)),
        "C/D upper": ((0, 100), (25, 100), (50, 125), (80, 215), (125, 550)),
        "C/D lower": ((250, 0), (250, 40), (550, 150)),
        "D/E upper": ((0, 150), (35, 155), (50, 550)),
    }
)

#: Parkes consensus error grid, type 2 diabetes: boundary polylines. [mg/dL]
PARKES_TYPE2_LINES: Final = MappingProxyType(
    {
        "A/B upper": ((0, 50), (30, 50), (230, 330), (440, 550)),
        "A/B lower": ((50, 0), (50, 30), (90, 80), (330, 230), (550, 450)),
        "B/C upper": ((0, 60), (30, 60), (280, 550)),
        "B/C lower": ((90, 0), (260, 130), (550, 250)),
        "C/D upper": ((0, 80), (25, 80), (35, 90), (125, 550)),
        "C/D lower": ((250, 0), (250, 40), (410, 110), (550, 160)),
        "D/E upper": ((0, 200), (35, 200), (50, 550)),
    }
)

#: Parkes grids by diabetes type.
PARKES_LINES: Final = MappingProxyType({1: PARKES_TYPE1_LINES, 2: PARKES_TYPE2_LINES})


# --- Diabetes Technology Society (DTS) error grid vertex lists ------------------------
#
# Vertices are (reference, monitor) in mg/dL, from Table A1 ("Coordinates (Reference/
# Monitor) of the lines defining the zones of the DTS Error Grid"), Supplemental
# Appendix 2 of Klonoff DC, Freckmann G, Pleus S, et al., "The Diabetes Technology Society
# Error Grid and Trend Accuracy Matrix for glucose monitors", J Diabetes Sci Technol
# 18(6):1346-1361, 2024, doi:10.1177/19322968241275701. The grid is drawn on 0-600 mg/dL;
# each border is a flat (upper) or vertical (lower) run up to the 50 mg/dL corner and then
# a straight line to the edge of the plot, continued along that line beyond 600 mg/dL.
# The supplement labels the two outermost borders "D lower"/"D upper"; they separate D
# from E (they lie outside the D/C borders in the paper's Figure A1), so they are the
# "D/E" lines here. The coordinates were read from the stored transcriptions of Table A1
# (two independent public transcriptions agree on all 16 numbers), which also agree
# with the paper's closed-form risk function (borders at |risk| 0.5, 1.5, 2.5, 3.5 with
# coefficients 2.75 above and 2.25 below the identity line, both glucose values clamped
# to 50 mg/dL) to 1.2 mg/dL; the paper itself was not in the stored corpus.

#: DTS error grid: boundary polylines (the grid is the same for BGMs and CGMs). [mg/dL]
DTS_LINES: Final = MappingProxyType(
    {
        "A/B upper": ((0, 60), (50, 60), (500, 600)),
        "A/B lower": ((62.5, 0), (62.5, 50), (600, 480)),
        "B/C upper": ((0, 86.5), (50, 86.5), (347, 600)),
        "B/C lower": ((97.5, 0), (97.5, 50), (600, 307)),
        "C/D upper": ((0, 124), (50, 124), (241, 600)),
        "C/D lower": ((153, 0), (153, 50), (600, 197)),
        "D/E upper": ((0, 179), (50, 179), (167, 600)),
        "D/E lower": ((238, 0), (238, 50), (600, 126)),
    }
)


class _Polyline:
    """A monotone boundary line evaluated as a function of one coordinate.

    "upper" lines (above the diagonal) start with a horizontal run at reference 0 and
    are evaluated as ``predicted = f(reference)``; "lower" lines start with a vertical
    run at predicted 0 and are evaluated as ``reference = g(predicted)``. Both are
    non-decreasing, so :func:`numpy.interp` evaluates them; past the last vertex the
    last segment is extended linearly (through an extra far vertex, so that the common
    case needs a single ``np.interp`` call).
    """

    __slots__ = ("t", "v", "t_last", "v_last", "slope_end")

    #: Coordinate of the extra vertex placed on the extended last segment. [mg/dL]
    _FAR = 1.0e7

    def __init__(self, vertices: tuple[tuple[float, float], ...], upper: bool) -> None:
        pts = np.asarray(vertices, dtype=np.float64)
        t, v = (pts[:, 0], pts[:, 1]) if upper else (pts[:, 1], pts[:, 0])
        if t[0] != 0.0 or np.any(np.diff(t) <= 0.0) or np.any(np.diff(v) < 0.0):
            raise ValueError(f"boundary vertices are not a monotone polyline: {vertices}")
        self.t_last = float(t[-1])
        self.v_last = float(v[-1])
        self.slope_end = float((v[-1] - v[-2]) / (t[-1] - t[-2]))
        far_v = self.v_last + self.slope_end * (self._FAR - self.t_last)
        self.t = np.append(t, self._FAR)
        self.v = np.append(v, far_v)

    def __call__(self, x: NDArray[np.float64]) -> NDArray[np.float64]:
        out = np.interp(x, self.t, self.v)
        if x.shape[0] and x.max() > self._FAR:  # absurd glucose, but stay exact
            beyond = x > self._FAR
            out[beyond] = self.v_last + self.slope_end * (x[beyond] - self.t_last)
        return out


def _compile_parkes(
    lines: MappingProxyType,
) -> tuple[tuple[_Polyline, ...], tuple[_Polyline, ...]]:
    uppers = tuple(_Polyline(lines[f"{z}/{n} upper"], True) for z, n in ("AB", "BC", "CD", "DE"))
    lowers = tuple(_Polyline(lines[f"{z}/{n} lower"], False) for z, n in ("AB", "BC", "CD"))
    return uppers, lowers


_PARKES_COMPILED: Final = {k: _compile_parkes(v) for k, v in PARKES_LINES.items()}
_DTS_COMPILED: Final = (
    tuple(_Polyline(DTS_LINES[f"{z}/{n} upper"], True) for z, n in ("AB", "BC", "CD", "DE")),
    tuple(_Polyline(DTS_LINES[f"{z}/{n} lower"], False) for z, n in ("AB", "BC", "CD", "DE")),
)


# --- kernels on validated mg/dL arrays: return int8 codes 0..4 = A..E ---------------


def _clarke_codes(ref: NDArray[np.float64], pred: NDArray[np.float64]) -> NDArray[np.int8]:
    # Ratios are cross-multiplied (5 pred vs 6 ref, ...) so integer inputs on a
    # boundary compare exactly. Each zone's inequalities are strict on the sides where
    # it meets a less severe zone and inclusive where it meets a more severe one.
    p5 = 5.0 * pred
    hypo_ref = ref < 70.0
    zone_a = ((ref <= 70.0) & (pred <= 70.0)) | ((p5 >= 4.0 * ref) & (p5 <= 6.0 * ref))
    zone_e = (hypo_ref & (pred > 180.0)) | ((ref > 180.0) & (pred < 70.0))
    zone_d = (hypo_ref & (pred > 70.0) & (pred <= 180.0) & (p5 > 6.0 * ref)) | (
        (ref > 240.0) & (pred >= 70.0) & (pred < 180.0)
    )
    zone_c = ((ref >= 70.0) & (ref < 290.0) & (pred > ref + 110.0)) | (
        (ref <= 180.0) & (p5 < 7.0 * ref - 910.0)
    )
    # The four sets are disjoint and B is "none of them": B=1, A=0, C=2, D=3, E=4.
    codes = np.ones(ref.shape[0], dtype=np.int8)
    codes -= zone_a
    codes += zone_c
    codes += 2 * zone_d.view(np.int8)
    codes += 3 * zone_e.view(np.int8)
    return codes


def _add_crossings(
    lines: tuple[_Polyline, ...],
    coord: NDArray[np.float64],
    other: NDArray[np.float64],
    codes: NDArray[np.int8],
) -> None:
    """Add to ``codes`` the number of nested ``lines`` with ``other > line(coord)``.

    The lines are nested (each lies beyond the previous one), so a pair beyond line k
    is beyond lines 0..k-1 too; only the pairs beyond line k are tested against line
    k+1, which keeps the work close to one pass for mostly accurate data.
    """
    idx: NDArray[np.intp] | None = None
    for line in lines:
        beyond = other > line(coord)
        idx = np.flatnonzero(beyond) if idx is None else idx[beyond]
        if idx.shape[0] == 0:
            return
        codes[idx] += 1
        coord = coord[beyond]
        other = other[beyond]


def _parkes_codes(
    ref: NDArray[np.float64], pred: NDArray[np.float64], diabetes_type: int
) -> NDArray[np.int8]:
    uppers, lowers = _PARKES_COMPILED[diabetes_type]
    # The zone index is the number of lines the pair lies strictly beyond: above the
    # upper lines (pred > f(ref)) or right of the lower lines (ref > g(pred)). A pair
    # cannot be both: the upper A/B line lies above the diagonal, the lower one below.
    codes = np.zeros(ref.shape[0], dtype=np.int8)
    _add_crossings(uppers, ref, pred, codes)
    _add_crossings(lowers, pred, ref, codes)
    return codes


def _dts_codes(ref: NDArray[np.float64], pred: NDArray[np.float64]) -> NDArray[np.int8]:
    # As the Parkes grid: the zone is the number of nested borders the pair lies strictly
    # beyond, above the upper borders (pred > f(ref)) or right of the lower ones
    # (ref > g(pred)); the upper A/B border lies above the identity line and the lower
    # one below it, so no pair crosses borders on both sides.
    uppers, lowers = _DTS_COMPILED
    codes = np.zeros(ref.shape[0], dtype=np.int8)
    _add_crossings(uppers, ref, pred, codes)
    _add_crossings(lowers, pred, ref, codes)
    return codes


def _check_diabetes_type(diabetes_type: int) -> int:
    if isinstance(diabetes_type, bool) or diabetes_type not in PARKES_LINES:
        raise DataError(f"diabetes_type must be 1 or 2, got {diabetes_type!r}")
    return int(diabetes_type)


def _percentages_from_codes(codes: NDArray[np.integer]) -> dict[str, float]:
    counts = np.bincount(codes, minlength=len(ZONE_LABELS))
    total = codes.shape[0]
    return {label: float(100.0 * counts[i] / total) for i, label in enumerate(ZONE_LABELS)}


# --- public API ------------------------------------------------------------------------


def clarke_zones(y_true: ArrayLike, y_pred: ArrayLike, *, units: str = "mg/dL") -> NDArray[np.str_]:
    """Clarke error grid zone of each (reference, prediction) pair.

    Zones as defined by Clarke et al. (1987), in mg/dL (reference ``r`` on the x axis,
    prediction ``p`` on the y axis):

    * **A** -- within 20 % of the reference (``0.8 r <= p <= 1.2 r``), or both in the
      hypoglycaemic range (``r <= 70`` and ``p <= 70``).
    * **C** -- upper: ``70 <= r < 290`` and ``p > r + 110`` (above the line from
      (70, 180) to (290, 400)); lower: ``r <= 180`` and ``p < 7/5 r - 182`` (below the
      line from (130, 0) to (180, 70)).
    * **D** -- upper left: ``r < 70`` and ``max(70, 1.2 r) < p <= 180``; lower right:
      ``r > 240`` and ``70 <= p < 180``.
    * **E** -- ``r < 70`` and ``p > 180``, or ``r > 180`` and ``p < 70``.
    * **B** -- every other pair (upper and lower benign-error zones).

    Boundary convention: a pair exactly on a boundary line gets the less severe of the
    zones meeting there (A before B before C before D before E); so ``(100, 120)`` and
    ``(70, 70)`` are 'A', ``(70, 180)`` (on the C line and the D/E corner) is 'B',
    ``(50, 180)`` is 'D', ``(180, 50)`` is 'C'. The grid is drawn to 400 mg/dL; the
    upper C zone keeps its vertical right edge at ``r = 290`` (where the C line meets
    the top of the published plot), every other line is extended as drawn.

    Parameters
    ----------
    y_true : array_like
        Reference glucose, strictly positive. [mg/dL, or ``units``]
    y_pred : array_like
        Predicted glucose, non-negative, same length. [mg/dL, or ``units``]
    units : {"mg/dL", "mmol/L"}, optional
        Unit of both inputs; mmol/L values are converted with 18.016 mg/dL per mmol/L
        before zoning. [-]

    Returns
    -------
    numpy.ndarray
        Array of one-letter strings 'A'..'E', one per pair. [-]

    Raises
    ------
    DataError
        On a length mismatch, empty input, NaN or infinite values, a reference value
        <= 0, a negative prediction, or unknown ``units``.

    References
    ----------
    .. [1] Clarke WL, Cox D, Gonder-Frederick LA, Carter W, Pohl SL. Evaluating clinical
       accuracy of systems for self-monitoring of blood glucose. Diabetes Care
       10(5):622-628, 1987. doi:10.2337/diacare.10.5.622

    Examples
    --------
    >>> ref = [100, 100, 300, 100, 50, 50, 250]
    >>> clarke_zones(ref, [110, 150, 200, 250, 150, 250, 50]).tolist()
    ['A', 'B', 'B', 'C', 'D', 'E', 'E']
    """
    _unit_factor(units)
    ref, pred = _validate_pairs(y_true, y_pred, allow_negative_pred=False)
    ref, pred = _to_mgdl(ref, pred, units)
    return _LABEL_ARRAY[_clarke_codes(ref, pred)]


def parkes_zones(
    y_true: ArrayLike,
    y_pred: ArrayLike,
    *,
    diabetes_type: int = 1,
    units: str = "mg/dL",
) -> NDArray[np.str_]:
    """Parkes (consensus) error grid zone of each (reference, prediction) pair.

    The consensus error grid of Parkes et al. (2000) divides the plane into zones A
    (no effect on clinical action) to E (could have dangerous consequences), with
    separate grids for type 1 and type 2 diabetes. The boundary lines are the
    polylines published by Pfützner et al. (2013), stored in :data:`PARKES_LINES`
    (:data:`PARKES_TYPE1_LINES`, :data:`PARKES_TYPE2_LINES`), in mg/dL. A pair's zone
    is the number of nested lines it lies strictly beyond (above an "upper" line or
    to the right of a "lower" line). Beyond 550 mg/dL, the end of the published grid,
    every line continues along its last segment.

    Boundary convention: a pair exactly on a line gets the less severe zone (e.g. a
    pair on the type 1 A/B upper line, such as (140, 170), is 'A').

    Parameters
    ----------
    y_true : array_like
        Reference glucose, strictly positive. [mg/dL, or ``units``]
    y_pred : array_like
        Predicted glucose, non-negative, same length. [mg/dL, or ``units``]
    diabetes_type : {1, 2}, optional
        Which grid to use. [-]
    units : {"mg/dL", "mmol/L"}, optional
        Unit of both inputs; mmol/L values are converted with 18.016 mg/dL per mmol/L
        before zoning. [-]

    Returns
    -------
    numpy.ndarray
        Array of one-letter strings 'A'..'E', one per pair. [-]

    Raises
    ------
    DataError
        On a length mismatch, empty input, NaN or infinite values, a reference value
        <= 0, a negative prediction, unknown ``units`` or a ``diabetes_type`` other
        than 1 or 2.

    References
    ----------
    .. [1] Parkes JL, Slatin SL, Pardo S, Ginsberg BH. A new consensus error grid to
       evaluate the clinical significance of inaccuracies in the measurement of blood
       glucose. Diabetes Care 23(8):1143-1148, 2000. doi:10.2337/diacare.23.8.1143
    .. [2] Pfützner A, Klonoff DC, Pardo S, Parkes JL. Technical aspects of the Parkes
       error grid. J Diabetes Sci Technol 7(5):1275-1281, 2013.
       doi:10.1177/193229681300700517

    Examples
    --------
    >>> parkes_zones([100, 100, 100, 40, 20], [110, 150, 200, 140, 300]).tolist()
    ['A', 'B', 'C', 'D', 'E']
    """
    dtype = _check_diabetes_type(diabetes_type)
    _unit_factor(units)
    ref, pred = _validate_pairs(y_true, y_pred, allow_negative_pred=False)
    ref, pred = _to_mgdl(ref, pred, units)
    return _LABEL_ARRAY[_parkes_codes(ref, pred, dtype)]


def dts_zones(y_true: ArrayLike, y_pred: ArrayLike, *, units: str = "mg/dL") -> NDArray[np.str_]:
    """Diabetes Technology Society (DTS) error grid zone of each pair.

    The DTS error grid (Klonoff et al. 2024) has five risk zones, A (no risk) to E
    (extreme risk), the same for blood-glucose monitors and continuous glucose monitors,
    with straight-line borders. Each border runs flat (above the identity line) or
    vertical (below it) up to the 50 mg/dL corner and then straight to the edge of the
    published 0-600 mg/dL grid; the vertices are those of the paper's Table A1
    (Supplemental Appendix 2), stored in :data:`DTS_LINES`. Beyond 600 mg/dL each border
    continues along its last segment. The paper reports the share in zone A as the
    measure of clinical point accuracy and advises against pooling A + B.

    Boundary convention: a pair exactly on a border gets the less severe zone (e.g.
    ``(50, 60)`` and ``(500, 600)`` on the A/B upper border are 'A').

    Parameters
    ----------
    y_true : array_like
        Reference glucose, strictly positive. [mg/dL, or ``units``]
    y_pred : array_like
        Monitor / predicted glucose, non-negative, same length. [mg/dL, or ``units``]
    units : {"mg/dL", "mmol/L"}, optional
        Unit of both inputs; mmol/L values are converted with 18.016 mg/dL per mmol/L
        before zoning. [-]

    Returns
    -------
    numpy.ndarray
        Array of one-letter strings 'A'..'E', one per pair. [-]

    Raises
    ------
    DataError
        On a length mismatch, empty input, NaN or infinite values, a reference value
        <= 0, a negative prediction, or unknown ``units``.

    References
    ----------
    .. [1] Klonoff DC, Freckmann G, Pleus S, Kovatchev BP, Kerr D, et al. The Diabetes
       Technology Society Error Grid and Trend Accuracy Matrix for glucose monitors.
       J Diabetes Sci Technol 18(6):1346-1361, 2024. doi:10.1177/19322968241275701
       (Supplemental Appendix 2, Table A1: border coordinates).

    Examples
    --------
    >>> dts_zones([100, 100, 100, 100, 100], [110, 150, 190, 250, 400]).tolist()
    ['A', 'B', 'C', 'D', 'E']
    """
    _unit_factor(units)
    ref, pred = _validate_pairs(y_true, y_pred, allow_negative_pred=False)
    ref, pred = _to_mgdl(ref, pred, units)
    return _LABEL_ARRAY[_dts_codes(ref, pred)]


def zone_percentages(zones: ArrayLike) -> dict[str, float]:
    """Percentage of pairs in each error-grid zone.

    ``100 * count(zone) / total`` for each of the five zones of a Clarke, Parkes or DTS
    grid
    (the usual way error-grid results are reported, e.g. Clarke et al. 1987, Table 1).

    Parameters
    ----------
    zones : array_like of str
        One-dimensional, non-empty sequence of zone letters 'A'..'E' (upper case), as
        returned by :func:`clarke_zones`, :func:`parkes_zones` or :func:`dts_zones`. [-]

    Returns
    -------
    dict of str to float
        ``{'A': pct, 'B': pct, 'C': pct, 'D': pct, 'E': pct}``; all five keys are always
        present and the values sum to 100. [%]

    Raises
    ------
    DataError
        If ``zones`` is empty, not one-dimensional, or holds anything but 'A'..'E'.

    References
    ----------
    .. [1] Clarke WL, Cox D, Gonder-Frederick LA, Carter W, Pohl SL. Evaluating clinical
       accuracy of systems for self-monitoring of blood glucose. Diabetes Care
       10(5):622-628, 1987. doi:10.2337/diacare.10.5.622

    Examples
    --------
    >>> zone_percentages(["A", "A", "B", "E"])
    {'A': 50.0, 'B': 25.0, 'C': 0.0, 'D': 0.0, 'E': 25.0}
    """
    arr = np.asarray(zones)
    if arr.ndim != 1:
        raise DataError(f"zones must be one-dimensional, got shape {arr.shape}")
    if arr.shape[0] == 0:
        raise DataError("zones is empty; at least one zone label is needed")
    if arr.dtype.kind == "O":
        arr = np.array([z if isinstance(z, str) else "" for z in arr.tolist()])
    if arr.dtype.kind != "U":
        raise DataError(f"zones must be the letters {list(ZONE_LABELS)}, got dtype {arr.dtype}")
    if arr.dtype.itemsize != np.dtype("<U1").itemsize:
        # Longer strings: any element that is not a single character is invalid.
        long = np.char.str_len(arr) != 1
        arr = np.where(long, "", arr).astype("<U1")
    codes = np.ascontiguousarray(arr).view(np.uint32).astype(np.int64) - ord("A")
    bad = (codes < 0) | (codes >= len(ZONE_LABELS))
    if bad.any():
        count = int(np.count_nonzero(bad))
        first = int(np.argmax(bad))
        raise DataError(
            f"zones must contain only {list(ZONE_LABELS)}: {count} invalid "
            f"{'label' if count == 1 else 'labels'}, first at index {first} "
            f"({str(np.asarray(zones)[first])!r})"
        )
    return _percentages_from_codes(codes)
