"""The rte-lut table from 1350 to 1700 nm (issue 30): the ``swir`` grid and its wiring.

Every test uses a temporary cache directory (NIRGLUCOSE_CACHE). The whole ``swir``
table's errors against independent Monte Carlo references are measured by
``studies/optics_reference.py --grid swir`` (README, "Layered skin optics").
"""

from __future__ import annotations

import numpy as np
import pytest

import nirglucose as ng
from nirglucose.exceptions import ConfigError
from nirglucose.optics import lut as L
from nirglucose.optics.lut import grid as LG
from nirglucose_reference import lut_checks as LV

RHO, T_EPI = 0.3, 0.008
pytestmark = pytest.mark.filterwarnings("ignore:lipid absorption above:UserWarning")

#: LED bands 100 nm wide across the range, the 1450 nm water peak included.
SWIR_LEDS = [{"wavelength_nm": w, "fwhm_nm": 100.0, "power_mw": 5.0,
              "responsivity_a_per_w": 1.0} for w in (1350, 1450, 1550, 1650)]


@pytest.fixture(autouse=True)
def _tmp_cache(tmp_path, monkeypatch):
    monkeypatch.setenv("NIRGLUCOSE_CACHE", str(tmp_path / "cache"))
    monkeypatch.delenv("NIRGLUCOSE_LUT_GRID", raising=False)


def test_swir_grid_has_its_own_kernel_and_keeps_the_default_key(monkeypatch):
    swir = LG.grid_mc_settings("swir")
    assert swir["half_width_cm"] == 0.035 < L.LUT_MC_SETTINGS["half_width_cm"]
    assert LG.grid_mc_settings(L.LUT_GRIDS["swir"]) == swir  # a spec equal to the named grid
    # ... takes its photons too: the same table, the same cache key
    assert L.lut_key(RHO, T_EPI, grid=dict(L.LUT_GRIDS["swir"])) == L.lut_key(RHO, T_EPI,
                                                                               grid="swir")
    assert LG.grid_mc_settings("default") == L.LUT_MC_SETTINGS
    default_key, swir_key = L.lut_key(RHO, T_EPI), L.lut_key(RHO, T_EPI, grid="swir")
    monkeypatch.setattr(LG, "LUT_MC_GRID_SETTINGS", {})
    # the default table's cache files stay valid; the swir key holds its own settings
    assert L.lut_key(RHO, T_EPI) == default_key
    assert L.lut_key(RHO, T_EPI, grid="swir") != swir_key


def test_swir_reference_absorption_is_the_box_minimum():
    from nirglucose.optics.lut.build import _mua_ref

    spec = L.LUT_GRIDS["swir"]
    lo = min(spec["mua_dermis_per_cm"][0], spec["mua_subcutis_per_cm"][0])
    assert _mua_ref(LG._resolve_grid("swir")) == pytest.approx(
        lo / spec["musp_dermis_per_cm"][1], rel=1e-12)


def test_interpolation_against_direct_solves_in_a_block_of_the_swir_grid(monkeypatch):
    # a 2 x 2 block of (ratio, thickness) runs, few photons, the box's less absorbing
    # part (a few thousand photons reach rho above a dermal mua of 10 /cm only with
    # millions launched): the table against direct solves (same random numbers, same
    # 0.35 mm kernel) at random off-grid points is within the Monte Carlo noise
    spec = dict(L.LUT_GRIDS["swir"])
    spec["mua_dermis_per_cm"] = (0.7, 6.0, 3, 1)
    spec["mua_subcutis_per_cm"] = (0.25, 3.0, 3, 1)
    lo, hi = spec["musp_ratio"][:2]
    spec["musp_ratio"] = (lo, 0.5 * (lo + hi), 2, 1)
    lo, hi, _, m = spec["skin_transport_thickness"]
    spec["skin_transport_thickness"] = (1.0, hi, 2, m)
    # the block is no named grid: give it the swir grid's Monte Carlo settings
    monkeypatch.setitem(LG.LUT_MC_SETTINGS, "half_width_cm",
                        LG.grid_mc_settings("swir")["half_width_cm"])
    monkeypatch.setitem(LG.LUT_MC_SETTINGS, "residual_fit_degrees",
                        LG.grid_mc_settings("swir")["residual_fit_degrees"])
    lut = L.build_lut(RHO, T_EPI, grid=spec, n_photons=20_000)
    assert LG.grid_mc_settings(lut.grid)["half_width_cm"] == 0.035
    pts = LV.random_lut_points(lut, 40, rng=4, groups=2)
    err = LV.lut_errors(lut, pts, n_photons=20_000)
    r, se = np.abs(err["reflectance"]), err["reflectance_se"]
    assert np.all(np.isfinite(r))
    assert np.all(r <= np.maximum(0.01, 4 * se))
    assert np.median(r) <= 1.5 * np.median(se)


