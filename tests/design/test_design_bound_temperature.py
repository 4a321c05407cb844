"""The design bound with water's temperature dependence (issue 40): the skin temperature
as one more nuisance, its prior the skin thermometer's error."""

from __future__ import annotations

import numpy as np
import pytest

from nirglucose.config import resolve_config
from nirglucose.design import design_bound, design_terms
from nirglucose.simulation.forward_model import NUISANCES, ForwardModel

pytestmark = pytest.mark.filterwarnings("ignore:lipid absorption above")

ON = {"noise.water_temperature.enabled": True}
#: A glucose-informative device (the paper regime's gain, physiology measured with the
#: instruments' errors) with InGaAs LEDs on the water bands' long flanks, and one at
#: 850-1150 nm; powers for mid-scale codes (design.search.drive_powers_mw, 10 mW cap).
DEVICE = {"glucose.signal_gain": 11.0, "device.physiology": "measured"}
SWIR_LEDS = [{"wavelength_nm": w, "fwhm_nm": f, "power_mw": 10.0}
             for w, f in ((1300, 64.0), (1550, 76.0), (1600, 78.5), (1650, 81.0))]
NIR_LEDS = [{"wavelength_nm": w, "fwhm_nm": f, "power_mw": 10.0}
            for w, f in ((850, 41.7), (940, 46.1), (1050, 51.5), (1150, 56.4))]


def test_forward_model_reads_the_skin_temperature_when_the_switch_is_on():
    cfg = resolve_config("physical", {**ON, "leds": SWIR_LEDS, "detector": "G17190-010K"})
    fm = ForwardModel(cfg, "beer-lambert")
    assert fm.nuisances == (*NUISANCES, "skin_temp_c")
    theta = np.array([[np.log(0.02), 0.7, 0.65, 0.8, 0.05, 1.8, 0.0, 0.0]])
    neutral = cfg.physiology.skin_temp_c_neutral
    # without the column: the thermoneutral skin temperature
    np.testing.assert_array_equal(
        fm.log_ratio(np.array([100.0]), theta),
        fm.log_ratio(np.array([100.0]), np.column_stack([theta, [neutral]])))
    warm = fm.log_ratio(np.array([100.0]), np.column_stack([theta, [neutral + 1.0]]))
    base = fm.log_ratio(np.array([100.0]), theta)
    # +1 degC on the 1450 nm band's long flank: less water absorption, more light
    assert np.all((warm - base)[0, 1:] > 0)
    with pytest.raises(ValueError, match="columns"):
        fm.log_ratio(np.array([100.0]), np.zeros((1, 5)))
    off = ForwardModel(resolve_config("physical"), "beer-lambert")
    assert off.nuisances == NUISANCES


def test_temperature_prior_is_the_thermometers_error():
    over = {**ON, **DEVICE, "leds": SWIR_LEDS, "detector": "G17190-010K"}
    measured = design_terms("paper", overrides=over, n_states=64)
    assert measured.jacobian.shape[-1] == 1 + len(NUISANCES) + 1
    sd = float(np.sqrt(measured.nuisance_cov[-1, -1]))
    assert sd == pytest.approx(0.2, rel=0.15)  # measurement.skin_temp_c
    exact = design_terms("paper", overrides={**over, "device.physiology": "exact"},
                         n_states=64)
    assert float(np.sqrt(exact.nuisance_cov[-1, -1])) < 0.01


@pytest.mark.parametrize(("leds", "moves"), [(SWIR_LEDS, True), (NIR_LEDS, False)])
def test_the_bound_sees_the_thermometer_only_with_the_switch_on(leds, moves):
    def bound(extra, err_c):
        over = {**DEVICE, **extra, "measurement.skin_temp_c": err_c}
        return design_bound("paper", leds=leds, detector="G17190-010K",
                            overrides=over).rmse_mgdl

    on = bound(ON, 5.0) / bound(ON, 0.05)
    off = bound({}, 5.0) / bound({}, 0.05)
    assert abs(off - 1.0) < 0.005  # off: the thermometer only informs perfusion
    if moves:  # measured numbers (issue 40): 17.17 -> 17.53 mg/dL
        assert on > 1.01
    else:  # 850-1150 nm: 9.64 -> 9.64 mg/dL in this device
        assert abs(on - 1.0) < 0.005
