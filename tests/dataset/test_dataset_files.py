"""Reading real files (nirglucose.dataset.files), the ADC-resolution policy and the
small-data policy, at the Python level (issue 28)."""

from __future__ import annotations

import warnings

import numpy as np
import pandas as pd
import pytest

import nirglucose as ng
from nirglucose.constants import MGDL_PER_MMOLL_GLUCOSE
from nirglucose.dataset.adc import resolve_adc_bits
from nirglucose.dataset.files import canonical_columns, sniff_csv
from nirglucose.dataset.small_data import MIN_SIGNIFICANCE_SUBJECTS, significance_withheld
from nirglucose.exceptions import DataError
from nirglucose.metrics import clarke_zones, rmse
from nirglucose.metrics.iso15197 import iso15197_2013_passes


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        ("a,b,c\n1,2.5,3\n", (",", ".")),
        ("a;b;c\n1;2,5;3\n", (";", ",")),
        ("a;b;c\n1;2.5;3\n", (";", ".")),
        ("a\tb\tc\n1\t2,5\t3\n", ("\t", ",")),
        ("a,b\n", (",", ".")),
    ],
)
def test_sniff_delimiter_and_decimal(text, expected):
    assert sniff_csv(text) == expected


def test_headers_are_case_folded_and_stripped_with_a_note_each():
    renames, notes = canonical_columns(["ADC_940", " adc_ref_940 ", "Glucose_mgdl", "Cohort",
                                        "Age_Yr"])
    assert renames == {"ADC_940": "adc_940", " adc_ref_940 ": "adc_ref_940",
                       "Glucose_mgdl": "glucose_mgdl", "Age_Yr": "age_yr"}
    assert len(notes) == 4 and "'ADC_940' as 'adc_940'" in notes[0]
    with pytest.raises(DataError, match="'ADC_940' and 'adc_940' both read as 'adc_940'"):
        canonical_columns(["ADC_940", "adc_940"])


def _frame(glucose, name="glucose_mmoll"):
    n = len(glucose)
    return pd.DataFrame({"subject_id": np.arange(n), name: glucose,
                         "adc_940": np.linspace(500.5, 700.25, n)})


def test_mmoll_column_converted_with_the_package_constant(tmp_path):
    path = tmp_path / "x.csv"
    _frame([5.0, 10.0, 20.0]).to_csv(path, index=False)
    ds = ng.load_dataset(path)
    np.testing.assert_allclose(ds.frame["glucose_mgdl"], np.array([5, 10, 20]) * 18.016)
    assert MGDL_PER_MMOLL_GLUCOSE == 18.016
    assert any("mmol/L" in n for n in ds.metadata["read_notes"])


def test_declared_unit_and_the_unit_guesses(tmp_path):
    path = tmp_path / "x.csv"
    _frame([20.0, 25.0, 33.0], "glucose_mgdl").to_csv(path, index=False)
    with pytest.raises(DataError, match="looks like mmol/L.*glucose_unit='mmol/L'"):
        ng.load_dataset(path)
    ds = ng.load_dataset(path, glucose_unit="mmol/L")
    assert ds.frame["glucose_mgdl"].max() == pytest.approx(33 * 18.016)
    _frame([90.0, 150.0, 200.0], "glucose_mgdl").to_csv(path, index=False)
    with pytest.raises(DataError, match="declared mmol/L but looks like mg/dL"):
        ng.load_dataset(path, glucose_unit="mmol/L")
    with pytest.raises(DataError, match="unknown glucose unit 'mg/dl'; valid: mg/dL, mmol/L"):
        ng.load_dataset(path, glucose_unit="mg/dl")


def test_parquet_rows_are_numbered_from_one(tmp_path):
    path = tmp_path / "x.parquet"
    f = _frame([90.0, 150.0, 200.0], "glucose_mgdl")
    f.loc[2, "adc_940"] = np.inf
    f.to_parquet(path)
    with pytest.raises(DataError, match=r"infinite values at row 3 \(first row = 1\)"):
        ng.load_dataset(path)


