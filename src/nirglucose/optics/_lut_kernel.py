"""Compiled kernel of the rte-lut fast path: R(rho) at every (row, node) in one call.

:func:`nirglucose.optics.lut.interpolate_node_lut` is the public entry; this module holds
only the numba kernel it calls, compiled for one signature and cached on disk
(``cache=True``: a fresh process loads it in a fraction of a second), and imported
lazily so that ``import nirglucose`` does not import numba.

The kernel does what the numpy reference (``nirglucose.optics.lut.
_interpolate_node_lut_numpy``) does in a few dozen array passes, chunk by chunk of
about 200 points so that every temporary stays in the L1 cache:

1. coordinates: the cell index and the fraction along each of the five axes (log, sqrt
   and linear coordinates, two-piece axes), in loops the compiler vectorises; any
   point outside the table's box (NaN included) stops the kernel;
2. gather: the (ln R, slope) pair of each of the 32 corners, as one 8-byte word each
   (the only scalar loop);
3. multilinear: five halvings of the corners, thickness axis first, value and slope
   interleaved, in float32 (vectorised); the same operations in the same order as the
   numpy reference on complex64, so ln R comes out bit for bit the same;
4. ln R = value + (q - q_node) slope along ``musp_ratio``, and R = exp(ln R).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, types

__all__ = ["KERNEL_AXES", "node_reflectance"]

#: Coordinates of the node table's axes, in order, that the kernel hard-codes:
#: mus'_dermis (log), mua_dermis (sqrt), mua_subcutis (sqrt), mua_epidermis (linear),
#: skin transport thickness mus'_dermis x thickness (log). The musp_ratio axis (linear)
#: is folded into each node's value and slope.
KERNEL_AXES = ("log", "sqrt", "sqrt", "linear", "log")

#: Points per chunk (rounded to whole rows): the chunk's scratch (32 corner words, five
#: fractions, index, slope step per point, about 300 bytes) then fits the L1 cache.
_CHUNK_POINTS = 384

_R64 = types.Array(types.float64, 1, "C", readonly=True)
_SIGNATURE = types.int64(
    types.Array(types.int64, 1, "C", readonly=True),  # table
    types.int64,  # n_cells
    _R64,  # ratio
    types.Array(types.float64, 2, "C", readonly=True),  # axis_f
    types.Array(types.int64, 2, "C", readonly=True),  # axis_i
    # ln mus'_d, mua_d, mua_s, mua_e, ln t, mus'_s, mus'_d
    _R64, _R64, _R64, _R64, _R64, _R64, _R64,
    types.Array(types.float64, 1, "C"),  # out
)


@njit(cache=True, nogil=True, boundscheck=False, error_model="numpy")
def _coordinate(src, ln_thickness, start, cnt, add, u):
    """u = sqrt(src), or src + ln t (``add``), for ``cnt`` points from ``start``."""
    if add:
        for e in range(cnt):
            u[e] = src[start + e] + ln_thickness[start + e]
    else:
        for e in range(cnt):
            u[e] = math.sqrt(src[start + e])


@njit(cache=True, nogil=True, boundscheck=False, error_model="numpy")
def _axis_cells(u, first, cnt, u0, inv_h, h_ratio, n_low, last, step, lo, hi, frac, cell):
    """Fractions (each stored twice) and cell steps of ``cnt`` coordinates on one axis.

    Its own function, free of branches on the axis, so that the compiler vectorises
    the loop. Returns the number of points inside the axis' range.
    """
    inside = 0
    for e in range(cnt):
        pos = (u[first + e] - u0) * inv_h
        if pos > n_low:  # two-piece axis: the spacing changes past node n_low
            pos = n_low + (pos - n_low) * h_ratio
        j = min(max(math.floor(pos), 0.0), last)
        f = np.float32(pos - j)
        frac[2 * e] = f
        frac[2 * e + 1] = f
        cell[e] += j * step
        inside += (pos >= lo) & (pos <= hi)  # False for NaN
    return inside


@njit(_SIGNATURE, cache=True, nogil=True, boundscheck=False, error_model="numpy")
def node_reflectance(table, n_cells, ratio, axis_f, axis_i, ln_musp_d, mua_d, mua_s, mua_e,
                     ln_thickness, musp_s, musp_d, out):
    """R(rho) at every point of the simulator's layout, written to ``out``.

    Points are the flattened (n_rows, n_nodes) grid, row-major: point g belongs to node
    g % n_nodes.

    Parameters
    ----------
    table : ndarray
        int64, (n_nodes * n_cells,): the node table's (ln R [ln(1/cm^2)],
        d(ln R)/d(musp_ratio)) float32 pairs as raw 8-byte words (``NodeLUT.values``
        viewed as int64), cells C-ordered over the axes :data:`KERNEL_AXES`.
    n_cells : int
        Cells per node (product of the five axes' node counts). [-]
    ratio : ndarray
        (n_nodes,): mus'_subcutis / mus'_dermis the table was specialised at, per
        node. [-]
    axis_f : ndarray
        (6, 4) float64: per axis (the five of :data:`KERNEL_AXES`, then musp_ratio)
        ``u0``, ``1 / h_low``, ``h_low / h_high``, tolerance: node i sits at
        u0 + i h_low up to node ``n_low``, then h_high apart (in the axis' coordinate).
    axis_i : ndarray
        (6, 3) int64: per axis ``n_low``, node count, stride in cells.
    ln_musp_d : ndarray
        ln of the dermis' reduced scattering. [ln(1/cm)]
    mua_d, mua_s, mua_e : ndarray
        Absorption of dermis, subcutis and epidermis. [1/cm]
    ln_thickness : ndarray
        ln of the skin (epidermis + dermis) thickness. [ln cm]
    musp_s, musp_d : ndarray
        Reduced scattering of subcutis and dermis. [1/cm]
    out : ndarray
        Written: R(rho). [1/cm^2]

    Returns
    -------
    int
        -1, or the first point of a chunk that has a point outside the table's box on
        some axis (``out`` is then incomplete; the caller reports the axis).
    """
    n_points = out.size
    n_nodes = ratio.size
    stride = axis_i[:, 2]
    offsets = np.empty(16, dtype=np.int64)  # corners over axes 0-3, axis 3 most significant
    for c in range(16):
        offsets[c] = (((c >> 3) & 1) * stride[3] + ((c >> 2) & 1) * stride[2]
                      + ((c >> 1) & 1) * stride[1] + (c & 1) * stride[0])
    m = max(_CHUNK_POINTS // n_nodes, 1) * n_nodes
    node_base = np.empty(m)  # first cell of each point's node, and the node's ratio
    node_q = np.empty(m)
    for e in range(m):
        node_base[e] = (e % n_nodes) * n_cells
        node_q[e] = ratio[e % n_nodes]
    lo = np.empty(6)
    hi = np.empty(6)
    for a in range(6):
        lo[a] = -axis_f[a, 3]
        hi[a] = axis_i[a, 1] - 1 + axis_f[a, 3]
    cell = np.empty(m)
    u = np.empty(m)
    base = np.empty(m, dtype=np.int64)
    dq = np.empty(m)
    frac = np.empty((5, 2 * m), dtype=np.float32)  # each fraction twice: value, slope
    words = np.empty((32, m), dtype=np.int64)
    v = words.view(np.float32)  # (32, 2 m): value and slope of each corner, interleaved
    for start in range(0, n_points, m):
        cnt = min(m, n_points - start)
        # 1. cells and fractions; count the points inside the box on each axis
        inside = 0
        for e in range(cnt):
            q = musp_s[start + e] / musp_d[start + e]
            dq[e] = q - node_q[e]
            pos = (q - axis_f[5, 0]) * axis_f[5, 1]
            inside += (pos >= lo[5]) & (pos <= hi[5])
            cell[e] = node_base[e]
        for a in range(5):  # coordinates: ln mus'_d, sqrt mua_d, sqrt mua_s, mua_e, ln(mus'_d t)
            if a == 0 or a == 3:
                src, first = (ln_musp_d if a == 0 else mua_e), start
            else:
                _coordinate(mua_d if a == 1 else mua_s if a == 2 else ln_musp_d,
                            ln_thickness, start, cnt, a == 4, u)
                src, first = u, 0
            inside += _axis_cells(src, first, cnt, axis_f[a, 0], axis_f[a, 1], axis_f[a, 2],
                                  np.float64(axis_i[a, 0]), np.float64(axis_i[a, 1] - 2),
                                  np.float64(stride[a]), lo[a], hi[a], frac[a], cell)
        if inside != 6 * cnt:
            return start
        for e in range(cnt):
            base[e] = np.int64(cell[e])
        # 2. the 32 corners: thickness bit (stride 1) on top, then axes 3, 2, 1, 0
        for c in range(16):
            off = offsets[c]
            for e in range(cnt):
                p = base[e] + off
                words[c, e] = table[p]
                words[c + 16, e] = table[p + 1]
        # 3. halve the corners along thickness, then axes 3, 2, 1, 0
        half = 32
        for a in (4, 3, 2, 1, 0):
            half //= 2
            for c in range(half):
                for j in range(2 * cnt):
                    v[c, j] = v[c, j] + (v[c + half, j] - v[c, j]) * frac[a, j]
        # 4. the musp_ratio slope, and R
        for e in range(cnt):
            out[start + e] = math.exp(np.float64(v[0, 2 * e])
                                      + dq[e] * np.float64(v[0, 2 * e + 1]))
    return -1
