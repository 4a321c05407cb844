"""Optics: pure functions over scalars or arrays, one module per topic.

absorption (chromophore tables), scattering (power laws, glucose), beer_lambert
(modified Beer-Lambert law), diffusion (dipole diffusion theory), skin (layers),
tissue (band-integrated tissue properties), forward (forward models by name),
layers (the three-layer skin model), lut (the ``rte-lut`` look-up table: grid, build,
cache, interpolate), kernels (compiled: mc_white, the white Monte Carlo behind the table;
lut_kernel and band_kernel, the simulator's fast path),
reference (validation only: the NumPy photon engine with its front ends ``mc_slab``,
``mc_layers``, ``mc_detected_paths``, adding-doubling ``slab_rt``, table checks).
The solvers load lazily: the simulator's fast path never imports iadpython.
"""

from __future__ import annotations

from .diffusion import (
    differential_pathlength_factor,
    effective_attenuation_per_cm,
    farrell_reflectance,
)
from .forward import FORWARD_MODELS, detected_fraction

_LAZY = {
    "slab_rt": "reference.adding_doubling",
    "mc_slab": "reference.monte_carlo",
    "mc_layers": "reference.monte_carlo",
    "mc_detected_paths": "reference.mc_paths",
    "reweight_detected": "reference.mc_paths",
    "three_layer_reflectance": "layers",
}


def __getattr__(name: str):
    if name in _LAZY:
        import importlib

        return getattr(importlib.import_module(f"{__name__}.{_LAZY[name]}"), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


__all__ = [
    *_LAZY,
    "FORWARD_MODELS",
    "detected_fraction",
    "differential_pathlength_factor",
    "effective_attenuation_per_cm",
    "farrell_reflectance",
]
