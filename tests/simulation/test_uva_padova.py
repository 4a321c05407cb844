"""The UVA/Padova model: published steady states, meal and insulin properties, and the
fixed-step integrator against an adaptive solver."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from nirglucose.exceptions import ConfigError
from nirglucose.simulation import uva_padova as uva
from nirglucose.simulation.meal_scenario import INSULIN_PMOL_PER_UNIT, meal_grid_mg

#: Basal plasma glucose of the paper's average subjects (Dalla Man et al. 2007, Results)
#: [mg/dL], independent of the parameter table the model reads.
PUBLISHED_GB = {"normal": 91.76, "type2": 164.18}
PUBLISHED_IB = {"normal": 25.49, "type2": 54.81}


@pytest.mark.parametrize("status", ["normal", "type2"])
def test_2007_steady_state_is_the_published_basal(status):
    p, x0 = uva.basal_2007(uva.parameters_2007(status))
    # the model's own equilibrium, from Table I, lands within 1 % of the paper's basal
    assert p["Gb_model"] == pytest.approx(PUBLISHED_GB[status], rel=0.01)
    assert x0[uva.STATES_2007.index("ip"), 0] / p["VI"] == pytest.approx(PUBLISHED_IB[status])
    assert np.abs(uva.rhs_2007(x0, p, np.zeros(1))).max() < 1e-12
    # and it is an attractor: from 20 % more plasma glucose, back to it within a day
    x = x0.copy()
    x[uva.STATES_2007.index("gp")] *= 1.2
    g = uva.integrate("meal_2007", p, x, np.zeros((1, 1440)))
    assert g[0, 0] == pytest.approx(1.2 * p["Gb_model"])
    assert abs(g[0, -1] - p["Gb_model"]) < 0.5


def test_type1_patients_hold_their_tabulated_basal_on_basal_insulin():
    names, p = uva.type1_patients()
    assert len(names) == 10 and names[0] == "adult#001"
    x0 = uva.basal_type1(p)
    dx = uva.rhs_type1(x0, p, np.zeros(10), p["u2ss"])
    assert np.abs(dx).max() < 1e-9 * np.abs(x0).max()
    g = uva.integrate("type1", p, x0, np.zeros((10, 720)), np.zeros((10, 720)))
    np.testing.assert_allclose(g[:, -1], p["Gb"], atol=0.05)


def _day(carbs_g, minute=60, n_min=480, n=1):
    return np.repeat(meal_grid_mg(np.array([minute]), np.array([carbs_g * 1000.0]), n_min)[None],
                     n, axis=0)


def test_a_meal_raises_glucose_and_it_returns_to_basal():
    p, x0 = uva.basal_2007(uva.parameters_2007("normal"))
    g = uva.integrate("meal_2007", p, x0, _day(70.0))[0]
    peak = int(np.argmax(g))
    assert 60 + 20 < peak < 60 + 150  # postprandial peak within 20-150 min
    assert g[peak] > p["Gb_model"] + 30  # a 70 g meal raises glucose by tens of mg/dL
    assert abs(g[-1] - p["Gb_model"]) < 10  # back near basal 7 h later
    g_small = uva.integrate("meal_2007", p, x0, _day(35.0))[0]
    assert g_small.max() < g[peak]  # a smaller meal, a smaller excursion


def test_an_insulin_bolus_lowers_glucose():
    names, p = uva.type1_patients()
    x0 = uva.basal_type1(p)
    meal = _day(60.0, n=10)
    units = 60.0 / p["carb_ratio_g_per_u"]
    bolus = meal_grid_mg(np.array([60]), np.array([1.0]), 480)[None] * (
        units * INSULIN_PMOL_PER_UNIT / p["BW"])[:, None]
    no_bolus = uva.integrate("type1", p, x0, meal, np.zeros_like(meal))
    with_bolus = uva.integrate("type1", p, x0, meal, bolus)
    assert (with_bolus.max(axis=1) < no_bolus.max(axis=1)).all()
    assert (with_bolus[:, -1] < no_bolus[:, -1] - 20).all()
    fasting = uva.integrate("type1", p, x0, np.zeros_like(meal), bolus)  # bolus, no meal
    assert (fasting[:, -1] < p["Gb"] - 20).all()


def _reference_solution(kind, p, x0, meal_mg, n_min):
    """LSODA (rtol 1e-8) on one subject, the meal a jump of the stomach at its minute."""
    rhs = ((lambda t, x: uva.rhs_2007(x[:, None], p, dose)[:, 0]) if kind == "meal_2007" else
           (lambda t, x: uva.rhs_type1(x[:, None], p, dose, p["u2ss"])[:, 0]))
    gp = (uva.STATES_2007 if kind == "meal_2007" else uva.STATES_TYPE1).index("gp")
    vg = p["VG"] if kind == "meal_2007" else p["Vg"]
    dose = np.zeros(1)
    first = solve_ivp(rhs, (0, 60), x0[:, 0], method="LSODA", rtol=1e-8, atol=1e-8,
                      t_eval=np.arange(0, 60))
    x = first.y[:, -1].copy()
    x = solve_ivp(rhs, (59, 60), x, method="LSODA", rtol=1e-8, atol=1e-8).y[:, -1]
    x[0] += meal_mg
    dose = np.array([meal_mg])
    second = solve_ivp(rhs, (60, n_min - 1), x, method="LSODA", rtol=1e-8, atol=1e-8,
                       t_eval=np.arange(60, n_min))
    return np.concatenate([first.y[gp], second.y[gp]]) / vg


@pytest.mark.parametrize("kind", ["meal_2007", "type1"])
def test_fixed_step_rk4_matches_an_adaptive_solver(kind):
    if kind == "meal_2007":
        p, x0 = uva.basal_2007(uva.parameters_2007("normal"))
    else:
        _, cols = uva.type1_patients()
        p = {k: v[:1] for k, v in cols.items()}
        x0 = uva.basal_type1(p)
    g = uva.integrate(kind, p, x0, _day(70.0, n_min=360), np.zeros((1, 360)))[0]
    ref = _reference_solution(kind, p, x0, 70e3, 360)
    assert np.abs(g - ref).max() < 0.05  # mg/dL


def test_unknown_names_raise_one_line():
    with pytest.raises(ConfigError, match="valid"):
        uva.parameters_2007("gestational")
    with pytest.raises(ConfigError, match="valid"):
        uva.integrate("euler", {}, np.zeros((12, 1)), np.zeros((1, 1)))


def test_sensitivity_is_refused_where_it_does_not_apply_or_fit():
    p, x0 = uva.basal_2007(uva.parameters_2007("normal"))
    meals = _day(70.0)
    with pytest.raises(ConfigError, match="type1 model only") as err:
        uva.integrate("meal_2007", p, x0, meals, sensitivity=np.ones(meals.shape))
    assert "\n" not in str(err.value)
    _names, cols = uva.type1_patients()
    p1 = {k: v[:1] for k, v in cols.items()}
    with pytest.raises(ConfigError, match=r"got kind 'type1', shape \(1, 2\)"):
        uva.integrate("type1", p1, uva.basal_type1(p1), meals, sensitivity=np.ones((1, 2)))
