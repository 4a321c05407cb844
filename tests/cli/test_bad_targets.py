"""Reference glucose: a blank cell at fit is one line; predicting ignores the column."""

from __future__ import annotations

import numpy as np
import pytest
from cli_helpers import assert_one_line_error

import nirglucose as ng
from nirglucose.exceptions import DataError
from nirglucose.models import SDNN, EnhancedBeerLambert


@pytest.fixture(scope="module")
def frame():
    return ng.simulate("wearable", 12, 3, seed=0).frame


def test_blank_reference_glucose_at_fit_is_one_line(cli, workdir, frame):
    f = frame.copy()
    f.loc[4, "glucose_mgdl"] = np.nan
    f.to_csv("blank.csv", index=False)
    code, _, err = cli("fit", "--model", "ebl", "--data", "blank.csv", "--out", "m.json")
    assert_one_line_error(code, err, contains=["glucose_mgdl", "line 6 (line 1 is the header)"])
    with pytest.raises(DataError, match="Input y contains NaN"):  # scikit-learn's words kept
        EnhancedBeerLambert().fit(f)


@pytest.mark.parametrize("cls", [EnhancedBeerLambert, SDNN])
def test_predict_does_not_read_the_glucose_column(frame, cls):
    kw = {} if cls is EnhancedBeerLambert else {"max_epochs": 3, "random_state": 0}
    m = cls(**kw).fit(frame)
    blank = frame.assign(glucose_mgdl=np.nan)
    np.testing.assert_array_equal(m.predict(blank), m.predict(frame))
