"""Compiled truncated normal draw, its normal CDF and inverse included.

:func:`nirglucose.simulation._random.truncated_normal` maps uniforms u to
mean + sd ndtri(clip(a + u (b - a), E, 1 - E)), clipped to [low, high], with a and b the
normal CDF at the limits (inverse-CDF sampling, Devroye 1986, ch. 2). Its NumPy form
makes about ten passes over the values (and gathers a, b and the mean by group);
:func:`truncated_normal` makes one, by blocks that stay in the L1 cache, the same
operations in the same order per value, with :func:`ndtri` the Cephes algorithm that
SciPy's ``ndtri`` runs, written with the same operations in the same order (and, by
blocks, vectorised but for the C library's ``log``): so the same bits (tests hold
:func:`ndtri` and :func:`ndtri_into` equal to ``scipy.special.ndtri`` and the draw equal
to the NumPy form, which stays the reference).
:func:`truncated_normal_limits` computes a and b too, with :func:`ndtr` (Cephes'
algorithm that SciPy's ``ndtr`` runs, the same way: a test holds :func:`ndtr` and
:func:`ndtr_into` equal to ``scipy.special.ndtr``), per value within each block or
once per mean, where the NumPy form takes a pass of SciPy's ``ndtr`` for each limit.
:func:`probabilities` and :func:`scale_and_clip` are its parts before and after the
inverse CDF as passes of their own (with SciPy's ``ndtri`` between them, the former
compiled form, which a test holds :func:`truncated_normal` equal to).
:func:`count_at_or_below` is the look-up of the categorical draw
(:func:`nirglucose.simulation._random.categorical`); :func:`seed_sequence_state` a block
stream's seed words (:class:`nirglucose.simulation._random.RandomStreams`).

``mode``: 0, a, b and the mean are one value (index 0); 1, one per value; 2, one per
group, value i taking ``group[i]``.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ...libm import exp1, exp_into

__all__ = [
    "count_at_or_below", "ndtr", "ndtr_into", "ndtri", "ndtri_into", "probabilities",
    "scale_and_clip",
    "seed_sequence_state", "truncated_normal", "truncated_normal_limits",
]


@njit(cache=True, inline="always")
def _at(mode, group, i):
    if mode == 0:
        return 0
    if mode == 1:
        return i
    return group[i]


@njit(cache=True, nogil=True, error_model="numpy")
def probabilities(u, a, b, group, mode, p_low, p_high, out):  # pragma: no cover - compiled
    """``out[i] = clip(a + u[i] (b - a), p_low, p_high)`` with a, b taken by ``mode``."""
    for i in range(u.shape[0]):
        g = _at(mode, group, i)
        p = u[i] * (b[g] - a[g]) + a[g]
        if p < p_low:
            p = p_low
        if p > p_high:
            p = p_high
        out[i] = p


@njit(cache=True, nogil=True, error_model="numpy")
def scale_and_clip(z, sd, mean, group, mode, low, high):  # pragma: no cover - compiled
    """In place, ``z[i] = clip(z[i] sd + mean, low, high)`` with the mean taken by
    ``mode``."""
    for i in range(z.shape[0]):
        x = z[i] * sd + mean[_at(mode, group, i)]
        if x < low:
            x = low
        if x > high:
            x = high
        z[i] = x


#: The inverse normal CDF's coefficients and constants: Cephes' ndtri.c (S. L. Moshier,
#: Cephes Math Library Release 2.1, 1989), as SciPy 1.17 carries them (xsf,
#: ``include/xsf/cephes/ndtri.h``; ``SQRT2PI`` from ``cephes/const.h``), highest power
#: first; the Q tables omit their leading coefficient 1. P0/Q0: x / sqrt(2 pi) = w + w^3
#: P0(w^2) / Q0(w^2), w = y - 1/2, for exp(-2) < y < 1 - exp(-2); P1/Q1 and P2/Q2: the tail,
#: x = t - log(t) / t - P(1/t) / (t Q(1/t)), t = sqrt(-2 log y), for t < 8 (y > exp(-32))
#: and t >= 8.
_NDTRI_P0 = (-5.99633501014107895267e1, 9.80010754185999661536e1, -5.66762857469070293439e1,
             1.39312609387279679503e1, -1.23916583867381258016e0)
_NDTRI_Q0 = (1.95448858338141759834e0, 4.67627912898881538453e0, 8.63602421390890590575e1,
             -2.25462687854119370527e2, 2.00260212380060660359e2, -8.20372256168333339912e1,
             1.59056225126211695515e1, -1.18331621121330003142e0)
_NDTRI_P1 = (4.05544892305962419923e0, 3.15251094599893866154e1, 5.71628192246421288162e1,
             4.40805073893200834700e1, 1.46849561928858024014e1, 2.18663306850790267539e0,
             -1.40256079171354495875e-1, -3.50424626827848203418e-2,
             -8.57456785154685413611e-4)
_NDTRI_Q1 = (1.57799883256466749731e1, 4.53907635128879210584e1, 4.13172038254672030440e1,
             1.50425385692907503408e1, 2.50464946208309415979e0, -1.42182922854787788574e-1,
             -3.80806407691578277194e-2, -9.33259480895457427372e-4)
_NDTRI_P2 = (3.23774891776946035970e0, 6.91522889068984211695e0, 3.93881025292474443415e0,
             1.33303460815807542389e0, 2.01485389549179081538e-1, 1.23716634817820021358e-2,
             3.01581553508235416007e-4, 2.65806974686737550832e-6, 6.23974539184983293730e-9)
_NDTRI_Q2 = (6.02427039364742014255e0, 3.67983563856160859403e0, 1.37702099489081330271e0,
             2.16236993594496635890e-1, 1.34204006088543189037e-2, 3.28014464682127739104e-4,
             2.89247864745380683936e-6, 6.79019408009981274425e-9)
_SQRT_2PI = 2.506628274631000502415765284811045253007
_EXP_M2 = 0.13533528323661269189  # exp(-2), Cephes' literal
_TAIL_SPLIT = 8.0  # t = sqrt(-2 log y) where the tail's P1/Q1 hands over to P2/Q2


@njit(cache=True, inline="always")
def _polevl(x, coef):
    """Cephes' ``polevl``: Horner's rule from the highest power, ``ans = ans x + c``."""
    ans = coef[0]
    for k in range(1, len(coef)):
        ans = ans * x + coef[k]
    return ans


@njit(cache=True, inline="always")
def _p1evl(x, coef):
    """Cephes' ``p1evl``: :func:`_polevl` with a leading coefficient 1 not stored."""
    ans = x + coef[0]
    for k in range(1, len(coef)):
        ans = ans * x + coef[k]
    return ans


