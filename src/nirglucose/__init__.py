"""nirglucose: a noise-stressed NIR glucose-sensor simulator and model benchmark.

>>> import nirglucose as ng
>>> ds = ng.simulate(preset="paper", n_subjects=3, per_subject=2, seed=0)
>>> ds.frame.shape[0]
6
"""

from __future__ import annotations

from importlib.metadata import PackageNotFoundError, version

try:
    __version__ = version("nirglucose")
except PackageNotFoundError:  # running from a source tree without installation
    __version__ = "0.0.0+unknown"

# The simulator subpackage first: importing it later would rebind the package attribute
# ``simulate`` from the function below to the subpackage (nothing else imports it now).
from . import simulate as _simulate_package  # noqa: F401
from .api import simulate
from .config import PRESETS, ScenarioConfig, resolve_config
from .dataset import Dataset, load_dataset
from .exceptions import ConfigError, DataError, NirGlucoseError, NotFittedError

__all__ = [
    "__version__",
    "simulate",
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
