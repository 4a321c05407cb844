"""Subject-grouped splits never leak a subject; the protocols and their errors."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from nirglucose.evaluation.splits import (
    PROTOCOLS,
    effective_layout,
    grouped_kfold,
    make_splits,
    paper_split,
)
from nirglucose.exceptions import ConfigError


@st.composite
def layouts(draw):
    sizes = draw(st.lists(st.integers(1, 5), min_size=3, max_size=30))
    labels = draw(st.permutations(list(range(len(sizes)))))
    groups = np.repeat(np.asarray(labels) * 7 + 3, sizes)  # arbitrary, non-contiguous ids
    order = draw(st.permutations(list(range(len(groups)))))
    return groups[np.asarray(order)]


@settings(max_examples=60, deadline=None)
@given(
    groups=layouts(),
    n_splits=st.integers(2, 6),
    repeats=st.integers(1, 3),
    seed=st.integers(0, 2**31),
)
def test_grouped_kfold_never_leaks_and_covers_each_row_once_per_repeat(
    groups, n_splits, repeats, seed
):
    n_splits = min(n_splits, len(np.unique(groups)))
    splits = grouped_kfold(groups, n_splits=n_splits, repeats=repeats, seed=seed)
    assert len(splits) == n_splits * repeats
    for s in splits:
        assert not set(groups[s.train]) & set(groups[s.test])
        assert len(s.train) + len(s.test) == len(groups)
        assert len(s.test) > 0 and len(s.train) > 0
    for r in range(repeats):
        tested = np.concatenate([s.test for s in splits if s.repeat == r])
        assert np.array_equal(np.sort(tested), np.arange(len(groups)))


@settings(max_examples=60, deadline=None)
@given(groups=layouts(), seed=st.integers(0, 2**31))
def test_paper_split_parts_are_disjoint_by_subject(groups, seed):
    s = paper_split(groups, seed=seed)
    parts = [set(groups[s.train]), set(groups[s.val]), set(groups[s.test])]
    assert all(parts)
    assert not (parts[0] & parts[1] or parts[0] & parts[2] or parts[1] & parts[2])
    assert len(s.train) + len(s.val) + len(s.test) == len(groups)


def test_paper_split_matches_the_study_sizes():
    s = paper_split(np.repeat(np.arange(80), 3), seed=0)
    assert (len(s.train), len(s.val), len(s.test)) == (144, 48, 48)


def test_splits_are_seeded_and_a_repeat_does_not_depend_on_the_number_of_repeats():
    g = np.repeat(np.arange(20), 2)
    a = grouped_kfold(g, 4, repeats=1, seed=5)
    b = grouped_kfold(g, 4, repeats=3, seed=5)
    for x, y in zip(a, b[:4], strict=True):
        assert np.array_equal(x.test, y.test)
    assert not np.array_equal(b[0].test, b[4].test)  # another shuffle per repeat
    c = grouped_kfold(g, 4, repeats=1, seed=6)
    assert any(not np.array_equal(x.test, y.test) for x, y in zip(a, c, strict=True))


def test_make_splits_protocols():
    g = np.repeat(np.arange(10), 3)
    assert len(make_splits(g, "grouped-cv", n_splits=5, repeats=2)) == 10
    (one,) = make_splits(g, "paper-split", n_splits=5, repeats=3)
    assert one.val is not None
    assert effective_layout("paper-split", 5, 3) == (1, 1)
    assert set(PROTOCOLS) == {"grouped-cv", "paper-split"}


def test_unknown_protocol_lists_the_valid_ones():
    with pytest.raises(ConfigError, match="grouped-cv, paper-split"):
        make_splits([0, 1, 2], "loo")


@pytest.mark.parametrize("kwargs", [{"n_splits": 1}, {"n_splits": 11}, {"repeats": 0}])
def test_bad_layout_raises(kwargs):
    with pytest.raises(ConfigError):
        grouped_kfold(np.arange(10), **{"n_splits": 2, "repeats": 1, **kwargs})
