"""Physical invariants of the simulator.

Sign of the glucose effect (derived, then tested). In the Beer-Lambert forward model
the detected fraction is G exp(-mua DPF rho) with DPF ~ (1/2) sqrt(3 mus'/mua) (...),
so d ln I / dC = -rho d(mua DPF)/dC. Glucose acts three ways:

1. scattering: mus' = mus'_0 exp(k C), k < 0, so DPF falls and ln I rises by about
   (1/2) |k| OD per mM (OD = mua DPF rho, about 0.3-1 here);
2. water displacement: mua falls by x_disp W mua_water per mM: ln I rises;
3. glucose absorption: mua rises by W eps_glc per mM: ln I falls.

With the documented magnitudes (k = -1.25e-3/mM, x_disp = 1.1e-4/mM,
eps_glc <= 1e-4 /cm/mM), term 1 is about 2e-4 to 6e-4 per mM, term 2 + term 3 at most
about 1e-4: the detected signal must RISE with glucose at every LED.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import nirglucose as ng
from nirglucose.dataset import adc_columns
from nirglucose.simulation.simulator import detected_fraction_given_glucose

QUIET = {"noise_scale": 0.0}


@pytest.fixture(scope="module")
def quiet_paper():
    return ng.simulate("paper", n_subjects=60, per_subject=2, seed=3, overrides=QUIET)


@pytest.fixture(scope="module")
def quiet_physical():
    return ng.simulate("physical", n_subjects=60, per_subject=2, seed=4, overrides=QUIET)


@settings(max_examples=25, deadline=None)
@given(
    g1=st.floats(60.0, 399.0),
    dg=st.floats(0.5, 300.0),
)
def test_detected_signal_rises_with_glucose_at_every_led(quiet_paper, g1, dg):
    g2 = min(g1 + dg, 400.0)
    frame = quiet_paper.frame
    n = len(frame)
    f1 = detected_fraction_given_glucose(quiet_paper.config, frame, np.full(n, g1))
    f2 = detected_fraction_given_glucose(quiet_paper.config, frame, np.full(n, g2))
    assert np.all(f2 > f1)


def test_sign_holds_at_literature_magnitudes(quiet_physical):
    frame = quiet_physical.frame
    n = len(frame)
    f1 = detected_fraction_given_glucose(quiet_physical.config, frame, np.full(n, 80.0))
    f2 = detected_fraction_given_glucose(quiet_physical.config, frame, np.full(n, 300.0))
    assert np.all(f2 > f1)
    # and the effect is tiny: < 1 % change of the detected signal over 80-300 mg/dL
    assert np.all(f2 / f1 - 1 < 1e-2)


def test_sign_reverses_when_only_glucose_absorption_acts(quiet_paper):
    cfg = ng.resolve_config(
        "paper",
        {**QUIET, "glucose.scattering_rel_per_mm": 0.0, "glucose.water_displacement_per_mm": 0.0},
    )
    frame = quiet_paper.frame
    n = len(frame)
    f1 = detected_fraction_given_glucose(cfg, frame, np.full(n, 80.0))
    f2 = detected_fraction_given_glucose(cfg, frame, np.full(n, 300.0))
    # the 1150 nm band absorbs: less light with more glucose
    assert np.all(f2[:, 3] < f1[:, 3])


@settings(max_examples=20, deadline=None)
@given(extra=st.floats(0.005, 0.1))
def test_more_melanin_lowers_detected_power_at_850(quiet_paper, extra):
    frame = quiet_paper.frame
    darker = frame.copy()
    darker["true_melanin_fraction"] = frame["true_melanin_fraction"] + extra
    g = frame["glucose_mgdl"].to_numpy()
    base = detected_fraction_given_glucose(quiet_paper.config, frame, g)
    dark = detected_fraction_given_glucose(quiet_paper.config, darker, g)
    assert np.all(dark[:, 0] < base[:, 0])
    # melanin absorbs less at longer wavelengths: relative loss largest at 850 nm
    loss = 1 - dark / base
    assert np.all(loss[:, 0] > loss[:, 3])


def test_thicker_skin_lowers_signal_at_1150_with_diffusion_model():
    ds = ng.simulate("paper", 30, 1, 0, overrides={**QUIET, "optics.model": "diffusion"})
    frame = ds.frame
    thick = frame.copy()
    thick["true_skin_thickness_probe_mm"] = frame["true_skin_thickness_probe_mm"] * 1.5
    g = frame["glucose_mgdl"].to_numpy()
    a = detected_fraction_given_glucose(ds.config, frame, g)
    b = detected_fraction_given_glucose(ds.config, thick, g)
    # more path in the wetter, bloodier dermis instead of the fat: more absorption
    assert np.all(b[:, 3] < a[:, 3])


@pytest.mark.parametrize("bits", [12, 14])
def test_adc_codes_are_integers_in_range(bits):
    ds = ng.simulate("field", 200, 2, 1, overrides={"hardware.adc_bits": bits})
    codes = ds.frame[adc_columns() + [c.replace("adc_", "adc_ref_") for c in adc_columns()]]
    assert all(pd.api.types.is_integer_dtype(t) for t in codes.dtypes)
    assert codes.to_numpy().min() >= 0
    assert codes.to_numpy().max() <= 2**bits - 1


def test_forward_models_agree_at_nominal_skin():
    # the Beer-Lambert geometry factor is fixed so both models agree at nominal skin
    over = {**QUIET, "physiology.variation_scale": 0.0, "environment.temperature_c": [24.9, 25.1]}
    a = ng.simulate("paper", 5, 1, 0, overrides={**over, "optics.model": "beer-lambert"})
    b = ng.simulate("paper", 5, 1, 0, overrides={**over, "optics.model": "diffusion"})
    fa = a.frame[[c for c in a.frame if c.startswith("true_detected_fraction")]].to_numpy()
    fb = b.frame[[c for c in b.frame if c.startswith("true_detected_fraction")]].to_numpy()
    np.testing.assert_allclose(fa, fb, rtol=0.1)
