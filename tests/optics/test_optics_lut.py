"""Tests of nirglucose.optics.lut (the rte-lut look-up table) and its simulator wiring.

Every test uses a temporary cache directory (NIRGLUCOSE_CACHE) and never a pre-existing
cache. "Direct solve" below is nirglucose_reference.lut_checks.direct_solve: a
white Monte Carlo run at the point with the table's settings and common random numbers
(the model the table is built from).
"""

from __future__ import annotations

import pickle

import numpy as np
import pytest

import nirglucose as ng
from nirglucose.exceptions import ConfigError
from nirglucose.optics import forward, layers, tissue
from nirglucose.optics import lut as L
from nirglucose.optics.kernels import mc_white
from nirglucose.optics.lut import build as LB
from nirglucose.optics.lut import cache as LC
from nirglucose.optics.lut import grid as LG
from nirglucose_reference import lut_checks as LV

RHO, T_EPI = 0.3, 0.008


@pytest.fixture(autouse=True)
def _tmp_cache(tmp_path, monkeypatch):
    monkeypatch.setenv("NIRGLUCOSE_CACHE", str(tmp_path / "cache"))
    monkeypatch.delenv("NIRGLUCOSE_LUT_GRID", raising=False)


@pytest.fixture(scope="module")
def tiny():
    return L.build_lut(RHO, T_EPI, grid="tiny")


def _sub_grid(n: int = 5, first: int = 1) -> dict:
    """A block of the default grid: its own node spacing, n solve nodes per axis.

    The block sits where the simulator's cohorts are dense (mid wavelengths, normal
    skin); it is refined exactly as the default grid is, so its interpolation error
    is that of the default table there, at a fraction of the build time.
    """
    spec = L.LUT_GRIDS["default"]
    out = {}
    start = {"musp_dermis_per_cm": first, "mua_dermis_per_cm": first,
             "mua_subcutis_per_cm": first, "mua_epidermis_per_cm": first - 1}
    for name, (lo, hi, ns, m) in spec.items():
        kind = L.LUT_AXES[name][0]
        if name == "musp_ratio":
            out[name] = (lo, hi, ns, m)
            continue
        if name == "skin_transport_thickness":
            # the right-hand piece of the default thickness axis, from tau = 1
            u_hi = np.log(hi)
            n_right = ns - int(np.clip(round((ns - 1) * -np.log(lo) / (u_hi - np.log(lo))),
                                       1, ns - 2))
            h = u_hi / (n_right - 1)
            out[name] = (float(np.exp(h * (first - 1))), float(np.exp(h * (first + n - 2))),
                         n, m)
            continue
        u = np.linspace(LG._forward(kind, np.float64(lo)), LG._forward(kind, np.float64(hi)), ns)
        i = start[name]
        out[name] = (float(LG._inverse(kind, u[i])), float(LG._inverse(kind, u[i + n - 1])), n, m)
    return out


def test_grids_and_axes_are_consistent():
    for spec in L.LUT_GRIDS.values():
        assert set(spec) == set(L.LUT_AXES)
    with pytest.raises(ConfigError, match="unknown LUT grid"):
        L.build_lut(RHO, T_EPI, grid="huge")
    bad = dict(L.LUT_GRIDS["tiny"])
    bad["mua_dermis_per_cm"] = (1.0, 0.5, 3, 1)
    with pytest.raises(ConfigError, match="mua_dermis_per_cm"):
        L.build_lut(RHO, T_EPI, grid=bad)


def test_tiny_table_is_exact_at_its_nodes(tiny):
    assert tiny.values.shape == (2, 2, 2, 2, 2, 3, 4)
    assert tiny.values.dtype == np.float32
    ax = {k: tiny.axis_nodes(k) for k in L.LUT_AXES}
    ax["musp_ratio"] = ax["musp_ratio"][:1]  # two (ratio, thickness) runs suffice
    ax["skin_transport_thickness"] = ax["skin_transport_thickness"][1:]
    mesh = np.meshgrid(*ax.values(), indexing="ij")
    p = dict(zip(ax, (m.ravel() for m in mesh), strict=True))
    args = dict(
        mua_epidermis_per_cm=p["mua_epidermis_per_cm"], mua_dermis_per_cm=p["mua_dermis_per_cm"],
        musp_dermis_per_cm=p["musp_dermis_per_cm"], mua_subcutis_per_cm=p["mua_subcutis_per_cm"],
        musp_subcutis_per_cm=p["musp_dermis_per_cm"] * p["musp_ratio"],
        skin_thickness_cm=p["skin_transport_thickness"] / p["musp_dermis_per_cm"],
    )
    r, paths = L.interpolate_lut(tiny, pathlengths=True, **args)
    r0, se0, p0 = LV.direct_solve(tiny, args)  # the same photons as the nodes' runs
    np.testing.assert_allclose(r, r0, rtol=1e-5)  # float32 storage of ln R
    np.testing.assert_allclose(paths, np.maximum(p0, 1e-6), rtol=1e-5)
    assert np.median(se0 / r0) < 0.1  # the tiny grid's few photons


