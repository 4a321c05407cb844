"""Physics residuals of the PINNs, tested as pure functions."""

from __future__ import annotations

import math

import numpy as np
import pytest
import torch

from nirglucose.constants import MGDL_PER_MMOLL_GLUCOSE
from nirglucose.models.physics_losses import (
    beer_lambert_loss,
    beer_lambert_residual,
    diffusion_absorbance,
    diffusion_reflectance_loss,
    glucose_absorptivity_per_cm_per_mgdl,
    scattering_prior_loss,
)
from nirglucose.optics.absorption import glucose_mua_per_cm_per_mm
from nirglucose.optics.diffusion import farrell_reflectance

WL = (850.0, 940.0, 1050.0, 1150.0)
GEOM = {"rho_cm": 0.3, "detector_area_cm2": 0.066, "n_tissue": 1.4}


# ----------------------------------------------------------------- glucose absorptivity


def test_absorptivity_at_band_peak_by_hand():
    # At 1150 nm the 2nd-overtone Gaussian is at its peak (the 920 nm band adds
    # 0.1 exp(-(230/30)^2) ~ 1e-27): eps = gain * peak / (ln 10 * 18.016).
    eps = glucose_absorptivity_per_cm_per_mgdl([1150.0], 1e-4, 13.5)
    assert eps[0] == pytest.approx(13.5 * 1e-4 / (math.log(10) * 18.016), rel=1e-12)


def test_absorptivity_matches_shared_optics_table():
    eps = glucose_absorptivity_per_cm_per_mgdl(WL, 2e-4, 2.0)
    ref = 2.0 * glucose_mua_per_cm_per_mm(WL, 2e-4) / (np.log(10) * MGDL_PER_MMOLL_GLUCOSE)
    np.testing.assert_allclose(eps, ref, rtol=1e-12)
    assert eps[3] > eps[2] > 0  # strongest at the 1150 nm overtone


# ----------------------------------------------------------------- Beer-Lambert


def test_beer_lambert_zero_when_relation_holds():
    eps = torch.tensor([1e-5, 2e-5, 5e-5, 3e-5], dtype=torch.float64)
    c = torch.tensor([80.0, 150.0, 320.0], dtype=torch.float64)
    a = eps * c[:, None] * 1.0
    assert float(beer_lambert_loss(a, c, eps)) == 0.0
    a2 = eps * c[:, None] * 2.5
    assert float(beer_lambert_loss(a2, c, eps, pathlength_cm=2.5)) == pytest.approx(0.0, abs=1e-30)


def test_beer_lambert_positive_otherwise_and_by_hand():
    eps = torch.tensor([1e-3, 2e-3], dtype=torch.float64)
    c = torch.tensor([100.0, 200.0], dtype=torch.float64)
    a = torch.tensor([[0.2, 0.3], [0.1, 0.4]], dtype=torch.float64)
    # residuals: [0.1, 0.1], [-0.1, 0.0] -> sums 0.02, 0.01 -> mean 0.015
    assert float(beer_lambert_loss(a, c, eps)) == pytest.approx(0.015, rel=1e-12)
    r = beer_lambert_residual(a, c, eps)
    np.testing.assert_allclose(r.numpy(), [[0.1, 0.1], [-0.1, 0.0]], atol=1e-15)


def test_beer_lambert_relative_form():
    eps = torch.tensor([1e-3, 2e-3], dtype=torch.float64)
    a_ref = torch.tensor([0.5, 0.7], dtype=torch.float64)
    c = torch.tensor([90.0, 210.0], dtype=torch.float64)
    a = a_ref + eps * (c[:, None] - 150.0)
    zero = beer_lambert_loss(a, c, eps, absorbance_ref=a_ref, glucose_ref_mgdl=150.0)
    assert float(zero) == pytest.approx(0.0, abs=1e-30)
    assert float(beer_lambert_loss(a, c, eps)) > 0.1  # absolute form sees the background


