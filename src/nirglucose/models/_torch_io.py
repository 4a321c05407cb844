"""Saving and loading the torch networks: a JSON document and safetensors weights.

Loading never executes code from the files: JSON, safetensors, or a ``.pt`` file read
with ``torch.load(weights_only=True)``; every array is checked (types, shapes, finite
values, positive scales) before a model is built from it.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import torch

from .._version import __version__
from ..dataset import atomic_write
from ..dataset.schema import DeviceSchema
from ..exceptions import DataError
from ._validate import (
    MODEL_FORMAT,
    check_calibration_doc,
    check_loaded_params,
    check_torch_doc,
    check_weights,
    read_model_document,
    unknown_params,
)

__all__ = ["FORMAT_VERSION", "TorchIOMixin", "WHITENING_KEY"]

#: Version of the saved-model JSON layout.
FORMAT_VERSION = 1
#: State-dict key of the whitening matrix (a buffer, not a trained parameter).
WHITENING_KEY = "whitening"


class TorchIOMixin:
    """:meth:`save` and :meth:`load` of :class:`~nirglucose.models._torch_base.TorchRegressor`."""

    def _json_params(self) -> dict:
        params = self.get_params(deep=False)
        rs = params.get("random_state")
        if not (rs is None or isinstance(rs, int | np.integer)):
            params["random_state"] = None  # a RandomState object has no JSON form
        return {k: (v.item() if isinstance(v, np.generic) else v) for k, v in params.items()}

    def save(self, path: str | Path) -> Path:
        """Write the model: ``path`` (JSON) and ``<stem>.safetensors`` beside it.

        Both files are written atomically (temporary file, then rename); the weights
        first, so a JSON document never names weights that are not there.

        Parameters
        ----------
        path : str or Path
            Destination of the JSON document (e.g. ``model.json``).

        Returns
        -------
        Path
            ``path``.
        """
        self._check_fitted()
        path = Path(path)
        weights = path.with_name(path.stem + ".safetensors")
        if weights == path:
            raise DataError(
                f"{str(path)!r}: the model document needs a suffix other than "
                f"'.safetensors' (e.g. 'model.json')"
            )
        tensors = {
            k: v.detach().to("cpu").contiguous() for k, v in self.module_.state_dict().items()
        }
        blob = _safetensors_bytes(tensors, {"format": MODEL_FORMAT, "model": self.registry_name})
        atomic_write(weights, lambda tmp: Path(tmp).write_bytes(blob))
        doc = {
            "format": MODEL_FORMAT,
            "format_version": FORMAT_VERSION,
            "model": self.registry_name,
            "nirglucose_version": __version__,
            "params": self._json_params(),
            "schema": self.schema_.to_json(),
            "scaler": {k: np.asarray(v).tolist() for k, v in self.scaler_.items()},
            "physics": self.physics_,
            "history": self.history_,
            "best_epoch": self.best_epoch_,
            "n_epochs": self.n_epochs_,
            "refit_history": self.refit_history_,
            "start_val_mse": self.start_val_mse_,
            "n_parameters": self.n_parameters,
            "weights_file": weights.name,
        }
        if getattr(self, "conformal_", None) is not None:  # its interval calibration
            doc["conformal"] = self.conformal_
        text = json.dumps(doc, indent=1, allow_nan=False)
        atomic_write(path, lambda tmp: Path(tmp).write_text(text))
        return path

    @classmethod
    def load(cls, path: str | Path):
        """Load a model written by :meth:`save`.

        Reads JSON and safetensors (or a ``.pt`` file through
        ``torch.load(weights_only=True)``); never executes code from the files.

        Raises
        ------
        DataError
            If the document is not a model of this class, or the weights miss keys,
            have extra keys or wrong shapes.
        """
        path = Path(path)
        doc = _read_document(cls, path)
        params = doc["params"]
        unknown, valid = unknown_params(cls, params)
        if unknown:
            raise DataError(f"{str(path)!r}: unknown parameters {unknown}; valid: {valid}")
        est = cls(**params)
        check_loaded_params(est, path)
        est._restore_fitted(doc, path)
        est.module_ = est._module_from_weights(_read_weights(path, doc["weights_file"]), path)
        est._prepare_physics_tensors()
        est._build_fast_path()
        return est

    def _restore_fitted(self, doc: dict, path: Path) -> None:
        """The fitted attributes of a checked document (all but the module)."""
        # Files written before the schema was saved are the study's device.
        self.schema_ = DeviceSchema.from_json(doc["schema"]) if "schema" in doc else DeviceSchema()
        self.scaler_ = {
            k: (float(v) if k.startswith("y_") else np.asarray(v, dtype=np.float64))
            for k, v in doc["scaler"].items()
        }
        self.physics_ = doc["physics"]
        self.history_ = doc["history"]
        self.best_epoch_ = doc.get("best_epoch", len(self.history_))
        self.n_epochs_ = doc.get("n_epochs", len(self.history_))
        self.refit_history_ = doc.get("refit_history", [])
        self.refit_epochs_ = len(self.refit_history_)
        self.start_val_mse_ = doc.get("start_val_mse")
        if "conformal" in doc:  # the interval calibration saved with the model
            self.conformal_ = check_calibration_doc(doc["conformal"], repr(str(path)))
        widths = {"nir": self.schema_.n_channels, "pmf": max(len(self.schema_.physiology), 1)}
        for part, width in widths.items():
            got = np.size(self.scaler_[f"{part}_mean"])
            if got != width:
                raise DataError(
                    f"{str(path)!r}: scaler.{part}_mean has {got} values, the device "
                    f"({self.schema_.describe()}) needs {width}; the file is corrupt, "
                    "refit the model")
        self.n_features_in_ = len(self.schema_.raw_columns)
        if not self.schema_.is_plain:
            self.feature_names_in_ = np.asarray(self.schema_.raw_columns, dtype=object)

    def _module_from_weights(self, state: dict[str, torch.Tensor], path: Path) -> torch.nn.Module:
        """The network built from the parameters with ``state`` loaded (eval mode);
        refuses missing or extra keys, wrong shapes and non-finite values."""
        name = self.registry_name
        module = self._wrap_inputs(self.build_module(), state.get(WHITENING_KEY))
        expected = module.state_dict()
        missing_keys = sorted(set(expected) - set(state))
        extra_keys = sorted(set(state) - set(expected))
        if missing_keys or extra_keys:
            raise DataError(
                f"weights for {name!r} do not match its network: "
                f"missing keys {missing_keys}, unexpected keys {extra_keys}"
            )
        bad = [k for k in expected if tuple(state[k].shape) != tuple(expected[k].shape)]
        if bad:
            k = bad[0]
            raise DataError(
                f"weights for {name!r}: {k} has shape {tuple(state[k].shape)}, "
                f"the network needs {tuple(expected[k].shape)}"
            )
        check_weights(state, path)  # finite, sane magnitudes (issue 20)
        module.load_state_dict(
            {k: state[k].to(dtype=expected[k].dtype) for k in expected}, strict=True
        )
        return module.eval()


def _safetensors_bytes(tensors: dict[str, torch.Tensor], metadata: dict[str, str]) -> bytes:
    """A safetensors file of ``tensors``, its header in one fixed order.

    safetensors writes ``__metadata__`` in the order of a Rust hash map, which is seeded
    per process: the same tensors gave different bytes from one run to the next. The
    header (8-byte little-endian length, JSON, space padding to a multiple of 8) is
    rewritten with the metadata keys sorted; the tensor data and their offsets (relative
    to the end of the header) are unchanged.
    """
    from safetensors.torch import save

    blob = save(tensors, metadata=metadata)
    n = int.from_bytes(blob[:8], "little")
    header = json.loads(blob[8 : 8 + n])
    meta = dict(sorted(header.pop("__metadata__", {}).items()))
    text = json.dumps({"__metadata__": meta, **header}, separators=(",", ":")).encode()
    text += b" " * (-len(text) % 8)
    return len(text).to_bytes(8, "little") + text + blob[8 + n :]


def _read_document(cls: type, path: Path) -> dict[str, Any]:
    """The checked JSON document of a saved ``cls`` model at ``path`` (DataError)."""
    doc = read_model_document(path, model=cls.registry_name, version=FORMAT_VERSION)
    required = ("params", "scaler", "physics", "history", "weights_file")
    missing = [k for k in required if k not in doc]
    if missing:
        raise DataError(f"{str(path)!r} lacks {missing}")
    check_torch_doc(doc, path)  # types, finite values, positive scales (issue 20)
    return doc


def _read_weights(doc_path: Path, name: Any) -> dict[str, torch.Tensor]:
    """Tensors of the weight file ``name`` beside ``doc_path`` (no code execution)."""
    if not isinstance(name, str) or Path(name).name != name or name in ("", ".", ".."):
        raise DataError(f"weights_file must be a plain file name beside the model, got {name!r}")
    wpath = doc_path.with_name(name)
    if not wpath.exists():
        raise DataError(f"weights file {str(wpath)!r} is missing")
    if wpath.suffix == ".safetensors":
        from safetensors import SafetensorError
        from safetensors.torch import load_file

        try:
            return load_file(str(wpath), device="cpu")
        except (SafetensorError, OSError, ValueError) as exc:
            raise DataError(f"{str(wpath)!r} is not a readable safetensors file: {exc}") from None
    if wpath.suffix in (".pt", ".pth"):
        try:
            state = torch.load(wpath, map_location="cpu", weights_only=True)
        except Exception:  # noqa: BLE001 - any unpickling refusal is a data error
            # torch's own message runs to several lines and suggests weights_only=False
            raise DataError(f"{str(wpath)!r} is not a weights-only torch file (it holds "
                            "objects or code, not only tensors); save the weights with "
                            "safetensors or torch.save(state_dict)") from None
        if not isinstance(state, dict) or not all(
            isinstance(v, torch.Tensor) for v in state.values()
        ):
            raise DataError(f"{str(wpath)!r} does not hold a state_dict of tensors")
        return state
    raise DataError(f"unknown weights format {wpath.suffix!r}; valid: .safetensors, .pt, .pth")
