"""Which preset directories a multi-preset report reads, and in what order."""

from __future__ import annotations

from nirglucose.report.presets import preset_dirs


def _run(d):
    d.mkdir(parents=True)
    (d / "metrics.csv").write_text("model\n")
    return d


def test_paper_first_then_the_built_in_presets_in_their_order_then_the_rest(tmp_path):
    for name in ("zeta", "physical", "field", "wearable", "alpha", "paper"):
        _run(tmp_path / name)
    (tmp_path / "notes").mkdir()  # no run in it: not a preset directory
    assert [d.name for d in preset_dirs(tmp_path)] == ["paper", "wearable", "physical", "field",
                                                       "alpha", "zeta"]


def test_a_one_run_directory_has_no_preset_directories(tmp_path):
    _run(tmp_path / "r")
    _run(tmp_path / "r" / "physical")
    assert preset_dirs(tmp_path / "r") == []