@njit(cache=True, inline="always", error_model="numpy")
def _ndtri_central(y):
    """:func:`ndtri` for exp(-2) < y <= 1 - exp(-2): sqrt(2 pi) (w + w^3 P0(w^2) /
    Q0(w^2)), w = y - 1/2 (Cephes' ndtri.c)."""
    y = y - 0.5
    y2 = y * y
    x = y + y * (y2 * _polevl(y2, _NDTRI_P0) / _p1evl(y2, _NDTRI_Q0))
    return x * _SQRT_2PI


@njit(cache=True, inline="always", error_model="numpy")
def _ndtri_tail(x, log_x):
    """:func:`ndtri`'s lower tail (y <= exp(-2)) after its logs: x - log(x) / x -
    P(1/x) / (x Q(1/x)), x = sqrt(-2 log y), ``log_x`` = log(x), P/Q = P1/Q1 for x < 8
    (y > exp(-32)), P2/Q2 beyond (Cephes' ndtri.c)."""
    x0 = x - log_x / x
    z = 1.0 / x
    if x < _TAIL_SPLIT:
        x1 = z * _polevl(z, _NDTRI_P1) / _p1evl(z, _NDTRI_Q1)
    else:
        x1 = z * _polevl(z, _NDTRI_P2) / _p1evl(z, _NDTRI_Q2)
    return x0 - x1


