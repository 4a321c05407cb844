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
