"""A device's twin: the simulator fitted to a device's own file, with its uncertainty.

:func:`fit_twin` reads what a device file declares (:mod:`.device`), summarises it
(:mod:`.summaries`), and returns the posterior over the scenario parameters the file
identifies (:mod:`.parameters`), from neural posterior estimation trained on the
package's own simulator (:mod:`.inference`), with posterior predictive checks
(:mod:`.checks`); :class:`Twin` reads and writes ``twin.json`` and turns a twin into a
scenario for every study (:meth:`Twin.overrides`).
"""

from .inference import InferenceSettings
from .twin import TWIN_MODES, Twin, fit_twin, load_twin

__all__ = ["InferenceSettings", "TWIN_MODES", "Twin", "fit_twin", "load_twin"]
