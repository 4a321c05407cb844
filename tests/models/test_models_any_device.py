"""Every estimator on any device: 1, 3 and 6 LEDs at 10, 12, 14 and 16 bits."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

import nirglucose as ng
from device_data import LED_SETS, simulate_device
from nirglucose.dataset import Dataset
from nirglucose.dataset.schema import DeviceSchema, meter_flags
from nirglucose.exceptions import DataError
from nirglucose.features import MeasurementTransformer
from nirglucose.models import available_models, get_model_class, load_model, make_model

NETWORKS = ("original-pinn", "optimized-pinn", "rte-pinn", "selective-rte-pinn", "sdnn",
            "original-pinn-fm", "optimized-pinn-fm", "rte-pinn-fm", "selective-rte-pinn-fm")
REFERENCES = ("mean", "gp", "gbr")
FAST_NET = {"max_epochs": 3, "batch_size": 16, "random_state": 0}
FAST = {name: FAST_NET for name in NETWORKS} | {
    "gp": {"random_state": 0},
    "gbr": {"n_estimators": 20, "random_state": 0},
    "physics-inversion": {"n_em": 3},
    "device-inversion": {"n_em": 3, "cv": 2},
    "ebl+gp": {"random_state": 0},
    "physics-inversion+gp": {"cv": 0, "backbone_params": {"n_em": 3}, "random_state": 0},
}
PHYSICS = ("physics-inversion", "device-inversion", "ebl+gp", "physics-inversion+gp")


def _make(name):
    return make_model(name, **FAST.get(name, {}))


def _package_models() -> list[str]:
    """The package's registered models (a test module may register its own stand-ins)."""
    return [
        n for n in available_models() if get_model_class(n).__module__.startswith("nirglucose.")
    ]


def test_every_registered_model_is_covered():
    assert set(_package_models()) == {"ebl", "pls", "oracle", *NETWORKS, *REFERENCES, *PHYSICS}


@pytest.mark.parametrize("bits", [10, 12, 14, 16])
@pytest.mark.parametrize("n_leds", [1, 3, 6])
def test_every_model_fits_predicts_and_round_trips(n_leds, bits, tmp_path):
    ds = simulate_device(n_leds, bits)
    codes = ds.frame[[c for c in ds.frame if c.startswith("adc_")]].to_numpy()
    assert codes.max() <= 2**bits - 1
    if bits > 12:
        assert codes.max() > 4095  # codes a 12-bit lock would have refused
    for name in _package_models():
        m = _make(name).fit(ds)
        pred = m.predict(ds)
        assert pred.shape == (len(ds),) and np.isfinite(pred).all(), name
        path = m.save(tmp_path / f"{name}.json")
        back = load_model(path)
        np.testing.assert_allclose(back.predict(ds), pred, rtol=1e-6, atol=1e-6, err_msg=name)
        if name == "oracle":
            continue
        s = m.schema_
        assert s.wavelengths_nm == LED_SETS[n_leds] and s.adc_bits == bits, name
        assert back.schema_ == s, name
        X = ds.frame[list(s.raw_columns)].to_numpy(float)
        np.testing.assert_allclose(m.predict(X[:5]), pred[:5], rtol=1e-4, err_msg=name)


def test_networks_take_their_widths_from_the_device():
    ds = simulate_device(3, 12)
    m = make_model("sdnn", **FAST_NET).fit(ds)
    net = m.module_.inner  # inside the input whitening
    assert net.front[0].in_features == 3
    assert net.stack[0].in_features == 16 + 12
    rte = make_model("rte-pinn", **FAST_NET).fit(ds)
    assert rte.physics_["wavelengths_nm"] == [850.0, 940.0, 1150.0]
    sel = make_model("selective-rte-pinn", **FAST_NET).fit(ds)
    assert sel.physics_["wavelengths_nm"] == [1150.0]  # 1050 nm is absent on this device
    bl = make_model("original-pinn", **FAST_NET).fit(ds)
    assert bl.physics_["wavelengths_nm"] == [850.0, 940.0, 1150.0]
    assert len(bl.physics_["absorptivity_per_cm_per_mgdl"]) == 3


@pytest.mark.parametrize("n_leds", [1, 6])
def test_reference_learners_take_their_inputs_from_the_device(n_leds):
    ds = simulate_device(n_leds, 14)
    want = tuple(f"A_{w:g}" for w in LED_SETS[n_leds]) + DeviceSchema.infer(ds).physiology
    assert len(want) == n_leds + 12
    U = MeasurementTransformer().fit(ds).transform(ds)
    for name in REFERENCES:
        m = _make(name).fit(ds)
        assert m.input_names_ == want and m.n_features_in_ == 2 * n_leds + 12, name
    gp = _make("gp").fit(ds)
    assert gp.length_scales_.shape == gp.x_mean_.shape == (n_leds + 12,)
    np.testing.assert_allclose(gp.x_mean_, U.mean(axis=0), rtol=1e-12)
    gbr = _make("gbr").fit(ds)
    assert gbr.feature_.max() < n_leds + 12


