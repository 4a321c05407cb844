"""design.state_bound: the per-state (linearised Bayesian) bound against van Trees."""

from __future__ import annotations

import dataclasses
import itertools

import numpy as np
import pytest

from nirglucose.design import design_terms
from nirglucose.design.state_bound import state_bound, state_bounds
from nirglucose.exceptions import ConfigError


@pytest.fixture(scope="module")
def quiet_terms():
    """physical, monitor photodiode, 16-bit ADC, 4,096 readings averaged."""
    t = design_terms("physical", overrides={"device.monitor_photodiode": True,
                                            "hardware.adc_bits": 16}, n_states=64)
    return dataclasses.replace(t, noise_var=t.noise_var / 4096)


def test_one_led_cannot_separate_glucose_from_eight_nuisances(quiet_terms):
    # the finding that makes the per-state bound the study's criterion: van Trees credits
    # one LED with a fraction of a mg/dL, the per-state bound says "no skill" (the prior)
    vt = quiet_terms.bound([0]).rmse_mgdl
    st = state_bound(quiet_terms, [0])
    prior_sd = float(np.sqrt(quiet_terms.glucose_var))
    assert vt < 2.0
    assert st > 0.95 * prior_sd
    assert st <= prior_sd * (1 + 1e-9)


def test_never_below_van_trees_and_batched_equals_single(quiet_terms):
    subsets = [s for k in (1, 2, 4) for s in itertools.combinations(range(4), k)]
    batched = state_bounds(quiet_terms, subsets)
    for s, b in zip(subsets, batched, strict=True):
        assert b == pytest.approx(state_bound(quiet_terms, s), rel=1e-7)
        assert b >= quiet_terms.bound(list(s)).rmse_mgdl * (1 - 1e-9)  # Jensen


def test_known_nuisances_give_the_oracle_bound():
    t = design_terms("physical", overrides={"device.monitor_photodiode": True}, n_states=32)
    # a prior that pins the nuisances (tiny covariance) leaves glucose's own information
    pinned = dataclasses.replace(t, nuisance_cov=t.nuisance_cov * 1e-14)
    assert state_bound(pinned) == pytest.approx(t.bound(condition="oracle").rmse_mgdl, rel=1e-4)


def test_common_noise_is_handled_as_the_full_covariance():
    t = design_terms("physical", n_states=16)  # no monitor: a common LED-drift term
    assert t.common_var > 0
    # brute force: S = D + c 1 1^T, F = J^T S^-1 J per state
    J = np.where(t.saturated[:, :, None], 0.0, t.jacobian)
    S = t.noise_var[:, :, None] * np.eye(4)[None] + t.common_var
    F = np.einsum("nki,nkj->nij", J, np.linalg.solve(S, J))
    P = np.zeros((9, 9))
    P[0, 0] = 1 / t.glucose_var
    P[1:, 1:] = np.linalg.inv(t.nuisance_cov)
    want = np.sqrt(np.mean(np.linalg.inv(F + P)[:, 0, 0]))
    assert state_bound(t) == pytest.approx(want, rel=1e-8)


def test_bad_subsets_are_refused(quiet_terms):
    for bad in ([[]], [[0, 0]], [[7]], []):
        with pytest.raises(ConfigError):
            state_bounds(quiet_terms, bad)