@pytest.mark.parametrize("preset", ["paper", "wearable", "field", "physical", "lab"])
def test_swir_box_covers_every_preset_through_wide_bands(preset, monkeypatch):
    # tiny-swir has the swir box: every preset's skin seen through 100 nm bands at
    # 1350-1650 nm falls inside it (the default box refuses them, naming the fix)
    monkeypatch.setenv("NIRGLUCOSE_LUT_GRID", "tiny-swir")
    over = {"optics.model": "rte-lut", "leds": SWIR_LEDS}
    d = ng.simulate(preset, n_subjects=20, per_subject=2, seed=2, overrides=over)
    cols = [f"true_detected_fraction_{w['wavelength_nm']:g}" for w in SWIR_LEDS]
    frac = d.frame[cols].to_numpy()
    assert np.all(np.isfinite(frac)) and np.all(frac > 0)
    # the water peak: far less light back at 1450 nm than at 1350 nm
    assert np.median(frac[:, 1]) < 0.2 * np.median(frac[:, 0])


def test_default_box_refuses_swir_bands_and_names_the_grid(monkeypatch):
    monkeypatch.setenv("NIRGLUCOSE_LUT_GRID", "tiny")
    over = {"optics.model": "rte-lut", "leds": SWIR_LEDS}
    with pytest.raises(ConfigError, match="'swir' covers 1160-1700 nm LED bands"):
        ng.simulate("paper", n_subjects=4, per_subject=1, seed=2, overrides=over)


def test_config_names_the_grid(monkeypatch):
    seen = []
    real = L.get_lut

    def spy(*args, **kwargs):
        seen.append(kwargs.get("grid"))
        return real(*args, **{**kwargs, "grid": "tiny-swir"})

    monkeypatch.setattr("nirglucose.optics.lut.get_lut", spy)
    over = {"optics.model": "rte-lut", "optics.lut_grid": "swir", "leds": SWIR_LEDS}
    ng.simulate("paper", n_subjects=4, per_subject=1, seed=2, overrides=over)
    assert seen == ["swir"]
    assert ng.resolve_config("paper").optics.lut_grid == "auto"
    with pytest.raises(ConfigError):
        ng.resolve_config("paper", {"optics.lut_grid": "tiny"})


def test_grid_of_each_band():
    assert L.lut_grids_for_bands([[830.0, 850.0, 870.0], [1290.0, 1300.0, 1319.0],
                                  [1200.0, 1300.0, 1400.0], [1600.0, 1650.0, 1699.0]]) == (
        "default", "default", "swir", "swir")
    with pytest.raises(ConfigError, match="LED 2's band spans 1100-1400 nm") as err:
        L.lut_grids_for_bands([[840.0, 850.0, 860.0], [1100.0, 1250.0, 1400.0]])
    assert "\n" not in str(err.value)


def _stand_ins(monkeypatch):
    """The tiny grids under the real names (a real build takes tens of minutes)."""
    for name, tiny in (("default", "tiny"), ("swir", "tiny-swir")):
        monkeypatch.setitem(L.LUT_GRIDS, name, L.LUT_GRIDS[tiny])
        monkeypatch.setitem(L.LUT_MC_PHOTONS, name, L.LUT_MC_PHOTONS[tiny])


#: The docs' InGaAs-era set (docs/user_guide/optics.md): 1050 nm in the default table's
#: band, the 1300 nm band (1256-1344 nm) and the others in swir's.
MIXED_LEDS = [
    {"wavelength_nm": 1050.0, "fwhm_nm": 50.0, "power_mw": 1.5, "responsivity_a_per_w": 0.58},
    {"wavelength_nm": 1300.0, "fwhm_nm": 60.0, "power_mw": 3.0, "responsivity_a_per_w": 0.86},
    {"wavelength_nm": 1550.0, "fwhm_nm": 80.0, "power_mw": 40.0, "responsivity_a_per_w": 1.0},
    {"wavelength_nm": 1650.0, "fwhm_nm": 80.0, "power_mw": 8.0, "responsivity_a_per_w": 0.95},
]


def test_a_device_across_both_tables_takes_one_per_led(monkeypatch):
    _stand_ins(monkeypatch)
    seen = []
    real = L.get_lut

    def spy(*args, **kwargs):
        seen.append(kwargs.get("grid"))
        return real(*args, **kwargs)

    monkeypatch.setattr("nirglucose.optics.lut.get_lut", spy)
    over = {"optics.model": "rte-lut", "leds": MIXED_LEDS}
    ds = ng.simulate("wearable", n_subjects=10, per_subject=2, seed=4, overrides=over)
    assert seen == ["default", "swir", "swir", "swir"]
    frac = ds.frame[[f"true_detected_fraction_{e['wavelength_nm']:g}"
                     for e in MIXED_LEDS]].to_numpy()
    assert np.all(np.isfinite(frac)) and np.all(frac > 0)
    # the oracle's forward model goes through the same tables
    from nirglucose.simulation.simulator import detected_fraction_given_glucose

    cfg = ng.resolve_config("wearable", over)
    again = detected_fraction_given_glucose(cfg, ds.frame, ds.frame["glucose_mgdl"].to_numpy())
    np.testing.assert_allclose(again, frac, rtol=1e-9)
    # $NIRGLUCOSE_LUT_GRID still names one grid for every LED (which refuses 1550 nm)
    monkeypatch.setenv("NIRGLUCOSE_LUT_GRID", "tiny")
    with pytest.raises(ConfigError, match="outside the look-up table"):
        ng.simulate("wearable", n_subjects=4, per_subject=1, seed=4, overrides=over)


