"""Water's temperature dependence (issue 40): the table against its sources, the optics
and the simulator with the ``water_temperature`` switch, glucose's first-overtone height."""

from __future__ import annotations

import numpy as np
import pytest

import nirglucose as ng
from nirglucose.config import resolve_config
from nirglucose.data import load_spectrum
from nirglucose.exceptions import ConfigError
from nirglucose.optics import absorption, tissue
from nirglucose.optics.kernels.band_kernel import band_detected_fraction
from nirglucose.simulation.simulator import (
    detected_fraction_given_glucose,
    scenario_tables,
    water_temperature_delta_c,
)

# the 1650 nm bands reach past the lipid table's end (a stated, warned assumption)
pytestmark = pytest.mark.filterwarnings("ignore:lipid absorption above")

SWIR = [{"wavelength_nm": w, "fwhm_nm": 80, "power_mw": p}
        for w, p in ((1050, 2.5), (1300, 4.0), (1550, 10.0), (1650, 10.0))]


def test_table_holds_the_sources_values():
    # WOPP v3 PsiT [1/(m degC)] / 100, read off the file (SOURCES.md): 1450, 1412, 1650 nm
    assert float(absorption.water_dmua_dt_per_cm_per_c(1450.0)) == pytest.approx(-0.03662597)
    assert float(absorption.water_dmua_dt_per_cm_per_c(1412.0)) == pytest.approx(0.13998464)
    assert float(absorption.water_dmua_dt_per_cm_per_c(1650.0)) == pytest.approx(-0.02917884)
    wl, _ = load_spectrum("water_dmua_dt_rottgers2014")
    np.testing.assert_array_equal(wl, np.arange(690.0, 2101.0, 2.0))  # the native 2 nm grid


def test_table_agrees_with_an_independent_measurement():
    # -0.259 +/- 0.003 (2014 nm) and -0.104 +/- 0.001 (2090 nm) 1/(K cm), linear 20-100
    # degC (holmium/thulium laser study, abstract; SOURCES.md): within 10 %
    wl, d = load_spectrum("water_dmua_dt_rottgers2014")
    got = np.interp([2014.0, 2090.0], wl, d)
    np.testing.assert_allclose(got, [-0.259, -0.104], rtol=0.10)


def test_warmer_water_moves_its_bands_to_shorter_wavelengths():
    d = absorption.water_dmua_dt_per_cm_per_c
    # positive on the short-wavelength flanks, negative on the long ones
    assert d(960.0) > 0 > d(1020.0) and d(1150.0) > 0 > d(1220.0) and d(1412.0) > 0 > d(1490.0)
    # the 1450 nm band's zero crossing lies at 1442-1444 nm
    assert d(1442.0) > 0 > d(1444.0)
    # about -0.5 % of mua per degC on the long flank (relative to Kou's 22 degC table)
    for nm in (1550.0, 1650.0):
        rel = float(d(nm) / absorption.water_mua_per_cm(nm))
        assert -0.006 < rel < -0.004


@pytest.mark.parametrize("source", list(absorption.WATER_SOURCES))
def test_water_at_its_tables_temperature_is_the_table(source):
    t_ref = absorption.WATER_TABLE_TEMPERATURE_C[source]
    wl = np.array([940.0, 1150.0, 1550.0])
    np.testing.assert_array_equal(
        absorption.water_mua_at_temperature_per_cm(wl, t_ref, source),
        absorption.water_mua_per_cm(wl, source))
    # linear: +1 degC adds d(mua)/dT
    np.testing.assert_allclose(
        absorption.water_mua_at_temperature_per_cm(wl, t_ref + 1.0, source)
        - absorption.water_mua_per_cm(wl, source),
        absorption.water_dmua_dt_per_cm_per_c(wl), rtol=1e-12)


def test_water_temperature_outside_the_linear_range_is_refused():
    with pytest.raises(ConfigError, match="70.0 degC is outside 0-60"):
        absorption.water_mua_at_temperature_per_cm([1550.0, 1550.0], [33.0, 70.0])


def test_first_overtone_height_is_a_parameter():
    f = absorption.glucose_mua_per_cm_per_mm
    assert f(1670.0, 1e-4, 3.0) == pytest.approx(3e-4, rel=1e-6)
    assert f(1670.0, 1e-4, 0.0) == pytest.approx(0.0, abs=1e-9)
    # the 1150 nm band does not move with it
    assert f(1150.0, 1e-4, 30.0) == pytest.approx(f(1150.0, 1e-4), rel=1e-12)
    with pytest.raises(ConfigError, match=">= 0"):
        f(1670.0, 1e-4, -1.0)
    cfg = resolve_config("physical", {"glucose.first_overtone_relative_peak": 3.0})
    tab = scenario_tables(cfg).spectra.spectra["glucose"]
    assert np.all(tab >= 0)


def _state(n, dt):
    rng = np.random.default_rng(7)
    return tissue.TissueState(
        rng.uniform(0.005, 0.05, n), rng.uniform(0.5, 0.95, n), rng.uniform(0.5, 0.75, n),
        rng.uniform(0.6, 0.9, n), rng.uniform(3.0, 30.0, n), dt)


