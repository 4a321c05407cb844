"""The simulator's fused optics equal the documented formulas they rearrange."""

from __future__ import annotations

import numpy as np
import pytest

from nirglucose.optics import beer_lambert, diffusion, forward, scattering, skin, tissue

SPECTRA = tissue.band_spectra([850, 940, 1050, 1150], [30, 40, 50, 60], 3)


def _state(n, seed=1):
    rng = np.random.default_rng(seed)
    return tissue.TissueState(
        rng.uniform(0.005, 0.05, n), rng.uniform(0.5, 0.95, n), rng.uniform(0.5, 0.75, n),
        rng.uniform(0.6, 0.9, n), rng.uniform(3.0, 300.0, n),
    )


def _reference_tissue(state, shift, x_disp, k_scat):
    """Jacques 2013 Eq. 12 written out chromophore by chromophore."""
    tab, der = SPECTRA.spectra, SPECTRA.derivatives
    shift = np.asarray(shift, dtype=float)
    shift = shift[:, None, None] if shift.ndim == 1 else shift[..., None]

    def spec(k):
        return tab[k][None] + shift * der[k][None]

    c, b, s, w, f = (np.asarray(getattr(state, k))[:, None, None] for k in (
        "glucose_mm", "blood_fraction", "saturation", "water_fraction", "subcutis_fat_fraction"))
    blood = s * spec("blood_oxy") + (1 - s) * spec("blood_deoxy")
    fluid = spec("water") * np.maximum(1 - x_disp * c, 0) + c * spec("glucose")
    base = tab["baseline"][None]
    b_sub = 0.5 * b
    rest = np.maximum(1 - b_sub - 0.2 - f, 0)
    g = np.exp(k_scat * c)
    return {
        "mua_dermis": b * blood + w * fluid + (1 - b - w) * base,
        "mua_subcutis": b_sub * blood + 0.2 * fluid + f * spec("fat") + rest * base,
        "musp_dermis": spec("musp_skin") * g,
        "musp_subcutis": spec("musp_fat") * g,
        "melanosome": spec("melanosome"),
    }


@pytest.mark.parametrize("shift_kind", ["zero", "per_sample", "per_led"])
def test_tissue_optics_equals_the_chromophore_sum(shift_kind):
    n = 500
    state = _state(n)
    rng = np.random.default_rng(2)
    shift = {"zero": np.zeros(n), "per_sample": rng.normal(0, 2, n),
             "per_led": rng.normal(0, 2, (n, 4))}[shift_kind]
    got = tissue.tissue_optics(SPECTRA, state, water_displacement_per_mm=2e-3,
                               scattering_rel_per_mm=-1e-3, shift_nm=shift)
    want = _reference_tissue(state, shift, 2e-3, -1e-3)
    for k, v in want.items():
        np.testing.assert_allclose(got[k], np.broadcast_to(v, got[k].shape), rtol=1e-13)


def test_fused_beer_lambert_equals_the_composed_model():
    n = 400
    rng = np.random.default_rng(3)
    optics = tissue.tissue_optics(SPECTRA, _state(n), water_displacement_per_mm=1e-3,
                                  scattering_rel_per_mm=-1e-3, shift_nm=rng.normal(0, 2, (n, 4)))
    mel = rng.uniform(0.01, 0.15, n)
    t_cm = rng.uniform(0.05, 0.4, n)
    geometry = rng.uniform(0.5, 2.0, (4, 3))
    rho, d_epi = 0.3, 0.008
    got = forward.detected_fraction(
        "beer-lambert", optics, melanin_fraction=mel, skin_thickness_cm=t_cm,
        epidermis_thickness_cm=d_epi, separation_cm=rho, detector_area_cm2=0.01,
        n_tissue=1.4, geometry_factor=geometry,
    )
    mua, musp, share = forward.mixed_optics(optics, t_cm, rho)
    mu_eff = diffusion.effective_attenuation_per_cm(optics["mua_dermis"], optics["musp_dermis"])
    depth = skin.mean_penetration_depth_cm(rho, mu_eff)
    np.testing.assert_allclose(share, skin.dermis_path_fraction(t_cm[:, None, None], depth))
    mua_epi = skin.epidermis_mua_per_cm(mel[:, None, None], optics["melanosome"],
                                        optics["baseline"])
    dpf = diffusion.differential_pathlength_factor(rho, mua, musp)
    want = (geometry * skin.epidermis_transmittance(mua_epi, d_epi)
            * beer_lambert.mbll_transmittance(mua, dpf, rho))
    np.testing.assert_allclose(got, want, rtol=1e-12)
    assert scattering.glucose_scattering_factor(0.0, -1e-3) == 1.0


@pytest.mark.parametrize("shift_kind", ["per_sample", "per_led"])
def test_compiled_band_kernel_equals_the_numpy_model(shift_kind):
    from nirglucose.optics.kernels.band_kernel import band_detected_fraction

    n = 700
    rng = np.random.default_rng(4)
    state = _state(n, seed=5)
    shift = rng.normal(0, 2, n) if shift_kind == "per_sample" else rng.normal(0, 2, (n, 4))
    mel = rng.uniform(0.01, 0.15, n)
    t_cm = rng.uniform(0.05, 0.4, n)
    geometry = rng.uniform(0.5, 2.0, (4, 3))
    kw = dict(water_displacement_per_mm=1.5e-3, scattering_rel_per_mm=-2e-3)
    optics = tissue.tissue_optics(SPECTRA, state, shift_nm=shift, **kw)
    nodes = forward.detected_fraction(
        "beer-lambert", optics, melanin_fraction=mel, skin_thickness_cm=t_cm,
        epidermis_thickness_cm=0.008, separation_cm=0.3, detector_area_cm2=0.01,
        n_tissue=1.4, geometry_factor=geometry,
    )
    want = np.einsum("nlp,lp->nl", nodes, SPECTRA.weights)
    got = band_detected_fraction(
        SPECTRA, state, shift_nm=shift, melanin_fraction=mel, skin_thickness_cm=t_cm,
        epidermis_thickness_cm=0.008, separation_cm=0.3, geometry_factor=geometry, **kw,
    )
    assert got.shape == (n, 4)
    np.testing.assert_allclose(got, want, rtol=1e-12)
    # and it moves with its inputs (a kernel ignoring one would pass the check above only
    # by accident): more melanin, less light
    darker = band_detected_fraction(
        SPECTRA, state, shift_nm=shift, melanin_fraction=mel + 0.05, skin_thickness_cm=t_cm,
        epidermis_thickness_cm=0.008, separation_cm=0.3, geometry_factor=geometry, **kw,
    )
    assert np.all(darker < got)
