"""Optical tables and the pure optics functions against hand-computed values."""

from __future__ import annotations

import numpy as np
import pytest

from nirglucose.exceptions import ConfigError
from nirglucose.optics import absorption, beer_lambert, scattering, skin, tissue


def test_values_at_leds_match_sources_md():
    # SOURCES.md "Key values at the LED wavelengths"
    wl = np.array([850.0, 940.0, 1050.0, 1150.0])
    np.testing.assert_allclose(
        absorption.water_mua_per_cm(wl), [0.042, 0.18, 0.166, 0.98], atol=0.01
    )
    np.testing.assert_allclose(absorption.blood_mua_per_cm(wl, 1.0), [4.9, 6.5, 4.9, 3.0], atol=0.1)
    np.testing.assert_allclose(absorption.blood_mua_per_cm(wl, 0.0), [4.2, 4.3, 2.2, 1.9], atol=0.1)
    np.testing.assert_allclose(absorption.melanosome_mua_per_cm(wl), [116, 83, 57, 42], atol=1)
    np.testing.assert_allclose(
        scattering.power_law_musp_per_cm(wl), [21.6, 18.8, 16.0, 14.1], atol=0.1
    )
    np.testing.assert_allclose(
        absorption.lipid_mua_per_cm(wl[:3]), [0.0064, 0.088, 0.065], atol=0.002
    )
    assert absorption.lipid_mua_per_cm(1150.0) == pytest.approx(0.22, abs=0.03)


def test_water_sources_selectable():
    a = absorption.water_mua_per_cm(940.0, "kou1993")
    b = absorption.water_mua_per_cm(940.0, "segelstein1981")
    assert a == pytest.approx(0.18, abs=0.01) and b == pytest.approx(0.29, abs=0.01)
    with pytest.raises(ConfigError, match="valid"):
        absorption.water_mua_per_cm(940.0, "nope")


def test_out_of_range_wavelength_raises():
    with pytest.raises(ConfigError, match="600"):
        absorption.water_mua_per_cm([850.0, 600.0])


def test_blood_saturation_mixing_and_range():
    # linear in S: halfway between oxy and deoxy
    mid = absorption.blood_mua_per_cm(850.0, 0.5)
    assert mid == pytest.approx(0.5 * (4.9 + 4.2), abs=0.1)
    with pytest.raises(ConfigError):
        absorption.blood_mua_per_cm(850.0, 70.0)


def test_glucose_absorption_peaks_at_1150():
    wl = np.array([850.0, 940.0, 1050.0, 1150.0])
    eps = absorption.glucose_mua_per_cm_per_mm(wl, 1e-4)
    assert eps[3] == pytest.approx(1e-4)
    assert np.argmax(eps) == 3 and eps[0] < 1e-6


def test_glucose_scattering_factor_first_order():
    # exp(kC) = 1 + kC + O((kC)^2): at C = 5 mM, k = -1.25e-3: 0.99377...
    assert scattering.glucose_scattering_factor(5.0, -1.25e-3) == pytest.approx(
        1 - 6.25e-3, abs=2e-5
    )


def test_mbll_and_absorbance():
    # exp(-0.2 * 4 * 0.3) = exp(-0.24) = 0.786628
    assert beer_lambert.mbll_transmittance(0.2, 4.0, 0.3) == pytest.approx(0.786628, rel=1e-6)
    assert beer_lambert.absorbance(10.0, 1000.0) == pytest.approx(2.0)


def test_skin_layers():
    # f_mel=0.05: 0.05*100 + 0.95*0.244 = 5.2318 /cm; T = exp(-4*5.2318*0.008) = 0.84575
    mua = skin.epidermis_mua_per_cm(0.05, 100.0, 0.244)
    assert mua == pytest.approx(5.2318)
    assert skin.epidermis_transmittance(mua, 0.008) == pytest.approx(np.exp(-4 * 5.2318 * 0.008))
    # z = sqrt(0.3/2)/(2 sqrt 2) = 0.13693
    assert skin.mean_penetration_depth_cm(0.3, 2.0) == pytest.approx(0.136931, rel=1e-5)
    assert skin.dermis_path_fraction(0.2, 0.1) == pytest.approx(1 - np.exp(-2))


def test_band_spectra_weights_and_narrow_band_limit():
    wide = tissue.band_spectra([940.0], [40.0], 5)
    assert wide.weights.sum() == pytest.approx(1.0)
    narrow = tissue.band_spectra([940.0], [1e-3], 5)
    water = (narrow.spectra["water"] * narrow.weights).sum()
    assert water == pytest.approx(float(absorption.water_mua_per_cm(940.0)), rel=1e-4)
    # the 940 nm LED band straddles the steep water edge: wide band absorbs more
    assert (wide.spectra["water"] * wide.weights).sum() > water


def test_the_validation_solvers_are_outside_the_package():
    import subprocess
    import sys
    from pathlib import Path

    validation = str(Path(__file__).resolve().parents[2] / "validation")
    code = (
        "import sys, nirglucose as ng; ng.simulate('paper', 2, 1, 0);"
        "assert 'iadpython' not in sys.modules;"
        "import nirglucose.optics as o\n"
        "try:\n    o.slab_rt\nexcept AttributeError as e:\n"
        "    assert 'nirglucose_reference.adding_doubling.slab_rt' in str(e)\n"
        f"sys.path.insert(0, {validation!r})\n"
        "from nirglucose_reference.adding_doubling import slab_rt\n"
        "r, t = slab_rt(10, 90, 0.75, 0.02, 1.0)\n"
        "assert abs(r - 0.09734) / 0.09734 < 0.01 and abs(t - 0.66096) / 0.66096 < 0.01"
    )
    subprocess.run([sys.executable, "-c", code], check=True)
