"""Tests of the compiled rte-lut kernel behind nirglucose.optics.lut.interpolate_node_lut.

The tables here are synthetic (smooth random ln R on a small grid with a two-piece
thickness axis, as the real grids have), so the tests need no table build: they check
the kernel against the numpy reference (``_interpolate_node_lut_numpy``) and against
the generic interpolation (``interpolate_lut``), not the physics of the table.
"""

from __future__ import annotations

import numpy as np
import pytest

from nirglucose.exceptions import ConfigError
from nirglucose.optics import lut as L
from nirglucose.optics.lut import interpolate as LI

#: Per axis (table order): node coordinates (in the axis' own coordinate).
_NODES = (
    np.linspace(np.log(7.0), np.log(30.0), 4),  # musp_dermis: log
    np.linspace(0.48, 0.85, 3),  # musp_ratio: linear
    np.linspace(np.sqrt(0.05), np.sqrt(2.0), 4),  # mua_dermis: sqrt
    np.linspace(np.sqrt(0.01), np.sqrt(2.0), 3),  # mua_subcutis: sqrt
    np.linspace(0.0, 35.0, 4),  # mua_epidermis: linear
    # skin transport thickness: log, two pieces meeting at tau = 1 (u = 0)
    np.concatenate([np.linspace(np.log(0.25), 0.0, 3)[:-1], np.linspace(0.0, np.log(13.0), 5)]),
)


@pytest.fixture(scope="module")
def table() -> L.SkinLUT:
    shape = tuple(u.size for u in _NODES)
    rng = np.random.default_rng(11)
    mesh = np.meshgrid(*_NODES, indexing="ij")
    ln_r = -1.0 - 0.5 * mesh[2] - 0.3 * mesh[3] - 0.05 * mesh[4] + 0.2 * mesh[0] \
        + 0.4 * mesh[1] + 0.1 * mesh[5] + 0.05 * rng.standard_normal(shape)
    values = np.stack([ln_r] + [ln_r * 0.5 - i for i in range(3)], axis=-1)
    grid = {name: (1.0, 2.0, 2, 1) for name in L.LUT_AXES}  # not used by interpolation
    geometry = {"rho_cm": 0.3, "epidermis_thickness_cm": 0.008, "n_tissue": 1.4,
                "n_ambient": 1.0}
    return L.SkinLUT(np.ascontiguousarray(values, dtype=np.float32), _NODES, shape, grid,
                     geometry, "synthetic")


def _points(n: int, node_shape=(4, 3), seed: int = 0, ratio=None) -> dict:
    """Random points inside the box, (n, *node_shape), thickness (n,)."""
    rng = np.random.default_rng(seed)
    full = (n, *node_shape)

    def axis(i: int, size) -> np.ndarray:
        u = _NODES[i]
        return u[0] + (u[-1] - u[0]) * rng.uniform(0.0, 1.0, size)

    musp = np.exp(axis(0, full))
    q = axis(1, full) if ratio is None else ratio + rng.uniform(-0.01, 0.01, full)
    tau_over_musp = np.exp(axis(5, n)) / np.exp(_NODES[0][-1])  # tau <= 13 for all mus'
    return {
        "mua_epidermis_per_cm": axis(4, full),
        "mua_dermis_per_cm": axis(2, full) ** 2,
        "musp_dermis_per_cm": musp,
        "mua_subcutis_per_cm": axis(3, full) ** 2,
        "musp_subcutis_per_cm": musp * q,
        "skin_thickness_cm": np.maximum(tau_over_musp, 0.25 / np.exp(_NODES[0][0]) * 1.001),
    }


def _ratio(node_shape=(4, 3), seed: int = 5) -> np.ndarray:
    # inside the first musp_ratio cell, so that the points' ratios (node +- 0.01) stay in
    # the node's cell, where the node table is exact for the multilinear interpolant
    return np.random.default_rng(seed).uniform(0.50, 0.65, node_shape)


def test_kernel_equals_the_numpy_reference(table):
    ratio = _ratio()
    nlut = L.node_lut(table, ratio)
    pts = _points(3000, ratio=ratio)
    fast = L.interpolate_node_lut(nlut, **pts)
    ref = LI._interpolate_node_lut_numpy(nlut, **pts)
    assert fast.shape == ref.shape == (3000, 4, 3)
    rel = np.abs(fast / ref - 1.0)
    assert rel.max() <= 1e-6  # float32 rounding of ln R, at worst
    assert np.mean(rel <= 1e-13) >= 0.99  # same operations in the same order: equal