def test_thickness_axis_has_a_node_at_one_transport_length(tiny):
    nodes = tiny.axis_nodes("skin_transport_thickness")
    assert np.any(np.isclose(nodes, 1.0, rtol=1e-12))
    # every node keeps the skin thicker than the epidermis
    assert nodes[0] / L.LUT_GRIDS["tiny"]["musp_dermis_per_cm"][1] > T_EPI


def test_interpolation_against_direct_solves_in_a_block_of_the_default_grid():
    # a 2 x 2 block of (ratio, thickness) runs at the default spacing, with few photons:
    # the table against direct solves (same random numbers) at random off-grid points
    # is within the Monte Carlo noise (a wrong axis, scaling or re-weighting is not);
    # the whole default grid's errors are in benchmarks/optics.py
    spec = L.LUT_GRIDS["default"]
    grid = _sub_grid(3, first=2)
    grid["musp_ratio"] = (spec["musp_ratio"][0], 0.5 * sum(spec["musp_ratio"][:2]), 2, 1)
    lo, hi, _, m = grid["skin_transport_thickness"]
    grid["skin_transport_thickness"] = (lo, float(np.sqrt(lo * hi)), 2, m)
    lut = L.build_lut(RHO, T_EPI, grid=grid, n_photons=15_000)
    pts = LV.random_lut_points(lut, 40, rng=2, groups=2)
    err = LV.lut_errors(lut, pts, n_photons=15_000)
    r, se = np.abs(err["reflectance"]), err["reflectance_se"]
    assert np.all(r <= np.maximum(0.01, 4 * se))
    assert np.median(r) <= 1.5 * np.median(se)
    assert np.median(np.abs(err["pathlength"][:, 1:])) <= 0.03


def test_out_of_box_raises_with_axis_name(tiny):
    kw = dict(mua_epidermis_per_cm=2.0, mua_dermis_per_cm=0.3, musp_dermis_per_cm=20.0,
              mua_subcutis_per_cm=0.1, musp_subcutis_per_cm=12.0, skin_thickness_cm=0.18)
    L.interpolate_lut(tiny, **kw)
    for key, value, axis in (("mua_dermis_per_cm", 9.0, "mua_dermis_per_cm"),
                             ("musp_dermis_per_cm", 50.0, "musp_dermis_per_cm"),
                             ("mua_epidermis_per_cm", np.nan, "mua_epidermis_per_cm"),
                             ("skin_thickness_cm", 3.0, "skin_transport_thickness")):
        bad = dict(kw)
        bad[key] = value
        with pytest.raises(ConfigError, match=axis):
            L.interpolate_lut(tiny, **bad)


def test_cache_round_trip_is_atomic_and_pickle_free(tmp_path):
    d = tmp_path / "c"
    lut = L.load_or_build_lut(RHO, T_EPI, grid="tiny", directory=d)
    files = sorted(p.name for p in d.iterdir())
    assert files == [f"lut-{lut.key}.npz"]  # no temporary file left behind
    assert lut.build_seconds > 0
    with np.load(d / files[0], allow_pickle=False) as f:
        assert str(f["key"]) == lut.key
    again = L.load_or_build_lut(RHO, T_EPI, grid="tiny", directory=d)
    assert again.build_seconds == 0.0
    np.testing.assert_array_equal(again.values, lut.values)
    for a, b in zip(again.nodes, lut.nodes, strict=True):
        np.testing.assert_array_equal(a, b)
    # a corrupt file is rebuilt, not trusted
    (d / files[0]).write_bytes(b"not a zip file")
    rebuilt = L.load_or_build_lut(RHO, T_EPI, grid="tiny", directory=d)
    assert rebuilt.build_seconds > 0
    np.testing.assert_array_equal(rebuilt.values, lut.values)


