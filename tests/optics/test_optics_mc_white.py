"""Tests of nirglucose.optics.kernels.mc_white (the compiled white Monte Carlo of the table)."""

from __future__ import annotations

import numpy as np
import pytest

from nirglucose.exceptions import ConfigError
from nirglucose.optics.kernels.mc_white import (
    kernel_weight,
    white_mc_points,
    white_mc_run,
    white_mc_tally,
)
from nirglucose_reference.mc_paths import mc_detected_paths, reweight_detected


def test_mcml_benchmark_slab():
    # mua = 10 /cm, mus = 90 /cm, g = 0.75, d = 0.02 cm, n = 1 (Wang, Jacques & Zheng
    # 1995; van de Hulst 1980): Rd = 0.09734, Tt = 0.66096. In transport units
    # (mus' = 22.5 /cm) the slab is 0.45 thick, absorbs 0.444 per unit (simulated
    # analogously by the path budget), and nothing scatters below it (q = 0).
    musp = 90.0 * 0.25
    run = white_mc_run(musp * 0.02, 0.0, [0.1], (0.0, 1.0), n_photons=1_000_000, seed=1,
                       mua_ref=10.0 / musp, g=0.75, n_tissue=1.0, n_ambient=1.0)
    for value, ref in ((run.escaped, 0.09734), (run.transmitted, 0.66096)):
        se = np.sqrt(ref * (1 - ref) / run.n_photons)
        assert abs(value - ref) < 3 * se  # 3 standard errors: 0.9 % and 0.2 %
        assert value == pytest.approx(ref, rel=0.01)


# a strongly absorbing skin (photons die fast, so the numpy reference runs in seconds)
MUSP, Q, G = 20.0, 0.7, 0.8
T_EPI, T_SKIN, RING = 0.01, 0.05, (0.05, 0.15)
MUA = (10.0, 2.0, 2.0)  # epidermis, dermis, subcutis [1/cm]


def _ring_average(run, mua_per_cm):
    """Ring-averaged R and mean paths from a white run (the estimator mc_paths uses)."""
    lo, hi = (v * MUSP for v in RING)
    sel = (run.radius >= lo) & (run.radius < hi)
    p = run.path[sel]
    ell = np.stack([p[:, 0], p[:, -2] - p[:, 0], p[:, -1]], axis=1)  # epi, dermis, sub
    delta = np.asarray(mua_per_cm) / MUSP - run.settings["mua_ref"]
    w = run.weight[sel] * np.exp(-ell @ delta)
    r_sp = ((1.4 - 1.0) / 2.4) ** 2
    area = np.pi * (RING[1] ** 2 - RING[0] ** 2)
    refl = (1 - r_sp) * w.sum() / run.n_photons / area
    batches = np.bincount(run.batch[sel], weights=w, minlength=run.n_batches)
    se = (1 - r_sp) * batches.std(ddof=1) / np.sqrt(run.n_batches) * run.n_batches \
        / run.n_photons / area
    return refl, se, (w @ ell) / w.sum() / MUSP


def test_parity_with_the_numpy_monte_carlo():
    # two independent implementations of the same transport: within 4 combined
    # standard errors in R, 5 % in the dermis and subcutis paths (about 2 standard errors)
    ref = mc_detected_paths(list(MUA), [MUSP / (1 - G)] * 2 + [Q * MUSP / (1 - G)], G,
                            [T_EPI, T_SKIN - T_EPI], RING, n_photons=15_000, rng=4)
    r_ref, se_ref, p_ref = reweight_detected(ref, list(MUA))
    run = white_mc_run(T_SKIN * MUSP, Q, [T_EPI * MUSP], (RING[0] * MUSP, RING[1] * MUSP),
                       n_photons=60_000, seed=2, mua_ref=1.0 / MUSP, g=G)
    r, se, p = _ring_average(run, MUA)
    assert abs(r - r_ref) < 4 * np.hypot(se, se_ref)
    np.testing.assert_allclose(p[1:], p_ref[1:], rtol=0.05)
    assert p[0] == pytest.approx(p_ref[0], rel=0.1)


def test_same_seed_same_bytes_for_any_thread_count():
    kw = dict(n_photons=9_000, mua_ref=0.01, g=0.9)
    a = white_mc_run(2.0, 0.6, [0.2, 0.3], (1.0, 4.0), seed=5, n_threads=1, **kw)
    b = white_mc_run(2.0, 0.6, [0.2, 0.3], (1.0, 4.0), seed=5, n_threads=2, **kw)
    c = white_mc_run(2.0, 0.6, [0.2, 0.3], (1.0, 4.0), seed=6, n_threads=1, **kw)
    np.testing.assert_array_equal(a.path, b.path)
    np.testing.assert_array_equal(a.radius, b.radius)
    assert a.escaped == b.escaped
    assert not np.array_equal(a.radius[:50], c.radius[:50])