def test_kernel_equals_the_generic_interpolation(table):
    ratio = _ratio()
    nlut = L.node_lut(table, ratio)
    pts = _points(500, ratio=ratio, seed=1)
    fast = L.interpolate_node_lut(nlut, **pts)
    t = pts.pop("skin_thickness_cm")
    slow, _ = L.interpolate_lut(table, skin_thickness_cm=t[:, None, None], **pts)
    np.testing.assert_allclose(fast, slow, rtol=2e-5)


def test_kernel_layouts(table):
    # extra leading axes, one node, per-node thickness and non-contiguous inputs
    ratio = _ratio((1,))
    nlut = L.node_lut(table, ratio)
    pts = _points(60, node_shape=(1,), ratio=ratio, seed=2)
    ref = LI._interpolate_node_lut_numpy(nlut, **pts)
    lead = {k: v.reshape(3, 20, *v.shape[1:]) for k, v in pts.items()}
    np.testing.assert_allclose(L.interpolate_node_lut(nlut, **lead), ref.reshape(3, 20, 1),
                               rtol=1e-6)
    ratio = _ratio((4, 3))
    nlut = L.node_lut(table, ratio)
    pts = _points(40, ratio=ratio, seed=3)
    ref = LI._interpolate_node_lut_numpy(nlut, **pts)
    per_node = dict(pts, skin_thickness_cm=np.broadcast_to(
        pts["skin_thickness_cm"][:, None, None], (40, 4, 3)))
    strided = {k: np.asfortranarray(v) for k, v in per_node.items()}
    np.testing.assert_allclose(L.interpolate_node_lut(nlut, **strided), ref, rtol=1e-6)


def test_kernel_at_the_corners_of_the_box(table):
    ratio = np.full((2,), 0.6)
    nlut = L.node_lut(table, ratio)
    lo = {i: u[0] for i, u in enumerate(_NODES)}
    hi = {i: u[-1] for i, u in enumerate(_NODES)}
    rows = []
    for ends in (lo, hi):
        musp = np.exp(ends[0])
        rows.append({
            "mua_epidermis_per_cm": ends[4], "mua_dermis_per_cm": ends[2] ** 2,
            "musp_dermis_per_cm": musp, "mua_subcutis_per_cm": ends[3] ** 2,
            "musp_subcutis_per_cm": musp * 0.6, "skin_thickness_cm": np.exp(ends[5]) / musp,
        })
    pts = {k: np.array([[r[k]] * 2 for r in rows]) for k in rows[0]}
    pts["skin_thickness_cm"] = pts["skin_thickness_cm"][:, 0]
    fast = L.interpolate_node_lut(nlut, **pts)
    np.testing.assert_allclose(fast, LI._interpolate_node_lut_numpy(nlut, **pts), rtol=1e-6)
    # the box's corners are table nodes: ln R is the stored value at the node's ratio
    v = table.values[..., 0].astype(np.float64)
    share = (0.6 - _NODES[1][0]) / (_NODES[1][1] - _NODES[1][0])
    low = v[0, 0, 0, 0, 0, 0] + share * (v[0, 1, 0, 0, 0, 0] - v[0, 0, 0, 0, 0, 0])
    high = v[-1, 0, -1, -1, -1, -1] + share * (v[-1, 1, -1, -1, -1, -1] - v[-1, 0, -1, -1, -1, -1])
    np.testing.assert_allclose(np.log(fast[:, 0]), [low, high], rtol=1e-6)
    assert np.all(np.isfinite(fast)) and np.all(fast > 0)


@pytest.mark.parametrize(("key", "value", "axis"), [
    ("musp_dermis_per_cm", 50.0, "musp_dermis_per_cm"),
    ("musp_dermis_per_cm", np.nan, "musp_dermis_per_cm"),
    ("musp_dermis_per_cm", -10.0, "musp_dermis_per_cm"),
    ("mua_dermis_per_cm", 9.0, "mua_dermis_per_cm"),
    ("mua_subcutis_per_cm", -0.5, "mua_subcutis_per_cm"),
    ("mua_epidermis_per_cm", np.nan, "mua_epidermis_per_cm"),
    ("musp_subcutis_per_cm", 100.0, "musp_ratio"),
    ("skin_thickness_cm", 3.0, "skin_transport_thickness"),
])
def test_kernel_raises_as_the_reference_for_points_outside(table, key, value, axis):
    ratio = _ratio()
    nlut = L.node_lut(table, ratio)
    pts = _points(300, ratio=ratio, seed=4)
    pts[key] = pts[key].copy()
    pts[key][250, ...] = value  # in a late chunk
    with pytest.raises(ConfigError, match=axis) as fast:
        L.interpolate_node_lut(nlut, **pts)
    with pytest.raises(ConfigError) as ref:
        LI._interpolate_node_lut_numpy(nlut, **pts)
    assert str(fast.value) == str(ref.value)


