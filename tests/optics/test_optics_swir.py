"""The optics from 1300 to 1700 nm (issue 30): tables, glucose bands, transport regime.

Reference numbers come from the companion collection's key-value table
(``shared/data/optics_ext/SOURCES.md``, "Key values at candidate LED wavelengths"),
transcribed here, and from independent solvers (adding-doubling, Monte Carlo).
"""

from __future__ import annotations

import csv
import re
import warnings
from importlib import resources

import numpy as np
import pytest

import nirglucose as ng
from nirglucose import portable as pm
from nirglucose.data import OPTICS_TABLES, load_spectrum
from nirglucose.exceptions import ConfigError
from nirglucose.optics import absorption, scattering, tissue
from nirglucose.optics.diffusion import differential_pathlength_factor, farrell_reflectance
from nirglucose.optics.layers import skin_layer_optics

# shared/data/optics_ext/SOURCES.md, "Key values at candidate LED wavelengths":
# nm -> water Kou / Segelstein / Hale-Querry / Palmer-Williams, blood oxy / deoxy,
# lipid (PROVISIONAL), skin mus' [1/cm]
KEY_VALUES = {
    1050: ((0.166, 0.170, 0.14, 0.171), (4.9, 2.2), 0.063, 16.0),
    1200: ((1.27, 1.25, 1.04, 1.25), (3.6, 2.0), 1.44, 13.3),
    1300: ((1.32, 1.35, 1.11, 1.36), (1.9, 2.0), 0.086, 11.8),
    1450: ((32.7, 31.5, 28.6, 30.9), (24.1, 24.8), 0.62, 10.1),
    1550: ((11.9, 10.8, 10.8, 10.9), (10.3, 10.5), 0.18, 9.2),
    1650: ((6.2, 5.8, 4.8, 5.9), (6.0, 5.9), None, 8.4),
}
pytestmark = pytest.mark.filterwarnings("ignore:lipid absorption above:UserWarning")

WATER = ("kou1993", "segelstein1981", "hale_querry1973", "palmer_williams1974")


def _rounding(value: float) -> float:
    """Half a unit in the last printed digit of a 2-3 significant digit key value."""
    digits = len(f"{value:.3g}".split(".")[1]) if "." in f"{value:.3g}" else 0
    return 0.5 * 10.0**-digits + 1e-9


@pytest.mark.parametrize("wl", list(KEY_VALUES))
def test_tables_reproduce_the_published_key_values(wl):
    water, blood, lipid, musp = KEY_VALUES[wl]
    for source, ref in zip(WATER, water, strict=True):
        got = float(absorption.water_mua_per_cm(wl, source))
        assert got == pytest.approx(ref, abs=_rounding(ref)), source
    assert float(absorption.blood_mua_per_cm(wl, 1.0)) == pytest.approx(blood[0], abs=0.05)
    assert float(absorption.blood_mua_per_cm(wl, 0.0)) == pytest.approx(blood[1], abs=0.05)
    if lipid is not None:  # the key value is the PROVISIONAL table's (van Veen below 1098 nm)
        x, y = load_spectrum("lipid_provisional")
        assert float(np.interp(wl, x, y)) == pytest.approx(lipid, abs=_rounding(lipid))
        if wl > 1098:
            assert float(absorption.lipid_mua_per_cm(wl)) == float(np.interp(wl, x, y))
    assert float(scattering.power_law_musp_per_cm(wl)) == pytest.approx(musp, abs=0.05)
    # the packaged mus' table is the same power law
    x, y = load_spectrum("skin_musp_jacques2013")
    assert float(np.interp(wl, x, y)) == pytest.approx(musp, abs=0.05)


def test_every_table_reaches_1700_nm_except_lipid_and_prahl():
    for name in OPTICS_TABLES:
        x, _ = load_spectrum(name)
        if name in ("hbo2_eps_prahl", "hb_eps_prahl", "lipid_vanveen2004"):
            assert x[-1] < 1100  # not used above 1000-1098 nm (blood: Bosschaart)
        elif name == "lipid_provisional":
            assert x[-1] == absorption.LIPID_TABLE_END_NM
        else:
            assert x[0] <= 700 and x[-1] >= 1700, name
            assert np.all(np.diff(x) > 0), name


def test_blood_absorbs_like_water_above_1400_nm():
    # shared SOURCES.md: 0.74 x (1450), 0.86 x (1550), 0.97 x (1650), 1.02 x (1700 nm)
    wl = np.array([1450.0, 1550.0, 1650.0, 1700.0])
    ratio = absorption.blood_mua_per_cm(wl, 1.0) / absorption.water_mua_per_cm(wl)
    np.testing.assert_allclose(ratio, [0.74, 0.86, 0.97, 1.02], atol=0.01)
    oxy, deoxy = absorption.blood_mua_per_cm(wl, 1.0), absorption.blood_mua_per_cm(wl, 0.0)
    assert np.all(np.abs(oxy / deoxy - 1) < 0.1)


