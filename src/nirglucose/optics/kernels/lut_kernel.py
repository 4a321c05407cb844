"""Compiled kernel of the rte-lut fast path: R(rho) at every (row, node) in one call.

:func:`nirglucose.optics.lut.interpolate_node_lut` is the public entry; this module holds
only the numba kernel it calls, compiled for one signature and cached on disk
(``cache=True``: a fresh process loads it in well under a second; the first compile
ever takes a few seconds), and imported lazily so that ``import nirglucose`` does not
import numba.

The kernel does what the numpy reference (``nirglucose.optics.lut.interpolate.
_interpolate_node_lut_numpy``) does in a few dozen array passes over the whole slice,
chunk by chunk of about 400 points, so that its scratch stays in the CPU's L1/L2 cache:

1. coordinates: the cell index and the fraction along each of the five axes (log, sqrt
   and linear coordinates, two-piece axes) and the step along ``musp_ratio``, in small
   loops the compiler vectorises (ln by :func:`_log`, arithmetic only); a point outside
   the table's box (NaN included) on any axis stops the kernel;
2. gather: for each of the 16 corners of the first four axes, the two (ln R, slope)
   float32 pairs along the thickness axis (adjacent in the table: one 16-byte stretch)
   are read in one 16-byte load and interpolated as they come (:func:`_lerp_at`);
3. multilinear: four halvings of the corners (axes 3, 2, 1, 0), value and slope
   interleaved, in float32 (vectorised); steps 2 and 3 are the numpy reference's
   complex64 operations in the same order, so ln R comes out bit for bit the same;
4. ln R = value + (q - q_node) slope along ``musp_ratio``, and R = exp(ln R) by
   :func:`_exp` (arithmetic only, vectorised; within 4e-16 of ``math.exp``).
"""

from __future__ import annotations

import math

import numpy as np
from llvmlite import ir
from numba import njit, types
from numba.extending import intrinsic

from ...libm import float_bits, from_bits

__all__ = ["KERNEL_AXES", "node_reflectance"]

#: Coordinates of the node table's axes, in order, that the kernel hard-codes:
#: mus'_dermis (log), mua_dermis (sqrt), mua_subcutis (sqrt), mua_epidermis (linear),
#: skin transport thickness mus'_dermis x thickness (log). The musp_ratio axis (linear)
#: is folded into each node's value and slope.
KERNEL_AXES = ("log", "sqrt", "sqrt", "linear", "log")

#: Points per chunk (rounded to whole rows): the chunk's scratch (16 corner words, five
#: fractions twice, cell, index, ratio step: about 230 bytes a point) then stays in the
#: L1/L2 cache (measured: 96 to 768 points are within 10 % of each other).
_CHUNK_POINTS = 384

_R64 = types.Array(types.float64, 1, "C", readonly=True)
_SIGNATURE = types.int64(
    types.Array(types.int64, 1, "C", readonly=True),  # table
    types.int64,  # n_cells
    _R64,  # ratio
    types.Array(types.float64, 2, "C", readonly=True),  # axis_f
    types.Array(types.int64, 2, "C", readonly=True),  # axis_i
    _R64, _R64, _R64, _R64, _R64, _R64,  # mua_d, mua_s, mua_e, ln t, mus'_s, mus'_d
    types.Array(types.float64, 1, "C"),  # out
)


@intrinsic
def _lerp_at(typingctx, table, p, f):
    """a + (b - a) f for the (value, slope) float32 pairs a = table[p], b = table[p + 1].

    The two 8-byte words are read as one 16-byte load, and the lerp runs on both float32
    lanes at once: the same float32 operations, lane by lane, as the numpy reference's
    complex64 lerp. Returns the result's pair as an int64 word.
    """
    quad = ir.VectorType(ir.FloatType(), 4)
    pair = ir.VectorType(ir.FloatType(), 2)
    lane = ir.IntType(32)

    def codegen(context, builder, signature, args):
        data = context.make_array(signature.args[0])(context, builder, args[0]).data
        ptr = builder.bitcast(builder.gep(data, [args[1]]), quad.as_pointer())
        both = builder.load(ptr, align=8)
        va = builder.shuffle_vector(both, both, ir.Constant(ir.VectorType(lane, 2), [0, 1]))
        vb = builder.shuffle_vector(both, both, ir.Constant(ir.VectorType(lane, 2), [2, 3]))
        vf = builder.insert_element(ir.Constant(pair, None), args[2], ir.Constant(lane, 0))
        vf = builder.insert_element(vf, args[2], ir.Constant(lane, 1))
        out = builder.fadd(builder.fmul(builder.fsub(vb, va), vf), va)
        return builder.bitcast(out, ir.IntType(64))

    return types.int64(table, types.int64, types.float32), codegen


