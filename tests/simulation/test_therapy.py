"""Type 1 therapy imperfection: each distribution against its cited value, the draws
independent of chunking, and their effect on the trajectories (issue 31)."""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import quad

import nirglucose as ng
from nirglucose.simulation import therapy, wear
from nirglucose.simulation import uva_padova as uva
from nirglucose.simulation._random import SubjectStreams
from nirglucose.simulation.meal_scenario import estimated_carbs_g

DATA = Path(ng.__file__).parent / "data" / "uva_padova"
#: The published values, as the sources state them (SOURCES.md): Brazeau et al. 2013
#: about 20 % mean error; Ampudia-Blasco et al. 2024 7.5 / 12.2 / 11.1 % missed at
#: breakfast / lunch / dinner; Ruan et al. 2016 CV 17 % of the daily insulin need.
PUBLISHED = {"carb_count_mean_abs_error": 0.20, "missed_bolus_prob_breakfast": 0.075,
             "missed_bolus_prob_lunch": 0.122, "missed_bolus_prob_dinner": 0.111,
             "daily_insulin_need_cv": 0.17}


def test_the_table_holds_the_published_values_and_has_a_source_row():
    assert therapy.therapy_table() == PUBLISHED
    assert "| type1_therapy.csv |" in (DATA / "SOURCES.md").read_text(encoding="utf-8")
    with (DATA / "type1_therapy.csv").open(encoding="utf-8") as fh:
        assert all(r["unit"] and r["what"] for r in csv.DictReader(fh))


def test_carb_count_error_has_the_published_mean_absolute_error():
    s = therapy.carb_count_log_sd()
    # the closed form against numerical integration of E|exp(sZ) - 1|
    pdf = lambda z: np.exp(-0.5 * z * z) / np.sqrt(2 * np.pi)  # noqa: E731
    integral = quad(lambda z: abs(np.exp(s * z) - 1.0) * pdf(z), -12, 12, points=[0.0])[0]
    assert integral == pytest.approx(0.20, abs=1e-9)
    # and the drawn estimates of a patient's meals
    carbs = np.full(200_000, 70.0)
    est = estimated_carbs_g(np.random.default_rng(1), carbs)
    assert np.mean(np.abs(est / carbs - 1.0)) == pytest.approx(0.20, abs=0.003)
    assert np.median(est / carbs) == pytest.approx(1.0, abs=0.005)


def test_missed_boluses_happen_at_each_meals_published_rate():
    n_days = 100_000
    missed = therapy.draw_missed_boluses(np.random.default_rng(2), n_days).reshape(n_days, 3)
    p = np.array([0.075, 0.122, 0.111])
    sd = np.sqrt(p * (1 - p) / n_days)
    assert np.all(np.abs(missed.mean(axis=0) - p) < 4 * sd)
    # independent meals: both of two meals missed at the product of the rates
    both = (missed[:, 1] & missed[:, 2]).mean()
    assert both == pytest.approx(p[1] * p[2], abs=4 * np.sqrt(p[1] * p[2] / n_days))


def test_the_days_sensitivity_varies_like_the_published_daily_insulin_need():
    f = therapy.draw_daily_sensitivity(np.random.default_rng(3), 200_000)
    cv = lambda x: x.std() / x.mean()  # noqa: E731
    assert cv(f) == pytest.approx(0.17, abs=0.003)
    assert cv(1.0 / f) == pytest.approx(0.17, abs=0.003)  # the need goes as 1 / SI
    assert np.median(f) == pytest.approx(1.0, abs=0.003)


def _type1_cfg():
    return ng.resolve_config("paper", {"glucose.status_probs": {
        "normal": 0.0, "prediabetes": 0.0, "type1": 1.0, "type2": 0.0}})


