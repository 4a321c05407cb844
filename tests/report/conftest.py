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


@pytest.fixture(scope="session")
def preset_results(tmp_path_factory) -> Path:
    """A two-preset results directory (``paper`` with λ = 0, ``wearable`` with λ > 0)."""
    from report_fixtures import write_preset_results

    root = tmp_path_factory.mktemp("presets")
    write_preset_results(root / "paper", "paper", lambda_phys=0.0, seed=0)
    write_preset_results(root / "wearable", "wearable", lambda_phys=0.01, seed=1)
    return root


@pytest.fixture(scope="session")
def preset_report(preset_results, tmp_path_factory) -> Path:
    """The HTML report of :func:`preset_results`, built once per session."""
    from nirglucose.report import build_report

    return build_report(preset_results, tmp_path_factory.mktemp("preset-report") / "r.html")
