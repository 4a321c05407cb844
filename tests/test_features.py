"""The 56 Enhanced Beer–Lambert features."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from sklearn.pipeline import make_pipeline
from sklearn.preprocessing import StandardScaler

import nirglucose as ng
import nirglucose.features as F
from common_checks import run_check, sklearn_checks
from nirglucose.dataset import PMF_COLUMNS, measured_columns
from nirglucose.exceptions import DataError, NotFittedError
from nirglucose.features import (
    FEATURE_NAMES,
    FEATURE_TABLE,
    N_FEATURES,
    EnhancedBeerLambertFeatures,
    ebl_feature_matrix,
    enhanced_beer_lambert,
    features_markdown,
    log10_absorbance,
    perfusion_index,
)

#: Every scikit-learn check runs (a plain array fits a plain schema); none may fail.
EXPECTED_FAILED: dict[str, dict[str, str]] = {}
DOCS = Path(__file__).resolve().parents[1] / "docs" / "features.md"
NOMINAL_PMF = [50.0, 28.0, 3.0, 0.05, 1.8, 100.0, 120.0, 72.0, 16.0, 33.0, 60.0, 1013.25]


def _row(adc, ref, pmf=NOMINAL_PMF):
    return np.r_[adc, ref, pmf].astype(float)[None, :]


@pytest.fixture(scope="module")
def small():
    return ng.simulate("wearable", n_subjects=15, per_subject=2, seed=3)


def test_count_names_and_categories():
    assert N_FEATURES == 56 == len(FEATURE_NAMES) == len(set(FEATURE_NAMES))
    counts = pd.Series([f.category for f in FEATURE_TABLE]).value_counts().to_dict()
    assert counts == {
        "absorbance": 4,
        "contrast": 3,
        "difference": 3,
        "curvature": 2,
        "product": 10,
        "pmf-weight": 4,
        "temp": 4,
        "hydration": 4,
        "pressure": 4,
        "pmf": 12,
        "env-2nd": 6,
    }
    assert FEATURE_NAMES[38:50] == PMF_COLUMNS
    assert FEATURE_NAMES[4:7] == ("dA_1150_940", "dA_1050_850", "dA_1150_1050")


def test_docs_table_in_sync():
    assert DOCS.read_text() == features_markdown()


def test_module_docstring_lists_every_feature():
    rows = [line for line in F.__doc__.splitlines() if re.match(r"^\d+\s{2,}", line)]
    assert len(rows) == N_FEATURES
    for i, (line, spec) in enumerate(zip(rows, FEATURE_TABLE, strict=True)):
        assert re.split(r"\s{2,}", line.strip()) == [
            str(i),
            spec.name,
            spec.formula,
            spec.category,
            spec.rationale,
        ]


def test_hand_computed_row():
    adc = [2000.0, 1000.0, 500.0, 250.0]
    ref = [2000.0, 2000.0, 2000.0, 2000.0]
    pmf = list(NOMINAL_PMF)
    pmf[9], pmf[5], pmf[11] = 35.0, 110.0, 1023.25  # dT = 2, dH = 0.1, dP = 10/1013.25
    f = dict(zip(FEATURE_NAMES, ebl_feature_matrix(_row(adc, ref, pmf))[0], strict=True))
    lg2 = np.log10(2.0)
    a = np.array([0.0, lg2, 2 * lg2, 3 * lg2])  # A = log10(2000 / adc)
    np.testing.assert_allclose([f["A_850"], f["A_940"], f["A_1050"], f["A_1150"]], a, atol=1e-15)
    assert f["dA_1150_940"] == pytest.approx(2 * lg2)
    assert f["dA_1050_850"] == pytest.approx(2 * lg2)
    assert f["dA_1150_1050"] == pytest.approx(lg2)
    assert f["A_940_x_A_1150"] == pytest.approx(3 * lg2 * lg2)
    assert f["dT_x_A_1150"] == pytest.approx(2.0 * 3 * lg2)
    assert f["dH_x_A_940"] == pytest.approx(0.1 * lg2)
    assert f["dP_x_A_1050"] == pytest.approx(10.0 / 1013.25 * 2 * lg2)
    assert f["dT_sq"] == pytest.approx(4.0)
    assert f["dT_x_dH"] == pytest.approx(0.2)
    perf = np.exp(0.03 * 2.0 + 0.002 * 0.0 + 0.001 * 10.0)
    w = F.ALPHA_SKIN_PER_MM[3] * 1.8 + F.ALPHA_PERF[3] * perf + F.ALPHA_MEL[3] * 0.05
    assert f["w_x_A_1150"] == pytest.approx(w * 3 * lg2, rel=1e-12)
    assert f["skin_temp_c"] == 35.0


def test_curvature_vanishes_on_a_linear_spectrum_and_sees_a_bend():
    wl = np.array([850.0, 940.0, 1050.0, 1150.0])
    np.testing.assert_allclose(F.CURVATURE_WEIGHTS @ (0.3 + 0.002 * wl), 0.0, atol=1e-12)
    np.testing.assert_allclose(F.CURVATURE_WEIGHTS.sum(axis=1), 0.0, atol=1e-12)
    # A quadratic in x = wl / 100 nm has second derivative 2 c everywhere.
    np.testing.assert_allclose(F.CURVATURE_WEIGHTS @ (0.7 * (wl / 100.0) ** 2), 1.4, rtol=1e-12)


def test_scalar_kernels():
    assert float(log10_absorbance(100.0, 1000.0)) == pytest.approx(1.0, abs=1e-15)
    assert float(perfusion_index(33.0, 120.0, 1013.25)) == pytest.approx(1.0, abs=1e-15)
    assert float(perfusion_index(34.0, 120.0, 1013.25)) == pytest.approx(np.exp(0.03))


def test_simulated_data_gives_finite_features(small):
    for preset in ("wearable", "physical", "lab", "field"):  # the study's 12-entry vector
        ds = ng.simulate(preset, n_subjects=6, per_subject=2, seed=1)
        feats = enhanced_beer_lambert(ds)
        assert feats.shape == (12, 56) and list(feats.columns) == list(FEATURE_NAMES)
        assert np.isfinite(feats.to_numpy()).all(), preset
    out = enhanced_beer_lambert(small.frame)
    pd.testing.assert_index_equal(out.index, small.frame.index)


def test_reads_measured_columns_only(small):
    frame = small.frame
    base = enhanced_beer_lambert(frame)
    rng = np.random.default_rng(0)
    mutated = frame.copy()
    true_cols = [c for c in frame.columns if c.startswith("true_")]
    assert len(true_cols) > 20
    for c in true_cols:
        if pd.api.types.is_numeric_dtype(mutated[c]):
            mutated[c] = rng.normal(size=len(mutated)) * 1e3
        else:
            mutated[c] = "changed"
    mutated["glucose_mgdl"] = 1.0
    pd.testing.assert_frame_equal(enhanced_beer_lambert(mutated), base)
    only = frame[measured_columns()]
    pd.testing.assert_frame_equal(enhanced_beer_lambert(only), base)


def test_column_layout_does_not_matter(small):
    X = small.frame[measured_columns()].to_numpy(float)
    c = ebl_feature_matrix(np.ascontiguousarray(X))
    f = ebl_feature_matrix(np.asfortranarray(X))
    np.testing.assert_array_equal(c, f)
    np.testing.assert_array_equal(c, enhanced_beer_lambert(small).to_numpy())


def test_bad_input_raises_clearly(small):
    frame = small.frame.copy()
    with pytest.raises(DataError, match="reference codes for some LEDs only.*adc_ref_940"):
        enhanced_beer_lambert(frame.drop(columns=["adc_ref_940"]))
    with pytest.raises(DataError, match="no ADC columns"):
        enhanced_beer_lambert(frame.drop(columns=measured_columns()[:8]))
    bad = frame.copy()
    bad.loc[1, "heart_rate_bpm"] = 900.0
    with pytest.raises(DataError, match="heart_rate_bpm.*physiological range.*rows 1"):
        enhanced_beer_lambert(bad)
    bad = frame.copy()
    bad.loc[3, "skin_temp_c"] = np.nan
    with pytest.raises(DataError, match="skin_temp_c.*NaN.*rows 3"):
        enhanced_beer_lambert(bad)
    bad = frame.copy()
    bad.loc[2, "adc_1150"] = 0
    with pytest.raises(DataError, match="adc_1150.*outside"):
        enhanced_beer_lambert(bad)
    with pytest.raises(DataError, match="20 measured columns"):
        ebl_feature_matrix(np.ones((3, 7)))
    with pytest.raises(DataError, match="positive"):
        ebl_feature_matrix(_row([-1.0, 2, 3, 4], [-5.0, 6, 7, 8]))


@settings(max_examples=30, deadline=None)
@given(
    codes=st.lists(st.integers(1, 4095), min_size=8, max_size=8),
    gain=st.floats(0.05, 20.0),
    temp=st.floats(25.0, 40.0),
)
def test_common_gain_leaves_features_unchanged(codes, gain, temp):
    """A = log10(I0 / I) sees only the ratio: a gain common to both paths cancels."""
    pmf = list(NOMINAL_PMF)
    pmf[9] = temp
    x = _row(codes[:4], codes[4:], pmf)
    y = x.copy()
    y[0, :8] *= gain
    fx, fy = ebl_feature_matrix(x), ebl_feature_matrix(y)
    assert np.isfinite(fx).all()
    np.testing.assert_allclose(fx, fy, rtol=1e-9, atol=1e-12)


def test_transformer(small):
    t = EnhancedBeerLambertFeatures()
    with pytest.raises(NotFittedError):
        t.transform(small.frame)
    out = t.fit_transform(small.frame)
    np.testing.assert_array_equal(out, enhanced_beer_lambert(small).to_numpy())
    assert list(t.get_feature_names_out()) == list(FEATURE_NAMES)
    assert t.n_features_in_ == 20 and list(t.feature_names_in_) == measured_columns()
    X = small.frame[measured_columns()].to_numpy(float)
    # fitted on the device's frame, an array in its column order is that device
    np.testing.assert_array_equal(t.transform(X), out)
    pipe = make_pipeline(EnhancedBeerLambertFeatures(), StandardScaler()).fit(small.frame)
    assert pipe.transform(X).shape == (len(X), 56)
    # a plain array has no names, so no device: its columns are generic channels
    plain = EnhancedBeerLambertFeatures().fit(X[:, :3])
    assert not hasattr(plain, "feature_names_in_") and plain.schema_.is_plain
    assert list(plain.get_feature_names_out()) == [
        "A_x0", "A_x1", "A_x2", "dA_x1_x0", "dA_x2_x0", "dA_x2_x1", "d2A_x1",
        "A_x0_x_A_x0", "A_x0_x_A_x1", "A_x0_x_A_x2", "A_x1_x_A_x1", "A_x1_x_A_x2",
        "A_x2_x_A_x2",
    ]  # fmt: skip
    with pytest.raises(ValueError, match="NaN"):
        t.transform(np.where(np.eye(len(X), 20, dtype=bool), np.nan, X))


@sklearn_checks([EnhancedBeerLambertFeatures()], EXPECTED_FAILED)
def test_sklearn_checks(estimator, check):
    run_check(check, estimator)


def test_transformer_contract(small):
    """Fitted on a device's frame, arrays in the device's order are read as it."""
    import pickle

    X = small.frame[measured_columns()].to_numpy(float)
    t = EnhancedBeerLambertFeatures()
    assert t.fit(small.frame) is t and t.get_params() == {"adc_bits": None}
    ref = t.transform(X)
    state = dict(vars(t))
    t.transform(X)
    assert vars(t).keys() == state.keys()
    np.testing.assert_array_equal(pickle.loads(pickle.dumps(t)).transform(X), ref)
    perm = np.random.default_rng(0).permutation(len(X))
    np.testing.assert_array_equal(t.transform(X[perm]), ref[perm])
    np.testing.assert_array_equal(t.transform(np.asfortranarray(X)), ref)
    np.testing.assert_array_equal(t.transform(X.tolist()), ref)
    assert t.transform(X.astype(np.float32)).dtype == np.float64
    with pytest.raises(ValueError, match="X has 3 features, but .* expecting 20"):
        t.transform(X[:, :3])
    with pytest.raises(ValueError, match="2D"):
        t.transform(X[0])
    Xb = X.copy()
    Xb[4, 0] = 5000.0
    with pytest.raises(DataError, match="adc_850.*outside 1-4095.*rows 4"):
        t.transform(Xb)
    # the declared resolution widens the valid codes
    t14 = EnhancedBeerLambertFeatures(adc_bits=14).fit(small.frame)
    assert t14.transform(Xb).shape == (len(X), 56)
