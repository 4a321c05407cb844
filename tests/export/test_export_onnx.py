"""``export-onnx`` (issue 28): every model with an ONNX path, run by onnxruntime, predicts
what Python predicts, flags unusable codes, and writes the same bytes twice."""

from __future__ import annotations

import json

import numpy as np
import pytest

import nirglucose as ng
from nirglucose.cli import main
from nirglucose.export.onnx_export import NO_ONNX_PATH, ONNX_MODELS
from nirglucose.models import make_model
from nirglucose.models.registry import MODELS

ort = pytest.importorskip("onnxruntime")
onnx = pytest.importorskip("onnx")

#: Short fits: the graph, not the accuracy, is under test.
FAST = {name: {"max_epochs": 5, "random_state": 0} for name in ONNX_MODELS
        if name not in ("ebl", "gp", "pls", "mean", "ebl+gp", "gbr")}
FAST["gbr"] = {"n_estimators": 60, "subsample": 0.8, "random_state": 0}


@pytest.fixture(scope="module")
def data():
    return ng.simulate("wearable", 20, 2, seed=0)


def test_every_registered_model_has_an_onnx_path_or_a_reason():
    assert set(ONNX_MODELS) | set(NO_ONNX_PATH) == set(MODELS)
    assert not set(ONNX_MODELS) & set(NO_ONNX_PATH)


@pytest.mark.parametrize("name", ONNX_MODELS)
def test_onnx_predicts_what_python_predicts(name, data, tmp_path, capsys):
    model = make_model(name, **FAST.get(name, {})).fit(data)
    model.save(tmp_path / "model.json")
    out = tmp_path / "model.onnx"
    assert main(["export-onnx", "--model", str(tmp_path / "model.json"), "--out", str(out)]) == 0
    assert "wrote" in capsys.readouterr().out
    session = ort.InferenceSession(str(out))
    raw = data.frame[list(model.schema_.raw_columns)].to_numpy(np.float32)
    glucose, status = session.run(None, {"raw": raw})
    np.testing.assert_allclose(glucose, model.predict(data), atol=0.05)
    assert status.dtype == np.int32 and not status.any()
    meta = {p.key: p.value for p in onnx.load(str(out)).metadata_props}
    assert json.loads(meta["raw_columns"]) == list(model.schema_.raw_columns)
    assert meta["adc_bits"] == str(model.schema_.adc_bits) and meta["nirglucose_model"] == name
    # a code of 0 or above full scale is flagged, never silently used
    bad = raw[:3].copy()
    bad[0, 0], bad[1, 0] = 0.0, 2.0**model.schema_.adc_bits
    assert session.run(None, {"raw": bad})[1].tolist() == [1, 1, 0]
    # the same model writes the same bytes
    again = tmp_path / "again.onnx"
    assert main(["export-onnx", "--model", str(tmp_path / "model.json"), "--out", str(again)]) == 0
    assert again.read_bytes() == out.read_bytes()


@pytest.mark.parametrize("name", ["oracle", "physics-inversion"])
def test_a_model_without_an_onnx_path_is_one_line_exit_2(name, data, tmp_path, capsys):
    params = {"n_em": 2} if name == "physics-inversion" else {}
    make_model(name, **params).fit(data).save(tmp_path / "model.json")
    code = main(["export-onnx", "--model", str(tmp_path / "model.json"),
                 "--out", str(tmp_path / "m.onnx")])
    err = capsys.readouterr().err.strip()
    assert code == 2 and "\n" not in err and "cannot be exported to ONNX" in err, err
    assert NO_ONNX_PATH[name].split(":")[0].split(" (")[0] in err
    assert not (tmp_path / "m.onnx").exists()


@pytest.mark.parametrize("device", ["paper", "three-led-10-bit"])
def test_ebl_features_in_onnx_follow_any_device(device, tmp_path):
    """The physics features in the graph are the device's own (PPG columns on `paper`,
    three LEDs and no reference codes below)."""
    from nirglucose.export.onnx_export import onnx_graph_bytes

    if device == "paper":
        ds = ng.simulate("paper", 20, 2, seed=1)
    else:
        led = {"fwhm_nm": 40, "power_mw": 3, "responsivity_a_per_w": 0.5}
        ds = ng.simulate("wearable", 20, 2, seed=1, overrides={
            "leds": [{"wavelength_nm": w, **led} for w in (850, 940, 1150)],
            "hardware.adc_bits": 10})
    model = make_model("ebl").fit(ds)
    session = ort.InferenceSession(onnx_graph_bytes(model))
    raw = ds.frame[list(model.schema_.raw_columns)].to_numpy(np.float32)
    np.testing.assert_allclose(session.run(None, {"raw": raw})[0], model.predict(ds), atol=0.05)


def test_gbr_trees_in_onnx_decide_every_split_as_python(tmp_path):
    """Inputs exactly at (the float32 neighbours of) every split threshold go the same way
    in onnxruntime's float32 tree ensemble as in the model's float64 comparison."""
    from nirglucose.export.onnx_export import _tree_ensemble

    ds = ng.simulate("wearable", 20, 2, seed=2)
    model = make_model("gbr", n_estimators=30, random_state=0).fit(ds)
    node, out = _tree_ensemble(model, onnx)
    p = model.whitening_.shape[0]
    graph = onnx.helper.make_graph(
        [node], "trees",
        [onnx.helper.make_tensor_value_info("tree_inputs", onnx.TensorProto.FLOAT, ["n", p])],
        [out])
    proto = onnx.helper.make_model(graph, opset_imports=[
        onnx.helper.make_opsetid("", 17), onnx.helper.make_opsetid("ai.onnx.ml", 3)],
        ir_version=8)  # what onnxruntime 1.16 and later read
    session = ort.InferenceSession(proto.SerializeToString())
    internal = model.left_ >= 0
    thr = model.threshold_[internal].astype(np.float32)
    feat = model.feature_[internal].astype(int)
    rng = np.random.default_rng(0)
    u = rng.normal(size=(3 * len(thr), p)).astype(np.float32)
    for k, step in enumerate((-np.inf, 0.0, np.inf)):  # below, at and above each threshold
        rows = np.arange(len(thr)) + k * len(thr)
        u[rows, feat] = thr if step == 0.0 else np.nextafter(thr, np.float32(step))
    expect = _python_trees(model, u.astype(np.float64))
    got = session.run(None, {"tree_inputs": u})[0].ravel()
    np.testing.assert_allclose(got, expect, atol=1e-3)


def _python_trees(model, u):
    """The model's own tree walk (GBRReference.predict after its inputs)."""
    out = np.full(len(u), model.init_)
    for t in range(model.value_.shape[0]):
        node = np.zeros(len(u), dtype=int)
        for _ in range(model.depth_):
            left = model.left_[t, node].astype(int)
            x = u[np.arange(len(u)), model.feature_[t, node].astype(int)]
            nxt = np.where(x <= model.threshold_[t, node], left, model.right_[t, node])
            node = np.where(left < 0, node, nxt).astype(int)
        out += model.value_[t, node]
    return out

# Long-running (whole studies, end-to-end runs, Monte Carlo or every model): `make test-slow`,
# which CI runs beside the fast `make test` (tests/test_slow_marks.py)
pytestmark = pytest.mark.slow
