"""The report of a worn run: findings computed from its tables, figures, one-line errors."""

from __future__ import annotations

import re

import pandas as pd
import pytest

from nirglucose.cli import main
from nirglucose.exceptions import DataError
from nirglucose.report.wear import build_wear_report, is_wear_results


@pytest.fixture(scope="module")
def worn(tmp_path_factory):
    out = tmp_path_factory.mktemp("wear")
    code = main(["wear-benchmark", "--out", str(out), "--subjects", "8", "--wear-days", "2",
                 "--every-min", "60", "--folds", "2", "--resamples", "100",
                 "--models", "ebl,mean"])
    assert code == 0
    return out


def test_the_page_states_its_findings_from_the_tables(worn, tmp_path):
    page = build_wear_report(worn, tmp_path / "r.html", figures_dir=tmp_path / "f").read_text()
    s = pd.read_csv(worn / "wear_schedules.csv")
    raw = s[(s["variant"] == "raw") & (s["model"] == "ebl")]  # mean: a reference row
    best = raw.loc[raw["rmse_mgdl"].idxmin()]
    assert f"RMSE {best['rmse_mgdl']:.1f} mg/dL" in page
    assert page.index("Findings") < page.index("Traces")
    assert len(re.findall(r'<img src="data:image/png;base64,', page)) == 2
    assert (tmp_path / "f" / "wear_traces.png").is_file()
    assert "iCGM criteria" in page


def test_the_cli_detects_a_worn_run(worn, tmp_path, capsys):
    assert is_wear_results(worn)
    assert main(["report", str(worn), "--out", str(tmp_path / "w.html")]) == 0
    assert (tmp_path / "w.html").is_file()


def test_an_incomplete_run_is_one_line(worn, tmp_path):
    (tmp_path / "wear_schedules.csv").write_text((worn / "wear_schedules.csv").read_text())
    with pytest.raises(DataError, match="wear-benchmark"):
        build_wear_report(tmp_path, tmp_path / "r.html")

# Long-running (whole studies, end-to-end runs, Monte Carlo or every model): `make test-slow`,
# which CI runs beside the fast `make test` (tests/test_slow_marks.py)
pytestmark = pytest.mark.slow