def test_key_depends_on_geometry_and_grid():
    k = L.lut_key(RHO, T_EPI, grid="tiny")
    assert k == L.lut_key(RHO, T_EPI, 1.4, 1.0, "tiny")
    assert k != L.lut_key(0.4, T_EPI, grid="tiny")
    assert k != L.lut_key(RHO, 0.01, grid="tiny")
    assert k != L.lut_key(RHO, T_EPI, 1.45, grid="tiny")
    assert k != L.lut_key(RHO, T_EPI, grid="default")
    assert k != L.lut_key(RHO, T_EPI, grid="tiny", n_photons=L.LUT_MC_PHOTONS["tiny"] + 1)


def test_cache_dir_env(monkeypatch, tmp_path):
    monkeypatch.setenv("NIRGLUCOSE_CACHE", str(tmp_path / "x"))
    assert L.cache_dir() == tmp_path / "x"
    monkeypatch.delenv("NIRGLUCOSE_CACHE")
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    assert L.cache_dir() == tmp_path / "xdg" / "nirglucose"


@pytest.mark.parametrize("value", ["abc", "0", "-2", "1.5"])
def test_mc_threads_env_that_is_no_count_is_one_config_error(monkeypatch, value):
    # was a bare ValueError traceback ("abc") or silently one thread ("0", "-2")
    monkeypatch.setenv("NIRGLUCOSE_MC_THREADS", value)
    with pytest.raises(ConfigError, match=r"NIRGLUCOSE_MC_THREADS = .* expected an integer "
                                          r"in \[1, inf\)"):
        LC.mc_threads_from_env()


def test_mc_threads_env_read_when_set(monkeypatch):
    monkeypatch.setenv("NIRGLUCOSE_MC_THREADS", "3")
    assert LC.mc_threads_from_env() == 3
    monkeypatch.delenv("NIRGLUCOSE_MC_THREADS")
    assert LC.mc_threads_from_env() is None


def _sim_optics(n=64, seed=0, n_led=4, n_pts=3):
    cfg = ng.resolve_config("paper", {"leds.band_points": n_pts})
    spectra = tissue.band_spectra(cfg.leds.wavelengths_nm, cfg.leds.fwhm_nm, n_pts)
    rng = np.random.default_rng(seed)
    state = tissue.TissueState(
        rng.uniform(0.01, 0.05, n), rng.uniform(0.6, 0.8, n), rng.uniform(0.6, 0.7, n),
        rng.uniform(0.7, 0.9, n), rng.uniform(4.0, 20.0, n),
    )
    shift = rng.normal(0.0, 2.0, (n, n_led))
    optics = tissue.tissue_optics(spectra, state, water_displacement_per_mm=1.1e-4,
                                  scattering_rel_per_mm=-1.25e-3 * 13.5, shift_nm=shift)
    nominal = tissue.tissue_optics(spectra, tissue.TissueState(*(np.full(1, v) for v in (
        0.02, 0.7, 0.65, 0.8, 5.5))), water_displacement_per_mm=0.0, scattering_rel_per_mm=0.0)
    ratio = nominal["musp_subcutis"][0] / nominal["musp_dermis"][0]
    return optics, rng.uniform(0.01, 0.15, n), rng.uniform(0.045, 0.4, n), ratio


def test_node_table_equals_the_generic_interpolation(tiny):
    optics, mel, thick, ratio = _sim_optics()
    nlut = L.node_lut(tiny, ratio)
    lay = layers.layers_from_tissue_optics(optics, mel)
    args = {
        "mua_epidermis_per_cm": lay["mua_epidermis"], "mua_dermis_per_cm": lay["mua_dermis"],
        "musp_dermis_per_cm": lay["musp_dermis"], "mua_subcutis_per_cm": lay["mua_subcutis"],
        "musp_subcutis_per_cm": lay["musp_subcutis"],
    }
    fast = L.interpolate_node_lut(nlut, skin_thickness_cm=thick, **args)
    slow, _ = L.interpolate_lut(tiny, skin_thickness_cm=thick[:, None, None], **args)
    assert fast.shape == slow.shape == lay["mua_dermis"].shape
    np.testing.assert_allclose(fast, slow, rtol=2e-5)