def test_adc_policy():
    low = pd.DataFrame({"adc_940": [500.5, 1000.0]})
    with pytest.raises(DataError, match="10-, 12-, 14- or 16-bit"):
        resolve_adc_bits(low)
    assert resolve_adc_bits(low, metadata_bits=10) == (10, "metadata")
    assert resolve_adc_bits(low, declared=14, metadata_bits=10) == (14, "declared")
    with pytest.warns(UserWarning, match="assuming 12 bits"):
        assert resolve_adc_bits(pd.DataFrame({"adc_940": [2000.0]})) == (12, "assumed")
    with pytest.raises(DataError, match="from 1 to 32"):
        resolve_adc_bits(low, declared=0)


def test_load_dataset_records_a_declared_resolution(tmp_path):
    path = tmp_path / "x.csv"
    _frame([5.0, 10.0, 20.0, 7.0, 12.0, 9.0]).to_csv(path, index=False)
    ds = ng.load_dataset(path, adc_bits=10)
    assert ds.metadata["adc_bits"] == 10
    from nirglucose.models import make_model

    m = make_model("pls").fit(ng.load_dataset(path, adc_bits=10))
    assert m.schema_.adc_bits == 10 and m.schema_.train_max[0] == pytest.approx(700.25)


def test_significance_policy():
    assert significance_withheld(MIN_SIGNIFICANCE_SUBJECTS) is None
    assert "only 9 test subjects" in significance_withheld(MIN_SIGNIFICANCE_SUBJECTS - 1)


def test_metrics_bad_inputs_are_said():
    assert rmse([1e200, 2e200], [1.5e200, 1e200]) == pytest.approx(np.sqrt(0.625) * 1e200)
    with pytest.warns(UserWarning, match="looks like mmol/L"):
        clarke_zones([5.0, 8.0, 12.0], [6.0, 8.0, 11.0])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        clarke_zones([5.0, 8.0, 12.0], [6.0, 8.0, 11.0], units="mmol/L")
    with pytest.warns(UserWarning, match="at least 600 results"):
        assert iso15197_2013_passes([80, 200], [90, 220])


def test_an_leds_wavelength_is_read_however_it_is_spelled(tmp_path):
    frame = ng.simulate("paper", n_subjects=6, per_subject=2, seed=0).frame
    path = tmp_path / "spelled.csv"
    frame.rename(columns={"adc_850": "ADC_0850", "adc_ref_850": "adc_ref_850.0"}).to_csv(
        path, index=False)
    ds = ng.load_dataset(path)
    assert {"adc_850", "adc_ref_850"} <= set(ds.frame.columns)
    assert "read column 'ADC_0850' as 'adc_850'" in ds.metadata["read_notes"]
    with pytest.raises(DataError, match="the same LED|both read as 'adc_850'"):
        canonical_columns(["adc_850", "adc_850.0"])


def test_a_header_given_twice_is_refused_not_renamed(tmp_path):
    """pandas would read a repeated adc_940 as adc_940.1, a 940.1 nm LED: refused."""
    frame = ng.simulate("paper", n_subjects=6, per_subject=2, seed=0).frame
    cols = ["subject_id", "glucose_mgdl", "adc_850", "adc_940", "age_yr"]
    path = tmp_path / "twice.csv"
    frame[cols + ["adc_940"]].to_csv(path, index=False)
    with pytest.raises(DataError, match="column 'adc_940' appears 2 times in the header"):
        ng.load_dataset(path, adc_bits=12)
    with pytest.raises(DataError, match="column 'adc_940' appears 2 times; keep one"):
        ng.Dataset(frame[cols + ["adc_940"]])
    for bad in (None, [1, 2, 3]):
        with pytest.raises(DataError, match="expected a pandas DataFrame"):
            ng.Dataset(bad)
    with pytest.raises(DataError, match="do not fit a dataset of 12 rows"):
        ng.Dataset(frame).rows([100])


def test_reference_glucose_of_zero_or_below_is_refused_as_such(tmp_path):
    frame = ng.simulate("paper", n_subjects=6, per_subject=2, seed=0).frame
    path = tmp_path / "neg.csv"
    frame.assign(glucose_mgdl=-50.0).to_csv(path, index=False)
    with pytest.raises(DataError, match="values of 0 or below at lines 2, 3, 4"):
        ng.load_dataset(path)
