"""Old import paths of moved modules, kept working for one release with a warning.

Two moves are served here, by one mechanism:

* 0.1 -> 0.2: the simulator package was ``nirglucose.simulate``, the same name as the
  function :func:`nirglucose.simulate`; it is :mod:`nirglucose.simulation` now, so that
  no module and function share a name.
* 0.2 (issue 42, "one room per verb"): the data boundary moved into
  :mod:`nirglucose.dataset` (``nirglucose.schema`` is ``nirglucose.dataset.schema``, ...),
  intervals and calibration into :mod:`nirglucose.calibration`, the evaluation into
  ``evaluation.engine``/``benchmark``/``sweep``, its statistics into
  :mod:`nirglucose.metrics.resampling`, and ``nirglucose.config_keys`` (a shim since
  0.1) is :mod:`nirglucose.config.keys`.

Every old path in :data:`RENAMED_MODULES` still imports until :data:`REMOVED_IN` and
warns (``DeprecationWarning``) once per old path; ``tests/test_renamed.py`` fails once
the version reaches :data:`REMOVED_IN` while any remain.

How: a finder on :data:`sys.meta_path` answers for the old names only
(:class:`RenamedModuleFinder`, the mechanism of PEP 451 [1]_). An old module path is the
new module object itself (``nirglucose.schema is nirglucose.dataset.schema``), unless
names left that module in the move (:data:`MOVED_NAMES`): then it is an alias module
with the new module's names that resolves the departed ones where they live now. The
old simulator package path is a module whose calls go to the function: Python's import
system binds an imported submodule as an attribute of its parent package, which would
replace ``nirglucose.simulate`` the function by the module; a callable module keeps
``ng.simulate(...)`` working after any old import.

References
----------
.. [1] PEP 451 -- A ModuleSpec Type for the Import System,
   https://peps.python.org/pep-0451/
"""

from __future__ import annotations

import importlib
import importlib.abc
import importlib.machinery
import sys
import types
import warnings
from typing import Any

__all__ = ["RENAMED_MODULES", "MOVED_NAMES", "REMOVED_IN", "RenamedModuleFinder", "install",
           "moved_name"]

_DATASET = {f"nirglucose.{old}": f"nirglucose.dataset.{new}" for old, new in {
    "schema": "schema", "io_files": "files", "dataset_meta": "meta", "columns": "columns",
    "adc_resolution": "adc", "small_data": "small_data"}.items()}

_EVALUATION = {f"nirglucose.evaluation.{old}": f"nirglucose.evaluation.{new}" for old, new in {
    "tasks": "engine.tasks", "executors": "engine.executors", "progress": "engine.progress",
    "benchmark_aggregate": "benchmark.aggregate", "benchmark_result": "benchmark.result",
    "drop_one": "benchmark.drop_one", "inverse": "benchmark.inverse",
    "subgroups": "benchmark.subgroups", "findings": "benchmark.findings",
    "finding": "benchmark.finding", "timing": "benchmark.timing",
    "sweep_analysis": "sweep.analysis", "studies": "sweep.studies",
    "scenario": "sweep.scenarios", "wavelength_study": "sweep.wavelengths",
    "fleet": "sweep.fleet", "transfer": "sweep.transfer", "wear_benchmark": "wear",
    "wear_sweep": "wear"}.items()}

#: Old dotted module name -> new one; every submodule follows its package.
RENAMED_MODULES: dict[str, str] = {
    "nirglucose.simulate": "nirglucose.simulation",
    "nirglucose.config_keys": "nirglucose.config.keys",
    **_DATASET,
    "nirglucose.evaluation.stats": "nirglucose.metrics.resampling",
    "nirglucose.evaluation.conformal": "nirglucose.calibration.conformal",
    "nirglucose.evaluation.calibration": "nirglucose.calibration.personal",
    "nirglucose.evaluation.wear_calibration": "nirglucose.calibration.schedules",
    **_EVALUATION,
}
#: Names that left their module in a move: old dotted name -> new dotted name (the old
#: module's path gives them, with a warning, until :data:`REMOVED_IN`).
MOVED_NAMES: dict[str, str] = {
    "nirglucose.schema.MeasurementTransformer":
        "nirglucose.features.transform.MeasurementTransformer",
    "nirglucose.schema.fit_schema": "nirglucose.fitted.fit_schema",
    "nirglucose.schema.as_raw_input": "nirglucose.fitted.as_raw_input",
    "nirglucose.evaluation.finding.label": "nirglucose.models.labels.label",
    "nirglucose.evaluation.reference.MODEL_LABELS": "nirglucose.models.labels.MODEL_LABELS",
}
#: Old package paths that are also a function of their parent package (a call of the
#: old module goes to the function).
_CALLABLE = frozenset({"nirglucose.simulate"})
#: The release that removes the old names.
REMOVED_IN = "0.3"


