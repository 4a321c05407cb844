"""The oracle reads its ADC codes through the schema boundary, like every model (issue 22)."""

from __future__ import annotations

import pytest

import nirglucose as ng
from nirglucose.exceptions import DataError
from nirglucose.models.registry import make_model


@pytest.fixture(scope="module")
def data():
    return ng.simulate("paper", n_subjects=8, per_subject=2, seed=0)


def _error(model, ds):
    with pytest.raises(DataError) as info:
        model.predict(ds)
    return str(info.value)


@pytest.mark.parametrize(("column", "value"), [("adc_940", 0), ("adc_ref_1050", 70000),
                                               ("adc_850", float("nan"))])
def test_oracle_errors_are_the_schema_errors(data, column, value):
    oracle = make_model("oracle").fit(data)
    ebl = make_model("ebl").fit(data)
    frame = data.frame.copy()
    frame[column] = frame[column].astype(float)
    frame.loc[3, column] = value
    bad = ng.Dataset(frame, config=data.config, seed=data.seed)
    message = _error(oracle, bad)
    assert message == _error(ebl, bad)
    assert column in message and "\n" not in message
