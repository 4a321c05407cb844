"""Export a fitted model as an ONNX graph, for any runtime beyond a microcontroller.

:func:`export_onnx` writes one ``.onnx`` file whose graph takes the device's raw columns
and returns glucose, with nothing to compute outside it:

* input ``raw``: float32 ``(n, width)``, the columns of the device the model was fitted
  on in ``schema.raw_columns`` order (ADC codes, then reference codes where the device
  has them, then the physiological columns; the file's metadata lists them);
* output ``glucose_mgdl``: float32 ``(n,)``;
* output ``status``: int32 ``(n,)``, 0 for a reading the model can use, 1 for a code
  outside (0, full scale] (its glucose is then meaningless, never silently used: a
  caller reads the status).

The graph is the model's own prediction written in torch and traced once by
:func:`torch.onnx.export`: decadic absorbances ``log10(I0 / I)`` from the codes (the
ADC's full scale as ``I0`` for a device without reference codes), the model's
standardisation, then its network (the torch networks), its physics features and ridge
coefficients (``ebl``: :func:`_features_torch`, the twin of
:func:`nirglucose.features.compute_features`), its Gaussian-process posterior mean
(``gp``), its folded linear map (``pls``), its constant (``mean``), or EBL then the GP
on EBL's residual stacked with their learned weights (``ebl+gp``). Float32
throughout; the tests hold it to the Python prediction within 0.05 mg/dL.

Gradient boosting (``gbr``): the traced part computes the trees' inputs (absorbances,
physiology, the whitening) in float64 as :meth:`GBRReference.predict` does, then casts
them to float32 as scikit-learn's trees do; the trees themselves are one ONNX-ML
``TreeEnsembleRegressor`` node (:func:`_tree_ensemble`, built with ``onnx.helper`` from
the model's node arrays: ``BRANCH_LEQ`` splits, summed leaf values plus ``init_``).

Models without an ONNX path (:data:`NO_ONNX_PATH` says why): the oracle (it reads the
truth), the forward-model estimators (privileged and deployable) and the hybrid.

Needs the optional packages ``onnx`` (and ``onnxruntime`` to run the file):
``pip install "nirglucose[onnx]"``.
"""

from __future__ import annotations

import io
import json
import math
import os
import warnings
from pathlib import Path
from typing import Any

import numpy as np

from ..dataset import atomic_write
from ..exceptions import ConfigError, DataError
from ..features.blocks import (
    _ENV,
    NOMINAL_BLOOD_PCT,
    PERFUSION_COEFFS,
    PRESSURE_CENTER_MBAR,
    SKIN_TEMP_CENTER_C,
)
from ..models.registry import model_from

__all__ = ["ONNX_MODELS", "NO_ONNX_PATH", "OPSET", "ML_OPSET", "export_onnx", "onnx_graph_bytes"]

#: ONNX operator set of the exported graphs (onnxruntime 1.16 and later run it).
OPSET = 17
#: Registered models with an ONNX path.
ONNX_MODELS = ("ebl", "sdnn", "original-pinn", "optimized-pinn", "rte-pinn",
               "selective-rte-pinn", "original-pinn-fm", "optimized-pinn-fm", "rte-pinn-fm",
               "selective-rte-pinn-fm", "gp", "pls", "mean", "ebl+gp", "gbr")
#: Operator-set version of the ONNX-ML domain (``TreeEnsembleRegressor``) for ``gbr``.
ML_OPSET = 3
#: Registered models without one, and why.
NO_ONNX_PATH = {
    "oracle": "it reads the simulation's truth, which no device has",
    "physics-inversion": "an iterative solver per reading (Levenberg-Marquardt), not a "
                         "fixed graph",
    "physics-inversion+gp": "its physics-inversion backbone has no ONNX path",
    "device-inversion": "an iterative solver per reading (Levenberg-Marquardt), not a "
                        "fixed graph",
}


def _torch():
    import torch  # heavy: only an export needs it

    return torch


