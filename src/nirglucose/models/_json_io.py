"""JSON save/load shared by the models whose state is a few arrays (no pickle).

A model file is one JSON document::

    {"format": "nirglucose-model", "format_version": 1, "model": "ebl",
     "nirglucose_version": "0.1.0", "params": {...}, "state": {...},
     "conformal": {...}}

``conformal`` (optional) is the model's prediction-interval calibration
(:func:`nirglucose.calibration.conformal.split_conformal`), validated on load.

``params`` are the constructor's keyword arguments (``get_params()``); ``state`` holds
the learned attributes as numbers and lists. Loading validates the schema, the model
name and the format version and never executes anything from the file.
"""

from __future__ import annotations

import json
import math
import os
from pathlib import Path
from typing import Any

import numpy as np

from .._version import __version__
from ..dataset import atomic_write
from ..exceptions import DataError
from ._validate import (
    MODEL_FORMAT,
    check_array,
    check_calibration_doc,
    check_loaded_params,
    read_model_document,
    unknown_params,
)

__all__ = ["FORMAT", "FORMAT_VERSION", "JsonModelMixin"]

FORMAT = MODEL_FORMAT
FORMAT_VERSION = 1


def _to_json(value: Any) -> Any:
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, tuple | list):
        return [_to_json(v) for v in value]
    if isinstance(value, dict):
        return {str(k): _to_json(v) for k, v in value.items()}
    if value is None or isinstance(value, bool | int | float | str):
        return value
    raise DataError(f"cannot store a {type(value).__name__} in a JSON model file")


def _check_finite(name: str, value: Any) -> None:
    arr = np.asarray(value, dtype=float)
    if not np.all(np.isfinite(arr)):
        raise DataError(f"model state {name!r} has NaN or infinite values; refit the model")


class JsonModelMixin:
    """``save(path)`` / ``Cls.load(path)`` for estimators whose state is plain arrays.

    Subclasses define ``_STATE``: a dict mapping each learned attribute to the
    expected shape of its array (``None`` for a scalar, ``"json"`` for any JSON value,
    or a tuple with ``-1`` for a free dimension).
    """

    _STATE: dict[str, Any] = {}

    def _state_dict(self) -> dict[str, Any]:
        out = {}
        for name, shape in self._STATE.items():
            value = getattr(self, name)
            if shape != "json":
                _check_finite(name, value)
            out[name] = _to_json(value)
        return out

    def save(self, path: str | os.PathLike) -> Path:
        """Write the fitted model as JSON, atomically.

        Parameters
        ----------
        path : str or path-like
            Destination ``.json`` file; its directory must exist.

        Returns
        -------
        pathlib.Path
            The written path.
        """
        self._require_fitted()
        doc = {
            "format": FORMAT,
            "format_version": FORMAT_VERSION,
            "model": type(self).registry_name,
            "nirglucose_version": __version__,
            "params": _to_json(self.get_params(deep=False)),
            "state": self._state_dict(),
        }
        if getattr(self, "conformal_", None) is not None:  # its interval calibration
            doc["conformal"] = _to_json(self.conformal_)
        text = json.dumps(doc, indent=1, allow_nan=False)

        def write(tmp: str) -> None:
            Path(tmp).write_text(text)

        return atomic_write(path, write)

    @classmethod
    def _params_from_json(cls, params: dict[str, Any]) -> dict[str, Any]:
        return params

    @classmethod
    def load(cls, path: str | os.PathLike):
        """Restore a model written by :meth:`save`.

        Raises
        ------
        DataError
            Missing file, not JSON, wrong format or version, another model's file, or
            a malformed state.
        """
        path = Path(path)
        doc = _read_document(path, cls.registry_name)
        params, state = doc["params"], doc["state"]
        unknown, valid = unknown_params(cls, params)
        if unknown:
            raise DataError(f"{str(path)!r} has unknown parameters {unknown}; valid: {valid}")
        try:
            model = cls(**cls._params_from_json(params))
        except (TypeError, ValueError) as exc:
            raise DataError(f"{str(path)!r}: invalid parameters: {exc}") from None
        check_loaded_params(model, path)
        for key, shape in cls._STATE.items():
            if key not in state:
                raise DataError(f"{str(path)!r} lacks state {key!r}")
            setattr(model, key, _state_value(path, key, state[key], shape))
        model._restore()
        if "conformal" in doc:
            model.conformal_ = check_calibration_doc(doc["conformal"], repr(str(path)))
        return model

    def _restore(self) -> None:
        """Rebuild derived attributes after :meth:`load` (override)."""


def _read_document(path: Path, name: str) -> dict[str, Any]:
    """The checked JSON document of a saved ``name`` model (DataError otherwise)."""
    doc = read_model_document(path, model=name, version=FORMAT_VERSION)
    if not isinstance(doc.get("params"), dict) or not isinstance(doc.get("state"), dict):
        raise DataError(f"{str(path)!r} lacks the 'params' and 'state' objects")
    return doc


def _state_value(path: Path, key: str, value: Any, shape: Any) -> Any:
    """One saved state entry, checked: ``shape`` is ``'json'`` (as is), None (a finite
    scalar) or a tuple (-1: any length); DataError on a wrong shape or non-finite value."""
    if shape == "json":
        return value
    positive = key.endswith(("scale_", "var_"))  # scales and variances
    arr = check_array(path, f"state {key}", value, positive=positive)
    if shape is None:
        ok = arr.ndim == 0 and math.isfinite(float(arr))
        value = float(arr) if ok else None
    else:
        ok = (
            arr.ndim == len(shape)
            and all(s == -1 or s == d for s, d in zip(shape, arr.shape, strict=True))
            and bool(np.all(np.isfinite(arr)))
        )
        value = arr
    if not ok:
        raise DataError(
            f"{str(path)!r}: state {key!r} has the wrong shape or non-finite values "
            f"(expected shape {shape})"
        )
    return value
