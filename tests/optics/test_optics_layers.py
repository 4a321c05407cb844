"""Tests of nirglucose.optics.layers (three-layer skin, layered diffusion)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import integrate, special

from nirglucose.exceptions import ConfigError
from nirglucose.optics.diffusion import boundary_coefficient, farrell_reflectance
from nirglucose.optics.layers import (
    LAYER_NAMES,
    SKIN_LAYERS,
    layered_diffusion_reflectance,
    skin_layer_optics,
    three_layer_reflectance,
)

SKIN = dict(
    mua_epidermis_per_cm=2.0, mua_dermis_per_cm=0.3, musp_dermis_per_cm=20.0,
    mua_subcutis_per_cm=0.1, musp_subcutis_per_cm=12.0, epidermis_thickness_cm=0.008,
    skin_thickness_cm=0.18,
)


def _robin_halfspace(rho, mua, musp, n_rel=1.4):
    """Independent closed form: semi-infinite medium, partial-current boundary.

    Point source (1 - R_sp) exp(-mua z0) at z0 = 1/mus'; in the Hankel domain
    phi(k, 0) = S/(2 D a) exp(-a z0) (1 + r), r = (a - h)/(a + h), h = 1/(2 A D);
    the surface flux is phi(k, 0)/(2A). Integrated with scipy.integrate.quad.
    """
    a_coef = float(boundary_coefficient(n_rel, 1.0))
    d = 1.0 / (3.0 * musp)
    z0 = 1.0 / musp
    h = 1.0 / (2.0 * a_coef * d)
    src = (1.0 - ((n_rel - 1) / (n_rel + 1)) ** 2) * np.exp(-mua * z0)

    def flux(k):
        a = np.sqrt(k * k + mua / d)
        return src / (2 * d * a) * np.exp(-a * z0) * (1 + (a - h) / (a + h)) / (2 * a_coef)

    val, _ = integrate.quad(lambda k: flux(k) * special.j0(k * rho) * k, 0, 40 * musp,
                            limit=2000)
    return val / (2 * np.pi)


def test_layer_table_matches_sources():
    assert LAYER_NAMES == ("epidermis", "dermis", "subcutis")
    assert SKIN_LAYERS["dermis"]["blood_fraction"] == (0.002, 0.05)
    assert SKIN_LAYERS["subcutis"]["fat_fraction"] == (0.7, 0.9)
    assert SKIN_LAYERS["epidermis"]["thickness_mm"] == (0.05, 0.10)


def test_skin_layer_optics_reference_values():
    o = skin_layer_optics([850.0, 1150.0], melanin_fraction=[0.02, 0.13])
    assert o["mua_dermis"].shape == (2, 2)
    # Jacques 2013 skin power law: 46 (850/500)^-1.421 = 21.64 /cm
    assert o["musp_dermis"][0, 0] == pytest.approx(46.0 * (850 / 500) ** -1.421, rel=1e-3)
    # epidermis: f mua_mel + (1 - f) mua_baseline, mua_mel = 6.6e11 850^-3.33
    mel = 6.6e11 * 850.0**-3.33
    assert o["mua_epidermis"][1, 0] == pytest.approx(0.13 * mel + 0.87 * 0.244, rel=0.02)
    # water band: the dermis absorbs more at 1150 than at 850 nm, and dark skin more
    assert np.all(o["mua_dermis"][:, 1] > 2 * o["mua_dermis"][:, 0])
    assert o["mua_epidermis"][1, 0] > 5 * o["mua_epidermis"][0, 0]


@pytest.mark.parametrize(("mua", "musp"), [(0.3, 20.0), (0.05, 10.0), (1.0, 15.0)])
def test_equal_layers_reduce_to_the_homogeneous_closed_form(mua, musp):
    r3, p3 = three_layer_reflectance(
        0.3, mua_epidermis_per_cm=mua, mua_dermis_per_cm=mua, musp_dermis_per_cm=musp,
        mua_subcutis_per_cm=mua, musp_subcutis_per_cm=musp, epidermis_thickness_cm=0.008,
        skin_thickness_cm=0.15,
    )
    r1, p1 = layered_diffusion_reflectance(0.3, [mua], [musp], np.zeros(0))
    assert float(r3) == pytest.approx(_robin_halfspace(0.3, mua, musp), rel=1e-4)
    assert float(r3) == pytest.approx(float(r1), rel=1e-9)
    assert float(p3.sum()) == pytest.approx(float(p1[0]), rel=1e-4)


def test_homogeneous_case_sits_above_farrell_like_monte_carlo():
    # Farrell's extrapolated-boundary dipole (flux only) is 15-20 % below the partial-
    # current solution at 3 mm; MC (mc_paths slow test, README) agrees with the latter.
    for mua, musp in ((0.3, 20.0), (0.1, 12.0)):
        r, _ = layered_diffusion_reflectance(0.3, [mua], [musp], np.zeros(0))
        ratio = float(r) / float(farrell_reflectance(0.3, mua, musp))
        assert 1.05 < ratio < 1.30


def test_paths_sum_to_the_total_mean_path():
    r, paths = three_layer_reflectance(0.3, **SKIN)
    # total mean path = -d ln R / d alpha when every layer's mua moves by alpha
    step = 1e-4
    shifted = dict(SKIN)
    for k in ("mua_epidermis_per_cm", "mua_dermis_per_cm", "mua_subcutis_per_cm"):
        shifted[k] = SKIN[k] + step
    r2, _ = three_layer_reflectance(0.3, pathlengths=False, **shifted)
    total = (np.log(r) - np.log(r2)) / step
    assert float(paths.sum()) == pytest.approx(float(total), rel=1e-3)
    assert np.all(paths > 0)


def test_path_shares_follow_the_geometry():
    thick = np.array([0.05, 0.1, 0.2, 0.4])
    kw = {k: v for k, v in SKIN.items() if k != "skin_thickness_cm"}
    r, paths = three_layer_reflectance(0.3, skin_thickness_cm=thick, **kw)
    assert paths.shape == (4, 3)
    assert np.all(np.diff(paths[:, 2]) < 0)  # thicker skin: less path in the fat
    assert np.all(np.diff(paths[:, 1]) > 0)  # ... and more in the dermis
    # with equal scattering, a dermis that absorbs more than the subcutis makes thicker
    # skin reflect less
    kw["musp_subcutis_per_cm"] = kw["musp_dermis_per_cm"]
    r, _ = three_layer_reflectance(0.3, skin_thickness_cm=thick, **kw)
    assert np.all(np.diff(r) < 0)
    # epidermal path: a few epidermal thicknesses (entry + diffuse exit + internal
    # reflections at the surface), about 0.02-0.1 cm for 80 um
    assert np.all((paths[:, 0] > 0.02) & (paths[:, 0] < 0.1))


def test_melanin_attenuates_as_exp_of_the_epidermal_path():
    kw = dict(SKIN)
    kw["mua_epidermis_per_cm"] = np.array([0.5, 0.6])
    r, paths = three_layer_reflectance(0.3, **kw)
    # microscopic Beer-Lambert: d ln R = -L_e d mua_e
    assert np.log(r[1] / r[0]) == pytest.approx(-0.1 * paths[:, 0].mean(), rel=1e-2)


def test_broadcasting_and_scalar_shapes():
    r, p = three_layer_reflectance(0.3, **SKIN)
    assert np.ndim(r) == 0 and p.shape == (3,)
    kw = dict(SKIN)
    kw["mua_dermis_per_cm"] = np.full((2, 3), 0.3)
    r, p = three_layer_reflectance(0.3, **kw)
    assert r.shape == (2, 3) and p.shape == (2, 3, 3)
    r_only, none = three_layer_reflectance(0.3, pathlengths=False, **kw)
    assert none is None
    np.testing.assert_allclose(r_only, r, rtol=1e-12)


@pytest.mark.parametrize(
    ("key", "value", "match"),
    [
        ("mua_dermis_per_cm", -0.1, "mua_per_cm"),
        ("musp_subcutis_per_cm", 0.0, "musp_per_cm"),
        ("skin_thickness_cm", 0.005, "skin_thickness_cm"),
        ("mua_subcutis_per_cm", np.nan, "mua_per_cm"),
    ],
)
def test_bad_inputs_raise(key, value, match):
    kw = dict(SKIN)
    kw[key] = value
    with pytest.raises(ConfigError, match=match):
        three_layer_reflectance(0.3, **kw)


def test_bad_geometry_raises():
    with pytest.raises(ConfigError, match="rho_cm"):
        three_layer_reflectance(-0.3, **SKIN)
    with pytest.raises(ConfigError):
        three_layer_reflectance(0.3, n_tissue=3.5, **SKIN)