_LN2_HI = 6.93147180369123816490e-01  # ln 2 = _LN2_HI + _LN2_LO (fdlibm's split)
_LN2_LO = 1.90821492927058770002e-10
_ROUND = 6755399441055744.0  # 1.5 * 2^52: x + _ROUND rounds x to an integer in the low bits
_TWO52 = 4503599627370496.0


@njit(cache=True, inline="always", error_model="numpy")
def _exp(x):
    """exp(x) for |x| <= 700 in arithmetic only (so loops of it vectorise): 2^k e^r.

    k = round(x / ln 2), r = x - k ln 2 with |r| <= ln(2) / 2, e^r by its Taylor series
    to r^12 (truncation below 2e-16); 2^k from its bits. Within 4e-16 of math.exp.
    """
    x = min(max(x, -700.0), 700.0)
    k_round = x * 1.4426950408889634 + _ROUND
    k = k_round - _ROUND
    r = (x - k * _LN2_HI) - k * _LN2_LO
    p = 1.0 / 479001600.0
    for d in (39916800.0, 3628800.0, 362880.0, 40320.0, 5040.0, 720.0, 120.0, 24.0, 6.0,
              2.0, 1.0, 1.0):
        p = p * r + 1.0 / d
    return p * from_bits((float_bits(k_round) - float_bits(_ROUND) + 1023) << 52)


@njit(cache=True, inline="always", error_model="numpy")
def _log(x):
    """ln(x) for finite x > 0 (normal) in arithmetic only: e ln 2 + 2 atanh(s).

    x = 2^e m with m in [sqrt(1/2), sqrt(2)), s = (m - 1) / (m + 1), atanh by its series
    to s^19 (truncation below 3e-16). Within 5e-16 of math.log. Zero, negative, NaN,
    infinite and subnormal x give NaN or |ln x| > 700, never a value inside a table.
    """
    b = float_bits(x)
    e = from_bits((b >> 52) | 0x4330000000000000) - (_TWO52 + 1023.0)
    m = from_bits((b & 0x000FFFFFFFFFFFFF) | 0x3FF0000000000000)  # [1, 2)
    big = np.float64(m > 1.4142135623730951)  # then halve m, and count one more 2
    m = m * (1.0 - 0.5 * big)
    e = e + big
    s = (m - 1.0) / (m + 1.0)
    z = s * s
    p = 1.0 / 19.0
    for d in (17.0, 15.0, 13.0, 11.0, 9.0, 7.0, 5.0, 3.0, 1.0):
        p = p * z + 1.0 / d
    return e * _LN2_HI + (2.0 * s * p + e * _LN2_LO)


@njit(cache=True, nogil=True, boundscheck=False, error_model="numpy")
def _log_into(src, start, cnt, u):
    """u[e] = ln src[start + e] (vectorised)."""
    for e in range(cnt):
        u[e] = _log(src[start + e])


@njit(cache=True, nogil=True, boundscheck=False, error_model="numpy")
def _sqrt_into(src, start, cnt, u):
    """u[e] = sqrt(src[start + e]) (vectorised)."""
    for e in range(cnt):
        u[e] = math.sqrt(src[start + e])


@njit(cache=True, nogil=True, boundscheck=False, error_model="numpy")
def _sum_into(a, b, start, cnt, u):
    """u[e] = a[e] + b[start + e] (vectorised)."""
    for e in range(cnt):
        u[e] = a[e] + b[start + e]


