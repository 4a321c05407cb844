"""Estimators by name: EBL, PLS, the oracle, four PINNs (and each with the forward-model
physics term, ``-fm``), a shallow DNN, three references, the forward-model inversions.

Each declares what it knows beyond the measured columns (:func:`privileged_knowledge`):
the privileged ones are references, never "best model".

The reference learners are the no-skill mean, a Gaussian process and gradient boosting.

Classes are imported lazily (torch loads only when a network is used). What a model is
called in tables, figures and reports is :func:`label` (:mod:`.labels`, beside the
registry).
"""

from __future__ import annotations

from .labels import MODEL_LABELS, label
from .registry import (
    available_models,
    get_model_class,
    load_model,
    make_model,
    privileged_knowledge,
    register,
)
from .tuning import tuned_params

__all__ = [
    "MODEL_LABELS",
    "label",
    "available_models",
    "get_model_class",
    "load_model",
    "make_model",
    "privileged_knowledge",
    "register",
    "tuned_params",
    "EnhancedBeerLambert",
    "PLSBaseline",
    "Oracle",
    "OriginalPINN",
    "OptimizedPINN",
    "RTEPINN",
    "SelectiveRTEPINN",
    "OriginalPINNForward",
    "OptimizedPINNForward",
    "RTEPINNForward",
    "SelectiveRTEPINNForward",
    "SDNN",
    "MeanReference",
    "GPReference",
    "GBRReference",
]

_LAZY = {
    "EnhancedBeerLambert": "nirglucose.models.linear",
    "PLSBaseline": "nirglucose.models.linear",
    "Oracle": "nirglucose.models.oracle",
    "OriginalPINN": "nirglucose.models.pinn",
    "OptimizedPINN": "nirglucose.models.pinn",
    "RTEPINN": "nirglucose.models.pinn",
    "SelectiveRTEPINN": "nirglucose.models.pinn",
    "OriginalPINNForward": "nirglucose.models.pinn",
    "OptimizedPINNForward": "nirglucose.models.pinn",
    "RTEPINNForward": "nirglucose.models.pinn",
    "SelectiveRTEPINNForward": "nirglucose.models.pinn",
    "SDNN": "nirglucose.models.sdnn",
    "MeanReference": "nirglucose.models.reference",
    "GPReference": "nirglucose.models.reference",
    "GBRReference": "nirglucose.models.reference",
}


def __getattr__(name: str):
    if name in _LAZY:
        import importlib

        return getattr(importlib.import_module(_LAZY[name]), name)
    raise AttributeError(f"module 'nirglucose.models' has no attribute {name!r}")
