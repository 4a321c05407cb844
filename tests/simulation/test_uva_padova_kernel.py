"""The compiled RK4 of the UVA/Padova model gives the NumPy reference's bits (issue 43).

:func:`nirglucose.simulation.uva_padova.integrate` runs a numba loop
(:mod:`nirglucose.simulation.kernels.uva_padova_rk4`) in place of
:func:`~nirglucose.simulation.uva_padova.integrate_reference`, the NumPy loop over the
documented right-hand sides. They must agree to the last bit, on random states,
parameters, meals (some eaten over consecutive minutes), boluses and sensitivity
changes, for both model variants, with scalar or per-subject parameters.
"""

from __future__ import annotations

import numpy as np
import pytest

from nirglucose.exceptions import ConfigError
from nirglucose.simulation import uva_padova as uva
from nirglucose.simulation.kernels import uva_padova_rk4 as kernel

N_MIN = 400


def _meals(rng, n, n_min=N_MIN):
    m = np.zeros((n, n_min))
    for i in range(n):
        for t in rng.choice(n_min - 5, size=4, replace=False):
            m[i, t:t + rng.integers(1, 4)] = rng.uniform(5e3, 80e3)
    return m


def _jitter(rng, p: dict, n: int) -> dict:
    """Each parameter scaled per subject by 0.9-1.1 (random but plausible sets)."""
    return {k: np.asarray(v, dtype=float) * rng.uniform(0.9, 1.1, n) for k, v in p.items()}


def _same_bits(a, b):
    # finite trajectories: a NaN's sign and payload are not IEEE 754's to fix (which
    # operand an operation returns, which NaN an invalid one makes), so they could differ
    assert np.isfinite(b).all()
    assert a.dtype == b.dtype and a.shape == b.shape
    assert a.tobytes() == b.tobytes(), f"max |diff| {np.nanmax(np.abs(a - b))}"


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_secreting_model_kernel_is_the_numpy_loop_bit_for_bit(seed):
    rng = np.random.default_rng(seed)
    sets = [uva.parameters_2007(s) for s in ("normal", "prediabetes", "type2", "normal")]
    table = {k: np.array([s[k] for s in sets]) for k in sets[0]}
    p, x0 = uva.basal_2007(_jitter(rng, table, 4) if seed else table)
    x0 = x0 * rng.uniform(0.3, 2.5, x0.shape)  # far from basal: every branch's both sides
    meals = _meals(rng, 4)
    _same_bits(uva.integrate("meal_2007", p, x0, meals),
               uva.integrate_reference("meal_2007", p, x0, meals))


def test_scalar_parameters_are_broadcast_as_numpy_does():
    rng = np.random.default_rng(3)
    p, x0 = uva.basal_2007(uva.parameters_2007("type2"))
    x0 = np.repeat(x0, 3, axis=1) * rng.uniform(0.5, 1.5, (12, 3))
    meals = _meals(rng, 3)
    _same_bits(uva.integrate("meal_2007", p, x0, meals),
               uva.integrate_reference("meal_2007", p, x0, meals))


@pytest.mark.parametrize("with_bolus, with_sensitivity", [(True, True), (True, False),
                                                          (False, True), (False, False)])
def test_type1_kernel_is_the_numpy_loop_bit_for_bit(with_bolus, with_sensitivity):
    rng = np.random.default_rng(4)
    _, cols = uva.type1_patients()
    rows = rng.integers(len(cols["BW"]), size=5)
    p = _jitter(rng, {k: v[rows] for k, v in cols.items()}, 5)
    x0 = uva.basal_type1(p) * rng.uniform(0.3, 2.5, (12, 5))
    meals = _meals(rng, 5)
    bolus = np.where(meals > 0, rng.uniform(5.0, 120.0, meals.shape), 0.0)
    bolus[:, 17] = 40.0 if with_bolus else 0.0
    sens = None
    if with_sensitivity:  # changes at random minutes, for one subject or several
        sens = np.repeat(rng.uniform(0.5, 1.6, (5, 8)), N_MIN // 8, axis=1)
        sens[2, 101:140] = 0.7
    args = ("type1", p, x0, meals, bolus if with_bolus else None)
    _same_bits(uva.integrate(*args, sensitivity=sens),
               uva.integrate_reference(*args, sensitivity=sens))


def test_the_kernel_floors_at_zero_as_np_maximum_does():
    for v in (-0.0, 0.0, np.nan, -np.nan, 1.5, -1.5, np.inf, -np.inf):
        want = np.maximum(np.float64(v), 0.0)
        assert np.float64(kernel._max0(v)).tobytes() == want.tobytes(), v


def test_the_coupled_steps_are_found_from_the_inputs():
    meals = np.zeros((2, 8))
    meals[0, 2] = meals[0, 3] = meals[1, 6] = 1.0
    assert kernel.meal_steps(meals).tolist() == [0, 0, 1, 1, 1, 0, 1, 1]
    sens = np.ones((2, 6))
    sens[1, 2:4] = 0.5
    assert kernel.sensitivity_columns(sens).tolist() == [0, 0, 2, 2, 4, 4]


def test_a_bolus_of_the_wrong_shape_is_refused_in_one_line():
    _, cols = uva.type1_patients()
    p = {k: v[:2] for k, v in cols.items()}
    with pytest.raises(ConfigError, match="bolus_pmol_per_kg must have"):
        uva.integrate("type1", p, uva.basal_type1(p), np.zeros((2, 10)), np.zeros((2, 9)))
