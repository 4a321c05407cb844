"""Compiled passes of the truncated normal draw around its inverse normal CDF.

:func:`nirglucose.simulation._random.truncated_normal` maps uniforms u to
mean + sd ndtri(clip(a + u (b - a), E, 1 - E)), clipped to [low, high], with a and b the
normal CDF at the limits (inverse-CDF sampling, Devroye 1986, ch. 2). Its NumPy form
makes about ten passes over the values (and gathers a, b and the mean by group); these
two kernels make one pass before SciPy's ``ndtri`` and one after, the same operations in
the same order per value, so the same bits (a test holds them equal to the NumPy form,
which stays the reference).
:func:`count_at_or_below` is the look-up of the categorical draw
(:func:`nirglucose.simulation._random.categorical`).

``mode``: 0, a, b and the mean are one value (index 0); 1, one per value; 2, one per
group, value i taking ``group[i]``.
"""

from __future__ import annotations

from numba import njit

__all__ = ["count_at_or_below", "probabilities", "scale_and_clip"]


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