def test_tissue_optics_takes_water_at_its_temperature():
    spectra = tissue.band_spectra([1450, 1550, 1650], [60, 80, 80], 5,
                                  water_temperature_scale=1.0)
    n = 300
    dt = np.random.default_rng(8).normal(11.0, 2.0, n)
    shift = np.random.default_rng(9).normal(0.0, 2.0, (n, 3))
    kw = dict(water_displacement_per_mm=1.1e-4, scattering_rel_per_mm=-1.25e-3, shift_nm=shift)
    warm = tissue.tissue_optics(spectra, _state(n, dt), **kw)
    table = tissue.tissue_optics(spectra, _state(n, None), **kw)
    # the difference is the water's share x dT x d(mua)/dT (with the thermal LED shift)
    st = _state(n, None)
    disp = 1.0 - 1.1e-4 * st.glucose_mm
    wdt = (spectra.spectra["water_dt"][None]
           + shift[..., None] * spectra.derivatives["water_dt"][None])
    np.testing.assert_allclose(
        warm["mua_dermis"] - table["mua_dermis"],
        (st.water_fraction * disp * dt)[:, None, None] * wdt, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(
        warm["mua_subcutis"] - table["mua_subcutis"],
        (tissue.SUBCUTIS["water_fraction"] * disp * dt)[:, None, None] * wdt,
        rtol=1e-9, atol=1e-12)
    # water's temperature scale 0: the table is zero, nothing moves
    cold = tissue.band_spectra([1450, 1550, 1650], [60, 80, 80], 5)
    np.testing.assert_array_equal(cold.spectra["water_dt"], 0.0)


def test_compiled_kernel_carries_the_temperature_term():
    from nirglucose.optics import forward

    spectra = tissue.band_spectra([940, 1150, 1550, 1650], [40, 60, 80, 80], 3,
                                  water_temperature_scale=1.0)
    n = 400
    rng = np.random.default_rng(10)
    state = _state(n, rng.normal(11.0, 2.0, n))
    shift = rng.normal(0, 2, (n, 4))
    mel, t_cm = rng.uniform(0.01, 0.15, n), rng.uniform(0.05, 0.4, n)
    geometry = rng.uniform(0.5, 2.0, (4, 3))
    kw = dict(water_displacement_per_mm=1.1e-4, scattering_rel_per_mm=-1.25e-3)
    optics = tissue.tissue_optics(spectra, state, shift_nm=shift, **kw)
    nodes = forward.detected_fraction(
        "beer-lambert", optics, melanin_fraction=mel, skin_thickness_cm=t_cm,
        epidermis_thickness_cm=0.008, separation_cm=0.3, detector_area_cm2=0.01,
        n_tissue=1.4, geometry_factor=geometry)
    want = np.einsum("nlp,lp->nl", nodes, spectra.weights)
    got = band_detected_fraction(
        spectra, state, shift_nm=shift, melanin_fraction=mel, skin_thickness_cm=t_cm,
        epidermis_thickness_cm=0.008, separation_cm=0.3, geometry_factor=geometry, **kw)
    np.testing.assert_allclose(got, want, rtol=1e-12)
    # warmer water absorbs less on the long flank of the 1450 nm band: more light there
    warmer = _state(n, np.asarray(state.water_temperature_delta_c) + 5.0)
    got_w = band_detected_fraction(
        spectra, warmer, shift_nm=shift, melanin_fraction=mel, skin_thickness_cm=t_cm,
        epidermis_thickness_cm=0.008, separation_cm=0.3, geometry_factor=geometry, **kw)
    assert np.all(got_w[:, 2:] > got[:, 2:])


def test_switch_off_is_the_default_and_the_delta_is_none():
    cfg = resolve_config("physical")
    assert cfg.noise_factor("water_temperature") == 0.0
    assert water_temperature_delta_c(cfg, np.array([33.0])) is None
    on = resolve_config("physical", {"noise.water_temperature.enabled": True})
    # Kou's table is at 22 degC
    np.testing.assert_array_equal(water_temperature_delta_c(on, np.array([33.0])), [11.0])


def test_simulated_readings_follow_the_skin_temperature():
    ov = {"leds": SWIR, "detector": "G17190-010K"}
    off = ng.simulate("physical", 20, 3, seed=3, overrides=ov).frame
    on = ng.simulate("physical", 20, 3, seed=3,
                     overrides={**ov, "noise.water_temperature.enabled": True}).frame
    # same random draws: the same skin temperatures, other readings
    np.testing.assert_array_equal(off["true_skin_temp_c"], on["true_skin_temp_c"])
    ratio = (on["true_detected_fraction_1550"] / off["true_detected_fraction_1550"]).to_numpy()
    assert np.all(ratio > 1.0)  # skin (about 33 degC) absorbs less than the 22 degC table
    # ... the more so the warmer the skin (the rest: each reading's water and path)
    dt = off["true_skin_temp_c"].to_numpy() - 22.0
    assert np.corrcoef(dt, np.log(ratio))[0, 1] > 0.95
    # the oracle's forward model reproduces the switched-on readings from true_* columns
    cfg = ng.simulate("physical", 1, 1, seed=3,
                      overrides={**ov, "noise.water_temperature.enabled": True}).config
    frac = detected_fraction_given_glucose(cfg, on, on["glucose_mgdl"].to_numpy(float))
    want = on[[f"true_detected_fraction_{w}" for w in (1050, 1300, 1550, 1650)]].to_numpy()
    np.testing.assert_allclose(frac, want, rtol=1e-12)