@njit(cache=True, nogil=True, error_model="numpy")
def ndtri(y0):  # pragma: no cover - compiled
    """The inverse of the standard normal CDF, ``scipy.special.ndtri`` bit for bit.

    Parameters
    ----------
    y0 : float
        A probability [-].

    Returns
    -------
    float
        x with Phi(x) = y0 [-]: -inf at 0, inf at 1, NaN outside [0, 1].

    Notes
    -----
    Cephes' ndtri (S. L. Moshier, Cephes Math Library Release 2.1, 1989; the algorithm
    and coefficients SciPy 1.17's ``scipy.special.ndtri`` runs, from its xsf headers,
    ``cephes/ndtri.h`` and ``cephes/polevl.h``): a rational approximation in
    w = y - 1/2 for exp(-2) < y < 1 - exp(-2), else in 1/t with t = sqrt(-2 log y) on
    the nearer tail. The same IEEE 754 operations in the same order as SciPy's compiled
    loop (its disassembly shows no fused multiply-add; numba fuses none without
    ``fastmath``), ``log`` the C library's (the one SciPy calls) and ``sqrt`` correctly
    rounded: so the same bits (a test holds them equal; a NaN input comes out as the
    NaN SciPy gives, sign flipped by the tail's negation as there).
    """
    if y0 == 0.0:
        return -np.inf
    if y0 == 1.0:
        return np.inf
    if y0 < 0.0 or y0 > 1.0:
        return np.nan
    negate = True
    y = y0
    if y > 1.0 - _EXP_M2:
        y = 1.0 - y
        negate = False
    if y > _EXP_M2:
        return _ndtri_central(y)
    x = math.sqrt(-2.0 * math.log(y))
    x = _ndtri_tail(x, math.log(x))
    if negate:
        x = -x
    return x


#: Values per block of :func:`ndtri_into` and :func:`truncated_normal`: their scratch
#: arrays (:func:`_scratch`, about 40 bytes a value) stay in the L1 cache. [-]
_BLOCK = 512


@njit(cache=True, inline="always")
def _scratch():
    """:func:`_ndtri_block`'s work arrays: a value's class (0: central, 1: tail, 2: the
    rest), the tail's and the rest's positions, and three values per tail value."""
    return (np.empty(_BLOCK, np.int8), np.empty((2, _BLOCK), np.int64),
            np.empty((3, _BLOCK)))


@njit(cache=True, inline="always", error_model="numpy")
def _ndtri_block(y, out, scratch):
    """``out[j] = ndtri(y[j])`` for a block of at most :data:`_BLOCK` values.

    :func:`ndtri`'s steps regrouped so that the compiler vectorises all but the C
    library's ``log`` (each value still gets the same IEEE 754 operations in the same
    order, so the same bits): the central approximation for every value (one branch-free
    loop); the tail values' positions gathered (no branch to mispredict); their two
    ``log`` and the ``sqrt`` between them value by value; the rest of their tail
    formula, both of its approximations computed and one kept, in one loop; last,
    :func:`ndtri` itself for the rest (0, 1, out of [0, 1], NaN).
    """
    kind, where, work = scratch
    m = y.shape[0]
    hi = 1.0 - _EXP_M2
    for j in range(m):
        y0 = y[j]
        yf = 1.0 - y0 if y0 > hi else y0
        kind[j] = 0 if yf > _EXP_M2 else (1 if yf > 0.0 else 2)
        out[j] = _ndtri_central(yf)
    n_tail = n_rest = 0
    for j in range(m):
        where[0, n_tail] = j
        n_tail += kind[j] == 1
        where[1, n_rest] = j
        n_rest += kind[j] == 2
    for t in range(n_tail):
        y0 = y[where[0, t]]
        x = math.sqrt(-2.0 * math.log(1.0 - y0 if y0 > hi else y0))
        work[0, t] = x
        work[1, t] = math.log(x)
        work[2, t] = y0 > hi  # 1: the upper tail, not negated
    for t in range(n_tail):
        x = _ndtri_tail(work[0, t], work[1, t])
        work[0, t] = x if work[2, t] != 0.0 else -x
    for t in range(n_tail):
        out[where[0, t]] = work[0, t]
    for t in range(n_rest):
        out[where[1, t]] = ndtri(y[where[1, t]])