def test_forward_model_by_name(tiny, monkeypatch):
    monkeypatch.setenv("NIRGLUCOSE_LUT_GRID", "tiny")
    optics, mel, thick, ratio = _sim_optics(n=16)
    kw = dict(melanin_fraction=mel, skin_thickness_cm=thick, epidermis_thickness_cm=T_EPI,
              separation_cm=RHO, detector_area_cm2=0.066, n_tissue=1.4)
    assert "rte-lut" in forward.FORWARD_MODELS
    implicit = forward.detected_fraction("rte-lut", optics, **kw)  # default table (tiny)
    explicit = forward.detected_fraction("rte-lut", optics, lut=tiny, **kw)
    node = forward.detected_fraction("rte-lut", optics, lut=L.node_lut(tiny, ratio), **kw)
    np.testing.assert_allclose(implicit, explicit, rtol=1e-12)
    np.testing.assert_allclose(node, explicit, rtol=2e-5)
    assert np.all((explicit > 0) & (explicit < 0.066))
    with pytest.raises(ConfigError, match="rho_cm"):
        forward.detected_fraction("rte-lut", optics, lut=tiny, **{**kw, "separation_cm": 0.4})


def test_node_table_pickles_as_a_recipe(tiny, monkeypatch):
    monkeypatch.setenv("NIRGLUCOSE_LUT_GRID", "tiny")
    _, _, _, ratio = _sim_optics(n=2)
    nlut = L.node_lut(L.get_lut(RHO, T_EPI), ratio)
    blob = pickle.dumps(nlut)
    assert len(blob) < 20_000  # the arrays do not travel to worker processes
    back = pickle.loads(blob)
    np.testing.assert_array_equal(back.values, nlut.values)


def test_simulator_runs_with_rte_lut(monkeypatch):
    monkeypatch.setenv("NIRGLUCOSE_LUT_GRID", "tiny")
    over = {"optics.model": "rte-lut"}
    a = ng.simulate("paper", n_subjects=12, per_subject=2, seed=3, overrides=over)
    b = ng.simulate("paper", n_subjects=12, per_subject=2, seed=3, overrides=over)
    d = ng.simulate("paper", n_subjects=12, per_subject=2, seed=3)
    cfg = ng.resolve_config("paper", over)
    cols = [f"true_detected_fraction_{w:g}" for w in cfg.leds.wavelengths_nm]
    frac = a.frame[cols].to_numpy()
    assert np.all(np.isfinite(frac)) and np.all(frac > 0)
    assert a.frame.equals(b.frame)  # deterministic
    # same physiology and noise draws as the default model; only the optics differ
    np.testing.assert_array_equal(a.frame["glucose_mgdl"], d.frame["glucose_mgdl"])
    assert not np.allclose(frac, d.frame[cols].to_numpy())
    # the oracle's forward model reproduces the simulated fractions
    from nirglucose.simulation.simulator import detected_fraction_given_glucose

    again = detected_fraction_given_glucose(cfg, a.frame, a.frame["glucose_mgdl"].to_numpy())
    np.testing.assert_allclose(again, frac, rtol=1e-9)


def test_solver_choice_keys_builds_and_validates():
    mc = L.lut_key(RHO, T_EPI, grid="tiny")
    assert mc == L.lut_key(RHO, T_EPI, grid="tiny", solver="monte-carlo")
    assert mc != L.lut_key(RHO, T_EPI, grid="tiny", solver="diffusion")
    with pytest.raises(ConfigError, match="valid: monte-carlo, diffusion"):
        L.lut_key(RHO, T_EPI, solver="adding-doubling")
    with pytest.raises(ConfigError, match="unknown look-up table solver"):
        L.build_lut(RHO, T_EPI, grid="tiny", solver="mcml")
    lut = L.build_lut(RHO, T_EPI, grid="tiny", solver="diffusion")
    assert lut.solver == "diffusion"
    # exact at its nodes: the diffusion model solved there
    pts = {k: lut.axis_nodes(k) for k in L.LUT_AXES}
    musp = pts["musp_dermis_per_cm"][1]
    tau = pts["skin_transport_thickness"][-1]
    r_dir, paths = layers.three_layer_reflectance(
        RHO, mua_epidermis_per_cm=pts["mua_epidermis_per_cm"][0],
        mua_dermis_per_cm=pts["mua_dermis_per_cm"][1], musp_dermis_per_cm=musp,
        mua_subcutis_per_cm=pts["mua_subcutis_per_cm"][0],
        musp_subcutis_per_cm=musp * pts["musp_ratio"][1], epidermis_thickness_cm=T_EPI,
        skin_thickness_cm=tau / musp)
    r_lut, p_lut = L.interpolate_lut(
        lut, mua_epidermis_per_cm=pts["mua_epidermis_per_cm"][0],
        mua_dermis_per_cm=pts["mua_dermis_per_cm"][1], musp_dermis_per_cm=musp,
        mua_subcutis_per_cm=pts["mua_subcutis_per_cm"][0],
        musp_subcutis_per_cm=musp * pts["musp_ratio"][1], skin_thickness_cm=tau / musp,
        pathlengths=True)
    np.testing.assert_allclose(r_lut, r_dir, rtol=1e-5)
    np.testing.assert_allclose(p_lut, paths, rtol=1e-5)
    # its direct solves are the diffusion model (no Monte Carlo noise)
    err = LV.lut_errors(lut, n_points=20, rng=3)
    assert np.all(err["reflectance_se"] == 0.0)


