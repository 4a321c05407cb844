"""The README documents what the code does."""

from __future__ import annotations

import re
from pathlib import Path

import pandas as pd

import nirglucose as ng
from nirglucose.cli import main
from nirglucose.features import enhanced_beer_lambert

README = Path(__file__).resolve().parents[1] / "README.md"


def test_readme_starts_with_the_two_commands():
    text = README.read_text()
    head = text[: text.index("## ")]
    assert "make run" in head and "make test" in head


def test_readme_lists_every_feature(paper_small):
    """The study's 56 at its device (the wearable records its 12-entry vector), plus the
    PPG entries the paper preset's device records; the features page the README links to
    lists every one."""
    assert "(docs/features.md)" in README.read_text()
    text = (README.parent / "docs" / "features.md").read_text()
    study = ng.simulate("wearable", n_subjects=4, per_subject=1, seed=0)
    assert len(enhanced_beer_lambert(study.frame).columns) == 56
    names = enhanced_beer_lambert(paper_small.frame.head(3)).columns
    assert len(names) == 66  # + 2 PPG entries + blood volume and SpO2 x A_k
    missing = [n for n in names if f"`{n}`" not in text]
    assert not missing, missing


def _blocks(text: str, lang: str) -> list[tuple[str, str]]:
    """``(info, body)`` of every fenced block whose info string starts with ``lang``."""
    return re.findall(rf"```{lang}([^\n]*)\n(.*?)```", text, flags=re.S)


def test_readme_python_example_runs_with_other_resolutions_and_led_sets(tmp_path, monkeypatch):
    """The README's Python tour (14-bit ADC, then a three-LED 10-bit device) runs."""
    text = README.read_text()
    code = next(body for _, body in _blocks(text, "python") if "ng.simulate" in body)
    assert '"hardware.adc_bits": 14' in code and "(850, 940, 1150)" in code
    code = code.replace("n_subjects=80", "n_subjects=12").replace("n_subjects=40", "n_subjects=8")
    monkeypatch.chdir(tmp_path)
    scope: dict = {}
    exec(compile(code, "README.md", "exec"), scope)  # noqa: S102 - our own README
    assert scope["model"].schema_.adc_bits == 14
    assert scope["ds3"].config.hardware.adc_bits == 10


def test_user_data_doc_runs_end_to_end(tmp_path, monkeypatch, capsys):
    """docs/user_guide/your_data.md: its one-LED and three-LED files through fit, predict,
    export-c."""
    doc = (README.parent / "docs" / "user_guide" / "your_data.md").read_text()
    monkeypatch.chdir(tmp_path)
    files = _blocks(doc, "csv ")
    assert {info.strip() for info, _ in files} == {"one_led.csv", "three_led.csv"}
    for info, body in files:
        (tmp_path / info.strip()).write_text(body)
    commands = [
        line.split()
        for _, body in _blocks(doc, "bash")
        if "my.csv" not in body  # the synopsis, not an example
        for line in body.splitlines()
        if line.startswith("nirglucose ")
    ]
    assert len(commands) >= 6
    for argv in commands:
        assert main(argv[1:]) == 0, (argv, capsys.readouterr().err)
    header = (tmp_path / "one_led_fw" / "nirglucose_model.h").read_text()
    claimed = re.search(r"`(float nirglucose_predict\(const float adc\[1\][^`]*);`", doc)
    assert claimed and claimed.group(1) + ";" in header
    pred = pd.read_csv(tmp_path / "three_led_pred.csv")
    assert list(pred.columns) == ["measurement_id", "subject_id", "predicted_glucose_mgdl",
                                  "glucose_lower_mgdl", "glucose_upper_mgdl", "flag",
                                  "outside_training"]  # fmt: skip
    assert (tmp_path / "three_led_fw" / "nirglucose_model.c").exists()
    # the documented refusal without the declared resolution
    capsys.readouterr()
    code = main(["fit", "--model", "pls", "--data", "three_led.csv", "--out", "x.json"])
    err = capsys.readouterr().err
    assert code == 2 and "above 4095 (the 12-bit full scale)" in err
    assert len(err.strip().splitlines()) == 1


def test_user_data_doc_lists_the_physiological_ranges():
    from nirglucose.dataset import PHYSIOLOGICAL_RANGES

    doc = (README.parent / "docs" / "user_guide" / "your_data.md").read_text()
    for col, (lo, hi, _) in PHYSIOLOGICAL_RANGES.items():
        assert f"| `{col}` |" in doc and f"{lo:g}–{hi:g}" in doc, col