@njit(cache=True, nogil=True, error_model="numpy")
def ndtri_into(y, out):  # pragma: no cover - compiled
    """``out[i] = ndtri(y[i])``: :func:`ndtri` over an array, by blocks of
    :data:`_BLOCK` (:func:`_ndtri_block`)."""
    scratch = _scratch()
    for start in range(0, y.shape[0], _BLOCK):
        stop = min(start + _BLOCK, y.shape[0])
        _ndtri_block(y[start:stop], out[start:stop], scratch)


#: The normal CDF's coefficients and constants: Cephes' ndtr.c (S. L. Moshier, Cephes Math
#: Library Release 2.2, 1992), as SciPy 1.17 carries them (xsf, ``include/xsf/cephes/
#: ndtr.h``; ``MAXLOG`` from ``cephes/const.h``; the bits read back from SciPy's compiled
#: ``_special_ufuncs`` module equal these), highest power first; the Q tables omit their
#: leading coefficient 1. T/U: erf(x) = x T(x^2) / U(x^2) for abs(x) <= 1; P/Q and R/S:
#: erfc(x) = exp(-x^2) P(x) / Q(x) for 1 <= x < 8 and R(x) / S(x) for x >= 8.
_NDTR_T = (9.60497373987051638749e0, 9.00260197203842689217e1, 2.23200534594684319226e3,
           7.00332514112805075473e3, 5.55923013010394962768e4)
_NDTR_U = (3.35617141647503099647e1, 5.21357949780152679795e2, 4.59432382970980127987e3,
           2.26290000613890934246e4, 4.92673942608635921086e4)
_NDTR_P = (2.46196981473530512524e-10, 5.64189564831068821977e-1, 7.46321056442269912687e0,
           4.86371970985681366614e1, 1.96520832956077098242e2, 5.26445194995477358631e2,
           9.34528527171957607540e2, 1.02755188689515710272e3, 5.57535335369399327526e2)
_NDTR_Q = (1.32281951154744992508e1, 8.67072140885989742329e1, 3.54937778887819891062e2,
           9.75708501743205489753e2, 1.82390916687909736289e3, 2.24633760818710981792e3,
           1.65666309194161350182e3, 5.57535340817727675546e2)
_NDTR_R = (5.64189583547755073984e-1, 1.27536670759978104416e0, 5.01905042251180477414e0,
           6.16021097993053585195e0, 7.40974269950448939160e0, 2.97886665372100240670e0)
_NDTR_S = (2.26052863220117276590e0, 9.39603524938001434673e0, 1.20489539808096656605e1,
           1.70814450747565897222e1, 9.60896809063285878198e0, 3.36907645100081516050e0)
#: erfc's four polynomials as two of nine coefficients each, for :func:`_ndtr_block`'s
#: coefficient-by-coefficient choice: R/S padded with leading zeros (0 x + 0 = 0 and
#: 0 x + 1 = 1 exactly for finite x, so Horner's rule then runs Cephes' steps), the
#: monic Q and S with their 1 written out (1 x + c = x + c: ``p1evl``'s first step).
_ERFC_NUM = (_NDTR_P, (0.0, 0.0, 0.0) + _NDTR_R)
_ERFC_DEN = ((1.0,) + _NDTR_Q, (0.0, 0.0, 1.0) + _NDTR_S)
_SQRT1_2 = 7.07106781186547524401e-1  # M_SQRT1_2
_MAXLOG = 7.09782712893383996843e2  # Cephes' MAXLOG: log(DBL_MAX)
_ERFC_SPLIT = 8.0  # erfc's P/Q hands over to R/S


@njit(cache=True, inline="always", error_model="numpy")
def _erf_small(x):
    """Cephes' erf for abs(x) <= 1: x T(x^2) / U(x^2) (ndtr.c)."""
    z = x * x
    return x * _polevl(z, _NDTR_T) / _p1evl(z, _NDTR_U)