def _absorbance_and_physiology(torch, schema, raw):
    """Torch twin of :meth:`nirglucose.dataset.schema.DeviceSchema.split` plus the status."""
    k = schema.n_channels
    full = torch.tensor(schema.full_scales, dtype=raw.dtype)  # per channel (issue 43)
    adc = raw[:, :k]
    if schema.reference:
        ref, start = raw[:, k : 2 * k], 2 * k
        codes, top = torch.cat([adc, ref], dim=1), torch.cat([full, full])
    else:
        ref, start = torch.zeros_like(adc) + full, k
        codes, top = adc, full
    bad = ((codes <= 0) | (codes > top)).any(dim=1)
    a = (torch.log(ref) - torch.log(adc)) / math.log(10.0)
    return a, raw[:, start:], bad.to(torch.int32)


def _standardise(torch, x, mean, scale):
    return (x - torch.as_tensor(np.asarray(mean), dtype=torch.float32)) / torch.as_tensor(
        np.asarray(scale), dtype=torch.float32)


def _features_torch(torch, table, schema, A, P):
    """Torch twin of :func:`nirglucose.features.compute_features`: (n, p) features from
    absorbances ``A`` (n, k) and physiology ``P`` (n, m), one column per table row."""
    col = {c: P[:, m] for m, c in enumerate(schema.physiology)}
    env = {s: (col[c] - c0) / sc for s, (c, c0, sc) in _ENV.items() if c in col}
    pc = PERFUSION_COEFFS
    if "blood_volume_pct" in col:
        perf = col["blood_volume_pct"] / NOMINAL_BLOOD_PCT
    elif {"skin_temp_c", "systolic_bp_mmhg", "pressure_mbar"} <= set(col):
        perf = torch.exp(pc["temp"] * (col["skin_temp_c"] - SKIN_TEMP_CENTER_C)
                         + pc["sbp"] * (col["systolic_bp_mmhg"] - pc["sbp_center"])
                         + pc["pressure"] * (col["pressure_mbar"] - PRESSURE_CENTER_MBAR))
    ops = {
        "A": lambda op: A[:, op[1]],
        "lin": lambda op: sum(w * A[:, c] for c, w in op[1]),
        "AA": lambda op: A[:, op[1]] * A[:, op[2]],
        "w": lambda op: (op[2] * col["skin_thickness_mm"] + op[3] * perf
                         + op[4] * col["melanin_fraction"]) * A[:, op[1]],
        "envA": lambda op: env[op[1]] * A[:, op[2]],
        "pmf": lambda op: P[:, op[1]],
        "env2": lambda op: env[op[1]] * env[op[2]],
    }
    return torch.stack([ops[spec.op[0]](spec.op) for spec in table], dim=1)


def _linear(torch, z, coef, intercept):
    return z @ torch.as_tensor(np.asarray(coef), dtype=torch.float32) + float(intercept)


def _gp_mean(torch, gp, u):
    """Posterior mean of a fitted :class:`~nirglucose.models.reference.GPReference` at
    inputs ``u`` (n, p), as its ``predict`` computes it."""
    f32 = torch.float32
    z = _standardise(torch, u, gp.x_mean_, gp.x_scale_ * gp.length_scales_)
    t = torch.as_tensor(gp.X_train_ / gp.length_scales_, dtype=f32)
    d2 = (z * z).sum(1, keepdim=True) + (t * t).sum(1)[None, :] - 2.0 * z @ t.T
    k = float(gp.signal_variance_) * torch.exp(-0.5 * torch.clamp(d2, min=0.0))
    return (k @ torch.as_tensor(gp.alpha_, dtype=f32)) * float(gp.y_std_) + float(gp.y_mean_)


def _network(torch, model, net, a, pmf):
    s = model.scaler_
    if pmf.shape[1] == 0:
        pmf = torch.zeros_like(a[:, :1])
    out = net(_standardise(torch, a, s["nir_mean"], s["nir_scale"]),
              _standardise(torch, pmf, s["pmf_mean"], s["pmf_scale"]))
    out = out[0] if isinstance(out, tuple) else out
    return out.reshape(-1) * float(s["y_scale"]) + float(s["y_mean"])


