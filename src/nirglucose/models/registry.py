"""Estimators by name: ``make_model("ebl")``, ``load_model("model.json")``.

Modules register their classes with :func:`register`; the registry imports them
lazily so that ``import nirglucose`` stays light (torch is imported only when a
network is asked for).
"""

from __future__ import annotations

import importlib
import inspect
import os
from collections.abc import Mapping
from dataclasses import dataclass
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
    "privileged_knowledge",
    # variants (issue 42), the block at the end of this module
    "Variant",
    "register_variant",
    "get_variant",
]

#: Registered name -> the module that defines it. Adding a model is a module with a
#: ``@register(name)`` class and one line here; the module is imported on first use, so
#: looking up a linear model does not import torch.
MODELS = {
    "ebl": "nirglucose.models.linear",
    "pls": "nirglucose.models.linear",
    "oracle": "nirglucose.models.oracle",
    "physics-inversion": "nirglucose.models.inversion",
    "device-inversion": "nirglucose.models.device_inversion",
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


def privileged_knowledge(model: Any) -> str | None:
    """What an estimator knows beyond the measured columns, or None (deployable).

    Each registered estimator declares it as its class attribute ``privileged``: None
    for one that reads only the measured columns, the device's declared parts and
    published tables (a deployable estimator), else a short phrase -- the oracle's
    true nuisances, the generating scenario and the simulator's own forward model.
    Privileged estimators are references, like the bound, never "best model".

    Parameters
    ----------
    model : str, type or estimator
        A registered name, an estimator class, or an estimator (fitted or not). A
        user's own estimator that declares nothing is taken as deployable (None).

    Returns
    -------
    str or None

    Raises
    ------
    ConfigError
        An unknown name.

    Examples
    --------
    >>> privileged_knowledge("ebl") is None
    True
    >>> privileged_knowledge("oracle")
    'true nuisances (true_* columns) and the generating scenario (Dataset.config)'
    """
    cls = get_model_class(model) if isinstance(model, str) else model
    if not isinstance(cls, type):
        cls = type(cls)
    value = getattr(cls, "privileged", None)
    return value if isinstance(value, str) and value.strip() else None


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


# ============================================================================ variants
# Issue 42: a registered name for an existing class with other defaults (the ``-fm``
# PINNs are their study twins with ``physics_form='forward'``). Everything of the
# mechanism is in this block; the rest of the registry sees a variant as a registered
# class (a generated subclass that only sets defaults), so ``get_model_class(name)``,
# ``make_model``, ``load_model``, the benchmark's ``get_model_class(name)(**params)``,
# saved files and the class's name and ``registry_name`` stay as they were.


@dataclass(frozen=True)
class Variant:
    """A registered name for an existing estimator class with other defaults.

    Attributes
    ----------
    name : str
        The variant's registered name (``original-pinn-fm``).
    base : str
        The registered name of the class it varies (``original-pinn``).
    defaults : Mapping[str, Any]
        The constructor defaults it changes; every other parameter is the base's.
    privileged : Any
        What the variant knows beyond the measured data (set as the generated class's
        ``privileged``), or None to keep the base's.
    """

    name: str
    base: str
    defaults: Mapping[str, Any]
    privileged: Any = None


_VARIANTS: dict[str, Variant] = {}


def _variant_doc(variant: Variant, base: type, summary: str, notes: str) -> str:
    values = ", ".join(f"{k}={v!r}" for k, v in variant.defaults.items())
    literal = ", ".join(f"``{k}={v!r}``" for k, v in variant.defaults.items())
    return (f"{variant.base} with {values}: {summary}\n\n"
            f"    The registered variant ``{variant.name}`` of :class:`{base.__name__}`\n"
            f"    (:func:`~nirglucose.models.registry.register_variant`): that class with the\n"
            f"    defaults {literal}; its parameters, network and prediction\n"
            f"    are the base's.\n" + notes)


def register_variant(
    name: str,
    base: type,
    *,
    defaults: Mapping[str, Any],
    summary: str,
    class_name: str,
    privileged: Any = None,
    notes: str = "",
) -> type:
    """Register ``name`` as the registered class ``base`` with other constructor defaults.

    Called where ``base`` is defined, after it; like any registered name, ``name`` needs
    its line in :data:`MODELS` (the module that registers it).

    Parameters
    ----------
    name : str
        The variant's registered name.
    base : type
        A registered class whose constructor is built from its ``own_params`` (the
        networks, :class:`~nirglucose.models._torch_base.TorchRegressor`).
    defaults : mapping
        Constructor defaults the variant changes (each a parameter of ``base``).
    summary : str
        What the variant is, in a few words; its docstring's first line (what
        ``nirglucose models`` prints) is the base's name, the changed defaults and this.
    class_name : str
        The name the generated class carries (and its module exports).
    privileged : optional
        What the variant knows beyond the measured data (the generated class's
        ``privileged``); None keeps the base's.
    notes : str
        Further docstring sections (numpydoc, indented by four spaces).

    Returns
    -------
    type
        The generated class: a subclass of ``base`` that sets only the defaults (and
        ``privileged``), registered under ``name``. ``variant_of`` on it names the base.

    Raises
    ------
    TypeError
        If ``base`` is not registered or builds no constructor from ``own_params``, a
        default is not one of its parameters, or ``name`` is taken.
    """
    base_name = getattr(base, "registry_name", "")
    if _REGISTRY.get(base_name) is not base:
        raise TypeError(f"variant {name!r}: {base.__name__} is not a registered class")
    # every network class gets its own generated __init__ (TorchRegressor.__init_subclass__)
    if not getattr(vars(base).get("__init__"), "generated", False):
        raise TypeError(f"variant {name!r}: {base.__name__} does not build its constructor "
                        "from own_params (a network class)")
    known = inspect.signature(base).parameters
    unknown = sorted(set(defaults) - set(known))
    if unknown:
        raise TypeError(f"variant {name!r}: {unknown[0]!r} is not a parameter of "
                        f"{base.__name__}; parameters: {', '.join(known)}")
    if name in _REGISTRY:
        raise TypeError(f"variant {name!r}: the name is registered already")
    own = {k for c in base.__mro__ for k in c.__dict__.get("own_params", {})}
    variant = Variant(name, base_name, dict(defaults), privileged)
    namespace: dict[str, Any] = {
        "__module__": base.__module__,
        "__qualname__": class_name,
        "__doc__": _variant_doc(variant, base, summary, notes),
        "own_params": {k: v for k, v in defaults.items() if k in own},
        "training_defaults": {k: v for k, v in defaults.items() if k not in own},
        "variant_of": base_name,
    }
    if privileged is not None:
        namespace["privileged"] = privileged
    cls = register(name)(type(class_name, (base,), namespace))
    _VARIANTS[name] = variant
    return cls


def get_variant(name: str) -> Variant | None:
    """The :class:`Variant` registered under ``name``, or None for a class of its own;
    an unknown name raises ConfigError (:func:`get_model_class`).

    Examples
    --------
    >>> get_variant("original-pinn-fm").base
    'original-pinn'
    >>> get_variant("ebl") is None
    True
    """
    get_model_class(name)
    return _VARIANTS.get(name)