@njit(cache=True, inline="always", error_model="numpy")
def _erfc_large(x):
    """Cephes' erfc for 1 <= x (ndtr.c): exp(-x^2) P(x) / Q(x) below 8, R(x) / S(x)
    above, 0 where -x^2 < -MAXLOG; ``exp`` the C library's (:func:`nirglucose.libm.exp1`,
    the same bits)."""
    z = -x * x
    if z < -_MAXLOG:
        return 0.0
    z = exp1(z)
    if x < _ERFC_SPLIT:
        p = _polevl(x, _NDTR_P)
        q = _p1evl(x, _NDTR_Q)
    else:
        p = _polevl(x, _NDTR_R)
        q = _p1evl(x, _NDTR_S)
    y = (z * p) / q
    return y if y != 0.0 else 0.0


@njit(cache=True, nogil=True, error_model="numpy")
def ndtr(a):  # pragma: no cover - compiled
    """The standard normal CDF, ``scipy.special.ndtr`` bit for bit.

    Parameters
    ----------
    a : float
        The argument [-].

    Returns
    -------
    float
        Phi(a) [-]: 0 at -inf, 1 at inf, NaN (the quiet NaN 0x7ff8...) at NaN.

    Notes
    -----
    Cephes' ndtr (S. L. Moshier, Cephes Math Library Release 2.2, 1992; the algorithm
    and coefficients SciPy 1.17's ``scipy.special.ndtr`` runs, ``xsf::cephes::ndtr``
    from its xsf headers, ``cephes/ndtr.h`` and ``cephes/polevl.h``): with
    x = a / sqrt(2) (a times M_SQRT1_2), 1/2 + erf(x) / 2 for abs(x) < 1, else
    erfc(abs(x)) / 2, taken from 1 for x > 0. The same IEEE 754 operations in the same order
    as SciPy's compiled ``xsf::ndtr(double)`` (its disassembly: no fused multiply-add,
    ``erf`` inlined, ``exp`` the C library's through the PLT), ``exp`` the C library's
    bits (:func:`nirglucose.libm.exp1`): so the same bits (a test holds them equal).
    SciPy's erf for x < 0 is -erf(-x), which is x T(x^2) / U(x^2) to the bit (rounding is
    symmetric in sign).
    """
    if a != a:
        return np.nan
    x = a * _SQRT1_2
    z = abs(x)
    if z < 1.0:
        return 0.5 + 0.5 * _erf_small(x)
    y = 0.5 * _erfc_large(z)
    if x > 0.0:
        y = 1.0 - y
    return y


@njit(cache=True, inline="always")
def _ndtr_scratch():
    """:func:`_ndtr_block`'s work arrays: the exponent's argument and value, and
    :func:`nirglucose.libm.exp_into`'s three."""
    return np.empty((4, _BLOCK)), np.empty(_BLOCK, np.int64)


@njit(cache=True, inline="always", error_model="numpy")
def _ndtr_block(t, out, scratch):
    """``out[j] = ndtr(t[j])`` for a block of at most :data:`_BLOCK` values (``out`` may
    be ``t``).

    :func:`ndtr`'s branches as choices, so that the compiler vectorises the loops: the
    exponent's argument -x^2 where erfc needs it (-1 elsewhere, which keeps
    :func:`nirglucose.libm.exp_into` on its vectorised path); the exponentials
    (:func:`nirglucose.libm.exp_into`, the C library's bits); then per value both erf's
    and erfc's formulas, erfc's coefficients chosen one by one (:data:`_ERFC_NUM`,
    :data:`_ERFC_DEN`), and the one :func:`ndtr` takes kept. Each value gets the same
    IEEE 754 operations as in :func:`ndtr`, so the same bits.
    """
    work, k = scratch
    m = t.shape[0]
    for j in range(m):
        z = abs(t[j] * _SQRT1_2)
        e = -z * z
        work[0, j] = e if z >= 1.0 and e >= -_MAXLOG else -1.0
    exp_into(work[0, :m], work[1, :m], work[2, :m], work[3, :m], k[:m])
    for j in range(m):
        a = t[j]
        x = a * _SQRT1_2
        z = abs(x)
        c = 0.5 + 0.5 * _erf_small(x)
        small = z < _ERFC_SPLIT
        p = _ERFC_NUM[0][0] if small else _ERFC_NUM[1][0]
        q = 1.0 if small else 0.0
        for i in range(1, 9):
            p = p * z + (_ERFC_NUM[0][i] if small else _ERFC_NUM[1][i])
            q = q * z + (_ERFC_DEN[0][i] if small else _ERFC_DEN[1][i])
        y = (work[1, j] * p) / q
        if -z * z < -_MAXLOG:
            y = 0.0
        y = 0.5 * y
        if x > 0.0:
            y = 1.0 - y
        if z < 1.0:
            y = c
        out[j] = y if a == a else np.nan