def test_simulator_lut_solver_from_the_config(monkeypatch):
    monkeypatch.setenv("NIRGLUCOSE_LUT_GRID", "tiny")
    over = {"optics.model": "rte-lut"}
    mc = ng.simulate("paper", n_subjects=6, per_subject=2, seed=1, overrides=over)
    dif = ng.simulate("paper", n_subjects=6, per_subject=2, seed=1,
                      overrides={**over, "optics.lut_solver": "diffusion"})
    col = "true_detected_fraction_850"
    assert not np.allclose(mc.frame[col], dif.frame[col])
    assert dif.config.optics.lut_solver == "diffusion"
    with pytest.raises(ConfigError):
        ng.resolve_config("paper", {"optics.lut_solver": "adding-doubling"})


def test_residual_fit_keeps_smooth_differences_and_removes_node_noise():
    # the default grid's scattering axes, two absorption nodes, one channel
    grid = LG._resolve_grid("default")
    geo = LG._geometry(RHO, T_EPI, 1.4, 1.0)
    coords, splits = LB._solve_axes(grid, geo)
    x, q, y = coords[0], coords[1], coords[-1]
    deg = L.LUT_MC_SETTINGS["residual_fit_degrees"]

    def smooth(y, q=q):  # a difference with a kink at tau = 1 (y = 0), inside the fit's span
        gx, gq, gy = np.meshgrid(x, q, y, indexing="ij")
        d = 0.05 * gx - 0.1 * gq * gx + 0.02 * gy**2 + 0.03 * np.maximum(gy, 0.0)
        return d[:, :, None, None, None, :, None]

    shape = (x.size, q.size, 1, 1, 2, y.size, 1)
    base = np.random.default_rng(0).normal(-3.0, 0.5, shape)
    mc = base + smooth(y)
    got = LB._residual_fit(mc, base, coords, splits[-1], deg)
    np.testing.assert_allclose(got, np.broadcast_to(smooth(y), got.shape), atol=1e-10)
    # evaluated between the ratio and thickness nodes (the table's refined axes)
    fine, fine_q = LB._refined_coords(y, 2, splits[-1]), LB._refined_coords(q, 3, None)
    got = LB._residual_fit(mc, base, coords, splits[-1], deg, at=(x, fine_q, fine))
    assert got.shape == (x.size, fine_q.size) + shape[2:-2] + (fine.size, 1)
    np.testing.assert_allclose(got, np.broadcast_to(smooth(fine, fine_q), got.shape),
                               atol=1e-10)
    # 1 % node noise is reduced (252 nodes, 150 terms: by about sqrt(150 / 252))
    noise = 0.01 * np.random.default_rng(1).standard_normal(shape)
    got = LB._residual_fit(mc + noise, base, coords, splits[-1], deg)
    left = np.sqrt(np.mean((got - smooth(y)) ** 2))
    assert left < 0.85 * 0.01
    # full rank (a unique fit between the nodes): 5 x 3 x (5 left of tau = 1 + 5 right)
    basis = LB._residual_basis(coords, splits[-1], deg)
    assert basis.shape == (x.size * q.size * y.size, 150)
    assert np.linalg.matrix_rank(basis) == 150