def test_kernel_is_deterministic_and_chunk_free(table):
    ratio = _ratio()
    nlut = L.node_lut(table, ratio)
    pts = _points(700, ratio=ratio, seed=6)
    a = L.interpolate_node_lut(nlut, **pts)
    b = L.interpolate_node_lut(nlut, **pts)
    np.testing.assert_array_equal(a, b)
    part = L.interpolate_node_lut(nlut, **{k: v[123:457] for k, v in pts.items()})
    np.testing.assert_array_equal(part, a[123:457])  # rows do not depend on their neighbours


def test_kernel_log_and_exp_match_the_c_library():
    # the kernel's arithmetic-only ln and exp (vectorisable), against numpy's
    from nirglucose.optics.kernels.lut_kernel import _exp, _log

    rng = np.random.default_rng(8)
    x = np.concatenate([np.exp(rng.uniform(-40.0, 40.0, 2000)), rng.uniform(0.5, 2.0, 500),
                        [1.0, 2.0, np.sqrt(2.0), 1e-300, 1e300]])
    np.testing.assert_allclose([_log(v) for v in x], np.log(x), rtol=1e-15, atol=2e-16)
    y = np.concatenate([rng.uniform(-40.0, 10.0, 2000), [0.0, -700.0, 700.0, 1e-12]])
    np.testing.assert_allclose([_exp(v) for v in y], np.exp(y), rtol=5e-16, atol=0.0)
    # what the box check relies on: bad inputs give NaN or |ln x| > 700, never a table value
    for bad in (0.0, -1.0, np.nan, np.inf, 1e-310):
        v = _log(bad)
        assert np.isnan(v) or abs(v) > 700.0


def test_simulator_fused_band_path_equals_tissue_optics_then_table(table):
    """band_kernel.band_detected_fraction_lut (layer optics compiled, then the kernel)
    equals tissue_optics -> detected_fraction('rte-lut') -> band weights."""
    from nirglucose.optics import forward, tissue
    from nirglucose.optics.kernels.band_kernel import band_detected_fraction_lut

    spectra = tissue.band_spectra([850, 940, 1050, 1150], [30, 40, 50, 60], 3)
    ratio = spectra.spectra["musp_fat"] / spectra.spectra["musp_skin"]
    nlut = L.node_lut(table, ratio)
    rng = np.random.default_rng(8)
    n = 600
    state = tissue.TissueState(rng.uniform(0.005, 0.05, n), rng.uniform(0.5, 0.95, n),
                               rng.uniform(0.55, 0.72, n), rng.uniform(0.6, 0.9, n),
                               rng.uniform(3.0, 30.0, n))
    shift = rng.normal(0.0, 1.0, (n, 4))
    mel = rng.uniform(0.01, 0.15, n)
    t_cm = rng.uniform(0.08, 0.35, n)
    kw = dict(water_displacement_per_mm=1.1e-4, scattering_rel_per_mm=-1.25e-3)
    optics = tissue.tissue_optics(spectra, state, shift_nm=shift, **kw)
    nodes = forward.detected_fraction(
        "rte-lut", optics, melanin_fraction=mel, skin_thickness_cm=t_cm,
        epidermis_thickness_cm=0.008, separation_cm=0.3, detector_area_cm2=0.066,
        n_tissue=1.4, lut=nlut,
    )
    want = np.einsum("nlp,lp->nl", nodes, spectra.weights)
    got = band_detected_fraction_lut(
        spectra, state, shift_nm=shift, melanin_fraction=mel, skin_thickness_cm=t_cm,
        node_lut=nlut, detector_area_cm2=0.066, **kw,
    )
    np.testing.assert_allclose(got, want, rtol=1e-6)  # float32 table rounding at worst
    assert np.median(np.abs(got / want - 1.0)) < 1e-12
    # a point outside the table raises the reference's message (names the axis)
    with pytest.raises(ConfigError, match="skin_transport_thickness"):
        band_detected_fraction_lut(
            spectra, state, shift_nm=shift, melanin_fraction=mel,
            skin_thickness_cm=np.full(n, 5.0), node_lut=nlut, detector_area_cm2=0.066, **kw,
        )
