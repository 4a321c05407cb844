"""Tests of nirglucose_reference.mc_paths (per-layer paths at a detector ring)."""

from __future__ import annotations

import numpy as np
import pytest

from nirglucose.exceptions import ConfigError
from nirglucose.optics.layers import three_layer_reflectance
from nirglucose_reference.mc_paths import DetectedPaths, mc_detected_paths, reweight_detected
from nirglucose_reference.monte_carlo import mc_layers

# a strongly absorbing medium: photons die fast, so these runs take a second or two
FAST = dict(mus_per_cm=[100.0, 100.0], g=0.8, thickness_cm=[0.05], n_tissue=1.4)


@pytest.fixture(scope="module")
def fast_run() -> DetectedPaths:
    return mc_detected_paths([2.0, 2.0], ring_cm=(0.05, 0.15), n_photons=5_000, rng=1, **FAST)


def test_agrees_with_mcml_reference(fast_run):
    ref = mc_layers([2.0, 2.0], [100.0, 100.0], [0.8, 0.8], [0.05, np.inf], [1.4, 1.4],
                    n_photons=5_000, rng=2, rho_edges_cm=[0.05, 0.15])
    se = np.hypot(ref.diffuse_reflectance_se, ref.diffuse_reflectance_se)
    assert abs(fast_run.diffuse_reflectance - ref.diffuse_reflectance) < 4 * se
    r, r_se, paths = reweight_detected(fast_run, [2.0, 2.0])
    r_ref, r_ref_se = ref.reflectance_per_cm2[0], ref.reflectance_per_cm2_se[0]
    assert abs(r - r_ref) < 4 * np.hypot(r_se, r_ref_se)
    # the per-layer paths sum to the total mean path, here tallied independently by MCML
    assert paths.sum() == pytest.approx(ref.pathlength_at_rho_cm[0], rel=0.05)


def test_reweighting_is_exact_and_matches_a_fresh_run(fast_run):
    r0, _, p0 = reweight_detected(fast_run, fast_run.mua_ref_per_cm)
    w = fast_run.weight.sum() / fast_run.n_photons / fast_run.ring_area_cm2
    assert r0 == pytest.approx(w, rel=1e-12)
    # absorption only in the top layer raised: compare with a run made there
    r1, se1, p1 = reweight_detected(fast_run, [4.0, 2.0])
    fresh = mc_detected_paths([4.0, 2.0], ring_cm=(0.05, 0.15), n_photons=5_000, rng=3,
                              **FAST)
    r2, se2, p2 = reweight_detected(fresh, [4.0, 2.0])
    assert abs(r1 - r2) < 4 * np.hypot(se1, se2)
    assert r1 < r0 and p1[0] < p0[0]  # more absorption: fewer, shorter top-layer paths
    # microscopic Beer-Lambert: d ln R / d mua_1 = -L_1
    r_eps, _, _ = reweight_detected(fast_run, [2.0 + 1e-6, 2.0])
    assert (np.log(r0) - np.log(r_eps)) / 1e-6 == pytest.approx(p0[0], rel=1e-4)


def test_reweighting_below_the_reference_raises(fast_run):
    with pytest.raises(ConfigError, match="reference"):
        reweight_detected(fast_run, [1.0, 2.0])


def test_same_seed_same_result():
    kw = dict(ring_cm=(0.05, 0.15), n_photons=500, **FAST)
    a = mc_detected_paths([2.0, 2.0], rng=5, **kw)
    b = mc_detected_paths([2.0, 2.0], rng=5, **kw)
    np.testing.assert_array_equal(a.weight, b.weight)
    np.testing.assert_array_equal(a.pathlength_cm, b.pathlength_cm)


@pytest.mark.parametrize(
    ("kw", "match"),
    [
        ({"mua_ref_per_cm": [1.0, 0.0]}, "mua_ref_per_cm"),
        ({"mus_per_cm": [100.0, -1.0]}, "mus_per_cm"),
        ({"g": 1.0}, "g"),
        ({"thickness_cm": [0.05, 0.1]}, "thickness_cm"),
        ({"ring_cm": (0.2, 0.1)}, "ring_cm"),
        ({"n_photons": 0}, "n_photons"),
    ],
)
def test_bad_inputs_raise(kw, match):
    args = dict(mua_ref_per_cm=[1.0, 1.0], mus_per_cm=[100.0, 100.0], g=0.8,
                thickness_cm=[0.05], ring_cm=(0.1, 0.2), n_photons=10, rng=0)
    args.update(kw)
    with pytest.raises(ConfigError, match=match):
        mc_detected_paths(**args)


