"""Prediction of the torch networks: batched torch, and a NumPy path for few rows.

Up to :data:`NUMPY_ROWS` rows go through the network's NumPy closure (no torch
dispatch; a single reading in tens of microseconds), more through the module in
``torch.inference_mode`` in chunks; the two agree to float32 rounding.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import torch

from ..exceptions import DataError
from ._base import predict_input

__all__ = ["NUMPY_ROWS", "PREDICT_CHUNK", "TorchPredictMixin"]

#: Rows per chunk of batched prediction.
PREDICT_CHUNK = 65536
#: Batches up to this many rows are predicted through the NumPy closure.
NUMPY_ROWS = 8


class TorchPredictMixin:
    """``predict``, ``predict_one`` and the fast NumPy path of
    :class:`~nirglucose.models._torch_base.TorchRegressor`."""

    def _inputs32(self, Xa: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Standardised float32 network inputs ``(nir, pmf)`` from measured columns."""
        a, pmf = self._nir_pmf(Xa)
        s = self.scaler_
        nir = ((a - s["nir_mean"]) / s["nir_scale"]).astype(np.float32)
        return nir, ((pmf - s["pmf_mean"]) / s["pmf_scale"]).astype(np.float32)

    def predict(self, X: Any) -> np.ndarray:
        """Glucose estimates.

        Up to :data:`NUMPY_ROWS` rows go through the network's NumPy closure (the
        low-latency path, see :meth:`predict_one`); larger batches through the torch
        module in ``torch.inference_mode`` in chunks of 65,536 rows. The two paths
        agree to float32 rounding.

        Parameters
        ----------
        X : Dataset, pandas.DataFrame or array_like (n, 20)
            Measurements.

        Returns
        -------
        numpy.ndarray
            (n,) glucose. [mg/dL]
        """
        self._check_fitted()
        Xa = predict_input(self, X)  # the measured columns only; a glucose column is not read
        fast = self.__dict__.get("_fast")
        if len(Xa) <= NUMPY_ROWS and fast is not None and fast["fn"] is not None:
            x = np.concatenate(self._nir_pmf(Xa), axis=1)
            x -= fast["mu"]
            x *= fast["inv_scale"]
            out = self._glucose(fast["fn"](x.astype(np.float32))).astype(np.float64)
        else:
            nir, pmf = self._inputs32(Xa)
            out = np.empty(len(Xa), dtype=np.float64)
            nir_t, pmf_t = torch.from_numpy(nir), torch.from_numpy(pmf)
            self.module_.eval()
            with torch.inference_mode():
                for start in range(0, len(Xa), PREDICT_CHUNK):
                    stop = start + PREDICT_CHUNK
                    g = self._glucose(self.module_(nir_t[start:stop], pmf_t[start:stop]))
                    out[start:stop] = g.numpy()
        return out * self.scaler_["y_scale"] + self.scaler_["y_mean"]

    def predict_one(self, adc: Any, adc_ref: Any, pmf: Any) -> float:
        """Glucose from one snapshot, on the low-latency path.

        No DataFrame handling and no autograd: the inputs are standardised into a
        pre-allocated float32 buffer and run through the network's NumPy closure
        (:meth:`~nirglucose.models.networks.OriginalPINNNet.numpy_forward` and
        siblings), a snapshot of the fitted weights that evaluates the same function
        as the torch module (tested to float32 rounding) without PyTorch's per-module
        dispatch cost. Not thread-safe: the buffers belong to the estimator.

        Parameters
        ----------
        adc : array_like
            The device's ADC codes, one per LED in ``schema_`` order. [code]
        adc_ref : array_like or None
            Its reference codes (None for a device without them). [code]
        pmf : array_like
            Its physiological values in ``schema_.physiology`` order. [column units]

        Returns
        -------
        float
            Glucose. [mg/dL]
        """
        self._check_fitted()
        fast = self._fast
        sch = self.schema_
        k = sch.n_channels
        i = np.asarray(adc, dtype=np.float64)
        r = (np.asarray(adc_ref, dtype=np.float64) if sch.reference
             else np.asarray(sch.full_scales, dtype=np.float64))
        p = np.asarray(pmf if pmf is not None else [], dtype=np.float64)
        if i.shape != (k,) or np.shape(r) not in ((k,), ()) or p.shape != (len(sch.physiology),):
            raise DataError(
                f"predict_one takes {k} ADC codes, {k if sch.reference else 'no'} reference "
                f"codes and {len(sch.physiology)} physiological values; got shapes "
                f"{np.shape(adc)}, {np.shape(adc_ref)}, {p.shape}"
            )
        with np.errstate(divide="ignore", invalid="ignore"):
            a = np.log10(r / i)
        if not sch.physiology:
            p = np.zeros(1)
        u = np.concatenate((a, p))
        u -= fast["mu"]
        u *= fast["inv_scale"]
        x = fast["x"]
        x[0] = u
        if not np.isfinite(x).all():
            raise DataError("predict_one: codes must be > 0 and every value finite")
        if fast["fn"] is not None:
            g = self._glucose(fast["fn"](x))
        else:
            with torch.inference_mode():
                t = torch.from_numpy(x)
                g = self._glucose(self.module_(t[:, :k], t[:, k:]))
        return float(g[0]) * fast["y_scale"] + fast["y_mean"]

    def _build_fast_path(self) -> None:
        """Snapshot the fitted weights and scaler for the low-latency path."""
        s = self.scaler_
        self.module_.eval()
        numpy_forward = getattr(self.module_, "numpy_forward", None)
        mu = np.concatenate((s["nir_mean"], s["pmf_mean"])).astype(np.float64)
        self._fast = {
            "fn": numpy_forward() if callable(numpy_forward) else None,
            "x": np.zeros((1, len(mu)), dtype=np.float32),
            "mu": mu,
            "inv_scale": 1.0 / np.concatenate((s["nir_scale"], s["pmf_scale"])).astype(np.float64),
            "y_mean": float(s["y_mean"]),
            "y_scale": float(s["y_scale"]),
        }

    def __getstate__(self) -> dict:
        state = self.__dict__.copy()
        state.pop("_fast", None)  # closures do not pickle; rebuilt on unpickling
        return state

    def __setstate__(self, state: dict) -> None:
        self.__dict__.update(state)
        if getattr(self, "module_", None) is not None:
            self._build_fast_path()

    # ------------------------------------------------------------------ save / load
