"""The bound of a design (nirglucose.design.bound): against the oracle, by hand, by property."""

from __future__ import annotations

import numpy as np
import pytest

import nirglucose as ng
from nirglucose.config import PRESETS, resolve_config
from nirglucose.constants import BOLTZMANN_J_PER_K, ELEMENTARY_CHARGE_C, ZERO_CELSIUS_K
from nirglucose.design import design_bound, design_terms, noise_covariance
from nirglucose.exceptions import ConfigError
from nirglucose.models.oracle import Oracle

#: Three LED sets other than the study's (700-1300 nm), each on a preset, powers chosen
#: so that neither reading nor reference saturates.
DESIGNS = {
    "si-catalogue": ("wearable", {
        "detector": "BPW34",
        "leds": [{"part": "L8957", "power_mw": 2.0}, {"part": "L1909", "power_mw": 2.0},
                 {"wavelength_nm": 1000, "fwhm_nm": 50, "power_mw": 3.0}],
    }),
    "ingaas-long": ("paper", {
        "detector": "G17190-010K",
        "leds": [{"wavelength_nm": w, "fwhm_nm": 60, "power_mw": p}
                 for w, p in ((950, 3.5), (1050, 2.5), (1200, 2.0), (1290, 1.7))],
    }),
    "six-led": ("wearable", {
        "leds": [{"wavelength_nm": w, "fwhm_nm": 40, "power_mw": p, "responsivity_a_per_w": r}
                 for w, p, r in ((760, 3, 0.45), (810, 2.5, 0.5), (900, 2, 0.6),
                                 (990, 2.5, 0.5), (1100, 6, 0.25), (1250, 20, 0.1))],
    }),
}
#: Three designs outside the study's band: InGaAs LEDs up to 1,650 nm (issue 30), where
#: the diffusion-based optics are qualitative; the bound must still hold for the oracle.
SWIR_DESIGNS = {
    "ingaas-1550": ("paper", {
        "detector": "G17190-010K",
        "leds": [{"wavelength_nm": w, "fwhm_nm": 80, "power_mw": p}
                 for w, p in ((1050, 2.5), (1300, 4.0), (1550, 10.0))],
    }),
    "ingaas-1650": ("wearable", {
        "detector": "G17190-010K",
        "leds": [{"wavelength_nm": w, "fwhm_nm": 80, "power_mw": p}
                 for w, p in ((1100, 2.5), (1450, 10.0), (1650, 10.0))],
    }),
    "ingaas-six-to-1600": ("wearable", {
        "detector": "G17190-010K",
        "leds": [{"wavelength_nm": w, "fwhm_nm": 60, "power_mw": p}
                 for w, p in ((900, 3), (1050, 2.5), (1100, 2.5), (1200, 2.0), (1400, 10),
                              (1600, 10))],
    }),
}
CASES = {**{p: (p, None) for p in PRESETS}, **DESIGNS, **SWIR_DESIGNS}


def _oracle_rmse_and_upper(preset, overrides, seed=1, model=None):
    """The oracle's (or ``model``'s) test RMSE (half the subjects held out) and its 99 %
    upper bound by a subject bootstrap (the bound is an expectation; the RMSE an
    estimate of it)."""
    ds = ng.simulate(preset, 150, 3, seed=seed, overrides=overrides)
    fr = ds.frame
    train = fr["subject_id"] < 75
    model = (model or Oracle()).fit(ng.Dataset(fr[train].reset_index(drop=True),
                                               config=ds.config))
    test = fr[~train].reset_index(drop=True)
    err2 = (model.predict(ng.Dataset(test, config=ds.config)) - test["glucose_mgdl"]) ** 2
    per_subject = err2.groupby(test["subject_id"]).agg(["sum", "count"]).to_numpy()
    rng = np.random.default_rng(0)
    pick = rng.integers(0, len(per_subject), size=(2000, len(per_subject)))
    boot = np.sqrt(per_subject[pick, 0].sum(axis=1) / per_subject[pick, 1].sum(axis=1))
    return float(np.sqrt(err2.mean())), float(np.quantile(boot, 0.99))


@pytest.mark.parametrize("case", list(CASES))
def test_bound_does_not_exceed_the_oracle(case):
    preset, overrides = CASES[case]
    bound = design_bound(preset, condition="oracle", overrides=overrides)
    rmse, upper = _oracle_rmse_and_upper(preset, overrides)
    ratio = bound.rmse_mgdl / rmse
    print(f"{case}: bound {bound.rmse_mgdl:.2f} oracle {rmse:.2f} ratio {ratio:.2f}")
    assert bound.saturated_fraction < 0.01  # field's outdoor extremes clip now and then
    assert bound.rmse_mgdl <= upper, (case, bound.rmse_mgdl, rmse)
    # informative, not a vacuous zero: the analytic noise is most of the oracle's error
    assert ratio > 0.4, (case, ratio)