def _glucose_torch(torch, model, a, pmf):
    """``model``'s glucose from absorbances and physiology, in torch (one per family)."""
    name = model.registry_name
    if name == "mean":
        return torch.zeros_like(a[:, 0]) + float(model.mean_)
    if name == "ebl":
        return _linear(torch, _features_torch(torch, model.table_, model.schema_, a, pmf),
                       model.coef_, model.intercept_)
    if name == "pls":
        return _linear(torch, torch.cat([a, pmf], dim=1), model.coef_, model.intercept_)
    if name == "gp":
        return _gp_mean(torch, model, torch.cat([a, pmf], dim=1))
    if name == "ebl+gp":  # the stack of the backbone and the GP on [inputs, backbone]
        base = _glucose_torch(torch, model.backbone_, a, pmf)
        gp = _gp_mean(torch, model.residual_, torch.cat([a, pmf, base[:, None]], 1))
        y_mean, weight = float(model.y_mean_), float(model.backbone_weight_)
        return y_mean + weight * (base - y_mean) + float(model.shrinkage_) * gp
    return _network(torch, model, model.module_.eval(), a, pmf)


def _tree_inputs(torch, model, raw):
    """``gbr``'s tree inputs from ``raw`` in float64 (its ``predict``), cast to float32."""
    a, pmf, status = _absorbance_and_physiology(torch, model.schema_, raw.double())
    u = torch.cat([a, pmf], dim=1) - torch.as_tensor(model.x_mean_, dtype=torch.float64)
    return (u @ torch.as_tensor(model.whitening_, dtype=torch.float64)).float(), status


def _tree_ensemble(model, onnx) -> tuple[Any, Any]:
    """``(node, output value_info)``: ``gbr``'s trees as one ONNX-ML
    ``TreeEnsembleRegressor`` on ``tree_inputs`` (float32), output ``tree_sum`` (n, 1).

    A split goes left (``BRANCH_LEQ``) when ``input <= threshold``. scikit-learn compares
    a float32 input with a float64 threshold; the node stores float32, so each threshold
    is rounded *down* to the largest float32 not above it, which decides every float32
    input the same way.
    """
    attrs: dict[str, list] = {k: [] for k in (
        "nodes_treeids", "nodes_nodeids", "nodes_featureids", "nodes_values", "nodes_modes",
        "nodes_truenodeids", "nodes_falsenodeids", "target_treeids", "target_nodeids",
        "target_ids", "target_weights")}
    for t in range(model.value_.shape[0]):
        for i in range(int(model.n_nodes_[t])):
            left, right = int(model.left_[t, i]), int(model.right_[t, i])
            leaf = left < 0
            thr = np.float32(model.threshold_[t, i])
            if not leaf and float(thr) > float(model.threshold_[t, i]):
                thr = np.nextafter(thr, np.float32(-np.inf))
            attrs["nodes_treeids"].append(t)
            attrs["nodes_nodeids"].append(i)
            attrs["nodes_featureids"].append(0 if leaf else int(model.feature_[t, i]))
            attrs["nodes_values"].append(0.0 if leaf else float(thr))
            attrs["nodes_modes"].append("LEAF" if leaf else "BRANCH_LEQ")
            attrs["nodes_truenodeids"].append(0 if leaf else left)
            attrs["nodes_falsenodeids"].append(0 if leaf else right)
            if leaf:
                attrs["target_treeids"].append(t)
                attrs["target_nodeids"].append(i)
                attrs["target_ids"].append(0)
                attrs["target_weights"].append(float(model.value_[t, i]))
    node = onnx.helper.make_node(
        "TreeEnsembleRegressor", ["tree_inputs"], ["tree_sum"], domain="ai.onnx.ml",
        n_targets=1, aggregate_function="SUM", post_transform="NONE",
        base_values=[float(model.init_)], **attrs)
    out = onnx.helper.make_tensor_value_info("tree_sum", onnx.TensorProto.FLOAT, ["n", 1])
    return node, out


def _append_trees(proto, model, onnx) -> None:
    """Turn the traced ``raw -> (tree_inputs, status)`` graph into ``raw ->
    (glucose_mgdl, status)`` by appending the tree ensemble and a flatten to (n,)."""
    graph = proto.graph
    tree, _ = _tree_ensemble(model, onnx)
    shape = onnx.helper.make_tensor("glucose_shape", onnx.TensorProto.INT64, [1], [-1])
    graph.initializer.append(shape)
    graph.node.extend([tree, onnx.helper.make_node(
        "Reshape", ["tree_sum", "glucose_shape"], ["glucose_mgdl"])])
    outputs = [o for o in graph.output if o.name != "tree_inputs"]
    del graph.output[:]
    graph.output.extend([onnx.helper.make_tensor_value_info(
        "glucose_mgdl", onnx.TensorProto.FLOAT, ["n"]), *outputs])
    proto.opset_import.append(onnx.helper.make_opsetid("ai.onnx.ml", ML_OPSET))
    onnx.checker.check_model(proto)


