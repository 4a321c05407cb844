"""Checks on what a model file holds, so a loaded model cannot predict nonsense.

A model file that parses can still hold NaN weights, a zero or huge target scale or a
coefficient of 1e308; its predictions would then be NaN, constant or +-1e299. These
helpers refuse such files with one :class:`~nirglucose.exceptions.DataError` line
naming the file, the entry and what is wrong. They never execute anything.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np

from ..exceptions import ConfigError, DataError

__all__ = [
    "MAX_ABS_STATE",
    "MAX_Y_SCALE_MGDL",
    "check_array",
    "check_calibration_doc",
    "check_loaded_params",
    "unknown_params",
    "check_predictions",
    "check_torch_doc",
    "check_weights",
]

#: Largest magnitude any stored number may have. Fitted coefficients act on
#: standardised features or on log absorbances and ADC-derived features (at most
#: 2^24 codes), so a magnitude beyond 1e12 can only come from a corrupt or forged
#: file; 1e12 x 2^24 still leaves float64 some 280 orders of magnitude from overflow. [-]
MAX_ABS_STATE = 1e12

#: Largest target (glucose) scale a network may store: the SD of glucose over a
#: training set cannot exceed the width of the physiological 0-1000 mg/dL range. [mg/dL]
MAX_Y_SCALE_MGDL = 1000.0

#: Predictions beyond this magnitude mean a broken model, whatever the input. [mg/dL]
MAX_ABS_PREDICTION_MGDL = 1e5


def _where(path: str | Path) -> str:
    return repr(str(path))


def check_array(path: str | Path, name: str, value: Any, *, positive: bool = False) -> np.ndarray:
    """A stored array as float64, refused if non-numeric, non-finite or absurd.

    Parameters
    ----------
    path : str or path-like
        The model file (for the message).
    name : str
        The entry's name in the file.
    value : array_like
        The stored value.
    positive : bool
        Whether every element must be > 0 (scales, variances).

    Returns
    -------
    numpy.ndarray
        The value as a float64 array.

    Raises
    ------
    DataError
        Not numeric, NaN or infinite, beyond :data:`MAX_ABS_STATE`, or not positive
        where it must be.
    """
    try:
        raw = np.asarray(value)
    except (TypeError, ValueError):  # a ragged list
        raise DataError(f"{_where(path)}: {name!r} is not a numeric array") from None
    if raw.dtype.kind not in "iuf":  # strings, booleans, nulls are not stored numbers
        raise DataError(f"{_where(path)}: {name!r} is not numeric; the file is corrupt")
    arr = raw.astype(np.float64)
    if not np.all(np.isfinite(arr)):
        raise DataError(f"{_where(path)}: {name!r} has NaN or infinite values; refit the model")
    if arr.size and float(np.max(np.abs(arr))) > MAX_ABS_STATE:
        raise DataError(
            f"{_where(path)}: {name!r} has a value of magnitude "
            f"{float(np.max(np.abs(arr))):.3g}, beyond {MAX_ABS_STATE:.0e}; the file is "
            "corrupt, refit the model"
        )
    if positive and arr.size and not bool(np.all(arr > 0)):
        raise DataError(f"{_where(path)}: {name!r} must be positive; the file is corrupt")
    return arr


def check_torch_doc(doc: dict[str, Any], path: str | Path) -> None:
    """Types and values of a network's JSON document (params, scaler, history).

    Raises
    ------
    DataError
        ``params`` not an object, a scaler entry missing, non-numeric, of the wrong
        length, non-finite, a non-positive scale, or a target scale outside
        (0, :data:`MAX_Y_SCALE_MGDL`] mg/dL; ``history`` not a list.
    """
    if not isinstance(doc.get("params"), dict):
        raise DataError(f"{_where(path)}: 'params' must be an object")
    scaler = doc.get("scaler")
    if not isinstance(scaler, dict):
        raise DataError(f"{_where(path)}: 'scaler' must be an object")
    for key in ("nir_mean", "nir_scale", "pmf_mean", "pmf_scale", "y_mean", "y_scale"):
        if key not in scaler:
            raise DataError(f"{_where(path)}: scaler lacks {key!r}")
        arr = check_array(path, f"scaler.{key}", scaler[key], positive=key.endswith("scale"))
        scalar = key.startswith("y_")
        if scalar != (arr.ndim == 0):
            shape = "a number" if scalar else "a list"
            raise DataError(f"{_where(path)}: scaler.{key} must be {shape}")
    for a, b in (("nir_mean", "nir_scale"), ("pmf_mean", "pmf_scale")):
        if np.shape(scaler[a]) != np.shape(scaler[b]):
            raise DataError(f"{_where(path)}: scaler.{a} and scaler.{b} differ in length")
    y_scale = float(scaler["y_scale"])
    if not 0 < y_scale <= MAX_Y_SCALE_MGDL:
        raise DataError(
            f"{_where(path)}: scaler.y_scale {y_scale:.3g} mg/dL is outside "
            f"(0, {MAX_Y_SCALE_MGDL:.0f}] mg/dL; the file is corrupt"
        )
    for key in ("history", "refit_history"):
        if key in doc and not isinstance(doc[key], list):
            raise DataError(f"{_where(path)}: {key!r} must be a list")
    if not isinstance(doc.get("physics", {}), dict):
        raise DataError(f"{_where(path)}: 'physics' must be an object")


def check_weights(state: dict[str, Any], path: str | Path) -> None:
    """Every weight tensor finite and of sane magnitude (see :func:`check_array`)."""
    for key, tensor in state.items():
        if hasattr(tensor, "is_floating_point") and not tensor.is_floating_point():
            raise DataError(f"{_where(path)}: weights {key} are {tensor.dtype}, not floating "
                            "point; the file is corrupt, refit the model")
        arr = tensor.detach().cpu().double().numpy() if hasattr(tensor, "detach") else tensor
        check_array(path, f"weights {key}", arr)


def unknown_params(cls: type, params: Any) -> tuple[list[str], list[str]]:
    """``(unknown, valid)``: the keys of ``params`` that estimator class ``cls`` does not
    take, and those it takes (sorted; scikit-learn's ``_get_param_names``)."""
    valid = sorted(cls._get_param_names())  # type: ignore[attr-defined]
    return sorted(set(params) - set(valid)), valid


def check_loaded_params(model: Any, path: str | Path) -> None:
    """Refuse a loaded model whose stored parameters break its constraints (one line
    naming the file), as :func:`~nirglucose.models.registry.make_model` would at fit."""
    validate = getattr(model, "_validate_params", None)
    if validate is None:
        return
    try:
        validate()
    except (ConfigError, ValueError) as exc:
        reason = " ".join(str(exc).split()).rstrip(".")
        raise DataError(f"{_where(path)}: {reason}; the file is corrupt, refit the model"
                        ) from None


def check_predictions(pred: Any, path: str | Path) -> np.ndarray:
    """Refuse predictions that only a broken model makes (NaN, infinite, beyond 1e5 mg/dL)."""
    arr = np.asarray(pred, dtype=np.float64)
    if not np.all(np.isfinite(arr)):
        raise DataError(f"model {_where(path)} predicted NaN or infinite glucose; refit it")
    if arr.size and float(np.max(np.abs(arr))) > MAX_ABS_PREDICTION_MGDL:
        worst = float(np.max(np.abs(arr)))
        raise DataError(
            f"model {_where(path)} predicted {worst:.3g} mg/dL, beyond "
            f"{MAX_ABS_PREDICTION_MGDL:.0e} mg/dL; the model file is corrupt, refit it"
        )
    return arr


#: The ``format`` of every saved model document.
MODEL_FORMAT = "nirglucose-model"


def read_model_document(
    path: Path, *, model: str | None = None, version: int | None = None
) -> dict[str, Any]:
    """The JSON document of a saved model, checked; the one reader of model files.

    Refuses (one-line :class:`~nirglucose.exceptions.DataError`) a missing file, text
    that is not JSON, a document without ``format: "nirglucose-model"`` and a
    ``model`` name, and, when given, another ``model``'s file or another
    ``format_version``. Never executes anything from the file.
    """
    if not path.is_file():
        raise DataError(f"no such model file {str(path)!r}")
    try:
        doc = json.loads(path.read_text())
    except (ValueError, UnicodeDecodeError):  # not JSON, or a number beyond Python's limit
        raise DataError(f"{str(path)!r} is not a nirglucose model (not JSON, or a number "
                        "in it is beyond what JSON readers take)") from None
    if not isinstance(doc, dict) or doc.get("format") != MODEL_FORMAT or "model" not in doc:
        raise DataError(
            f"{str(path)!r} is not a nirglucose model file (no 'format': {MODEL_FORMAT!r} "
            "and 'model' keys)"
        )
    if not isinstance(doc["model"], str):
        raise DataError(
            f"{str(path)!r}: 'model' must be a model name (a string such as 'ebl'), got "
            f"{type(doc['model']).__name__} {str(doc['model'])[:40]}; the file is corrupt"
        )
    if model is not None and doc["model"] != model:
        raise DataError(
            f"{str(path)!r} holds a {doc['model']!r} model, not {model!r}; load it with "
            "nirglucose.models.load_model"
        )
    if version is not None and doc.get("format_version") != version:
        raise DataError(
            f"{str(path)!r} has format_version {doc.get('format_version')!r}; this "
            f"nirglucose reads version {version}"
        )
    return doc


def check_calibration_doc(doc: Any, where: str = "model file") -> dict[str, Any]:
    """Validate a stored split-conformal calibration (from a model file); returns it.

    Lives with the model-file checks, so loading a model never imports the evaluation
    package; :mod:`nirglucose.calibration.conformal` writes what it reads.
    """
    ok = (
        isinstance(doc, dict)
        and doc.get("method") == "split"
        and isinstance(doc.get("half_width_mgdl"), dict)
        and len(doc["half_width_mgdl"]) > 0
    )
    if ok:
        for key in ("half_width_mgdl", "half_width_offset1_mgdl"):
            for k, v in (doc.get(key) or {}).items():
                if v is None and key == "half_width_offset1_mgdl":
                    continue
                if (
                    not str(k).isdigit()
                    or not 0 < int(k) < 100
                    or isinstance(v, bool)
                    or not isinstance(v, int | float)
                    or not math.isfinite(v)
                    or v < 0
                ):
                    ok = False
    if not ok:
        raise DataError(f"{where}: malformed conformal calibration; refit the model")
    return doc
