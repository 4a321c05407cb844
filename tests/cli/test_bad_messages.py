"""Messages name the real cause (issue 20)."""

from __future__ import annotations

from cli_helpers import assert_one_line_error

import nirglucose as ng


def test_report_missing_results_dir(cli, workdir):
    code, _, err = cli("report", "nothere")
    line = assert_one_line_error(code, err, contains=["results directory 'nothere'"])
    assert "output" not in line


def test_report_given_a_file(cli, workdir):
    (workdir / "good.csv").write_text("a\n1\n")
    code, _, err = cli("report", "good.csv")
    line = assert_one_line_error(code, err, contains=["is a file"])
    assert "does not exist" not in line


def test_report_given_an_unrelated_directory(cli, workdir):
    (workdir / "d").mkdir()
    code, _, err = cli("report", "d")
    assert_one_line_error(code, err, contains=["not the output of `nirglucose benchmark`"])
    assert not (workdir / "d" / "report.html").exists()


def test_14_bit_codes_name_the_resolution(cli, workdir):
    ds = ng.simulate("paper", 3, 2, seed=0, overrides={"hardware.adc_bits": 14})
    ds.frame.to_csv(workdir / "d14.csv", index=False)  # a CSV carries no config
    code, _, err = cli("fit", "--model", "ebl", "--data", "d14.csv", "--out", "m.json")
    assert_one_line_error(code, err, contains=["14-bit"])