@pytest.mark.parametrize(
    ("kw", "match"),
    [
        ({"roulette_chance": 2.0},
         r"roulette_chance = 2\.0 is out of range; valid range is \(0, 1\)"),
        ({"roulette_chance": 0.0}, r"roulette_chance = 0\.0 is out of range"),
        ({"weight_threshold": 1.5}, r"weight_threshold = 1\.5 is out of range"),
        ({"n_ambient": 0.0}, r"n_ambient = 0\.0 is out of range; valid range is \(0, inf\)"),
        ({"n_tissue": -1.4, "n_ambient": -1.0}, r"n_tissue = -1\.4 is out of range"),
        ({"n_tissue": np.inf}, r"n_tissue = inf is out of range"),
        ({"ring_cm": 0.2}, r"ring_cm = 0\.2 must be two radii"),
        ({"ring_cm": (0.1, 0.2, 0.3)}, r"ring_cm = \(0\.1, 0\.2, 0\.3\) must be two radii"),
        ({"ring_cm": (0.1, np.inf)}, "ring_cm"),
        ({"mua_ref_per_cm": [[1.0, 1.0]]}, "mua_ref_per_cm must be a scalar or a 1-D"),
    ],
)
def test_bad_inputs_the_engine_or_the_ring_once_let_through_raise_one_config_error(kw, match):
    # each of these once ran biased, warned, or died with ZeroDivisionError, TypeError,
    # ValueError (unpacking, or an ambiguous truth value) instead of a ConfigError
    args = dict(mua_ref_per_cm=[1.0, 1.0], mus_per_cm=[100.0, 100.0], g=0.8,
                thickness_cm=[0.05], ring_cm=(0.1, 0.2), n_photons=10, rng=0)
    args.update(kw)
    with pytest.raises(ConfigError, match=match):
        mc_detected_paths(**args)


@pytest.mark.slow
def test_three_layer_model_against_monte_carlo():
    # skin: epidermis 80 um, dermis to 1.58 mm (mus' 20 /cm), fat below (mus' 14 /cm),
    # g = 0.9, n = 1.4, detector ring 2.5-3.5 mm. One run (about 1-2 min of CPU),
    # re-weighted to several melanin and blood contents.
    g = 0.9
    run = mc_detected_paths([0.2, 0.1, 0.03], [200.0, 200.0, 140.0], g, [0.008, 0.15],
                            ring_cm=(0.25, 0.35), n_photons=20_000, rng=2)
    x, w = np.polynomial.legendre.leggauss(6)  # the model averaged over the same ring
    rho = 0.3 + 0.05 * x
    weight = w * 0.05 * 2 * np.pi * rho / run.ring_area_cm2
    for mua in ([0.25, 0.3, 0.1], [5.0, 0.3, 0.1], [15.0, 0.3, 0.1], [0.25, 1.0, 1.0]):
        r_mc, se, p_mc = reweight_detected(run, mua)
        r_model, p_model = 0.0, 0.0
        for r_i, w_i in zip(rho, weight, strict=True):
            r, p = three_layer_reflectance(
                r_i, mua_epidermis_per_cm=mua[0], mua_dermis_per_cm=mua[1],
                musp_dermis_per_cm=20.0, mua_subcutis_per_cm=mua[2],
                musp_subcutis_per_cm=14.0, epidermis_thickness_cm=0.008,
                skin_thickness_cm=0.158)
            r_model += w_i * r
            p_model += w_i * r * p
        p_model /= r_model
        assert abs(r_model / r_mc - 1.0) < 0.04 + 3 * se / r_mc
        np.testing.assert_allclose(p_model[1:], p_mc[1:], rtol=0.12)
        assert p_model[0] == pytest.approx(p_mc[0], rel=0.25)  # diffusion near the surface

# Long-running (whole studies, end-to-end runs, Monte Carlo or every model): `make test-slow`,
# which CI runs beside the fast `make test` (tests/test_slow_marks.py)
pytestmark = pytest.mark.slow