def _new_name(fullname: str) -> str | None:
    for old, new in RENAMED_MODULES.items():
        if fullname == old or fullname.startswith(old + "."):
            return new + fullname[len(old):]
    return None


def _warn(old: str, new: str, stacklevel: int) -> None:
    warnings.warn(f"{old} was renamed {new}; the old name is removed in nirglucose "
                  f"{REMOVED_IN}: import {new}", DeprecationWarning, stacklevel=stacklevel)


class _CallableModule(types.ModuleType):
    """The old package path: the new package's names, and calls go to the function of the
    same name in the parent package (``nirglucose.simulate(...)``)."""

    def __call__(self, *args: Any, **kwargs: Any) -> Any:
        return self.__dict__["_function"](*args, **kwargs)


def moved_name(module: str, name: str, stacklevel: int = 3) -> Any:
    """Name ``name`` that left ``module`` (:data:`MOVED_NAMES`), from its new home, with a
    warning; an AttributeError for any other name.

    A module that stays but lost a name serves it through this, as its ``__getattr__``
    (PEP 562), e.g. ``nirglucose.evaluation.reference.MODEL_LABELS``.
    """
    new = MOVED_NAMES.get(f"{module}.{name}")
    if new is None:
        raise AttributeError(f"module {module!r} has no attribute {name!r}")
    _warn(f"{module}.{name}", new, stacklevel=stacklevel + 1)
    home, _, attr = new.rpartition(".")
    return getattr(importlib.import_module(home), attr)


class _AliasModule(types.ModuleType):
    """An old module path that lost names in the move: the new module's names, and each
    departed name (:data:`MOVED_NAMES`) from its new home, with a warning."""

    def __getattr__(self, name: str) -> Any:
        return moved_name(self.__name__, name)


class _Loader(importlib.abc.Loader):
    def __init__(self, new: str):
        self.new = new

    def create_module(self, spec: importlib.machinery.ModuleSpec) -> types.ModuleType:
        _warn(spec.name, self.new, stacklevel=3)
        module = importlib.import_module(self.new)
        if spec.name in _CALLABLE:
            alias = _CallableModule(spec.name, module.__doc__)
            parent, _, child = spec.name.rpartition(".")
            alias.__dict__["_function"] = getattr(sys.modules[parent], child)
        elif any(name.rpartition(".")[0] == spec.name for name in MOVED_NAMES):
            alias = _AliasModule(spec.name, module.__doc__)
        else:
            # the very same module object; the import system overwrites its __spec__
            # with the old name's, which exec_module puts back
            self.spec = module.__spec__
            return module
        alias.__dict__.update({k: v for k, v in vars(module).items() if not k.startswith("__")})
        if hasattr(module, "__path__"):
            alias.__path__ = []  # a package: its submodules are found by this finder
        return alias

    def exec_module(self, module: types.ModuleType) -> None:
        """Nothing to run (the module is the renamed one, already executed); its own
        ``__spec__`` is restored, so its relative imports keep resolving to new names."""
        if getattr(self, "spec", None) is not None:
            module.__spec__ = self.spec


class RenamedModuleFinder(importlib.abc.MetaPathFinder):
    """Finds the old names of :data:`RENAMED_MODULES` (and only those)."""

    def find_spec(self, fullname: str, path: Any = None, target: Any = None):
        new = _new_name(fullname)
        if new is None:
            return None
        is_package = hasattr(importlib.import_module(new), "__path__")
        return importlib.machinery.ModuleSpec(fullname, _Loader(new), is_package=is_package)


def install() -> None:
    """Put the finder on :data:`sys.meta_path` once (idempotent)."""
    if not any(isinstance(f, RenamedModuleFinder) for f in sys.meta_path):
        # first: an old package folder left behind (say its __pycache__) would otherwise
        # be found as an empty namespace package before the finder is asked
        sys.meta_path.insert(0, RenamedModuleFinder())