def test_beer_lambert_gradient_flows_to_glucose():
    eps = torch.tensor([1e-3, 2e-3])
    c = torch.tensor([100.0], requires_grad=True)
    a = torch.tensor([[0.5, 0.5]])
    beer_lambert_loss(a, c, eps).backward()
    # d/dc sum (a - eps c)^2 = -2 sum eps (a - eps c)
    expected = -2 * (1e-3 * (0.5 - 0.1) + 2e-3 * (0.5 - 0.2))
    assert float(c.grad) == pytest.approx(expected, rel=1e-5)


# ----------------------------------------------------------------- diffusion


def test_diffusion_absorbance_is_the_simulators_farrell_function():
    mua = np.array([[0.3, 0.5, 0.4, 1.1]])
    musp = np.array([[14.0, 12.0, 10.5, 9.5]])
    offset = np.array([0.1, -0.2, 0.3, 0.0])
    a = diffusion_absorbance(torch.tensor(mua), torch.tensor(musp), torch.tensor(offset), **GEOM)
    ref = -np.log10(farrell_reflectance(0.3, mua, musp, 1.4) * 0.066) + offset
    np.testing.assert_allclose(a.numpy(), ref, rtol=1e-12)


def test_diffusion_loss_zero_when_optics_reproduce_absorbance():
    rng = np.random.default_rng(0)
    mua = torch.tensor(rng.uniform(0.1, 1.5, size=(6, 4)))
    musp = torch.tensor(rng.uniform(6.0, 20.0, size=(6, 4)))
    offset = torch.tensor([0.4, 0.3, 0.2, 0.1], dtype=torch.float64)
    a = diffusion_absorbance(mua, musp, offset, **GEOM)
    loss = diffusion_reflectance_loss(a, mua, musp, offset, **GEOM, scale=0.05)
    assert float(loss) == pytest.approx(0.0, abs=1e-20)
    perturbed = diffusion_reflectance_loss(a, mua * 1.2, musp, offset, **GEOM, scale=0.05)
    assert float(perturbed) > 0


def test_diffusion_loss_by_hand_and_scale():
    mua = torch.tensor([[0.4]], dtype=torch.float64)
    musp = torch.tensor([[10.0]], dtype=torch.float64)
    a_model = diffusion_absorbance(mua, musp, 0.0, **GEOM)
    loss = diffusion_reflectance_loss(a_model + 0.02, mua, musp, 0.0, **GEOM, scale=0.01)
    assert float(loss) == pytest.approx(4.0, rel=1e-9)  # (0.02 / 0.01)^2


def test_diffusion_loss_gradient_reaches_optics():
    mua = torch.tensor([[0.4, 0.6]], dtype=torch.float64, requires_grad=True)
    musp = torch.tensor([[10.0, 9.0]], dtype=torch.float64, requires_grad=True)
    a = torch.tensor([[1.5, 1.6]], dtype=torch.float64)
    diffusion_reflectance_loss(a, mua, musp, 0.0, **GEOM).backward()
    assert torch.all(torch.isfinite(mua.grad)) and torch.any(mua.grad != 0)
    assert torch.all(torch.isfinite(musp.grad))


# ----------------------------------------------------------------- scattering prior


def test_scattering_prior_zero_at_prior_positive_elsewhere():
    prior = torch.tensor([15.0, 12.0], dtype=torch.float64)
    assert float(scattering_prior_loss(prior.repeat(3, 1), prior)) == 0.0
    doubled = scattering_prior_loss(torch.tensor([[30.0, 12.0]], dtype=torch.float64), prior)
    assert float(doubled) == pytest.approx(math.log(2.0) ** 2, rel=1e-12)


def test_scattering_prior_accepts_a_sequence():
    musp = torch.tensor([[10.0, 10.0]])
    assert float(scattering_prior_loss(musp, [10.0, 10.0])) == 0.0