def test_refined_thickness_nodes_are_those_of_the_spline_refinement():
    grid = LG._resolve_grid("default")
    coords, splits = LB._solve_axes(grid, LG._geometry(RHO, T_EPI, 1.4, 1.0))
    y = coords[-1]
    fine = LB._refined_coords(y, 3, splits[-1])
    _, spline_nodes = LB._upsample(np.zeros((y.size, 1)), 0, y, 3, splits[-1])
    np.testing.assert_array_equal(fine, spline_nodes)
    np.testing.assert_allclose(fine[::3], y, rtol=1e-15, atol=1e-15)  # solve node j: 3 j
    assert np.any(fine == 0.0)  # tau = 1 stays a node


@pytest.mark.parametrize("axis", ["skin_transport_thickness", "musp_ratio"])
def test_diffusion_table_solves_every_refined_scattering_node_directly(axis, monkeypatch):
    # refined thickness and ratio nodes are diffusion solves, not spline values: exact
    # there before the table's node values are centred (checked on its own below)
    monkeypatch.setattr(LB, "_centre_nodes", lambda values, splits: values)
    grid = dict(L.LUT_GRIDS["tiny"])
    grid[axis] = grid[axis][:2] + (3, 3)
    lut = L.build_lut(RHO, T_EPI, grid=grid, solver="diffusion")
    nodes = {k: lut.axis_nodes(k) for k in L.LUT_AXES}
    moving = nodes[axis]
    assert moving.size == 7
    pts = {k: np.full(moving.size, v[1] if v.size > 1 else v[0]) for k, v in nodes.items()}
    pts["mua_dermis_per_cm"][:] = nodes["mua_dermis_per_cm"][0]
    pts[axis] = moving
    musp = pts["musp_dermis_per_cm"]
    kw = dict(mua_epidermis_per_cm=pts["mua_epidermis_per_cm"],
              mua_dermis_per_cm=pts["mua_dermis_per_cm"], musp_dermis_per_cm=musp,
              mua_subcutis_per_cm=pts["mua_subcutis_per_cm"],
              musp_subcutis_per_cm=musp * pts["musp_ratio"],
              skin_thickness_cm=pts["skin_transport_thickness"] / musp)
    r_dir, _ = layers.three_layer_reflectance(RHO, epidermis_thickness_cm=T_EPI, **kw)
    np.testing.assert_allclose(L.interpolate_lut(lut, **kw)[0], r_dir, rtol=1e-5)


def test_direct_solve_with_other_random_numbers_is_an_independent_reference(tiny):
    pts = LV.random_lut_points(tiny, 6, rng=4, groups=1)
    same, se, _ = LV.direct_solve(tiny, pts)
    other, se_o, _ = LV.direct_solve(tiny, pts, seed=777)
    again, _, _ = LV.direct_solve(tiny, pts, seed=777)
    np.testing.assert_array_equal(other, again)  # seeded
    assert not np.allclose(other, same, rtol=1e-9)  # other photons
    assert np.all(np.abs(other / same - 1.0) < 5.0 * np.hypot(se / same, se_o / other))


def test_direct_solve_runs_once_per_group_despite_round_off(tiny, monkeypatch):
    # a group of random_lut_points shares (ratio, thickness); recovered from the solver
    # arguments (tau = skin x mus') they differ in the last bits, which must not split
    # the group into several runs (each a full Monte Carlo run)
    pts = LV.random_lut_points(tiny, 60, rng=3, groups=2)
    musp = pts["musp_dermis_per_cm"]
    tau = pts["skin_thickness_cm"] * musp
    assert np.unique(np.stack([pts["musp_subcutis_per_cm"] / musp, tau], 1), axis=0).shape[0] > 2
    calls = []
    real = mc_white.white_mc_points

    def counted(*args, **kwargs):
        calls.append(kwargs["skin_transport_thickness"])
        return real(*args, **kwargs)

    monkeypatch.setattr(mc_white, "white_mc_points", counted)
    r, se, _ = LV.direct_solve(tiny, pts, n_photons=9000)
    assert len(calls) == 2
    assert np.all(r > 0) and np.all(np.isfinite(se))
    # a group solved alone gives the same values as within the whole set
    first = {k: v[:30] for k, v in pts.items()}
    np.testing.assert_array_equal(LV.direct_solve(tiny, first, n_photons=9000)[0], r[:30])


