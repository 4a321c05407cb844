"""nirglucose.libm: the C library's exp, vectorised, the same bits."""

from __future__ import annotations

import hashlib
import math

import numpy as np
import pytest
from numba import njit

from nirglucose import portable
from nirglucose.libm import exp, exp1, exp_into, exp_table

#: sha256 of glibc 2.36's ``__exp_data.tab`` (256 little-endian uint64), read from the
#: loaded libm with gdb (``x/256gx ((char*)&__exp_data)+112``) on the development machine;
#: and three of its entries, as a worked example of the table's definition.
GLIBC_TABLE_SHA256 = "a4014caf214c2bab90ea0fdf3f57941e0235ae04dc2282a6c2f72e7a480c87e4"
GLIBC_ENTRIES = {2: 0x3C9B3B4F1A88BF6E, 3: 0x3FEFF63DA9FB3335, 200: 0xBC68D6F438AD9334,
                 201: 0x3FEEFF76F2FB5E47, 254: 0x3C5305C14160CC89, 255: 0x3FEFF3C22B8F71F1}


def test_table_is_glibcs():
    table = exp_table().view(np.uint64)
    assert {i: int(table[i]) for i in GLIBC_ENTRIES} == GLIBC_ENTRIES
    assert hashlib.sha256(table.astype("<u8").tobytes()).hexdigest() == GLIBC_TABLE_SHA256


def _c_exp(x):
    """The C library's exp (:mod:`nirglucose.portable`), overflow to inf without a warning."""
    with np.errstate(over="ignore"):
        return portable.exp(x)


def _bits_equal(a, b) -> int:
    """How many values differ in their bits."""
    return int((np.asarray(a).view(np.int64) != np.asarray(b).view(np.int64)).sum())


@pytest.mark.parametrize("low, high", [(-60.0, 1.0), (-745.2, 709.8), (-1e-3, 1e-3),
                                       (-1e-15, 1e-15)])
def test_equals_the_c_library(low, high):
    x = np.random.default_rng(7).uniform(low, high, 250_000)
    assert _bits_equal(exp(x), _c_exp(x)) == 0


def test_equals_the_c_library_at_the_edges():
    tiny = 2.0 ** -54
    edges = [0.0, -0.0, 5e-324, -5e-324, tiny, -tiny, 512.0, -512.0, 709.78, 709.79, -708.4,
             -745.1, -745.2, -746.0, 1000.0, -1000.0, math.log(2) / 256, 1.0, -1.0,
             np.inf, -np.inf]
    x = np.array(edges + [np.nextafter(v, d) for v in (tiny, -tiny, 512.0, -512.0)
                          for d in (-np.inf, np.inf)])
    y = exp(x)
    assert _bits_equal(y, _c_exp(x)) == 0
    assert math.isnan(exp(np.array([np.nan]))[0])


def test_the_work_arrays_may_be_longer_and_shapes_are_kept():
    x = np.linspace(-5.0, 5.0, 101)
    out = np.empty(101)
    exp_into(x, out, np.empty(200), np.empty(200), np.empty(200, np.int64))
    assert _bits_equal(out, _c_exp(x)) == 0
    grid = x[:100].reshape(10, 10)
    assert exp(grid).shape == (10, 10)
    assert _bits_equal(exp(grid), _c_exp(grid)) == 0


@njit(cache=True)
def _exp1_each(x, out):
    for i in range(x.shape[0]):
        out[i] = exp1(x[i])


def test_the_one_value_form_equals_the_c_library():
    x = np.concatenate([np.random.default_rng(3).uniform(-745.2, 709.8, 200_000),
                        [0.0, 2.0 ** -60, 600.0, -800.0, np.inf, -np.inf]])
    out = np.empty_like(x)
    _exp1_each(x, out)
    assert _bits_equal(out, _c_exp(x)) == 0