@njit(cache=True, nogil=True, error_model="numpy")
def ndtr_into(t, out):  # pragma: no cover - compiled
    """``out[i] = ndtr(t[i])``: :func:`ndtr` over an array (``out`` may be ``t``), by
    blocks of :data:`_BLOCK` (:func:`_ndtr_block`)."""
    scratch = _ndtr_scratch()
    for start in range(0, t.shape[0], _BLOCK):
        stop = min(start + _BLOCK, t.shape[0])
        _ndtr_block(t[start:stop], out[start:stop], scratch)


@njit(cache=True, inline="always", error_model="numpy")
def _draw_block(u, a, b, group, mode, p_low, p_high, sd, mean, low, high, p, z,
                scratch):
    """:func:`truncated_normal` for one block: ``z[j]`` from ``u[j]``, with a, b, the
    mean and the group indices those of the block (mode 1) or all (modes 0 and 2)."""
    probabilities(u, a, b, group, mode, p_low, p_high, p)
    _ndtri_block(p[:u.shape[0]], z, scratch)
    scale_and_clip(z, sd, mean, group, mode, low, high)


@njit(cache=True, nogil=True, error_model="numpy")
def truncated_normal(u, a, b, group, mode, p_low, p_high, sd, mean, low,
                     high, out):  # pragma: no cover - compiled
    """``out[i] = clip(ndtri(clip(a + u[i] (b - a), p_low, p_high)) sd + mean, low,
    high)`` with a, b and the mean taken by ``mode``: :func:`probabilities`,
    :func:`ndtri` and :func:`scale_and_clip` by blocks of :data:`_BLOCK` values (the
    same operations in the same order per value, so the same bits as the three passes)."""
    p = np.empty(_BLOCK)
    scratch = _scratch()
    for start in range(0, u.shape[0], _BLOCK):
        stop = min(start + _BLOCK, u.shape[0])
        # mode 1: the block's own a, b and means; mode 2: its group indices into them
        a_s, b_s, mean_s = (a[start:stop], b[start:stop], mean[start:stop]) if mode == 1 \
            else (a, b, mean)
        group_s = group[start:stop] if mode == 2 else group
        _draw_block(u[start:stop], a_s, b_s, group_s, mode, p_low, p_high, sd, mean_s, low,
                    high, p, out[start:stop], scratch)


@njit(cache=True, inline="always", error_model="numpy")
def _cdf_at(limit, mean, sd, out, scratch):
    """``out[j] = ndtr((limit - mean[j]) / sd)`` for a block of at most :data:`_BLOCK`
    values: the NumPy form's ``np.subtract(limit, mean); a /= sd``, then
    :func:`_ndtr_block` in place."""
    for j in range(mean.shape[0]):
        out[j] = (limit - mean[j]) / sd
    _ndtr_block(out, out, scratch)


