"""Random streams: one generator per (block of subjects, named stream), counted.

Randomness enters once, as ``seed``. Subjects are grouped in fixed blocks of
:data:`BLOCK_SUBJECTS`; each block and each named stream (one per layer or noise
source) gets its own :class:`numpy.random.SeedSequence` child, keyed by the block index
and a stable hash of the stream name. Hence

* the output does not depend on how blocks are grouped into chunks or workers, and
* switching one noise source off leaves every other source's draws unchanged, so its
  variance contribution can be removed exactly.
"""

from __future__ import annotations

import functools
import zlib

import numpy as np
import pandas as pd
from scipy.special import ndtr, ndtri

__all__ = [
    "BLOCK_SUBJECTS", "RandomStreams", "SubjectStreams", "categorical", "categories",
    "truncated_normal",
]

#: Subjects per random block (a chunk holds whole blocks).
BLOCK_SUBJECTS = 4096


class _Counted:
    """A Generator proxy that counts the variates it draws.

    The block's draws (``normal``, ``random``, ``uniform``, ``beta``, ``lognormal``) are
    methods of the class, the rest through ``__getattr__``: a block makes about 45
    draws, and a closure built per draw costs more than some of them."""

    __slots__ = ("_gen", "_owner")

    def __init__(self, gen: np.random.Generator, owner: RandomStreams) -> None:
        self._gen = gen
        self._owner = owner

    def _count(self, out):
        self._owner.n_variates += out.size if isinstance(out, np.ndarray) else int(np.size(out))
        return out

    def normal(self, *args, size=None, **kwargs):
        if args or kwargs:
            return self._count(self._gen.normal(*args, size=size, **kwargs))
        # N(0, 1): NumPy's normal returns 0.0 + 1.0 z of the same ziggurat draw z
        # (random_normal: loc + scale z), which is z + 0.0 bit for bit (-0.0 becomes
        # +0.0); without the multiply-add's extra cost per variate
        out = self._gen.standard_normal(size=size)
        if isinstance(out, np.ndarray):
            out += 0.0
        else:
            out = out + 0.0
        return self._count(out)

    def random(self, *args, size=None, **kwargs):
        return self._count(self._gen.random(*args, size=size, **kwargs))

    def uniform(self, *args, size=None, **kwargs):
        return self._count(self._gen.uniform(*args, size=size, **kwargs))

    def beta(self, *args, size=None, **kwargs):
        return self._count(self._gen.beta(*args, size=size, **kwargs))

    def lognormal(self, *args, size=None, **kwargs):
        return self._count(self._gen.lognormal(*args, size=size, **kwargs))

    def __getattr__(self, name: str):
        method = getattr(self._gen, name)

        def draw(*args, size=None, **kwargs):
            return self._count(method(*args, size=size, **kwargs))

        return draw


class RandomStreams:
    """Named, independent random generators of one block of subjects.

    Parameters
    ----------
    seed : int
        The scenario seed.
    block : int
        Index of the block of subjects.

    Examples
    --------
    >>> a = RandomStreams(0, 3)("shot").normal(size=2)
    >>> b = RandomStreams(0, 3)("shot").normal(size=2)
    >>> bool((a == b).all())
    True
    """

    def __init__(self, seed: int, block: int) -> None:
        self.seed = int(seed)
        self.block = int(block)
        self.n_variates = 0
        self._cache: dict[str, _Counted] = {}

    def __call__(self, name: str) -> _Counted:
        if name not in self._cache:
            key = zlib.crc32(name.encode("utf-8"))
            ss = _block_seed(self.seed, self.block, key)
            self._cache[name] = _Counted(np.random.Generator(np.random.PCG64(ss)), self)
        return self._cache[name]


class _SeedWords:
    """A seed sequence that is its words: what ``PCG64`` takes from a
    :class:`numpy.random.SeedSequence` (``generate_state(4, np.uint64)``), computed
    before (:func:`_block_seed`)."""

    __slots__ = ("words",)

    def __init__(self, words: np.ndarray) -> None:
        self.words = words

    def generate_state(self, n_words: int, dtype=np.uint32) -> np.ndarray:
        if n_words != 4 or np.dtype(dtype) != np.uint64:
            raise ValueError("a block stream's seed holds 4 uint64 words only")
        return self.words.copy()


np.random.bit_generator.ISeedSequence.register(_SeedWords)


