"""Old import paths of renamed modules, kept working for one release with a warning.

The simulator package was ``nirglucose.simulate`` in 0.1, the same name as the function
:func:`nirglucose.simulate`; it is :mod:`nirglucose.simulation` now, so that no module
and function share a name. ``import nirglucose.simulate.wear`` (and every other old
path) still works until 0.3 and warns (``DeprecationWarning``) once per old path.

How: a finder on :data:`sys.meta_path` answers for the old names only
(:class:`RenamedModuleFinder`, the mechanism of PEP 451 [1]_). An old submodule path is
the new module object itself (``nirglucose.simulate.wear is nirglucose.simulation.wear``).
The old package path is a module whose calls go to the function: Python's import
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

__all__ = ["RENAMED_MODULES", "RenamedModuleFinder", "install"]

#: Old dotted module name -> new one; every submodule follows its package.
RENAMED_MODULES = {"nirglucose.simulate": "nirglucose.simulation"}
#: The release that removes the old names.
REMOVED_IN = "0.3"


def _new_name(fullname: str) -> str | None:
    for old, new in RENAMED_MODULES.items():
        if fullname == old or fullname.startswith(old + "."):
            return new + fullname[len(old):]
    return None


class _CallableModule(types.ModuleType):
    """The old package path: the new package's names, and calls go to the function of the
    same name in the parent package (``nirglucose.simulate(...)``)."""

    def __call__(self, *args: Any, **kwargs: Any) -> Any:
        return self.__dict__["_function"](*args, **kwargs)


class _Loader(importlib.abc.Loader):
    def __init__(self, new: str):
        self.new = new

    def create_module(self, spec: importlib.machinery.ModuleSpec) -> types.ModuleType:
        warnings.warn(
            f"{spec.name} was renamed {self.new}; the old name is removed in "
            f"nirglucose {REMOVED_IN}: import {self.new}",
            DeprecationWarning,
            stacklevel=2,
        )
        module = importlib.import_module(self.new)
        if spec.name not in RENAMED_MODULES:
            # a submodule: the very same module object; the import system overwrites its
            # __spec__ with the old name's, which exec_module puts back
            self.spec = module.__spec__
            return module
        alias = _CallableModule(spec.name, module.__doc__)
        alias.__dict__.update({k: v for k, v in vars(module).items() if not k.startswith("__")})
        parent, _, child = spec.name.rpartition(".")
        alias.__dict__["_function"] = getattr(sys.modules[parent], child)
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
        is_package = fullname in RENAMED_MODULES or hasattr(importlib.import_module(new),
                                                              "__path__")
        return importlib.machinery.ModuleSpec(fullname, _Loader(new), is_package=is_package)


def install() -> None:
    """Put the finder on :data:`sys.meta_path` once (idempotent)."""
    if not any(isinstance(f, RenamedModuleFinder) for f in sys.meta_path):
        # first: an old package folder left behind (say its __pycache__) would otherwise
        # be found as an empty namespace package before the finder is asked
        sys.meta_path.insert(0, RenamedModuleFinder())
