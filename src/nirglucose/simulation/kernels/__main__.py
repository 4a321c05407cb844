"""Compile the simulation's numba kernels into numba's on-disk cache, once.

``python -m nirglucose.simulation.kernels`` (``make install`` runs it) simulates a few
snapshots of each optics model and one worn day, so that every kernel is compiled and
cached (``cache=True``) at install time, as ``pip`` compiles ``.pyc`` files, rather than
by the first simulation or by every test worker at once. The data are discarded; what a
later run computes does not depend on whether this ran.
"""

from __future__ import annotations

import time

from ...config import resolve_config
from ..simulator import simulate_frame
from ..wear import simulate_wear_frame


def main() -> None:
    t0 = time.perf_counter()
    for preset, model in (("paper", "beer-lambert"), ("paper", "diffusion"),
                          ("wearable", "beer-lambert")):
        simulate_frame(resolve_config(preset, {"optics.model": model}), 4, 2, 0)
    simulate_wear_frame(resolve_config("paper"), 2, 1, 60, 0)
    print(f"numba kernels compiled and cached in {time.perf_counter() - t0:.0f} s")


if __name__ == "__main__":
    main()
