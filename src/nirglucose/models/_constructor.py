"""The networks' constructor parameters: the training ones, declared once.

scikit-learn estimators declare every parameter in ``__init__`` (``get_params``,
``clone`` and ``set_params`` read its signature). The networks share eleven training
parameters; rather than re-declaring them in every subclass, each class states its
own parameters (``own_params``) and changed training defaults
(``training_defaults``), and :func:`keyword_init` builds the ``__init__`` with an
explicit signature.
"""

from __future__ import annotations

import inspect
from collections.abc import Callable
from typing import Any

__all__ = [
    "DEFAULT_EPOCHS",
    "DEFAULT_LR",
    "DEFAULT_WEIGHT_DECAY",
    "TRAINING_PARAMS",
    "constructor_defaults",
    "keyword_init",
]

#: Default training: full-batch AdamW for a fixed number of epochs with cosine annealing
#: and no validation split (the epoch count, lr and weight decay are hyper-parameters,
#: chosen per preset by ``tools/tune.py``; see :func:`nirglucose.models.tuned_params`).
#: These untuned defaults are mid-grid values of that search's space.
DEFAULT_EPOCHS = 300
DEFAULT_LR = 3e-3
DEFAULT_WEIGHT_DECAY = 1e-3


#: The training keyword arguments every network takes (name -> default), in the
#: constructor's order; documented in :class:`TorchRegressor`.
TRAINING_PARAMS: dict[str, Any] = {
    "max_epochs": DEFAULT_EPOCHS,
    "batch_size": None,
    "lr": DEFAULT_LR,
    "weight_decay": DEFAULT_WEIGHT_DECAY,
    "dropout": 0.0,
    "whiten_inputs": True,
    "patience": None,
    "val_fraction": 0.0,
    "lr_schedule": "cosine",
    "refit": True,
    "random_state": None,
}


def constructor_defaults(cls: type) -> dict[str, Any]:
    """``cls``'s constructor parameters and defaults: its own (most derived first),
    then :data:`TRAINING_PARAMS` with the hierarchy's ``training_defaults``."""
    own: dict[str, Any] = {}
    training = dict(TRAINING_PARAMS)
    for klass in reversed(cls.__mro__):
        training.update(klass.__dict__.get("training_defaults", {}))
    for klass in cls.__mro__:
        for name, default in klass.__dict__.get("own_params", {}).items():
            own.setdefault(name, default)
    clash = sorted(set(own) & set(training))
    if clash:
        raise TypeError(f"{cls.__name__}.own_params repeats training parameters {clash}")
    return {**own, **training}


def keyword_init(cls: type) -> Callable[..., None]:
    """A keyword-only ``__init__`` for ``cls`` storing each parameter unchanged.

    scikit-learn reads an estimator's parameters from its ``__init__`` signature
    (``BaseEstimator._get_param_names``), so the generated function carries an explicit
    ``__signature__``: ``get_params``, ``clone`` and ``set_params`` see every
    parameter, and no network re-declares the eleven training ones.
    """
    defaults = constructor_defaults(cls)

    def __init__(self, **params: Any) -> None:
        unknown = sorted(set(params) - set(defaults))
        if unknown:
            raise TypeError(
                f"{cls.__name__}() got an unexpected keyword argument {unknown[0]!r}; "
                f"parameters: {', '.join(defaults)}"
            )
        for name, default in defaults.items():
            setattr(self, name, params.get(name, default))

    self_param = inspect.Parameter("self", inspect.Parameter.POSITIONAL_OR_KEYWORD)
    __init__.__signature__ = inspect.Signature(
        [self_param]
        + [
            inspect.Parameter(name, inspect.Parameter.KEYWORD_ONLY, default=default)
            for name, default in defaults.items()
        ]
    )
    __init__.__qualname__ = f"{cls.__qualname__}.__init__"
    __init__.__module__ = cls.__module__
    __init__.generated = True  # see test_training_parameters_are_declared_once
    return __init__