def test_default_diffusion_table_is_unbiased_and_within_half_a_percent_off_grid():
    # the default grid's interpolation (refined nodes solved or splined, then
    # multilinear) against the model it tabulates, noise-free: the part of the Monte
    # Carlo table's error that is not Monte Carlo noise
    # (measured: max 0.37 %, RMS 0.080 %, mean -0.003 %; with the solver's own node
    # values instead of centred ones: max 0.59 %, RMS 0.167 %, mean -0.095 %)
    lut = L.build_lut(RHO, T_EPI, solver="diffusion")
    err = LV.lut_errors(lut, n_points=300, rng=11, groups=None)
    assert np.all(err["reflectance_se"] == 0.0)
    assert np.max(np.abs(err["reflectance"])) <= 0.005
    assert np.sqrt(np.mean(err["reflectance"] ** 2)) <= 0.0011
    assert abs(np.mean(err["reflectance"])) <= 0.0003  # unbiased: no sign of the curvature
    assert np.median(np.abs(err["pathlength"])) <= 0.01


def test_centred_nodes_make_multilinear_interpolation_unbiased_over_each_cell():
    from scipy.interpolate import RegularGridInterpolator

    # f = a x^2 + b y^2: through its node values the bilinear interpolant errs by
    # a hx^2 t (1 - t) + b hy^2 s (1 - s), with the sign of the curvature everywhere;
    # through the centred values by the same less (a hx^2 + b hy^2) / 6: zero on
    # average over every cell, -(a hx^2 + b hy^2) / 6 at the nodes and
    # +(a hx^2 + b hy^2) / 12 in the middle
    x, y = np.linspace(0.0, 1.0, 6), np.linspace(-1.0, 2.0, 5)
    a, b = 1.3, -0.4
    hx2, hy2 = (x[1] - x[0]) ** 2, (y[1] - y[0]) ** 2

    def f(xx, yy):
        return a * xx**2 + b * yy**2

    nodes = f(x[:, None], y[None, :])[..., None] * np.ones(2)  # two channels
    centred = LB._centre_nodes(nodes, [None, None])
    interp = RegularGridInterpolator((x, y), centred[..., 1])
    t = (np.arange(40) + 0.5) / 40  # a fine midpoint grid over each cell
    for i in range(x.size - 1):  # every cell, the edge cells included
        for j in range(y.size - 1):
            gx, gy = np.meshgrid(x[i] + t * (x[1] - x[0]), y[j] + t * (y[1] - y[0]))
            err = interp(np.stack([gx.ravel(), gy.ravel()], 1)) - f(gx.ravel(), gy.ravel())
            assert abs(err.mean()) < 1e-4 * (abs(a) * hx2 + abs(b) * hy2)
    mid = interp([[0.5 * (x[2] + x[3]), 0.5 * (y[1] + y[2])]])[0]
    np.testing.assert_allclose(mid - f(0.5 * (x[2] + x[3]), 0.5 * (y[1] + y[2])),
                               (a * hx2 + b * hy2) / 12, rtol=1e-9)
    np.testing.assert_allclose(centred[..., 0] - nodes[..., 0], -(a * hx2 + b * hy2) / 6,
                               rtol=1e-9)
    # a kink where an axis is split (tau = 1) leaks no shift: |x - x_3| is linear on
    # either side; a two-node piece, with no curvature to see, is left as it is
    kink = np.abs(x - x[3])[:, None] * np.ones((1, 2))
    np.testing.assert_allclose(LB._centre_nodes(kink, [3]), kink, atol=1e-15)
    assert not np.allclose(LB._centre_nodes(kink, [None]), kink)
    two = np.array([[0.0, 1.0], [4.0, 1.0], [1.0, 1.0]])
    np.testing.assert_array_equal(LB._centre_nodes(two, [1]), two)


def test_a_default_monte_carlo_build_is_announced_as_a_warning(tiny, monkeypatch, tmp_path,
                                                               caplog):
    # the hours-long first build must show without logging configured (a warning)
    monkeypatch.setattr(LC, "build_lut", lambda *a, **k: tiny)
    with caplog.at_level("INFO", logger="nirglucose.optics.lut"):
        L.load_or_build_lut(RHO, T_EPI, directory=tmp_path)
        L.load_or_build_lut(RHO, T_EPI, directory=tmp_path, solver="diffusion")
    levels = [(r.levelname, "about 2 hours" in r.getMessage()) for r in caplog.records]
    assert levels == [("WARNING", True), ("INFO", False)]

# Long-running (whole studies, end-to-end runs, Monte Carlo or every model): `make test-slow`,
# which CI runs beside the fast `make test` (tests/test_slow_marks.py)
pytestmark = pytest.mark.slow
