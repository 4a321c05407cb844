"""Compiled passes of the truncated normal draw around its inverse normal CDF.

:func:`nirglucose.simulation._random.truncated_normal` maps uniforms u to
mean + sd ndtri(clip(a + u (b - a), E, 1 - E)), clipped to [low, high], with a and b the
normal CDF at the limits (inverse-CDF sampling, Devroye 1986, ch. 2). Its NumPy form
makes about ten passes over the values (and gathers a, b and the mean by group); these
two kernels make one pass before SciPy's ``ndtri`` and one after, the same operations in
the same order per value, so the same bits (a test holds them equal to the NumPy form,
which stays the reference).
:func:`count_at_or_below` is the look-up of the categorical draw
(:func:`nirglucose.simulation._random.categorical`); :func:`seed_sequence_state` a block
stream's seed words (:class:`nirglucose.simulation._random.RandomStreams`).

``mode``: 0, a, b and the mean are one value (index 0); 1, one per value; 2, one per
group, value i taking ``group[i]``.
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["count_at_or_below", "probabilities", "scale_and_clip", "seed_sequence_state"]


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