def test_device_without_reference_or_physiology(tmp_path):
    """A one-LED, 10-bit device that records neither reference codes nor physiology."""
    ds = simulate_device(1, 10)
    frame = ds.frame[["subject_id", "adc_940", "glucose_mgdl"]]
    # codes that fit 10 bits fit 12, 14, 16 alike: the resolution must be declared (issue 28)
    with pytest.raises(DataError, match="fit a 10-, 12-, 14- or 16-bit ADC alike"):
        _make("ebl").fit(frame)
    declared = Dataset(frame, metadata={"adc_bits": 10})
    for name in ("ebl", "pls", "sdnn", "original-pinn", "rte-pinn", *REFERENCES):
        m = _make(name).fit(declared)
        assert not m.schema_.reference and m.schema_.physiology == ()
        assert m.schema_.adc_bits == 10
        p = m.predict(frame)
        np.testing.assert_allclose(
            load_model(m.save(tmp_path / "m.json")).predict(frame), p, rtol=1e-6
        )
    with pytest.raises(DataError, match="missing columns"):
        m.predict(frame.drop(columns="adc_940"))


def test_physiology_used_is_what_is_present_at_fit_and_required_at_predict():
    ds = simulate_device(3, 12)
    some = ds.frame.drop(columns=["bmi_kgm2", "heart_rate_bpm"])
    m = make_model("ebl").fit(some)
    assert "bmi_kgm2" not in m.schema_.physiology and "age_yr" in m.schema_.physiology
    m.predict(ds.frame)  # extra columns are ignored
    with pytest.raises(DataError, match="missing columns \\['age_yr'\\]"):
        m.predict(some.drop(columns=["age_yr"]))


def test_declared_adc_bits_and_range_checks():
    ds = simulate_device(3, 14)
    frame = ds.frame  # a CSV would lose the scenario: only the frame's columns remain
    with pytest.raises(DataError, match="outside 1-4095 \\(12-bit ADC\\)"):
        make_model("ebl").fit(frame)
    m = make_model("ebl", adc_bits=14).fit(frame)
    assert m.schema_.full_scale == 16383
    assert make_model("ebl").fit(ds).schema_.adc_bits == 14  # from the scenario


def test_refuses_values_no_device_produces():
    ds = simulate_device(3, 12)
    f = ds.frame.copy()
    f.loc[4, "systolic_bp_mmhg"] = 20.0
    with pytest.raises(DataError, match="systolic_bp_mmhg.*physiological range 50-300.*rows 4"):
        make_model("pls").fit(f)
    f = ds.frame.copy()
    f.loc[7, "glucose_mgdl"] = 700.0
    for name in ("ebl", "sdnn", "oracle", *REFERENCES):
        data = ng.Dataset(f, config=ds.config) if name == "oracle" else f
        with pytest.raises(DataError, match=r"20-600 \[mg/dL\].*rows 7"):
            _make(name).fit(data)


@pytest.mark.parametrize("name", ["ebl", "pls", "sdnn", "oracle", *REFERENCES])
def test_one_fit_size_policy(name):
    ds = simulate_device(3, 12, n_subjects=1, per_subject=4)
    with pytest.raises(DataError, match="too few rows to fit: 4 sample"):
        _make(name).fit(ds)
    ds = simulate_device(3, 12, n_subjects=1, per_subject=6)
    with pytest.raises(DataError, match="too few subjects to fit: 1"):
        _make(name).fit(ds)


def test_meter_flags():
    assert meter_flags([19.9, 20.0, 600.0, 600.1, -4e5]).tolist() == ["LO", "", "", "HI", "LO"]


def test_measurement_transformer_is_the_one_boundary():
    ds = simulate_device(3, 16)
    t = MeasurementTransformer().fit(ds)
    out = t.transform(ds)
    names = list(t.get_feature_names_out())
    assert names[:3] == ["A_850", "A_940", "A_1150"] and out.shape == (len(ds), 3 + 12)
    f = ds.frame
    np.testing.assert_allclose(out[:, 0], np.log10(f.adc_ref_850 / f.adc_850))
    assert t.schema_ == DeviceSchema.infer(ds)
    assert DeviceSchema.from_json(t.schema_.to_json()) == t.schema_
    bad = f.drop(columns="adc_ref_940")
    with pytest.raises(DataError, match="reference codes for some LEDs only"):
        MeasurementTransformer().fit(bad)
    with pytest.raises(DataError, match="no ADC columns"):
        MeasurementTransformer().fit(pd.DataFrame({"glucose_mgdl": [100.0]}))

# Long-running (whole studies, end-to-end runs, Monte Carlo or every model): `make test-slow`,
# which CI runs beside the fast `make test` (tests/test_slow_marks.py)
pytestmark = pytest.mark.slow
