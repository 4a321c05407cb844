"""Tests of nirglucose.optics.diffusion (dipole diffusion model, mu_eff, DPF)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import integrate

from nirglucose.exceptions import ConfigError
from nirglucose.optics.diffusion import (
    boundary_coefficient,
    differential_pathlength_factor,
    effective_attenuation_per_cm,
    farrell_reflectance,
)

torch = pytest.importorskip("torch")


# ----------------------------------------------------------------- hand-computed values


def test_boundary_coefficient_hand_value():
    # n = 1.4: r_id = -1.440/1.96 + 0.710/1.4 + 0.668 + 0.0636*1.4
    #               = -0.734694 + 0.507143 + 0.668 + 0.089040 = 0.529489
    # A = 1.529489 / 0.470511 = 3.25070
    assert boundary_coefficient(1.4, 1.0) == pytest.approx(3.25070, abs=1e-5)
    # matched: r_id = -1.440 + 0.710 + 0.668 + 0.0636 = 0.0016 -> A = 1.0016/0.9984
    assert boundary_coefficient(1.33, 1.33) == pytest.approx(1.0016 / 0.9984, rel=1e-12)


def test_effective_attenuation_hand_value():
    # sqrt(3 * 0.1 * (0.1 + 10)) = sqrt(3.03) = 1.740690
    assert effective_attenuation_per_cm(0.1, 10.0) == pytest.approx(1.740690, abs=1e-6)
    assert effective_attenuation_per_cm(0.0, 10.0) == 0.0


def test_farrell_hand_value():
    # mua = 0.1, musp = 10, rho = 1, n = 1.4 / 1.0 (A = 3.250697):
    # mu_t' = 10.1, z0 = 1/10.1 = 0.0990099, D = 1/30.3 = 0.0330033
    # zb = 2 A D = 0.2145675, z0 + 2 zb = 0.5281449, mu_eff = sqrt(3.03) = 1.7406895
    # r1 = sqrt(0.0990099^2 + 1) = 1.0048895, r2 = sqrt(0.5281449^2 + 1) = 1.1309010
    # term1 = 0.0990099 (1.7406895 + 1/1.0048895) e^(-1.7406895*1.0048895) / 1.0048895^2
    #       = 0.0466511
    # term2 = 0.5281449 (1.7406895 + 1/1.1309010) e^(-1.7406895*1.1309010) / 1.1309010^2
    #       = 0.1513889
    # R = (10/10.1) / (4 pi) * (0.0466511 + 0.1513889) = 0.0156035 1/cm^2
    assert farrell_reflectance(1.0, 0.1, 10.0, 1.4, 1.0) == pytest.approx(0.0156035, rel=1e-5)


def test_dpf_hand_value():
    # 0.5 sqrt(3*10/0.1) = 0.5 sqrt(300) = 8.660254
    # rho sqrt(3 mua musp) = 3 sqrt(3) = 5.196152 ; 1 - 1/6.196152 = 0.838611
    # DPF = 8.660254 * 0.838611 = 7.262572
    assert differential_pathlength_factor(3.0, 0.1, 10.0) == pytest.approx(7.262572, abs=1e-5)


# ----------------------------------------------------------------- physics consistency


@pytest.mark.parametrize(
    ("mua", "musp", "n"), [(0.1, 10.0, 1.4), (0.5, 8.0, 1.0), (0.02, 15, 1.33)]
)
def test_farrell_integrates_to_total_diffuse_reflectance(mua, musp, n):
    # int_0^inf R(rho) 2 pi rho drho = a'/2 [exp(-mu_eff z0) + exp(-mu_eff (z0 + 2 zb))]
    # (Farrell et al. 1992, eq. 6) -- an independent closed form.
    a_coef = boundary_coefficient(n, 1.0)
    mutp = mua + musp
    z0 = 1 / mutp
    zi = z0 + 4 * a_coef / (3 * mutp)
    mu_eff = np.sqrt(3 * mua * mutp)
    rd = musp / mutp / 2 * (np.exp(-mu_eff * z0) + np.exp(-mu_eff * zi))
    val, _ = integrate.quad(
        lambda r: 2 * np.pi * r * farrell_reflectance(r, mua, musp, n, 1.0),
        1e-9,
        np.inf,
        limit=200,
        epsabs=1e-12,
    )
    assert val == pytest.approx(rd, rel=1e-6)


def test_farrell_relative_index_only():
    r1 = farrell_reflectance(1.0, 0.1, 10.0, 1.4, 1.0)
    r2 = farrell_reflectance(1.0, 0.1, 10.0, 2.1, 1.5)
    assert r1 == pytest.approx(r2, rel=1e-12)


def test_farrell_monotonic():
    rho = np.linspace(0.05, 4.0, 80)
    r = farrell_reflectance(rho, 0.1, 10.0)
    assert np.all(np.diff(r) < 0)  # decreasing with distance
    mua = np.linspace(0.0, 2.0, 50)
    r = farrell_reflectance(1.0, mua, 10.0)
    assert np.all(np.diff(r) < 0)  # decreasing with absorption

    # index mismatch traps light under the boundary: less total diffuse reflectance,
    # but the trapped light spreads sideways, so more of it far from the source
    def total(n):
        f = lambda r: 2 * np.pi * r * farrell_reflectance(r, 0.1, 10.0, n)  # noqa: E731
        return integrate.quad(f, 1e-9, np.inf, limit=200)[0]

    assert total(1.4) < total(1.0)
    assert farrell_reflectance(2.0, 0.1, 10.0, 1.4) > farrell_reflectance(2.0, 0.1, 10.0, 1.0)


def test_farrell_broadcasting():
    rho = np.linspace(0.5, 3.0, 6)[:, None]
    mua = np.array([0.05, 0.1, 0.2])[None, :]
    r = farrell_reflectance(rho, mua, 10.0)
    assert r.shape == (6, 3)
    assert r[2, 1] == pytest.approx(farrell_reflectance(rho[2, 0], mua[0, 1], 10.0))


def test_dpf_limits_and_monotonic():
    # large rho -> 0.5 sqrt(3 musp/mua)
    assert differential_pathlength_factor(1e6, 0.1, 10.0) == pytest.approx(
        0.5 * np.sqrt(300.0), rel=1e-5
    )
    dpf = differential_pathlength_factor(np.linspace(0.2, 5, 30), 0.1, 10.0)
    assert np.all(np.diff(dpf) > 0)
    dpf = differential_pathlength_factor(2.0, np.linspace(0.01, 1, 30), 10.0)
    assert np.all(np.diff(dpf) < 0)


def test_dpf_matches_autograd_of_farrell_far_from_source():
    # DPF * rho = -d ln R / d mua in the far field of the dipole model (mua << musp).
    rho = torch.tensor([2.0, 3.0, 4.0], dtype=torch.float64)
    mua = torch.tensor(0.05, dtype=torch.float64, requires_grad=True)
    r = farrell_reflectance(rho, mua, 12.0, 1.0, 1.0)
    jac = [torch.autograd.grad(torch.log(r[i]), mua, retain_graph=True)[0] for i in range(3)]
    path_ad = -torch.stack(jac).numpy()
    path_dpf = differential_pathlength_factor(rho.numpy(), 0.05, 12.0) * rho.numpy()
    np.testing.assert_allclose(path_ad, path_dpf, rtol=0.03)


# ----------------------------------------------------------------- numpy / torch


def test_numpy_torch_agree():
    rng = np.random.default_rng(1)
    rho = rng.uniform(0.1, 3.0, 20)
    mua = rng.uniform(0.01, 1.0, 20)
    musp = rng.uniform(5.0, 20.0, 20)
    r_np = farrell_reflectance(rho, mua, musp, 1.4)
    r_t = farrell_reflectance(torch.from_numpy(rho), torch.from_numpy(mua), torch.from_numpy(musp))
    assert isinstance(r_t, torch.Tensor)
    assert r_t.dtype == torch.float64
    np.testing.assert_allclose(r_t.numpy(), r_np, rtol=1e-12)
    d_np = differential_pathlength_factor(rho, mua, musp)
    d_t = differential_pathlength_factor(torch.from_numpy(rho), torch.from_numpy(mua), musp)
    np.testing.assert_allclose(d_t.numpy(), d_np, rtol=1e-12)
    m_t = effective_attenuation_per_cm(torch.from_numpy(mua), musp)
    np.testing.assert_allclose(m_t.numpy(), effective_attenuation_per_cm(mua, musp), rtol=1e-12)


def test_torch_float32_mixed_inputs_keep_dtype():
    mua = torch.tensor([0.1, 0.2], dtype=torch.float32)
    r = farrell_reflectance(np.array([1.0, 1.5]), mua, 10.0)
    assert r.dtype == torch.float32
    assert r.shape == (2,)


def test_torch_gradients_finite_and_signed():
    rho = torch.tensor([0.5, 1.0, 2.0], dtype=torch.float64)
    mua = torch.tensor([0.1, 0.1, 0.1], dtype=torch.float64, requires_grad=True)
    musp = torch.tensor([10.0, 10.0, 10.0], dtype=torch.float64, requires_grad=True)
    r = farrell_reflectance(rho, mua, musp)
    r.sum().backward()
    assert torch.isfinite(mua.grad).all()
    assert torch.isfinite(musp.grad).all()
    assert (mua.grad < 0).all()  # more absorption -> less reflectance
    # finite-difference check of d R / d mua
    h = 1e-6
    fd = (
        farrell_reflectance(rho.numpy(), 0.1 + h, 10.0)
        - farrell_reflectance(rho.numpy(), 0.1 - h, 10.0)
    ) / (2 * h)
    np.testing.assert_allclose(mua.grad.numpy(), fd, rtol=1e-6)
    assert torch.autograd.gradcheck(
        lambda a, s: farrell_reflectance(rho, a, s),
        (mua.detach().clone().requires_grad_(), musp.detach().clone().requires_grad_()),
    )


def test_validate_does_not_break_autograd():
    mua = torch.tensor(0.1, dtype=torch.float64, requires_grad=True)
    r = farrell_reflectance(1.0, mua, 10.0, validate=True)
    assert r.requires_grad
    (g,) = torch.autograd.grad(r, mua)
    assert g < 0
    r2 = farrell_reflectance(1.0, mua, 10.0, validate=False)
    assert r2.item() == pytest.approx(r.item())
    # validate=False skips every check, the relative index included
    r3 = farrell_reflectance(1.0, mua, 10.0, 1.3, 1.33, validate=False)
    assert torch.isfinite(r3)


# ----------------------------------------------------------------- bad input


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"rho_cm": 0.0}, "rho_cm"),
        ({"rho_cm": -1.0}, "rho_cm"),
        ({"mua_per_cm": -0.1}, "mua_per_cm"),
        ({"mua_per_cm": np.nan}, "mua_per_cm"),
        ({"musp_per_cm": 0.0}, "musp_per_cm"),
        ({"musp_per_cm": np.inf}, "musp_per_cm"),
        ({"n_tissue": 0.9}, "n_tissue / n_ambient"),
    ],
)
def test_farrell_bad_input_raises(kwargs, match):
    args = {"rho_cm": 1.0, "mua_per_cm": 0.1, "musp_per_cm": 10.0} | kwargs
    with pytest.raises(ConfigError, match=match):
        farrell_reflectance(**args)


def test_error_message_has_value_range_and_unit():
    with pytest.raises(ConfigError) as exc:
        farrell_reflectance(np.array([1.0, 2.0]), np.array([0.1, -0.3]), 10.0)
    msg = str(exc.value)
    assert "-0.3" in msg and "[0, inf]" in msg and "[1/cm]" in msg
    assert isinstance(exc.value, ValueError)


def test_bad_tensor_input_raises():
    with pytest.raises(ConfigError, match="mua_per_cm"):
        farrell_reflectance(1.0, torch.tensor([-0.1], requires_grad=True), 10.0)
    with pytest.raises(ConfigError, match="rho_cm"):
        differential_pathlength_factor(torch.tensor([0.0]), 0.1, 10.0)


def test_dpf_requires_positive_mua():
    with pytest.raises(ConfigError, match="mua_per_cm"):
        differential_pathlength_factor(1.0, 0.0, 10.0)
    with pytest.raises(ConfigError, match="musp_per_cm"):
        effective_attenuation_per_cm(0.1, -1.0)
