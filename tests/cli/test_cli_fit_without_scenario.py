"""Issue 39: ``fit --data my.csv`` on a file without a scenario. The privileged models
refuse it in one line naming the deployable one; ``device-inversion`` fits it, and the
same model as from the simulator's Parquet file (which carries the scenario)."""

from __future__ import annotations

import numpy as np
import pytest
from cli_helpers import assert_one_line_error

import nirglucose as ng
from nirglucose.models import load_model


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    root = tmp_path_factory.mktemp("no-scenario")
    ds = ng.simulate("paper", 16, 3, seed=4)
    return ds, ds.save(root / "x.csv"), ds.save(root / "x.parquet")


def _fit(cli, name, data, out, *extra):
    return cli("fit", "--model", name, "--data", data, "--out", out, "--cv-folds", "0",
               "--intervals", "none", *extra)


@pytest.mark.parametrize("name", ["physics-inversion", "physics-inversion+gp",
                                  "original-pinn-fm"])
def test_privileged_models_refuse_a_csv_in_one_line(cli, files, tmp_path, name):
    _, csv, _ = files
    out = tmp_path / "m.json"
    code, _, err = _fit(cli, name, csv, out, "--adc-bits", "12")
    assert_one_line_error(code, err, contains=("generating scenario", "'device-inversion'"))
    assert not out.exists()


def test_device_inversion_fits_the_csv_as_the_parquet(cli, files, tmp_path):
    ds, csv, parquet = files
    code, out, err = _fit(cli, "device-inversion", csv, tmp_path / "csv.json", "--adc-bits", "12")
    assert code == 0, err
    assert "fitted 'device-inversion'" in out
    code, _, err = _fit(cli, "device-inversion", parquet, tmp_path / "pq.json")
    assert code == 0, err
    from_csv, from_parquet = load_model(tmp_path / "csv.json"), load_model(tmp_path / "pq.json")
    np.testing.assert_array_equal(from_csv.predict(ds), from_parquet.predict(ds))
    assert (tmp_path / "csv.json").read_bytes() == (tmp_path / "pq.json").read_bytes()

# Long-running (whole studies, end-to-end runs, Monte Carlo or every model): `make test-slow`,
# which CI runs beside the fast `make test` (tests/test_slow_marks.py)
pytestmark = pytest.mark.slow
