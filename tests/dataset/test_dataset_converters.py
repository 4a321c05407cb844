"""Issue 43: per-channel converters in the schema and model files, backward compatible."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import nirglucose as ng
from nirglucose.dataset.adc import check_headroom, parse_channel_spec
from nirglucose.dataset.schema import DeviceSchema
from nirglucose.exceptions import DataError
from real_files import two_converter_frame


@pytest.fixture
def two(tmp_path):
    path = tmp_path / "two.csv"
    two_converter_frame().to_csv(path, index=False)
    return path


def test_each_channel_reads_its_own_full_scale(two):
    ds = ng.load_dataset(two, adc_bits={"adc_940": 10, "adc_1050": 18})
    s = DeviceSchema.infer(ds)
    assert s.channel_bits == (10, 18) and s.full_scales == (1023.0, 262143.0)
    a = s.measurements(ds).absorbance
    f = ds.frame
    np.testing.assert_allclose(a[:, 0], np.log10(1023.0 / f["adc_940"]))
    np.testing.assert_allclose(a[:, 1], np.log10(262143.0 / f["adc_1050"]))
    # a declared full scale other than 2^bits - 1 (an AC-coupled or trimmed converter)
    s2 = DeviceSchema.infer(ds, adc_full_scale={"adc_1050": 200000})
    np.testing.assert_allclose(s2.measurements(ds).absorbance[:, 1],
                               np.log10(200000.0 / f["adc_1050"]))


def test_a_python_model_takes_a_mapping_and_its_file_keeps_it(two, tmp_path):
    ds = ng.load_dataset(two)
    model = ng.models.make_model("pls", adc_bits={"adc_940": 10, "adc_1050": 18}).fit(ds)
    assert model.schema_.channel_bits == (10, 18)
    model.save(tmp_path / "m.json")
    back = ng.models.load_model(tmp_path / "m.json")
    assert back.schema_ == model.schema_ and back.schema_.channel_bits == (10, 18)
    np.testing.assert_allclose(back.predict(ds), model.predict(ds))


def test_a_model_file_written_before_issue_43_still_loads():
    s = DeviceSchema((940.0,), reference=False, adc_bits=10, physiology=())
    old = {k: v for k, v in s.to_json().items()
           if k not in ("channel_bits", "channel_full_scale", "glucose_unit", "train_rows",
                        "train_rows_every", "train_row_ids")}
    back = DeviceSchema.from_json(old)
    assert back == s and not back.per_channel and back.glucose_unit == "mg/dL"
    assert back.full_scales == (1023.0,)


def test_codes_under_a_quarter_of_the_declared_scale_warn_once():
    import pandas as pd

    f = pd.DataFrame({"adc_940": [500.0, 1000.0], "adc_1050": [150000.0, 160000.0]})
    with pytest.warns(UserWarning, match="under a quarter") as caught:
        check_headroom(f, ("adc_940", "adc_1050"), (262143.0, 262143.0), (18, 18))
    assert len(caught) == 1 and "'adc_940'" in str(caught[0].message)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        check_headroom(f, ("adc_940", "adc_1050"), (1023.0, 262143.0), (10, 18))


@pytest.mark.parametrize(("text", "match"), [
    ("adc_940=10,adc_940=12", "twice"), ("adc_ref_940=10", "name an LED"), ("", "names nothing"),
])
def test_bad_channel_specs_are_refused(text, match):
    with pytest.raises(DataError, match=match):
        parse_channel_spec(text)


def test_full_scale_above_the_converter_is_refused(two):
    ds = ng.load_dataset(two, adc_bits={"adc_940": 10, "adc_1050": 18})
    with pytest.raises(DataError, match="from 1 to 1023"):
        DeviceSchema.infer(ds, adc_full_scale={"adc_940": 5000})
