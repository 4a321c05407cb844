"""Tests of nirglucose_reference.adding_doubling.slab_rt (iadpython wrapper)."""

from __future__ import annotations

import numpy as np
import pytest

from nirglucose.exceptions import ConfigError
from nirglucose_reference.adding_doubling import slab_rt

pytest.importorskip("iadpython")

# MCML benchmark slab (Wang, Jacques & Zheng 1995, table 2; van de Hulst 1980):
# mua = 10 /cm, mus = 90 /cm, g = 0.75, d = 0.02 cm, n = 1 -> albedo 0.9, tau = 2.
MCML_RD = 0.09734
MCML_TT = 0.66096


def _clear_slab(mua, d, n):
    """Non-scattering slab: incoherent sum of the multiple reflections.

    The beam enters with (1 - r); each round trip inside multiplies it by r^2 T^2
    (T = exp(-mua d)), so
        T_t = (1-r) T (1-r) [1 + r^2 T^2 + r^4 T^4 + ...] = (1-r)^2 T / (1 - r^2 T^2)
        R   = r + (1-r) T r T (1-r) [1 + r^2 T^2 + ...] = r + (1-r)^2 r T^2 / (1 - r^2 T^2)
    with the normal-incidence Fresnel reflectance r = ((n-1)/(n+1))^2.
    """
    r = ((n - 1) / (n + 1)) ** 2
    t = np.exp(-mua * d)
    den = 1 - r**2 * t**2
    return r + (1 - r) ** 2 * r * t**2 / den, (1 - r) ** 2 * t / den


def test_mcml_benchmark_slab():
    r, t = slab_rt(10.0, 90.0, 0.75, 0.02, 1.0)
    assert r == pytest.approx(MCML_RD, rel=0.01)
    assert t == pytest.approx(MCML_TT, rel=0.01)
    # the adding-doubling answer is in fact much closer than 1 %
    assert r == pytest.approx(MCML_RD, rel=2e-3)
    assert t == pytest.approx(MCML_TT, rel=2e-4)


@pytest.mark.parametrize("n", [1.0, 1.33, 1.5])
@pytest.mark.parametrize("mua", [0.0, 5.0, 40.0])
def test_non_scattering_slab_matches_multiple_reflection_formula(n, mua):
    # e.g. n = 1.5, mua = 5 /cm, d = 0.1 cm: r = 0.04, T = e^-0.5 = 0.606531,
    # T_t = 0.9216 * 0.606531 / (1 - 0.0016 * 0.367879) = 0.558979 / 0.999411 = 0.559308
    r, t = slab_rt(mua, 0.0, 0.0, 0.1, n)
    r_ref, t_ref = _clear_slab(mua, 0.1, n)
    assert r == pytest.approx(r_ref, rel=1e-4, abs=1e-8)
    assert t == pytest.approx(t_ref, rel=1e-4)


def test_clear_slab_hand_value():
    # n = 1.5, mua = 5 /cm, d = 0.1 cm (worked numbers in the test above)
    _, t = slab_rt(5.0, 0.0, 0.3, 0.1, 1.5)
    assert t == pytest.approx(0.559308, abs=5e-6)


@pytest.mark.parametrize("n", [1.0, 1.4])
def test_non_absorbing_slab_conserves_energy(n):
    r, t = slab_rt(0.0, np.array([1.0, 10.0, 100.0]), 0.8, 0.5, n)
    np.testing.assert_allclose(r + t, 1.0, atol=2e-4)


def test_optically_thick_non_absorbing_slab_reflects_everything():
    # tau = 1000 /cm * 10 cm = 1e4, transport optical thickness 1e4 * (1 - g)
    r, t = slab_rt(0.0, 1000.0, 0.0, 10.0, 1.4)
    assert r > 0.999
    assert t < 1e-3


def test_optically_thick_absorbing_slab_transmits_nothing():
    r, t = slab_rt(1.0, 100.0, 0.9, 20.0, 1.4)
    assert t < 1e-12
    assert 0.0278 < r < 1.0  # at least the specular ((0.4/2.4)^2 = 0.02778)


def test_matched_vs_mismatched_index():
    # mismatch adds specular reflection and traps diffuse light (more absorption)
    r1, t1 = slab_rt(1.0, 100.0, 0.9, 0.2, 1.0)
    r2, t2 = slab_rt(1.0, 100.0, 0.9, 0.2, 1.4)
    assert t2 < t1
    assert 1 - r2 - t2 > 1 - r1 - t1  # absorbed fraction grows
    # only the relative index matters
    r3, t3 = slab_rt(1.0, 100.0, 0.9, 0.2, 1.4 * 1.33, 1.33)
    assert r3 == pytest.approx(r2, rel=1e-10)
    assert t3 == pytest.approx(t2, rel=1e-10)


def test_monotonic_in_absorption():
    mua = np.linspace(0.0, 20.0, 9)
    r, t = slab_rt(mua, 100.0, 0.9, 0.1, 1.4)
    assert np.all(np.diff(r) < 0)
    assert np.all(np.diff(t) < 0)


def test_broadcasting_and_shapes():
    mua = np.array([[1.0], [10.0]])
    mus = np.array([90.0, 50.0, 20.0])
    g = np.array([0.75, 0.0, 0.9])
    r, t = slab_rt(mua, mus, g, 0.02, 1.4)
    assert r.shape == t.shape == (2, 3)
    r_el, t_el = slab_rt(10.0, 20.0, 0.9, 0.02, 1.4)
    assert r[1, 2] == pytest.approx(float(r_el), rel=1e-12)
    assert t[1, 2] == pytest.approx(float(t_el), rel=1e-12)
    r0, t0 = slab_rt(np.zeros(0), 1.0, 0.5, 0.1, 1.4)
    assert r0.shape == t0.shape == (0,)
    r_s, _ = slab_rt(1.0, 90.0, 0.75, 0.02, 1.0)
    assert np.ndim(r_s) == 0


def test_quadrature_convergence():
    r8, t8 = slab_rt(10.0, 90.0, 0.75, 0.02, 1.4, quad_pts=8)
    r24, t24 = slab_rt(10.0, 90.0, 0.75, 0.02, 1.4, quad_pts=24)
    assert r8 == pytest.approx(r24, rel=5e-3)
    assert t8 == pytest.approx(t24, rel=5e-3)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"mua_per_cm": -1.0}, "mua_per_cm"),
        ({"mus_per_cm": np.nan}, "mus_per_cm"),
        ({"g": 1.0}, "g = "),
        ({"g": -1.0}, "g = "),
        ({"thickness_cm": 0.0}, "thickness_cm"),
        ({"thickness_cm": np.inf}, "thickness_cm"),
        ({"n_slab": 0.9}, "n_slab / n_ambient"),
        ({"n_ambient": 0.0}, "n_ambient"),
        ({"quad_pts": 7}, "quad_pts"),
        ({"quad_pts": 64}, "quad_pts"),
    ],
)
def test_bad_input_raises(kwargs, match):
    args = {
        "mua_per_cm": 1.0,
        "mus_per_cm": 100.0,
        "g": 0.9,
        "thickness_cm": 0.1,
        "n_slab": 1.4,
    } | kwargs
    with pytest.raises(ConfigError, match=match):
        slab_rt(**args)
