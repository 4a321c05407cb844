"""Subject-grouped splits: no subject is ever in both the training and the test part.

Two protocols (:data:`PROTOCOLS`):

``"grouped-cv"``
    Repeated grouped K-fold: each repeat shuffles the subjects with its own seed and
    deals them into ``n_splits`` folds of (nearly) equal subject count; every snapshot
    is tested exactly once per repeat. Networks take their own inner validation split
    by subject from the training part.
``"paper-split"``
    The reference study's single 60/20/20 train/validation/test split by subject; the
    validation part is handed to the estimators that take one (early stopping,
    hyper-parameters). ``n_splits`` and ``repeats`` do not apply (one split).

Random numbers come from ``numpy.random.SeedSequence([seed, repeat])``, so the split of
a repeat does not depend on how many repeats are asked for.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..exceptions import ConfigError, unknown_name

__all__ = [
    "PROTOCOLS",
    "PAPER_FRACTIONS",
    "Split",
    "grouped_kfold",
    "paper_split",
    "make_splits",
    "check_protocol",
    "effective_layout",
]

#: Valid protocol names.
PROTOCOLS = ("grouped-cv", "paper-split")

#: The study's train / validation / test fractions of subjects.
PAPER_FRACTIONS = (0.6, 0.2, 0.2)

_SPLIT_STREAM = 0x5B117  # separates the split streams from every other use of the seed


@dataclass(frozen=True)
class Split:
    """One train/test split of row positions.

    Attributes
    ----------
    repeat, fold : int
        Position of the split in the protocol.
    train, test : numpy.ndarray of int
        Row positions (sorted).
    val : numpy.ndarray of int or None
        Row positions of an explicit validation part (``paper-split`` only).
    """

    repeat: int
    fold: int
    train: NDArray[np.intp]
    test: NDArray[np.intp]
    val: NDArray[np.intp] | None = None


def check_protocol(protocol: str) -> str:
    """Return ``protocol`` if valid, else raise ConfigError listing the valid names."""
    if protocol not in PROTOCOLS:
        raise ConfigError(unknown_name("protocol", protocol, PROTOCOLS))
    return protocol


def effective_layout(protocol: str, n_splits: int, repeats: int) -> tuple[int, int]:
    """``(n_splits, repeats)`` the protocol actually runs (``paper-split``: one split)."""
    check_protocol(protocol)
    return (1, 1) if protocol == "paper-split" else (int(n_splits), int(repeats))


def _rng(seed: int, repeat: int) -> np.random.Generator:
    return np.random.default_rng(np.random.SeedSequence([_SPLIT_STREAM, int(seed), int(repeat)]))


def _groups(groups: ArrayLike) -> tuple[NDArray, NDArray[np.intp]]:
    g = np.asarray(groups)
    if g.ndim != 1 or g.size == 0:
        raise ConfigError(f"groups must be a non-empty 1-D array, got shape {g.shape}")
    subjects, codes = np.unique(g, return_inverse=True)
    return subjects, codes.astype(np.intp)


def _rows(codes: NDArray[np.intp], chosen: NDArray[np.intp]) -> NDArray[np.intp]:
    return np.flatnonzero(np.isin(codes, chosen))


def grouped_kfold(
    groups: ArrayLike, n_splits: int = 5, repeats: int = 3, seed: int = 0
) -> list[Split]:
    """Repeated grouped K-fold splits.

    Parameters
    ----------
    groups : array_like
        Subject id of every row. [-]
    n_splits : int
        Folds per repeat, 2 to the number of subjects. [-]
    repeats : int
        Repeats, each a different seeded shuffle of the subjects. [-]
    seed : int
        Seed of the shuffles. [-]

    Returns
    -------
    list of Split
        ``repeats * n_splits`` splits, repeat-major.

    Examples
    --------
    >>> s = grouped_kfold([0, 0, 1, 1, 2, 2, 3, 3], n_splits=2, repeats=1)
    >>> len(s), sorted(len(x.test) for x in s)
    (2, [4, 4])
    """
    subjects, codes = _groups(groups)
    n_sub = len(subjects)
    if isinstance(n_splits, bool) or int(n_splits) != n_splits or not 2 <= n_splits <= n_sub:
        raise ConfigError(
            f"n_splits (--folds on the command line) must be an integer from 2 to the "
            f"{n_sub} subjects, got {n_splits!r}"
        )
    if isinstance(repeats, bool) or int(repeats) != repeats or repeats < 1:
        raise ConfigError(f"repeats must be a positive integer, got {repeats!r}")
    out = []
    for r in range(int(repeats)):
        order = _rng(seed, r).permutation(n_sub)
        for k, test_subjects in enumerate(np.array_split(order, int(n_splits))):
            test = _rows(codes, test_subjects)
            train = np.setdiff1d(np.arange(len(codes)), test)
            out.append(Split(repeat=r, fold=k, train=train, test=test))
    return out


def paper_split(
    groups: ArrayLike, seed: int = 0, fractions: tuple[float, float, float] = PAPER_FRACTIONS
) -> Split:
    """The study's single train/validation/test split by subject.

    Subject counts are ``round(fraction * n_subjects)`` for validation and test, the
    rest for training: with 80 subjects, 48 / 16 / 16 (48 test snapshots at 3 each).

    Examples
    --------
    >>> s = paper_split(np.repeat(np.arange(80), 3), seed=0)
    >>> len(s.train), len(s.val), len(s.test)
    (144, 48, 48)
    """
    subjects, codes = _groups(groups)
    n_sub = len(subjects)
    f = np.asarray(fractions, dtype=float)
    if f.shape != (3,) or np.any(f <= 0) or not np.isclose(f.sum(), 1.0):
        raise ConfigError(f"fractions must be three positive numbers summing to 1, got {fractions}")
    n_val, n_test = (max(1, int(round(x * n_sub))) for x in f[1:])
    if n_sub - n_val - n_test < 1:
        raise ConfigError(f"paper-split needs at least 3 subjects, got {n_sub}")
    order = _rng(seed, 0).permutation(n_sub)
    test = _rows(codes, order[:n_test])
    val = _rows(codes, order[n_test : n_test + n_val])
    train = _rows(codes, order[n_test + n_val :])
    return Split(repeat=0, fold=0, train=train, test=test, val=val)


def make_splits(
    groups: ArrayLike,
    protocol: str = "grouped-cv",
    *,
    n_splits: int = 5,
    repeats: int = 3,
    seed: int = 0,
) -> list[Split]:
    """Splits of ``protocol`` (one of :data:`PROTOCOLS`).

    Raises
    ------
    ConfigError
        Unknown protocol (the message lists the valid ones), bad ``n_splits`` or
        ``repeats``.
    """
    check_protocol(protocol)
    if protocol == "paper-split":
        return [paper_split(groups, seed=seed)]
    return grouped_kfold(groups, n_splits=n_splits, repeats=repeats, seed=seed)
