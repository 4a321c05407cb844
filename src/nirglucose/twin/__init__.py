"""A device's twin: the simulator fitted to a device's own file, with its uncertainty.

:func:`fit_twin` reads what a device file declares (:mod:`.device`), summarises it
(:mod:`.summaries`), and returns the posterior over the scenario parameters the file
identifies (:mod:`.parameters`), from neural posterior estimation trained on the
package's own simulator (:mod:`.inference`), with posterior predictive checks
(:mod:`.checks`); :class:`Twin` reads and writes ``twin.json`` and turns a twin into a
scenario for every study (:meth:`Twin.overrides`).
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING

from .inference import InferenceSettings
from .twin import TWIN_MODES, Twin, load_twin, twin_scenario

if TYPE_CHECKING:
    from .fit import fit_twin

__all__ = ["InferenceSettings", "TWIN_MODES", "Twin", "fit_twin", "load_twin", "twin_scenario"]


def __getattr__(name: str):
    """``fit_twin``, imported on first access: fitting loads the estimators and the
    design bound, which reading a twin does not need."""
    if name == "fit_twin":
        return importlib.import_module(".fit", __name__).fit_twin
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