def test_one_table_per_led_equals_one_table_for_all():
    from nirglucose.optics.kernels.band_kernel import band_detected_fraction_lut
    from nirglucose.simulation.simulator import nominal_tissue, scenario_band_spectra

    cfg = ng.resolve_config("paper")
    spectra = scenario_band_spectra(cfg)
    lut = L.build_lut(RHO, T_EPI, grid="tiny")
    ratio = np.full(spectra.nodes_nm.shape, 0.6)
    n = 7
    state = nominal_tissue(n, cfg.optics.reference_tissue)
    kw = dict(shift_nm=np.linspace(-2.0, 2.0, n), melanin_fraction=np.full(n, 0.05),
              skin_thickness_cm=np.linspace(0.12, 0.3, n), detector_area_cm2=0.066,
              water_displacement_per_mm=0.0, scattering_rel_per_mm=-0.00125)
    one = band_detected_fraction_lut(spectra, state, node_lut=L.node_lut(lut, ratio), **kw)
    per_led = tuple(L.node_lut(lut, ratio[i:i + 1]) for i in range(ratio.shape[0]))
    each = band_detected_fraction_lut(spectra, state, node_lut=per_led, **kw)
    np.testing.assert_array_equal(each, one)
    with pytest.raises(ConfigError, match="node tables are for nodes"):
        band_detected_fraction_lut(spectra, state, node_lut=per_led[:2], **kw)


def test_white_monte_carlo_matches_the_numpy_engine_at_swir_absorption():
    # 1550 nm skin (dermis 8 /cm, mus' 9 /cm, fat 2.5 /cm, g 0.9): the white runs re-weight
    # from the swir table's reference absorption (the box's least, 0.25 /cm at the
    # largest mus'), 45 times below the dermis'; the NumPy photon engine absorbs as it
    # goes. Ring 0.5-1.5 mm, so both detect enough light in seconds (measured: R 0.2713
    # and 0.2715 /cm^2, standard errors 0.007 and 0.008; dermal path within 2 %).
    from nirglucose.optics.kernels.mc_white import white_mc_run
    from nirglucose_reference.mc_paths import mc_detected_paths, reweight_detected

    musp, q, g, ring = 9.0, 0.9, 0.9, (0.05, 0.15)
    t_epi, t_skin, mua = 0.008, 0.15, (0.5, 8.0, 2.5)
    ref = mc_detected_paths(list(mua), [musp / (1 - g)] * 2 + [q * musp / (1 - g)], g,
                            [t_epi, t_skin - t_epi], ring, n_photons=12_000, rng=7)
    r_ref, se_ref, p_ref = reweight_detected(ref, list(mua))
    from nirglucose.optics.lut.build import _mua_ref

    mua_ref = _mua_ref(LG._resolve_grid("swir"))
    run = white_mc_run(t_skin * musp, q, [t_epi * musp], (ring[0] * musp, ring[1] * musp),
                       n_photons=120_000, seed=3, mua_ref=mua_ref, g=g)
    lo, hi = (v * musp for v in ring)
    sel = (run.radius >= lo) & (run.radius < hi)
    p = run.path[sel]
    ell = np.stack([p[:, 0], p[:, -2] - p[:, 0], p[:, -1]], axis=1)
    w = run.weight[sel] * np.exp(-ell @ (np.asarray(mua) / musp - mua_ref))
    fresnel = ((1.4 - 1.0) / 2.4) ** 2
    area = np.pi * (ring[1] ** 2 - ring[0] ** 2)
    r = (1 - fresnel) * w.sum() / run.n_photons / area
    per_batch = np.bincount(run.batch[sel], weights=w, minlength=run.n_batches)
    se = (1 - fresnel) * per_batch.std(ddof=1) * np.sqrt(run.n_batches) / run.n_photons / area
    assert r_ref > 0 and abs(r - r_ref) < 4 * np.hypot(se, se_ref)
    np.testing.assert_allclose((w @ ell)[1] / w.sum() / musp, p_ref[1], rtol=0.05)

# Long-running (whole studies, end-to-end runs, Monte Carlo or every model): `make test-slow`,
# which CI runs beside the fast `make test` (tests/test_slow_marks.py)
pytestmark = [pytestmark, pytest.mark.slow]