def test_range_is_700_to_1700_nm():
    assert absorption.WAVELENGTH_RANGE_NM == (700.0, 1700.0)
    absorption.water_mua_per_cm([700.0, 1700.0])
    with pytest.raises(ConfigError, match="1701"):
        absorption.water_mua_per_cm([850.0, 1701.0])


def test_lipid_above_its_table_is_held_and_warns():
    end = absorption.LIPID_TABLE_END_NM
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        at_end = float(absorption.lipid_mua_per_cm(end))  # the table itself: no warning
    with pytest.warns(UserWarning, match="1597.85 nm is not tabulated"):
        held = absorption.lipid_mua_per_cm([1600.0, 1650.0, 1700.0])
    np.testing.assert_array_equal(held, at_end)
    assert at_end == pytest.approx(0.165188)  # the last row of the digitised curve


def _published_bands():
    text = resources.files("nirglucose.data").joinpath(
        "optics", "glucose_band_positions.csv").read_text()
    return list(csv.DictReader(text.splitlines()))


def test_glucose_bands_sit_where_published():
    rows = _published_bands()
    assert any("Golic" in r["citation"] and r["wavelength_low_nm"] == "910" for r in rows)
    fwhm_per_width = 2.0 * np.sqrt(np.log(2.0))  # Gaussian exp(-(x/w)^2): FWHM = 2 sqrt(ln2) w
    for centre, width, _rel, order in absorption.GLUCOSE_BANDS_NM:
        same = [r for r in rows if r["bond"] == "C-H" and r["overtone_order"] == str(order)]
        assert same, order
        gap = min(max(float(r["wavelength_low_nm"]) - centre,
                      centre - float(r["wavelength_high_nm"]), 0.0) for r in same)
        assert gap <= fwhm_per_width * width, (centre, order, gap)


def test_glucose_first_overtone_band_is_stated_relative_to_the_second():
    eps = absorption.glucose_mua_per_cm_per_mm([1150.0, 1670.0, 920.0], 1e-4)
    # the assumption: a factor of 10 per overtone order (3rd : 2nd : 1st = 0.1 : 1 : 10)
    np.testing.assert_allclose(eps, [1e-4, 1e-3, 1e-5], rtol=1e-6)
    # the added band leaves the 700-1300 nm window as it was (no change at the presets)
    wl = np.linspace(700.0, 1300.0, 601)
    old = np.zeros_like(wl)
    for c, w, rel, _ in absorption.GLUCOSE_BANDS_NM[:2]:  # the first model's two bands
        old = old + rel * pm.exp(-(((wl - c) / w) ** 2))
    np.testing.assert_array_equal(absorption.glucose_mua_per_cm_per_mm(wl, 1.0), old)


def test_every_packaged_table_has_a_sources_row():
    folder = resources.files("nirglucose.data").joinpath("optics")
    sources = folder.joinpath("SOURCES.md").read_text()
    rows = set(re.findall(r"^\| ([\w.-]+\.csv) \|", sources, flags=re.M))
    csvs = {p.name for p in folder.iterdir() if p.name.endswith(".csv")}
    assert csvs <= rows, csvs - rows


# --------------------------------------------------------------------- transport regime

SWIR_NM = (1450.0, 1550.0, 1650.0)
G = 0.9
N_TISSUE = 1.4


def _dermis(wl):
    o = skin_layer_optics(list(wl), melanin_fraction=0.02)
    return np.ravel(o["mua_dermis"]), np.ravel(o["musp_dermis"])


def test_dermis_is_in_the_high_absorption_regime():
    mua, musp = _dermis(SWIR_NM)
    # water-dominated: mua > mus' at 1450 nm, within a factor 2-3 of it at 1550-1650 nm
    assert mua[0] > musp[0] and np.all(mua[1:] > 0.3 * musp[1:])
    assert np.all(np.diff(mua) < 0)  # falling off the 1450 nm water band


@pytest.mark.parametrize("wl", SWIR_NM)
def test_adding_doubling_and_monte_carlo_agree_at_high_absorption(wl):
    pytest.importorskip("iadpython")
    from nirglucose_reference.adding_doubling import slab_rt
    from nirglucose_reference.monte_carlo import mc_slab

    (mua,), (musp,) = _dermis([wl])
    mus = musp / (1.0 - G)
    r_ad, _ = slab_rt(mua, mus, G, 0.3, N_TISSUE)
    res = mc_slab(mua, mus, G, 0.3, N_TISSUE, n_photons=80_000, rng=6)
    assert res.total_reflectance_se / res.total_reflectance < 0.01
    # within 1 % and 3 standard errors of the Monte Carlo
    assert abs(res.total_reflectance / float(r_ad) - 1) < 0.01 + 3 * (
        res.total_reflectance_se / res.total_reflectance)


