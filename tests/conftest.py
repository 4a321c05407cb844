"""Shared fixtures."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")

import pytest  # noqa: E402

import nirglucose as ng  # noqa: E402


@pytest.fixture(scope="session")
def paper_small():
    """A small paper-preset dataset (80 subjects x 3), seed 0."""
    return ng.simulate("paper", n_subjects=80, per_subject=3, seed=0)


@pytest.fixture(scope="module")
def torch_one_thread():
    """Tiny networks: torch's intra-op threads only add contention on a shared machine.

    Use with ``pytestmark = pytest.mark.usefixtures("torch_one_thread")``.
    """
    import torch  # only the network tests pay for importing torch

    before = torch.get_num_threads()
    torch.set_num_threads(1)
    yield
    torch.set_num_threads(before)
