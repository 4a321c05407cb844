"""Fixtures of the report tests: a synthetic results directory and its report."""

from __future__ import annotations

from pathlib import Path

import pytest
from report_fixtures import REPORT_TEST_MODELS, write_synthetic_results


@pytest.fixture(scope="session")
def synthetic_results(tmp_path_factory) -> Path:
    """A complete synthetic results directory (session-wide, read-only by convention)."""
    return write_synthetic_results(tmp_path_factory.mktemp("results"), models=REPORT_TEST_MODELS)


@pytest.fixture(scope="session")
def synthetic_report(synthetic_results, tmp_path_factory) -> Path:
    """The HTML report of :func:`synthetic_results`, built once per session."""
    from nirglucose.report import build_report

    out = tmp_path_factory.mktemp("report")
    return build_report(synthetic_results, out / "report.html")