def _block_seed(seed: int, block: int, key: int):
    """``SeedSequence(seed, spawn_key=(block, key))`` as ``PCG64`` seeds from it: where
    all three fit 32 bits, its 4 state words from the compiled hash (the same words, a
    test holds them equal; about a tenth of the cost of building the SeedSequence and
    drawing them from it, which a block pays for each of its 19 streams); else the
    SeedSequence itself."""
    if 0 <= seed < 2**32 and 0 <= block < 2**32 and 0 <= key < 2**32:
        from .kernels.random_kernel import seed_sequence_state

        return _SeedWords(seed_sequence_state(seed, block, key))
    return np.random.SeedSequence(seed, spawn_key=(block, key))


class SubjectStreams(RandomStreams):
    """Named random generators of one subject (the wear simulation's per-reading draws).

    Keyed by ``(WEAR, subject_id, name)`` (a three-part spawn key, so never one of the
    two-part keys of :class:`RandomStreams`' blocks): a subject's draws are the same
    whichever chunk or worker simulates it.

    Examples
    --------
    >>> a = SubjectStreams(0, 7)("shot").normal(size=2)
    >>> bool((a == SubjectStreams(0, 7)("shot").normal(size=2)).all())
    True
    >>> bool((a == SubjectStreams(0, 8)("shot").normal(size=2)).any())
    False
    """

    _TAG = zlib.crc32(b"wear")

    def __init__(self, seed: int, subject_id: int) -> None:
        super().__init__(seed, -1)
        self.subject_id = int(subject_id)

    def __call__(self, name: str) -> _Counted:
        if name not in self._cache:
            key = zlib.crc32(name.encode("utf-8"))
            ss = np.random.SeedSequence(self.seed, spawn_key=(self._TAG, self.subject_id, key))
            self._cache[name] = _Counted(np.random.Generator(np.random.PCG64(ss)), self)
        return self._cache[name]


def truncated_normal(
    rng: _Counted | np.random.Generator,
    mean: np.ndarray | float,
    sd: np.ndarray | float,
    low: float,
    high: float,
    size: int,
    *,
    group: np.ndarray | None = None,
) -> np.ndarray:
    """Draw from N(mean, sd) truncated to [low, high] by inverse-CDF sampling.

    One uniform per value (no rejection loop), so the number of variates is fixed.
    With ``sd == 0`` it returns ``mean`` (which must lie in the range).

    ``group`` (optional, with a scalar ``sd``): ``mean`` is given per group and value i
    has mean ``mean[group[i]]``; the truncation probabilities are then computed once per
    group. The values equal those of ``truncated_normal(rng, mean[group], ...)`` exactly.
    """
    u = rng.random(size=size)
    mean_a = np.asarray(mean, dtype=float)
    sd_a = np.asarray(sd, dtype=float)
    if group is not None and (sd_a.ndim != 0 or mean_a.ndim != 1):
        raise ValueError("group needs a scalar sd and one mean per group")
    if sd_a.ndim == 0 and mean_a.ndim <= 1:
        return _truncated_normal_scalar_sd(u, mean_a, float(sd_a), low, high, size, group)
    mean = np.broadcast_to(mean_a, (size,))
    sd = np.broadcast_to(sd_a, (size,))
    safe_sd = np.where(sd > 0, sd, 1.0)
    a = ndtr((low - mean) / safe_sd)
    b = ndtr((high - mean) / safe_sd)
    p = np.clip(a + u * (b - a), _P_EDGE, 1 - _P_EDGE)
    out = mean + safe_sd * ndtri(p)
    out = np.where(sd > 0, out, mean)
    # Numerical safety only (inverse CDF can land a rounding error outside).
    return np.minimum(np.maximum(out, low), high)


#: Keeps the inverse normal CDF finite: p in [1e-15, 1 - 1e-15] (|z| <= 7.9). [-]
_P_EDGE = 1e-15