def test_draws_are_the_same_whatever_the_chunking():
    cfg = _type1_cfg()
    codes = np.full(4, list(cfg.glucose.status_probs).index("type1"))
    ids = np.arange(10, 14)
    whole = wear.glucose_trajectories(cfg, 7, ids, codes, 2)
    for part in ([0], [1, 2], [3]):
        one = wear.glucose_trajectories(cfg, 7, ids[part], codes[part], 2)
        assert one["blood_mgdl"].tobytes() == whole["blood_mgdl"][part].tobytes()
        assert one["sensitivity"].tobytes() == whole["sensitivity"][part].tobytes()
        for j, i in enumerate(part):
            np.testing.assert_array_equal(one["bolus_missed"][j], whole["bolus_missed"][i])
    # the draws are the subject's own named streams
    np.testing.assert_array_equal(
        whole["bolus_missed"][0],
        therapy.draw_missed_boluses(SubjectStreams(7, 10)("wear.missed_bolus"), 2))


def test_only_type1_subjects_get_therapy_errors():
    cfg = ng.resolve_config("paper")
    names = list(cfg.glucose.status_probs)
    codes = np.array([names.index(s) for s in names])
    out = wear.glucose_trajectories(cfg, 0, np.arange(len(codes)), codes, 1)
    t1 = names.index("type1")
    assert (np.delete(out["sensitivity"], t1, axis=0) == 1.0).all()
    assert not any(out["bolus_missed"][i].any() for i in range(len(codes)) if i != t1)


def test_more_insulin_sensitivity_lowers_glucose_and_ones_change_nothing():
    names, cols = uva.type1_patients()
    p = {k: v[:2] for k, v in cols.items()}
    x0 = uva.basal_type1(p)
    meals = np.zeros((2, 600))
    meals[:, 60] = 50e3
    base = uva.integrate("type1", p, x0, meals)
    ones = uva.integrate("type1", p, x0, meals, sensitivity=np.ones((2, 600)))
    assert ones.tobytes() == base.tobytes()
    more = uva.integrate("type1", p, x0, meals, sensitivity=np.full((2, 600), 1.2))
    less = uva.integrate("type1", p, x0, meals, sensitivity=np.full((2, 600), 0.8))
    assert (more[:, 300:] < base[:, 300:]).all() and (less[:, 300:] > base[:, 300:]).all()


def test_each_error_can_be_left_out_without_moving_the_others():
    cfg = _type1_cfg()
    codes = np.full(3, list(cfg.glucose.status_probs).index("type1"))
    ids = np.arange(3)
    full = wear.glucose_trajectories(cfg, 4, ids, codes, 2)
    ideal = wear.glucose_trajectories(cfg, 4, ids, codes, 2, therapy_errors=())
    assert not any(m.any() for m in ideal["bolus_missed"])
    assert (ideal["sensitivity"] == 1.0).all()
    only = wear.glucose_trajectories(cfg, 4, ids, codes, 2, therapy_errors=["missed_bolus"])
    for a, b in zip(only["bolus_missed"], full["bolus_missed"], strict=True):
        np.testing.assert_array_equal(a, b)
    assert (only["sensitivity"] == 1.0).all()
    with pytest.raises(ng.ConfigError, match="unknown therapy error.*valid: carb_count"):
        wear.glucose_trajectories(cfg, 4, ids, codes, 1, therapy_errors=["snacks"])


def test_the_errors_widen_the_glucose_excursions():
    cfg = _type1_cfg()
    codes = np.full(6, list(cfg.glucose.status_probs).index("type1"))
    out = lambda g: float(((g < 70) | (g > 180)).mean())  # noqa: E731
    full = wear.glucose_trajectories(cfg, 0, np.arange(6), codes, 3)["blood_mgdl"]
    ideal = wear.glucose_trajectories(cfg, 0, np.arange(6), codes, 3,
                                      therapy_errors=())["blood_mgdl"]
    assert out(full) > out(ideal) and full.std() > ideal.std()


def test_one_missed_bolus_probability_per_daily_meal():
    """Each type 1 subject's missed boluses are drawn per meal of the day: the therapy's
    meal list and the meal scenario's must be the same length."""
    from nirglucose.simulation import meal_scenario

    assert len(therapy.MEALS_PER_DAY) == len(meal_scenario.DAILY_MEALS)
    missed = therapy.draw_missed_boluses(SubjectStreams(0, 0)("wear.missed_bolus"), 2)
    assert missed.shape == (2 * len(meal_scenario.DAILY_MEALS),)
