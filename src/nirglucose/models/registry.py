"""Estimators by name: ``make_model("ebl")``, ``load_model("model.json")``.

Modules register their classes with :func:`register`; the registry imports them
lazily so that ``import nirglucose`` stays light (torch is imported only when a
network is asked for).
"""

from __future__ import annotations

import importlib
import inspect
import os
from pathlib import Path
from typing import Any

import numpy as np

from ..exceptions import ConfigError, unknown_name
from ._validate import read_model_document, unknown_params

__all__ = [
    "register",
    "get_model_class",
    "make_model",
    "describe_model",
    "available_models",
    "load_model",
    "model_from",
    "MODEL_MODULES",
    "MODELS",
    "is_network",
    "is_pinn",
]

#: Registered name -> the module that defines it. Adding a model is a module with a
#: ``@register(name)`` class and one line here; the module is imported on first use, so
#: looking up a linear model does not import torch.
MODELS = {
    "ebl": "nirglucose.models.linear",
    "pls": "nirglucose.models.linear",
    "oracle": "nirglucose.models.oracle",
    "physics-inversion": "nirglucose.models.inversion",
    "ebl+gp": "nirglucose.models.hybrid",
    "physics-inversion+gp": "nirglucose.models.hybrid",
    "original-pinn": "nirglucose.models.pinn",
    "optimized-pinn": "nirglucose.models.pinn",
    "rte-pinn": "nirglucose.models.pinn",
    "selective-rte-pinn": "nirglucose.models.pinn",
    "original-pinn-fm": "nirglucose.models.pinn",
    "optimized-pinn-fm": "nirglucose.models.pinn",
    "rte-pinn-fm": "nirglucose.models.pinn",
    "selective-rte-pinn-fm": "nirglucose.models.pinn",
    "sdnn": "nirglucose.models.sdnn",
    "mean": "nirglucose.models.reference",
    "gp": "nirglucose.models.reference",
    "gbr": "nirglucose.models.reference",
}
#: Modules that define registered estimators (imported on first use).
MODEL_MODULES = tuple(dict.fromkeys(MODELS.values()))

_REGISTRY: dict[str, type] = {}
_loaded = False


def register(name: str):
    """Class decorator registering an estimator under ``name``."""

    def deco(cls):
        _REGISTRY[name] = cls
        cls.registry_name = name
        return cls

    return deco


def _load_all() -> None:
    global _loaded
    if _loaded:
        return
    for mod in MODEL_MODULES:
        try:
            importlib.import_module(mod)
        except ModuleNotFoundError as exc:  # a module not written yet
            if exc.name != mod:
                raise
    _loaded = True


def available_models() -> list[str]:
    """Names of every registered estimator."""
    _load_all()
    return sorted(_REGISTRY)


def get_model_class(name: str) -> type:
    """The estimator class registered under ``name``; unknown names raise ConfigError."""
    if name in MODELS and name not in _REGISTRY:
        importlib.import_module(MODELS[name])
    if name not in _REGISTRY:
        _load_all()
    if name not in _REGISTRY:
        raise ConfigError(unknown_name("model", name, sorted(_REGISTRY)))
    return _REGISTRY[name]


def is_network(name: str) -> bool:
    """Whether ``name`` is a torch network (trained by the shared loop, tuned on the
    shared training grid). Reads the class hierarchy by name, so asking about a
    linear model does not import torch."""
    return any(
        c.__name__ == "TorchRegressor" and c.__module__ == "nirglucose.models._torch_base"
        for c in get_model_class(name).__mro__
    )


def is_pinn(name: str) -> bool:
    """Whether ``name`` is a physics-informed network: a network with a physics weight
    ``lambda_phys`` (0 switches its physics term off, e.g. for the ablation)."""
    return is_network(name) and "lambda_phys" in inspect.signature(get_model_class(name)).parameters


def describe_model(model: Any) -> str:
    """One line on a model: its summary, and for a fitted one its device's inputs.

    Parameters
    ----------
    model : str or estimator
        A registered name (the class's summary: the first line of its docstring), or a
        fitted estimator (e.g. from :func:`load_model`): then the counts follow the
        device it was fitted on (its LEDs, resolution and physiology), not the study's.

    Examples
    --------
    >>> describe_model("mean")
    'No skill: predicts the training mean of glucose for every row.'
    """
    cls = get_model_class(model) if isinstance(model, str) else type(model)
    doc = (cls.__doc__ or "").strip().splitlines()
    summary = doc[0] if doc else ""
    schema = None if isinstance(model, str) else model.__dict__.get("schema_")
    if schema is None:
        return summary
    parts = [f"{len(schema.raw_columns)} input columns"]
    coef = model.__dict__.get("coef_")
    if coef is not None:
        parts.append(f"{np.size(coef)} features")
    n_par = getattr(model, "n_parameters", None)
    if isinstance(n_par, int | np.integer):
        parts.append(f"{int(n_par):,} parameters")
    name = getattr(cls, "registry_name", "") or cls.__name__
    return f"{name} fitted on {schema.describe()}: {', '.join(parts)}"


def make_model(name: str, **params: Any):
    """A new, unfitted estimator of the registered ``name``.

    Raises
    ------
    ConfigError
        An unknown name, or a parameter the model does not take (one line listing those
        it takes).

    Examples
    --------
    >>> make_model("ebl", foo=1)  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    nirglucose.exceptions.ConfigError: unknown parameter 'foo' of model 'ebl'; valid: ...
    """
    cls = get_model_class(name)
    unknown, valid = unknown_params(cls, params)
    if unknown:
        raise ConfigError(f"unknown parameter {unknown[0]!r} of model {name!r}; valid: "
                          f"{', '.join(valid)}")
    return cls(**params)


def model_from(model: Any):
    """A fitted estimator as given, or loaded from the path of a model file
    (:func:`load_model`): what prediction and export accept as ``model``."""
    if isinstance(model, str | os.PathLike):
        return load_model(Path(model))
    return model


def load_model(path: str | Path):
    """Load a model saved with ``model.save(path)`` (a JSON document naming its class).

    Never executes code from the file: JSON, plus safetensors / ``weights_only`` torch
    weights for networks.
    """
    doc = read_model_document(Path(path))
    cls: Any = get_model_class(doc["model"])  # every registered class has a load()
    return cls.load(path)