def test_disjoint_photon_ranges_are_independent_and_make_up_the_whole_run():
    kw = dict(seed=5, mua_ref=0.01, g=0.9, n_threads=2)
    args = (2.0, 0.6, [0.2, 0.3], (1.0, 4.0))
    whole = white_mc_run(*args, n_photons=10_000, **kw)
    a = white_mc_run(*args, n_photons=6_000, **kw)
    b = white_mc_run(*args, n_photons=4_000, first_photon=6_000, **kw)
    # the same photons, recorded in the same order
    np.testing.assert_array_equal(np.concatenate([a.radius, b.radius]), whole.radius)
    np.testing.assert_array_equal(np.concatenate([a.path, b.path]), whole.path)
    assert b.batch.min() == 0 and b.n_batches == 1  # standard errors within the range
    tally = [white_mc_tally(r, 0.2, 0.05, [10.0, 15.0], [5.0], [0.3], [0.2])
             for r in (whole, a, b)]
    mean = (6_000 * tally[1]["reflectance_per_cm2"] + 4_000 * tally[2]["reflectance_per_cm2"]
            ) / 10_000
    np.testing.assert_allclose(mean, tally[0]["reflectance_per_cm2"], rtol=1e-12)
    assert not np.allclose(tally[1]["reflectance_per_cm2"], tally[2]["reflectance_per_cm2"])
    for bad in (-1, 1.5, True):
        with pytest.raises(ConfigError, match="first_photon"):
            white_mc_run(*args, n_photons=10, first_photon=bad, **kw)


def test_tally_reweighting_is_the_microscopic_beer_lambert_law():
    run = white_mc_run(3.0, 0.6, [0.16, 0.3], (1.0, 12.0), n_photons=20_000, seed=3,
                       mua_ref=0.01 / 30)
    musp = np.array([20.0, 37.5])  # epidermis depths 0.16 / 20 = 0.3 / 37.5 = 80 um
    kw = dict(rho_cm=0.2, half_width_cm=0.075, musp_skin_per_cm=musp)
    base = white_mc_tally(run, mua_epidermis_per_cm=5.0, mua_dermis_per_cm=0.3,
                          mua_subcutis_per_cm=0.2, **kw)
    eps = 1e-5
    for layer, name in enumerate(("mua_epidermis_per_cm", "mua_dermis_per_cm",
                                  "mua_subcutis_per_cm")):
        mua = {"mua_epidermis_per_cm": 5.0, "mua_dermis_per_cm": 0.3,
               "mua_subcutis_per_cm": 0.2}
        mua[name] += eps
        up = white_mc_tally(run, **mua, **kw)
        d_ln_r = (np.log(base["reflectance_per_cm2"]) - np.log(up["reflectance_per_cm2"])) / eps
        np.testing.assert_allclose(d_ln_r.ravel(), base["pathlength_cm"][..., layer].ravel(),
                                   rtol=1e-3)
    assert np.all(base["reflectance_se_per_cm2"] < 0.2 * base["reflectance_per_cm2"])
    # more absorption anywhere: less light
    more = white_mc_tally(run, mua_epidermis_per_cm=[5.0, 20.0], mua_dermis_per_cm=0.3,
                          mua_subcutis_per_cm=[0.2, 1.0], **kw)["reflectance_per_cm2"]
    assert np.all(np.diff(more, axis=1) < 0) and np.all(np.diff(more, axis=3) < 0)


def test_points_share_the_run_of_their_layer_geometry():
    kw = dict(mua_ref=0.01 / 30, n_photons=8_000, seed=1, musp_ratio=0.6,
              skin_transport_thickness=4.0)
    r, se, p = white_mc_points(0.3, 0.075, 0.008, mua_epidermis_per_cm=[1.0, 20.0],
                               mua_dermis_per_cm=[0.2, 0.2], musp_dermis_per_cm=[15.0, 15.0],
                               mua_subcutis_per_cm=[0.1, 0.1], **kw)
    assert r[1] < r[0] and p[1, 0] < p[0, 0]  # melanin: less light, shorter epidermal path
    assert np.all(se < 0.2 * r) and np.all(p > 0)


def test_kernel_is_fourth_order_and_continuous():
    u = np.linspace(-1.2, 1.2, 240_001)
    k = kernel_weight(u)
    du = u[1] - u[0]
    assert np.sum(k) * du == pytest.approx(1.0, abs=1e-6)
    assert np.sum(k * u * u) * du == pytest.approx(0.0, abs=1e-6)
    assert kernel_weight(np.array([1.0, -1.0, 0.999999])) == pytest.approx(0.0, abs=1e-5)


def test_bad_inputs_raise():
    kw = dict(n_photons=10, seed=0, mua_ref=0.01)
    with pytest.raises(ConfigError, match="depths"):
        white_mc_run(1.0, 0.5, [1.5], (0.0, 1.0), **kw)
    with pytest.raises(ConfigError, match="musp_ratio"):
        white_mc_run(1.0, -0.5, [0.5], (0.0, 1.0), **kw)
    with pytest.raises(ConfigError, match="mua_ref"):
        white_mc_run(1.0, 0.5, [0.5], (0.0, 1.0), n_photons=10, seed=0, mua_ref=0.0)
    with pytest.raises(ConfigError, match="n_photons"):
        white_mc_run(1.0, 0.5, [0.5], (0.0, 1.0), n_photons=0, seed=0, mua_ref=0.01)
