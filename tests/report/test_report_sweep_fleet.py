"""The report's sweep section for a fleet study: its table and its figure."""

from __future__ import annotations

import pytest

from nirglucose.evaluation.sweep.run import run_sweep
from nirglucose.report.sweep import sweep_figures, sweep_section


def test_fleet_section_has_table_and_figure(tmp_path):
    out = tmp_path / "fleet"
    run_sweep({"tolerance_scale": [0, 1]}, study="fleet", seeds=1, models=["ebl"],
              n_subjects=24, n_boot=10, jobs=1, out=out)
    html = sweep_section(out)
    assert 'id="sweep-fleet"' in html and "slope-bias" in html
    names = [f.name for f in sweep_figures(out)]
    assert names == ["sweep_fleet"]
    assert html.count("<img") == 1

# Long-running (whole studies, end-to-end runs, Monte Carlo or every model): `make test-slow`,
# which CI runs beside the fast `make test` (tests/test_slow_marks.py)
pytestmark = pytest.mark.slow