@njit(cache=True, nogil=True, boundscheck=False, error_model="numpy")
def _ratio_step(musp_s, musp_d, start, cnt, node_q, u0, inv_h, lo, hi, dq):
    """dq = mus'_s / mus'_d - the node's ratio (vectorised); the count inside the box."""
    inside = 0
    for e in range(cnt):
        q = musp_s[start + e] / musp_d[start + e]
        dq[e] = q - node_q[e]
        pos = (q - u0) * inv_h
        inside += (pos >= lo) & (pos <= hi)  # False for NaN
    return inside


@njit(cache=True, nogil=True, boundscheck=False, error_model="numpy")
def _to_int(cell, cnt, base):
    """base[e] = int(cell[e]) (vectorised)."""
    for e in range(cnt):
        base[e] = np.int64(cell[e])


@njit(cache=True, nogil=True, boundscheck=False, error_model="numpy")
def _reflectance_into(v, dq, start, cnt, out):
    """out[start + e] = exp(value + dq slope) (vectorised)."""
    for e in range(cnt):
        out[start + e] = _exp(np.float64(v[0, 2 * e]) + dq[e] * np.float64(v[0, 2 * e + 1]))


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
def node_reflectance(table, n_cells, ratio, axis_f, axis_i, mua_d, mua_s, mua_e, ln_thickness,
                     musp_s, musp_d, out):
    """R(rho) at every point of the simulator's layout, written to ``out``.

    Points are the flattened (n_rows, n_nodes) grid, row-major: point g belongs to node
    g % n_nodes. One long function on purpose: it is the compiled chunk loop, whose
    scratch arrays must stay in local variables of one numba function to stay in the
    CPU cache (module docstring).

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
    ln_musp = np.empty(m)
    base = np.empty(m, dtype=np.int64)
    dq = np.empty(m)
    frac = np.empty((5, 2 * m), dtype=np.float32)  # each fraction twice: value, slope
    words = np.empty((16, m), dtype=np.int64)
    v = words.view(np.float32)  # (16, 2 m): value and slope of each corner, interleaved
    for start in range(0, n_points, m):
        cnt = min(m, n_points - start)
        # 1. cells and fractions; count the points inside the box on each axis
        inside = _ratio_step(musp_s, musp_d, start, cnt, node_q, axis_f[5, 0], axis_f[5, 1],
                             lo[5], hi[5], dq)
        cell[:cnt] = node_base[:cnt]
        _log_into(musp_d, start, cnt, ln_musp)
        for a in range(5):  # coordinates: ln mus'_d, sqrt mua_d, sqrt mua_s, mua_e, ln(mus'_d t)
            if a == 0:
                src, first = ln_musp, 0
            elif a == 3:
                src, first = mua_e, start
            else:
                if a == 4:
                    _sum_into(ln_musp, ln_thickness, start, cnt, u)
                else:
                    _sqrt_into(mua_d if a == 1 else mua_s, start, cnt, u)
                src, first = u, 0
            inside += _axis_cells(src, first, cnt, axis_f[a, 0], axis_f[a, 1], axis_f[a, 2],
                                  np.float64(axis_i[a, 0]), np.float64(axis_i[a, 1] - 2),
                                  np.float64(stride[a]), lo[a], hi[a], frac[a], cell)
        if inside != 6 * cnt:
            return start
        _to_int(cell, cnt, base)
        # 2. the 16 corners of axes 0-3 (axis 3 most significant), each interpolated along
        # the thickness axis (stride 1) from its two (value, slope) words as it is read
        for c in range(16):
            off = offsets[c]
            for e in range(cnt):
                p = base[e] + off
                words[c, e] = _lerp_at(table, p, frac[4, 2 * e])
        # 3. halve the corners along axes 3, 2, 1, 0 (value and slope interleaved)
        half = 16
        for a in (3, 2, 1, 0):
            half //= 2
            for c in range(half):
                for j in range(2 * cnt):
                    v[c, j] = v[c, j] + (v[c + half, j] - v[c, j]) * frac[a, j]
        # 4. the musp_ratio slope, and R
        _reflectance_into(v, dq, start, cnt, out)
    return -1