@pytest.mark.parametrize("preset", ["lab", "wearable"])
def test_device_bound_does_not_exceed_a_device_estimator(preset):
    """The device bound (nuisances unknown) bounds an estimator that reads only the
    device's columns: the Enhanced Beer-Lambert ridge."""
    from nirglucose.models import EnhancedBeerLambert

    bound = design_bound(preset).rmse_mgdl
    rmse, upper = _oracle_rmse_and_upper(preset, None, model=EnhancedBeerLambert())
    assert bound <= upper, (preset, bound, rmse)


def test_not_knowing_the_nuisances_costs():
    for preset in ("paper", "wearable"):
        device = design_bound(preset).rmse_mgdl
        oracle = design_bound(preset, condition="oracle").rmse_mgdl
        assert device > oracle


def test_more_leds_never_raise_the_bound():
    terms = design_terms("wearable", overrides=DESIGNS["six-led"][1])
    for cond in ("device", "oracle"):
        full = terms.bound(condition=cond).rmse_mgdl
        for drop in range(6):
            keep = [i for i in range(6) if i != drop]
            assert terms.bound(keep, condition=cond).rmse_mgdl >= full - 1e-9


def test_more_noise_raises_the_bound_and_no_prior_is_wider():
    quiet = design_bound("wearable", condition="oracle").rmse_mgdl
    loud = design_bound("wearable", condition="oracle", overrides={"noise_scale": 2.0})
    assert loud.rmse_mgdl > quiet
    assert design_bound("wearable", condition="oracle", prior=False).rmse_mgdl > quiet
    # with the prior the bound never exceeds the prior's own spread
    assert quiet < loud.glucose_sd_mgdl


def test_leds_and_detector_arguments_are_the_overrides():
    a = design_bound("paper", leds=DESIGNS["ingaas-long"][1]["leds"], detector="G17190-010K")
    b = design_bound("paper", overrides=DESIGNS["ingaas-long"][1])
    assert a == b and a.detector == "G17190-010K"
    assert a.wavelengths_nm == (950.0, 1050.0, 1200.0, 1290.0)


def test_noise_covariance_matches_a_hand_computation():
    # one LED, monitor photodiode (no drift terms), shot and Johnson at 25 degC
    cfg = resolve_config("paper", {
        "leds": [{"wavelength_nm": 900, "fwhm_nm": 40, "power_mw": 2.0,
                  "responsivity_a_per_w": 0.5}],
    })
    hw = cfg.hardware
    m = np.array([[np.log(0.01)]])  # detected fraction 1 % of the reference path's 2 %
    var, common, sat = noise_covariance(cfg, m, np.array([25.0]))
    i_ref = 0.5 * 2e-3 * 0.02  # 20 uA
    dark = hw.dark_current_25c_na * 1e-9
    johnson = 4 * BOLTZMANN_J_PER_K * (25 + ZERO_CELSIUS_K) * hw.bandwidth_hz / hw.tia_gain_ohm
    expected = 0.0
    for i in (i_ref * 0.01, i_ref):
        code = i * hw.tia_gain_ohm / hw.adc_vref_v * 4095
        expected += (2 * ELEMENTARY_CHARGE_C * (i + dark) * hw.bandwidth_hz + johnson) / i**2
        expected += 1 / (12 * code**2)
    assert var[0, 0] == pytest.approx(expected, rel=1e-12)
    assert common == 0.0 and not sat.any()


def test_saturated_channels_carry_no_information():
    over = {"leds": [{"wavelength_nm": 900, "fwhm_nm": 40, "power_mw": 900.0,
                      "responsivity_a_per_w": 0.6}]}
    b = design_bound("wearable", condition="oracle", overrides=over)
    assert b.saturated_fraction == 1.0
    assert b.rmse_mgdl == pytest.approx(b.glucose_sd_mgdl)


def test_bad_arguments_are_one_config_error():
    with pytest.raises(ConfigError, match="unknown condition 'orcale'"):
        design_bound("paper", condition="orcale")
    with pytest.raises(ConfigError, match="unknown detector"):
        design_bound("paper", detector="G1719")
    with pytest.raises(ConfigError, match="preset name or a ScenarioConfig"):
        design_bound(42)
    with pytest.raises(ConfigError, match="n_states"):
        design_bound("paper", n_states=0)
    with pytest.raises(ConfigError, match="must index"):
        design_terms("paper").bound([7])
