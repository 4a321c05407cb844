"""nirglucose: a noise-stressed NIR glucose-sensor simulator and model benchmark.

>>> import nirglucose as ng
>>> ds = ng.simulate(preset="paper", n_subjects=3, per_subject=2, seed=0)
>>> ds.frame.shape[0]
6
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING

from . import _renamed
from ._version import __version__
from .api import simulate, simulate_wear
from .config import PRESETS, ScenarioConfig, resolve_config
from .dataset import Dataset, load_dataset
from .exceptions import ConfigError, DataError, NirGlucoseError, NotFittedError

_renamed.install()  # ``nirglucose.simulate.*`` imports: the renamed modules, with a warning

if TYPE_CHECKING:  # the lazy attributes below, as the type checker sees them
    from .prediction import PredictionResult, predict
    from .twin import Twin, fit_twin, load_twin

__all__ = [
    "__version__",
    "simulate",
    "simulate_wear",
    "predict",
    "PredictionResult",
    "fit_twin",
    "load_twin",
    "Twin",
    "twin_scenario",
    "load_dataset",
    "Dataset",
    "ScenarioConfig",
    "resolve_config",
    "PRESETS",
    "NirGlucoseError",
    "ConfigError",
    "DataError",
    "NotFittedError",
]

#: Subpackages reachable as attributes (``ng.models``, ``ng.metrics``, ...), imported on
#: first access so that ``import nirglucose`` stays light (torch, numba and matplotlib
#: load only when a model, kernel or figure asks for them).
SUBPACKAGES = ("calibration", "config", "dataset", "design", "evaluation", "export", "features",
               "metrics", "models", "optics", "plots", "portable", "report", "twin")


#: Functions and classes reachable as attributes, name -> module, imported on first
#: access: ``ng.predict`` needs the models and their intervals (:mod:`.calibration`), which
#: ``import nirglucose`` does not load.
LAZY_ATTRIBUTES = {"predict": "nirglucose.prediction", "PredictionResult": "nirglucose.prediction",
                   "fit_twin": "nirglucose.twin", "load_twin": "nirglucose.twin",
                   "Twin": "nirglucose.twin", "twin_scenario": "nirglucose.twin"}


def __getattr__(name: str):
    """``ng.models``, ``ng.metrics``, ``ng.evaluation``, ...: the subpackage, imported on
    first access (then a plain attribute).

    Examples
    --------
    >>> import nirglucose as ng
    >>> ng.metrics.rmse([100.0, 120.0], [110.0, 120.0]) > 0
    True
    """
    if name in SUBPACKAGES:
        return importlib.import_module(f".{name}", __name__)
    if name in LAZY_ATTRIBUTES:
        return getattr(importlib.import_module(LAZY_ATTRIBUTES[name]), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted({*globals(), *SUBPACKAGES, *LAZY_ATTRIBUTES})
