"""Model files that parse but would predict nonsense are refused in one line (issue 20)."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest
from cli_helpers import assert_one_line_error, listing

import nirglucose as ng
from nirglucose.exceptions import DataError
from nirglucose.models import load_model
from nirglucose.models.sdnn import SDNN


@pytest.fixture(scope="module")
def fitted(tmp_path_factory):
    d = tmp_path_factory.mktemp("models")
    ds = ng.simulate("paper", 12, 3, seed=0)
    ds.save(d / "d.parquet")
    for name in ("ebl", "pls", "oracle"):
        ng.models.make_model(name).fit(ds).save(d / f"{name}.json")
    SDNN(max_epochs=2, random_state=0).fit(ds).save(d / "sdnn.json")
    return d


def _edit(src, dst, fn):
    doc = json.loads(src.read_text())
    fn(doc)
    dst.write_text(json.dumps(doc))  # json writes NaN / Infinity literals, as a forger could


def _set(path, value):
    def fn(doc):
        node = doc
        for k in path[:-1]:
            node = node[k]
        node[path[-1]] = value(node[path[-1]]) if callable(value) else value

    return fn


CASES = {
    "ebl-nan-coef": ("ebl", _set(["state", "coef_"], lambda v: [float("nan")] + v[1:])),
    "ebl-huge-coef": ("ebl", _set(["state", "coef_"], lambda v: [1e308] + v[1:])),
    "ebl-zero-scale": ("ebl", _set(["state", "scaler_scale_"], lambda v: [0.0] + v[1:])),
    "ebl-negative-scale": ("ebl", _set(["state", "scaler_scale_"], lambda v: [-1.0] + v[1:])),
    "ebl-short-coef": ("ebl", _set(["state", "coef_"], lambda v: v[:-1])),
    "ebl-text-coef": ("ebl", _set(["state", "coef_"], "abc")),
    "ebl-dict-intercept": ("ebl", _set(["state", "intercept_"], {"a": 1})),
    "ebl-inf-intercept": ("ebl", _set(["state", "intercept_"], float("inf"))),
    "ebl-params-list": ("ebl", _set(["params"], [1])),
    "pls-nan-mean": ("pls", _set(["state", "x_mean_"], lambda v: [float("nan")] + v[1:])),
    "pls-long-coef": ("pls", _set(["state", "coef_"], lambda v: v + [1.0])),
    "oracle-zero-var": ("oracle", _set(["state", "prior_var_"], 0.0)),
    "sdnn-zero-y-scale": ("sdnn", _set(["scaler", "y_scale"], 0.0)),
    "sdnn-huge-y-scale": ("sdnn", _set(["scaler", "y_scale"], 1e300)),
    "sdnn-nan-y-mean": ("sdnn", _set(["scaler", "y_mean"], float("nan"))),
    "sdnn-scale-list": ("sdnn", _set(["scaler", "y_scale"], [1.0, 2.0])),
    "sdnn-short-nir-scale": ("sdnn", _set(["scaler", "nir_scale"], lambda v: v[:-1])),
    "sdnn-zero-nir-scale": ("sdnn", _set(["scaler", "nir_scale"], lambda v: [0.0] + v[1:])),
    "sdnn-scaler-list": ("sdnn", _set(["scaler"], [1, 2])),
    "sdnn-params-text": ("sdnn", _set(["params"], "x")),
}


@pytest.mark.parametrize("case", list(CASES))
def test_corrupt_model_refused(cli, fitted, tmp_path, case):
    name, fn = CASES[case]
    bad = tmp_path / f"{name}.json"
    _edit(fitted / f"{name}.json", bad, fn)
    if name == "sdnn":  # the weights file travels beside the document
        weights = json.loads((fitted / "sdnn.json").read_text())["weights_file"]
        (tmp_path / weights).write_bytes((fitted / weights).read_bytes())
    with pytest.raises(DataError):
        load_model(bad)
    before = listing(tmp_path)
    code, _, err = cli("predict", "--model", bad, "--data", fitted / "d.parquet",
                       "--out", tmp_path / "p.csv")
    assert_one_line_error(code, err)
    assert listing(tmp_path) == before


def test_nan_weights_refused(cli, fitted, tmp_path):
    from safetensors.torch import load_file, save_file

    doc = json.loads((fitted / "sdnn.json").read_text())
    tensors = load_file(str(fitted / doc["weights_file"]))
    key = sorted(tensors)[0]
    tensors[key] = tensors[key].clone().fill_(float("nan"))
    save_file(tensors, str(tmp_path / doc["weights_file"]))
    (tmp_path / "sdnn.json").write_text(json.dumps(doc))
    code, _, err = cli("predict", "--model", tmp_path / "sdnn.json",
                       "--data", fitted / "d.parquet", "--out", tmp_path / "p.csv")
    assert_one_line_error(code, err, contains=["NaN"])
    assert not (tmp_path / "p.csv").exists()


@pytest.mark.parametrize("name", ["ebl", "pls", "oracle", "sdnn"])
def test_intact_models_still_predict(cli, fitted, tmp_path, name):
    code, _, err = cli("predict", "--model", fitted / f"{name}.json",
                       "--data", fitted / "d.parquet", "--out", tmp_path / "p.csv")
    assert code == 0, err
    pred = pd.read_csv(tmp_path / "p.csv")["predicted_glucose_mgdl"].to_numpy()
    assert np.isfinite(pred).all()
