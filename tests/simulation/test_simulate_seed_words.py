"""A block stream's seed words equal NumPy's SeedSequence's, and so do its draws.

:class:`nirglucose.simulation._random.RandomStreams` seeds each named stream's PCG64 with
the words ``SeedSequence(seed, spawn_key=(block, crc32(name))).generate_state(4,
np.uint64)``, computed by a compiled hash
(:func:`nirglucose.simulation.kernels.random_kernel.seed_sequence_state`) where seed,
block and key fit 32 bits, else by the SeedSequence itself.
"""

from __future__ import annotations

import zlib

import numpy as np
import pytest

from nirglucose.simulation import _random
from nirglucose.simulation.kernels.random_kernel import seed_sequence_state

_EDGES = [(0, 0, 0), (2**32 - 1, 2**32 - 1, 2**32 - 1), (1, 0, 2**31), (0, 2**16, 65535)]
_DRAWN = [tuple(int(x) for x in row)
          for row in np.random.default_rng(7).integers(0, 2**32, size=(3000, 3))]


def _reference(seed, block, key):
    return np.random.SeedSequence(seed, spawn_key=(block, key)).generate_state(4, np.uint64)


def test_seed_words_equal_the_seed_sequence():
    for seed, block, key in _EDGES + _DRAWN:
        got = seed_sequence_state(seed, block, key)
        assert got.dtype == np.uint64
        assert got.tobytes() == _reference(seed, block, key).tobytes(), (seed, block, key)


@pytest.mark.parametrize(("seed", "block"), [(0, 0), (3, 17), (2**32 - 1, 5), (2**40, 2),
                                             (7, 2**33)])
def test_block_streams_draw_as_seeded_by_the_seed_sequence(seed, block):
    for name in ("glucose", "shot", "physiology.state", "led_flicker.cal"):
        key = zlib.crc32(name.encode("utf-8"))
        want = np.random.Generator(np.random.PCG64(
            np.random.SeedSequence(seed, spawn_key=(block, key)))).random(64)
        got = _random.RandomStreams(seed, block)(name).random(size=64)
        assert got.tobytes() == want.tobytes(), name


def test_seed_words_give_only_what_pcg64_asks():
    words = _random._SeedWords(seed_sequence_state(0, 1, 2))
    with pytest.raises(ValueError):
        words.generate_state(2, np.uint32)
    assert words.generate_state(4, np.uint64).tobytes() == _reference(0, 1, 2).tobytes()