def test_diffusion_falls_behind_transport_as_absorption_rises():
    """States the regime: the dipole model's error grows with mua / mus'."""
    from nirglucose_reference.monte_carlo import mc_slab

    mua, musp = _dermis(SWIR_NM)
    ratio, path_ratio = [], []
    for a, s in zip(mua, musp, strict=True):
        res = mc_slab(a, s / (1 - G), G, np.inf, N_TISSUE, n_photons=40_000, rng=5,
                      rho_edges_cm=np.array([0.25, 0.35]))
        assert res.reflectance_per_cm2_se[0] < 0.2 * res.reflectance_per_cm2[0]
        ratio.append(res.reflectance_per_cm2[0] / float(farrell_reflectance(0.3, a, s, N_TISSUE)))
        dpf_path = 0.3 * float(differential_pathlength_factor(0.3, a, s))
        path_ratio.append(res.pathlength_at_rho_cm[0] / dpf_path)
    order = np.argsort(mua / musp)  # 1650, 1550, 1450 nm
    assert np.all(np.diff(np.asarray(ratio)[order]) > 0)
    assert ratio[0] > 5  # 1450 nm: mua > mus', diffusion breaks down
    assert min(path_ratio) > 1.5  # the diffusion path is too short (glucose sensitivity)


def test_rte_lut_refuses_the_water_band_with_one_config_error(monkeypatch, tmp_path):
    monkeypatch.setenv("NIRGLUCOSE_LUT_GRID", "tiny")
    monkeypatch.setenv("NIRGLUCOSE_CACHE", str(tmp_path))
    leds = [{"wavelength_nm": 1550.0, "fwhm_nm": 80.0, "power_mw": 20.0,
             "responsivity_a_per_w": 1.0}]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)  # the lipid hold above 1598 nm
        with pytest.raises(ConfigError, match="is outside the look-up table") as err:
            ng.simulate("wearable", 2, 1, 0, overrides={
                "leds": leds, "optics.model": "rte-lut", "optics.lut_solver": "diffusion"})
    assert "\n" not in str(err.value)
    assert "np.float64" not in str(err.value)  # a plain number, not numpy's repr


# --------------------------------------------------------------------- end to end

#: An InGaAs-era LED set beyond the study's band. Responsivities: Hamamatsu G17190
#: typical curve (shared/data/optics_ext/SOURCES.md key values: 0.58 / 0.86 / 1.00 /
#: 0.95 A/W); powers chosen so the codes sit mid-scale.
SWIR_LEDS = [
    {"wavelength_nm": 1050.0, "fwhm_nm": 50.0, "power_mw": 1.5, "responsivity_a_per_w": 0.58},
    {"wavelength_nm": 1300.0, "fwhm_nm": 60.0, "power_mw": 3.0, "responsivity_a_per_w": 0.86},
    {"wavelength_nm": 1550.0, "fwhm_nm": 80.0, "power_mw": 40.0, "responsivity_a_per_w": 1.0},
    {"wavelength_nm": 1650.0, "fwhm_nm": 80.0, "power_mw": 8.0, "responsivity_a_per_w": 0.95},
]


@pytest.mark.parametrize("model", ["beer-lambert", "diffusion"])
def test_a_swir_led_set_simulates_end_to_end(model):
    over = {"leds": SWIR_LEDS, "optics.model": model}
    with pytest.warns(UserWarning, match="lipid"):
        ds = ng.simulate("wearable", 6, 2, 0, overrides=over)
    f = ds.frame
    cols = [f"adc_{w:g}" for w in (1050, 1300, 1550, 1650)]
    codes = f[cols].to_numpy()
    assert np.all((codes > 0) & (codes < 4095))  # on scale: nothing clipped
    frac = f[[f"true_detected_fraction_{w:g}" for w in (1050, 1300, 1550, 1650)]].to_numpy()
    # water: 1550 nm absorbs most, then 1650, 1300, 1050 nm
    med = np.median(frac, axis=0)
    assert med[2] < med[3] < med[1] < med[0]
    again = ng.simulate("wearable", 6, 2, 0, overrides=over)
    assert again.frame.equals(f)


def test_band_nodes_are_no_longer_clipped_at_1300_nm():
    spectra = tissue.band_spectra([1300.0], [60.0], 3)
    assert spectra.nodes_nm.max() > 1320.0
    water = (spectra.spectra["water"] * spectra.weights).sum()
    # the 1300 nm band's red tail climbs the 1450 nm water band: more than the centre
    assert water > float(absorption.water_mua_per_cm(1300.0))

# Long-running (whole studies, end-to-end runs, Monte Carlo or every model): `make test-slow`,
# which CI runs beside the fast `make test` (tests/test_slow_marks.py)
pytestmark = [pytestmark, pytest.mark.slow]