def _truncated_normal_scalar_sd(u, mean, sd, low, high, size, group=None, *, compiled=True):
    """:func:`truncated_normal` for one SD (the common case), in place: the same
    operations in the same order, so the same values to the last bit. ``compiled``: one
    compiled pass, ``ndtri`` included (:mod:`nirglucose.simulation.kernels.random_kernel`),
    the same bits; False: the NumPy form below, the reference."""
    if compiled and sd > 0:
        return _truncated_normal_compiled(u, mean, sd, low, high, size, group)
    if sd <= 0:
        out = np.array(np.broadcast_to(mean if group is None else mean[group], (size,)),
                       dtype=float)
    else:
        if mean.ndim == 0:
            a = float(ndtr((low - mean) / sd))
            p = u * (float(ndtr((high - mean) / sd)) - a)
            p += a
        else:
            # truncation probabilities, once per group when the mean is per group
            a = np.subtract(low, mean)
            a /= sd
            ndtr(a, out=a)
            p = np.subtract(high, mean)
            p /= sd
            ndtr(p, out=p)
            if group is not None:
                a, p = a[group], p[group]
            p -= a
            p *= u
            p += a
        np.maximum(p, _P_EDGE, out=p)
        np.minimum(p, 1 - _P_EDGE, out=p)
        out = ndtri(p, out=p)
        out *= sd
        out += mean if group is None else mean[group]
    np.maximum(out, low, out=out)
    np.minimum(out, high, out=out)
    return out


def categorical(rng, probs, size: int, *, compiled: bool = True) -> np.ndarray:
    """``rng.choice(len(probs), p=probs, size=size)``, the same draws and the same values.

    NumPy's ``Generator.choice`` with ``p`` (sampling with replacement) draws
    ``rng.random(size)`` and returns ``cdf.searchsorted(u, side="right")`` with
    ``cdf = p.cumsum(); cdf /= cdf[-1]`` (numpy/random/_generator.pyx); this does the
    same, the look-up compiled (one pass counting the ``cdf`` values at or below each
    uniform, about ten times faster than the binary search over a handful of categories;
    ``compiled=False``: ``searchsorted``, the reference). ``probs`` is checked as NumPy
    checks it (1-D, finite, non-negative, summing to 1 within sqrt(eps)).

    Examples
    --------
    >>> a = categorical(np.random.default_rng(0), [0.2, 0.5, 0.3], 5)
    >>> b = np.random.default_rng(0).choice(3, p=[0.2, 0.5, 0.3], size=5)
    >>> bool((a == b).all())
    True
    """
    p = np.asarray(probs, dtype=np.float64)
    if (p.ndim != 1 or not p.size or not np.all(np.isfinite(p)) or np.any(p < 0)
            or abs(float(p.sum()) - 1.0) > np.sqrt(np.finfo(np.float64).eps)):
        raise ValueError("probabilities must be 1-D, non-negative and sum to 1")
    cdf = p.cumsum()
    cdf /= cdf[-1]
    u = rng.random(size=size)
    if not compiled:
        return np.asarray(cdf.searchsorted(u, side="right"), dtype=np.int64)
    from .kernels import random_kernel as rk

    out = np.empty(np.shape(u), np.int64)
    rk.count_at_or_below(np.ravel(u), cdf, out.reshape(-1))
    return out


@functools.lru_cache(maxsize=32)
def categories(names: tuple[str, ...]) -> pd.CategoricalDtype:
    """The categorical dtype of a drawn label column (``pd.Categorical.from_codes(codes,
    dtype=categories(names))``), built once per set of names: building it validates
    the names, which costs more than the column (the same dtype either way).

    Examples
    --------
    >>> categories(("sun", "led")) is categories(("sun", "led"))
    True
    """
    return pd.CategoricalDtype(list(names))


def _truncated_normal_compiled(u, mean, sd, low, high, size, group):
    """:func:`_truncated_normal_scalar_sd` (``sd > 0``) in one compiled pass per value
    (:func:`nirglucose.simulation.kernels.random_kernel.truncated_normal_limits`, its
    ``ndtr`` and ``ndtri`` SciPy's bit for bit), a and b (the normal CDF at the limits)
    included, from the same operations as the reference's."""
    from .kernels import random_kernel as rk

    if mean.ndim == 0:
        means, mode = np.array([float(mean)]), 0
    else:
        means, mode = np.ascontiguousarray(mean, dtype=np.float64), 1 if group is None else 2
    index = np.empty(0, np.int64) if group is None else np.asarray(group, dtype=np.int64)
    out = np.empty(size)
    rk.truncated_normal_limits(u, index, mode, _P_EDGE, 1 - _P_EDGE, float(sd), means,
                               float(low), float(high), out)
    return out
