"""Small network fits run on one torch thread, whatever the caller's count (issue 27)."""

from __future__ import annotations

import pytest
import torch

import nirglucose as ng
from nirglucose.models import SDNN, _training
from nirglucose.models._training import SMALL_FIT_ROWS, training_threads


@pytest.fixture
def two_threads():
    """The caller runs torch on 2 threads (any machine can set it); restored after."""
    before = torch.get_num_threads()
    torch.set_num_threads(2)
    yield
    torch.set_num_threads(before)


def test_one_thread_below_the_bound_and_restored(two_threads):
    with training_threads(SMALL_FIT_ROWS - 1) as n:
        assert n == torch.get_num_threads() == 1
    assert torch.get_num_threads() == 2
    with training_threads(SMALL_FIT_ROWS) as n:  # large data: the caller's choice
        assert n == torch.get_num_threads() == 2
    with pytest.raises(RuntimeError), training_threads(10):
        raise RuntimeError("a failed fit")
    assert torch.get_num_threads() == 2


def test_small_fit_runs_on_one_thread_and_gives_the_caller_its_threads_back(
    two_threads, monkeypatch
):
    ds = ng.simulate("wearable", 8, 2, seed=0)
    seen = []
    step = SDNN.train_step
    monkeypatch.setattr(
        SDNN, "train_step", lambda self, b: seen.append(torch.get_num_threads()) or step(self, b)
    )
    a = SDNN(max_epochs=3, random_state=0).fit(ds)
    assert seen == [1, 1, 1] and torch.get_num_threads() == 2
    torch.set_num_threads(1)
    b = SDNN(max_epochs=3, random_state=0).fit(ds)
    sa, sb = a.module_.state_dict(), b.module_.state_dict()
    assert all(torch.equal(sa[k], sb[k]) for k in sa)  # the caller's count changes nothing


def test_bound_is_read_at_fit_time(two_threads, monkeypatch):
    """Large fits keep the caller's threads (the bound moved below this data's rows)."""
    monkeypatch.setattr(_training, "SMALL_FIT_ROWS", 4)
    seen = []
    step = SDNN.train_step
    monkeypatch.setattr(
        SDNN, "train_step", lambda self, b: seen.append(torch.get_num_threads()) or step(self, b)
    )
    SDNN(max_epochs=2, random_state=0).fit(ng.simulate("wearable", 4, 2, seed=0))
    assert seen == [2, 2]
