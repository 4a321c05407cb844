"""``wear-benchmark`` and ``sweep --study wear`` from the command line (issue 31)."""

from __future__ import annotations

import pandas as pd
import pytest
from cli_helpers import assert_one_line_error, cli  # noqa: F401 - fixture

SMALL = ["--subjects", "8", "--folds", "2", "--resamples", "100", "--models", "ebl,mean"]


def test_wear_benchmark_writes_every_table(cli, tmp_path):  # noqa: F811
    out = tmp_path / "wear"
    code, stdout, err = cli("wear-benchmark", "--out", out, "--wear-days", "2",
                            "--every-min", "60", *SMALL)
    assert code == 0, err
    for name in ("wear_schedules.csv", "wear_by_day.csv", "wear_standards.csv",
                 "wear_icgm.csv", "wear_predictions.csv", "wear_smoothers.csv",
                 "wear_meta.json"):
        assert (out / name).is_file(), name
    s = pd.read_csv(out / "wear_schedules.csv")
    assert set(s["schedule"]) == {"factory", "day1-1", "day1-2", "every-24h", "every-12h"}
    assert "RMSE [mg/dL] by calibration schedule" in stdout


def test_the_wear_sweep_resumes(cli, tmp_path):  # noqa: F811
    out = tmp_path / "sweep"
    args = ("sweep", "--study", "wear", "--out", out, "--vary", "wear_days=1",
            "--preset", "paper", *SMALL)
    code, _, err = cli(*args)
    assert code == 0, err
    first = pd.read_csv(out / "wear_summary.csv")
    assert set(first["wear_days"]) == {1} and (first["n_seeds"] == 1).all()
    code, _, err = cli(*args)
    assert code == 0 and "cached" in err
    pd.testing.assert_frame_equal(first, pd.read_csv(out / "wear_summary.csv"))


@pytest.mark.parametrize("args, says", [
    (["wear-benchmark", "--schedules", "weekly"], "--schedules"),
    (["wear-benchmark", "--resamples", "10"], "--resamples"),
    (["wear-benchmark", "--preset", "nope"], "nope"),
    (["sweep", "--study", "wear", "--vary", "noise_scale=1,2"], "wear_days"),
])
def test_bad_wear_options_are_one_line(cli, tmp_path, args, says):  # noqa: F811
    code, _, err = cli(*args, "--out", tmp_path / "o")
    assert_one_line_error(code, err, contains=(says,))

# Long-running (whole studies, end-to-end runs, Monte Carlo or every model): `make test-slow`,
# which CI runs beside the fast `make test` (tests/test_slow_marks.py)
pytestmark = pytest.mark.slow