@njit(cache=True, nogil=True, error_model="numpy")
def truncated_normal_limits(u, group, mode, p_low, p_high, sd, mean, low, high,
                            out):  # pragma: no cover - compiled
    """:func:`truncated_normal` with a and b computed here: a = ndtr((low - mean) / sd)
    and b = ndtr((high - mean) / sd) (:func:`ndtr`, SciPy's bits), per value within
    each block (mode 1) or once per mean before the draw (modes 0 and 2)."""
    p = np.empty(_BLOCK)
    scratch, cdf_scratch = _scratch(), _ndtr_scratch()
    n_par = _BLOCK if mode == 1 else mean.shape[0]
    a, b = np.empty(n_par), np.empty(n_par)
    if mode != 1:
        for start in range(0, n_par, _BLOCK):
            stop = min(start + _BLOCK, n_par)
            _cdf_at(low, mean[start:stop], sd, a[start:stop], cdf_scratch)
            _cdf_at(high, mean[start:stop], sd, b[start:stop], cdf_scratch)
    for start in range(0, u.shape[0], _BLOCK):
        stop = min(start + _BLOCK, u.shape[0])
        a_s, b_s, mean_s = a, b, mean
        if mode == 1:  # the block's own means, a and b
            mean_s = mean[start:stop]
            a_s, b_s = a[:stop - start], b[:stop - start]
            _cdf_at(low, mean_s, sd, a_s, cdf_scratch)
            _cdf_at(high, mean_s, sd, b_s, cdf_scratch)
        group_s = group[start:stop] if mode == 2 else group
        _draw_block(u[start:stop], a_s, b_s, group_s, mode, p_low, p_high, sd, mean_s, low,
                    high, p, out[start:stop], scratch)


@njit(cache=True, nogil=True)
def count_at_or_below(u, cdf, out):  # pragma: no cover - compiled
    """``out[i]`` = the number of ``cdf`` values at or below ``u[i]``: for a sorted
    ``cdf``, ``cdf.searchsorted(u, side="right")`` (a test holds them equal), in one pass
    with no binary search (a categorical draw has a handful of categories)."""
    k = cdf.shape[0]
    for i in range(u.shape[0]):
        x = u[i]
        c = 0
        for j in range(k):
            if cdf[j] <= x:
                c += 1
        out[i] = c


#: numpy.random.SeedSequence's hash constants (NumPy's bit_generator.pyx, after
#: M. E. O'Neill's seed_seq_fe, "Developing a seed_seq Alternative", 2015). The arithmetic
#: below is uint32's, done in uint64 (numba widens uint32 operands) and masked to 32 bits.
_INIT_A, _MULT_A = np.uint64(0x43B0D7E5), np.uint64(0x931E8875)
_INIT_B, _MULT_B = np.uint64(0x8B51F9DD), np.uint64(0x58F38DED)
_MIX_L, _MIX_R = np.uint64(0xCA01F9DD), np.uint64(0x4973F715)
_MASK, _SHIFT = np.uint64(0xFFFFFFFF), np.uint64(16)


@njit(cache=True, inline="always")
def _hashmix(value, hash_const):
    """SeedSequence's hashmix: (the mixed value, the next hash constant)."""
    value ^= hash_const
    hash_const = (hash_const * _MULT_A) & _MASK
    value = (value * hash_const) & _MASK
    return value ^ (value >> _SHIFT), hash_const


@njit(cache=True, inline="always")
def _mix(x, y):
    result = (_MIX_L * x - _MIX_R * y) & _MASK
    return result ^ (result >> _SHIFT)


@njit(cache=True, nogil=True)
def seed_sequence_state(seed, block, key):  # pragma: no cover - compiled
    """``SeedSequence(seed, spawn_key=(block, key)).generate_state(4, np.uint64)`` for
    ``seed``, ``block`` and ``key`` in [0, 2**32) (a test holds them equal): its entropy
    is then the words seed, 0, 0, 0 (the run entropy padded to the pool's 4 words), block
    and key, mixed into a pool of 4 and drawn out as 8 words."""
    entropy = np.zeros(6, np.uint64)
    entropy[0], entropy[4], entropy[5] = seed, block, key
    pool = np.empty(4, np.uint64)
    h = _INIT_A
    for i in range(4):
        pool[i], h = _hashmix(entropy[i], h)
    for src in range(4):
        for dst in range(4):
            if src != dst:
                v, h = _hashmix(pool[src], h)
                pool[dst] = _mix(pool[dst], v)
    for src in range(4, 6):
        for dst in range(4):
            v, h = _hashmix(entropy[src], h)
            pool[dst] = _mix(pool[dst], v)
    words = np.empty(8, np.uint32)
    h = _INIT_B
    for i in range(8):
        v = pool[i % 4] ^ h
        h = (h * _MULT_B) & _MASK
        v = (v * h) & _MASK
        words[i] = v ^ (v >> _SHIFT)
    return words.view(np.uint64)
