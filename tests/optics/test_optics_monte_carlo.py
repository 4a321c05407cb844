"""Tests of nirglucose_reference.monte_carlo (the photon engine's MCML front end)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import integrate

from nirglucose.exceptions import ConfigError
from nirglucose.optics.diffusion import differential_pathlength_factor, farrell_reflectance
from nirglucose_reference.adding_doubling import slab_rt
from nirglucose_reference.monte_carlo import MCResult, mc_layers, mc_slab

# MCML benchmark slab (Wang, Jacques & Zheng 1995; van de Hulst 1980):
# mua = 10 /cm, mus = 90 /cm, g = 0.75, d = 0.02 cm, n = 1.
BENCH = (10.0, 90.0, 0.75, 0.02, 1.0)
MCML_RD = 0.09734
MCML_TT = 0.66096
REF_ROUNDING = 1e-4  # uncertainty of the published reference values themselves


def _clear_slab(mua, d, n):
    """Non-scattering slab, incoherent multiple reflections (see the AD tests)."""
    r = ((n - 1) / (n + 1)) ** 2
    t = np.exp(-mua * d)
    den = 1 - r**2 * t**2
    return r + (1 - r) ** 2 * r * t**2 / den, (1 - r) ** 2 * t / den


def test_mcml_benchmark_fast():
    res = mc_slab(*BENCH, n_photons=100_000, rng=7)
    assert isinstance(res, MCResult)
    assert res.specular == 0.0
    assert res.diffuse_reflectance_se < 0.001  # sanity of the error estimate
    assert abs(res.diffuse_reflectance - MCML_RD) < 4 * res.diffuse_reflectance_se + REF_ROUNDING
    assert abs(res.total_transmittance - MCML_TT) < 4 * res.total_transmittance_se + REF_ROUNDING
    # unscattered beam: exp(-tau) = exp(-2) = 0.135335, binomial SE sqrt(p (1-p) / N)
    p = np.exp(-2.0)
    assert abs(res.unscattered_transmittance - p) < 4 * np.sqrt(p * (1 - p) / 100_000)


def test_mcml_benchmark_within_one_percent():
    # 1e6 packets (~3 s): SE(Rd) ~ 2.4e-4 = 0.25 %, SE(Tt) ~ 3.3e-4 = 0.05 %
    res = mc_slab(*BENCH, n_photons=1_000_000, rng=2024)
    assert res.diffuse_reflectance == pytest.approx(MCML_RD, rel=0.01)
    assert res.total_transmittance == pytest.approx(MCML_TT, rel=0.01)


def test_agrees_with_adding_doubling_mismatched_slab():
    mua, mus, g, d, n = 2.0, 60.0, 0.8, 0.05, 1.4
    res = mc_slab(mua, mus, g, d, n, n_photons=40_000, rng=11)
    r_ad, t_ad = slab_rt(mua, mus, g, d, n)
    assert res.specular == pytest.approx((0.4 / 2.4) ** 2, rel=1e-12)  # 0.027778
    assert abs(res.total_reflectance - r_ad) < 4 * res.total_reflectance_se
    assert abs(res.total_transmittance - t_ad) < 4 * res.total_transmittance_se


def test_clear_slab_matches_multiple_reflection_formula():
    # no scattering: packets are absorbed at their first interaction, so
    # T = (1-r)^2 T0 / (1 - r^2 T0^2) with a binomial error
    n_ph = 20_000
    res = mc_slab(5.0, 0.0, 0.0, 0.1, 1.5, n_photons=n_ph, rng=3)
    r_ref, t_ref = _clear_slab(5.0, 0.1, 1.5)  # 0.053569, 0.559308
    assert abs(res.total_transmittance - t_ref) < 4 * np.sqrt(t_ref * (1 - t_ref) / n_ph)
    assert abs(res.total_reflectance - r_ref) < 4 * res.total_reflectance_se + 1e-3
    assert res.unscattered_transmittance == pytest.approx(res.total_transmittance, rel=1e-12)


def test_non_absorbing_slab_conserves_energy():
    res = mc_slab(0.0, 50.0, 0.8, 0.05, 1.4, n_photons=5_000, rng=5)
    total = res.total_reflectance + res.total_transmittance
    # roulette conserves energy only on average
    assert total == pytest.approx(1.0, abs=5e-3)
    assert np.all(res.absorbed_per_layer == 0.0)


def test_layers_conserve_energy_and_split_like_one_slab():
    res = mc_layers(
        [1.0, 1.0], [60.0, 60.0], [0.8, 0.8], [0.02, 0.03], [1.4, 1.4], n_photons=20_000, rng=8
    )
    budget = res.total_reflectance + res.total_transmittance + res.absorbed_per_layer.sum()
    assert budget == pytest.approx(1.0, abs=5e-3)
    r_ad, t_ad = slab_rt(1.0, 60.0, 0.8, 0.05, 1.4)
    assert abs(res.total_reflectance - r_ad) < 4 * res.total_reflectance_se
    assert abs(res.total_transmittance - t_ad) < 4 * res.total_transmittance_se
    assert res.mean_pathlength_cm.shape == (2,)
    assert np.all(res.mean_pathlength_cm > 0)


def test_index_step_between_layers_conserves_energy():
    res = mc_layers(
        [1.0, 2.0], [100.0, 50.0], [0.9, 0.8], [0.05, 0.1], [1.4, 1.5], n_photons=5_000, rng=9
    )
    budget = res.total_reflectance + res.total_transmittance + res.absorbed_per_layer.sum()
    assert budget == pytest.approx(1.0, abs=1e-2)
    assert np.all(res.absorbed_per_layer > 0)


def test_radial_profile_integrates_to_diffuse_reflectance():
    edges = np.concatenate([np.linspace(0.0, 0.2, 21), [1e3]])
    res = mc_slab(*BENCH, n_photons=20_000, rng=4, rho_edges_cm=edges)
    area = np.pi * (edges[1:] ** 2 - edges[:-1] ** 2)
    assert np.sum(res.reflectance_per_cm2 * area) == pytest.approx(
        res.diffuse_reflectance, rel=1e-10
    )
    assert res.rho_cm.shape == res.reflectance_per_cm2_se.shape == (21,)
    assert np.all(res.reflectance_per_cm2_se[:5] > 0)


def _farrell_annulus_mean(r0, r1, mua, musp, n):
    num, _ = integrate.quad(lambda r: 2 * np.pi * r * farrell_reflectance(r, mua, musp, n), r0, r1)
    return num / (np.pi * (r1**2 - r0**2))


def _check_against_farrell(res, edges, mua, musp, n, rel_tol):
    for i, (r0, r1) in enumerate(zip(edges[:-1], edges[1:], strict=True)):
        ref = _farrell_annulus_mean(r0, r1, mua, musp, n)
        mc, se = res.reflectance_per_cm2[i], res.reflectance_per_cm2_se[i]
        assert abs(mc / ref - 1) < rel_tol + 3 * se / ref, (r0, r1, mc, ref, se)


def test_semi_infinite_radial_reflectance_matches_farrell_far_from_source():
    # mua = 0.1, musp = 10 /cm (g = 0), matched index: at rho = 10-15 transport mean
    # free paths the dipole model is within a few % of transport theory. Tolerance:
    # 8 % model error + 3 batch standard errors.
    mua, mus = 0.1, 10.0
    edges = np.array([0.9, 1.1, 1.35, 1.65])
    res = mc_slab(mua, mus, 0.0, np.inf, 1.0, n_photons=30_000, rng=21, rho_edges_cm=edges)
    _check_against_farrell(res, edges[[0, 1]], mua, mus, 1.0, 0.08)
    r_far = res.reflectance_per_cm2[[0, 2]]
    assert r_far[0] > r_far[1]
    # mean path of the detected light vs diffusion DPF * rho (15 % tolerance)
    rho = res.rho_cm[[0, 2]]
    dpf_path = differential_pathlength_factor(rho, mua, mus) * rho
    np.testing.assert_allclose(res.pathlength_at_rho_cm[[0, 2]], dpf_path, rtol=0.15)


@pytest.mark.slow
def test_semi_infinite_mismatched_matches_farrell_slow():
    mua, mus, n = 0.1, 10.0, 1.4
    edges = np.array([0.45, 0.55, 0.7, 0.8, 0.95, 1.05, 1.45, 1.55])
    res = mc_slab(mua, mus, 0.0, np.inf, n, n_photons=100_000, rng=22, rho_edges_cm=edges)
    keep = [0, 2, 4, 6]
    for i in keep:
        ref = _farrell_annulus_mean(edges[i], edges[i + 1], mua, mus, n)
        mc, se = res.reflectance_per_cm2[i], res.reflectance_per_cm2_se[i]
        assert abs(mc / ref - 1) < 0.10 + 3 * se / ref


def test_seed_reproducible_and_generator_accepted():
    a = mc_slab(*BENCH, n_photons=2_000, rng=123)
    b = mc_slab(*BENCH, n_photons=2_000, rng=np.random.default_rng(123))
    assert a.diffuse_reflectance == b.diffuse_reflectance
    assert a.total_transmittance == b.total_transmittance
    c = mc_slab(*BENCH, n_photons=2_000, rng=124)
    assert c.diffuse_reflectance != a.diffuse_reflectance


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"mua_per_cm": -1.0}, "mua_per_cm"),
        ({"mus_per_cm": np.nan}, "mus_per_cm"),
        ({"g": 1.0}, "g = "),
        ({"thickness_cm": 0.0}, "thickness_cm"),
        ({"n_slab": 0.0}, "n_layers"),
        ({"n_photons": 0}, "n_photons"),
        ({"thickness_cm": np.inf, "mua_per_cm": 0.0}, "semi-infinite"),
        ({"rho_edges_cm": [1.0, 0.5]}, "rho_edges_cm"),
    ],
)
def test_bad_input_raises(kwargs, match):
    args = {
        "mua_per_cm": 1.0,
        "mus_per_cm": 10.0,
        "g": 0.5,
        "thickness_cm": 0.1,
        "n_slab": 1.4,
        "n_photons": 10,
        "rng": 0,
    } | kwargs
    with pytest.raises(ConfigError, match=match):
        mc_slab(**args)


def test_layer_length_mismatch_raises():
    with pytest.raises(ConfigError, match="per layer"):
        mc_layers([1.0, 1.0], [10.0, 10.0, 10.0], 0.9, [0.1, 0.1], 1.4, n_photons=10, rng=0)

# Long-running (whole studies, end-to-end runs, Monte Carlo or every model): `make test-slow`,
# which CI runs beside the fast `make test` (tests/test_slow_marks.py)
pytestmark = pytest.mark.slow