def _graph_module(model):
    """A torch module ``raw -> (glucose_mgdl, status)`` equal to ``model.predict``
    (``gbr``: ``raw -> (tree_inputs, status)``, the trees appended after tracing)."""
    torch = _torch()
    schema = model.schema_
    if model.registry_name == "gbr":

        class Inputs(torch.nn.Module):
            def forward(self, raw):
                return _tree_inputs(torch, model, raw)

        return Inputs().eval()

    class Graph(torch.nn.Module):
        def __init__(self):
            super().__init__()
            self.net = getattr(model, "module_", None)  # registered: traced as a submodule

        def forward(self, raw):
            a, pmf, status = _absorbance_and_physiology(torch, schema, raw)
            return _glucose_torch(torch, model, a, pmf).reshape(-1), status

    return Graph().eval()


def _trace(torch, graph, example, buf, first: str = "glucose_mgdl") -> None:
    torch.onnx.export(graph, (example,), buf, input_names=["raw"],
                      output_names=[first, "status"],
                      dynamic_axes={"raw": {0: "n"}, first: {0: "n"}, "status": {0: "n"}},
                      opset_version=OPSET, dynamo=False)


def onnx_graph_bytes(model: Any) -> bytes:
    """The ONNX file of a fitted ``model`` as bytes (see the module docstring).

    Raises
    ------
    ConfigError
        If the model has no ONNX path, or ``onnx`` is not installed.
    DataError
        If the model is not fitted on a device's data.
    """
    name = getattr(model, "registry_name", type(model).__name__)
    if name not in ONNX_MODELS:
        why = NO_ONNX_PATH.get(name, "no ONNX path is written for it")
        raise ConfigError(f"model {name!r} cannot be exported to ONNX: {why}; models with an "
                          f"ONNX path: {', '.join(ONNX_MODELS)}")
    schema = getattr(model, "schema_", None)
    if schema is None:
        raise DataError(f"model {name!r} is not fitted (or was fitted on a plain array, "
                        "with no device to describe); fit it on a Dataset or a file first")
    try:
        import onnx
    except ImportError as exc:
        raise ConfigError('ONNX export needs the onnx package: pip install "nirglucose[onnx]"'
                          ) from exc
    torch = _torch()
    graph = _graph_module(model)
    example = torch.ones((2, len(schema.raw_columns)), dtype=torch.float32)
    buf = io.BytesIO()
    fastpath = torch.backends.mha.get_fastpath_enabled()
    # attention's fused inference kernel has no ONNX form: trace the composite operators
    torch.backends.mha.set_fastpath_enabled(False)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # the TorchScript exporter's deprecation notice
            _trace(torch, graph, example, buf,
                   "tree_inputs" if name == "gbr" else "glucose_mgdl")
    finally:
        torch.backends.mha.set_fastpath_enabled(fastpath)
    proto = onnx.load_from_string(buf.getvalue())
    if name == "gbr":
        _append_trees(proto, model, onnx)
    meta = {"nirglucose_model": name, "raw_columns": json.dumps(list(schema.raw_columns)),
            "adc_bits": str(schema.adc_bits), "glucose_unit": "mg/dL"}
    for key, value in meta.items():
        entry = proto.metadata_props.add()
        entry.key, entry.value = key, value
    proto.producer_name = "nirglucose"
    return proto.SerializeToString()


def export_onnx(model: Any, path: str | Path) -> Path:
    """Write ``model`` as one ONNX file at ``path`` (atomically).

    Parameters
    ----------
    model : estimator or path
        A fitted model with an ONNX path (:data:`ONNX_MODELS`), fitted on a device's data,
        or the path of its model file.
    path : str or Path
        The ``.onnx`` file to write; its directory must exist.

    Returns
    -------
    Path
        ``path``.
    """
    if not isinstance(path, str | os.PathLike):
        raise DataError(f"path must be the .onnx file's path, got {type(path).__name__}")
    path = Path(path)
    blob = onnx_graph_bytes(model_from(model))
    atomic_write(path, lambda tmp: Path(tmp).write_bytes(blob))
    return path
