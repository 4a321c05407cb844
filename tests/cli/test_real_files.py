"""Issue 43: real files as they come -- cohorts judged against their own mean, units as
declared, intervals inside the meter's range, per-channel converters, one-line refusals."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest
from cli_helpers import assert_one_line_error

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from real_files import one_led_mmoll_frame, two_converter_frame  # noqa: E402


@pytest.fixture
def one_led(tmp_path):
    path = tmp_path / "one_led.csv"
    one_led_mmoll_frame().to_csv(path, index=False)
    return path


@pytest.fixture
def two_converters(tmp_path):
    path = tmp_path / "two.csv"
    two_converter_frame().to_csv(path, index=False)
    return path


def test_fit_judges_each_cohort_against_its_own_mean(cli, two_converters, tmp_path):
    code, out, err = cli("fit", "--model", "pls", "--data", two_converters, "--out",
                         tmp_path / "m.json", "--adc-bits", "18")
    assert code == 0, err
    lines = [ln for ln in out.splitlines() if ln.strip().startswith("diabetic ")]
    assert len(lines) == 2 and all("this group's own training mean" in ln for ln in lines)
    # the file's channels carry the group only: inside neither group does it beat the mean
    assert "the pooled skill is mostly the offset between diabetic groups" in err
    # the correlation is read on the channel that carries the pooled one
    assert "r(adc_" in lines[0]


def test_group_by_names_a_column_of_the_file(cli, two_converters, tmp_path):
    code, _, err = cli("fit", "--model", "pls", "--data", two_converters, "--out",
                       tmp_path / "m.json", "--adc-bits", "18", "--group-by", "visit")
    assert_one_line_error(code, err, contains=("--group-by", "'visit'"))


def test_fit_prints_in_the_reference_columns_unit(cli, one_led, tmp_path):
    code, out, err = cli("fit", "--model", "pls", "--data", one_led, "--out",
                         tmp_path / "m.json", "--adc-bits", "10")
    assert code == 0, err
    cv = next(ln for ln in out.splitlines() if ln.startswith("grouped"))
    assert "mmol/L" in cv and "mg/dL" not in cv
    code, out, err = cli("fit", "--model", "pls", "--data", one_led, "--out",
                         tmp_path / "m.json", "--adc-bits", "10", "--glucose-unit", "mmol/L")
    assert code == 0, err


def test_benchmark_and_report_judge_cohorts_against_their_own_mean(cli, two_converters,
                                                                   tmp_path):
    from nirglucose.report.cohorts import cohorts_section
    from nirglucose.report.figures import load_results

    out_dir = tmp_path / "b"
    code, out, err = cli("benchmark", "--data", two_converters, "--out", out_dir, "--models",
                         "pls", "--adc-bits", "18", "--repeats", "1", "--resamples", "100",
                         "--no-ablation", "--no-references", "--jobs", "1")
    assert code == 0, err
    assert "no skill is each group's own training mean" in out
    assert "diabetic no:" in out and "diabetic yes:" in out
    assert "PLS: the pooled skill is mostly the offset between diabetic groups" in err
    html = cohorts_section([load_results(out_dir)])
    assert 'id="cohorts"' in html and "no skill (own mean)" in html
    assert "mostly the offset between diabetic groups" in html
