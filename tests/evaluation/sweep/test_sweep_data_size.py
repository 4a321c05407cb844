"""The data-size sweep study: plan, independent test draw, ranking crossings."""

from __future__ import annotations

import pandas as pd
import pytest

from nirglucose.evaluation.sweep.run import (
    DATA_SIZE_PRESETS,
    DATA_SIZE_SUBJECTS,
    DATA_SIZE_TEST_SUBJECTS,
    plan_sweep,
    ranking_crossings,
    run_sweep,
    study_scenarios,
)
from nirglucose.exceptions import ConfigError


def test_defaults():
    assert set(DATA_SIZE_SUBJECTS) >= {80, 320, 1280}
    assert DATA_SIZE_PRESETS == ("paper", "wearable")
    assert DATA_SIZE_TEST_SUBJECTS >= 200


def test_plan_trains_on_each_size_and_tests_on_an_independent_draw():
    sc = study_scenarios("data-size", [10, 40], ["paper", "lab"])
    assert [s.name for s in sc] == ["paper:n=10", "paper:n=40", "lab:n=10", "lab:n=40"]
    specs = plan_sweep(sc, seeds=[0, 1], models=["mean", "ebl"])
    assert len(specs) == 4 * 2 * 2
    for s in specs:
        assert s["kind"] == "shift"
        assert s["test_n_subjects"] == DATA_SIZE_TEST_SUBJECTS
    assert [s["preset"] for s in specs[::4]] == ["paper", "paper", "lab", "lab"]
    assert [s["n_subjects"] for s in specs[::4]] == [10, 40, 10, 40]


@pytest.mark.parametrize(
    ("values", "presets"), [([0], None), (["x"], None), ([10], ["nope"]), ([], None)]
)
def test_bad_plan_raises(values, presets):
    with pytest.raises(ConfigError):
        study_scenarios("data-size", values, presets)


def test_ranking_crossings():
    s = pd.DataFrame({
        "preset": ["p"] * 6 + ["q"] * 2,
        "n_train_subjects": [10, 20, 40] * 2 + [10, 20],
        "model": ["a"] * 3 + ["b"] * 3 + ["a", "b"],
        "rmse_mgdl_mean": [30.0, 20.0, 10.0, 25.0, 22.0, 21.0, 5.0, 6.0],
    })
    c = ranking_crossings(s)
    assert len(c) == 1  # q never crosses
    r = c.iloc[0]
    assert (r["preset"], r["overtaker"], r["overtaken"]) == ("p", "a", "b")
    assert (r["n_before"], r["n_after"]) == (10, 20)
    assert r["diff_before"] == pytest.approx(5.0) and r["diff_after"] == pytest.approx(-2.0)


def test_small_run(tmp_path):
    res = run_sweep(
        {"n_train_subjects": [6, 24]}, study="data-size", preset="lab", seeds=1,
        models=["mean", "ebl"], n_boot=20, jobs=1, out=tmp_path / "s",
    )
    f = res.frame
    assert set(f["n_train_subjects"]) == {6, 24}
    assert (f["n_predictions"] == DATA_SIZE_TEST_SUBJECTS * 3).all()
    assert list(f.loc[f["model"] == "ebl", "n_train"]) == [18, 72]
    ebl = f[f["model"] == "ebl"].set_index("n_train_subjects")["rmse_mgdl"]
    mean = f[f["model"] == "mean"].set_index("n_train_subjects")["rmse_mgdl"]
    assert ebl[24] < 0.5 * mean[24]  # lab is easy: 24 subjects teach EBL a lot
    assert res.meta["preset"] == ["lab"]
    assert (tmp_path / "s" / "effects.csv").is_file()
    with pytest.raises(ConfigError):
        run_sweep({"noise_scale": [1.0]}, study="data-size", preset="lab", seeds=1)
