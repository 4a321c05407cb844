"""A compiled layer against its NumPy reference: one block simulated each way, compared
byte for byte (the simulation kernels' tests)."""

from __future__ import annotations

import numpy as np

from nirglucose.simulation import simulator


def block_with(module, name: str, compiled: bool, cfg, seed: int, block: int, first: int,
               n_sub: int, monkeypatch):
    """One block's columns and variate count with ``module.name`` called as
    ``compiled=compiled`` (the compiled layer or its NumPy reference)."""
    orig = getattr(module, name)
    monkeypatch.setattr(module, name, lambda *args, **kwargs: orig(*args, compiled=compiled))
    try:
        return simulator.simulate_block(cfg, seed, block, first, n_sub, 3)
    finally:
        monkeypatch.setattr(module, name, orig)


def assert_same_block(want: tuple, got: tuple) -> None:
    """The same draws, the same columns in order, every numeric column's bytes equal."""
    (cols_want, n_want), (cols_got, n_got) = want, got
    assert n_got == n_want  # the same draws
    assert list(cols_got) == list(cols_want)
    for col in cols_want:
        a, b = np.asarray(cols_want[col]), np.asarray(cols_got[col])
        if a.dtype.kind in "fiu":
            assert a.dtype == b.dtype and a.tobytes() == b.tobytes(), col
