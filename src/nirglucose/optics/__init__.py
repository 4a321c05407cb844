"""Optics: pure functions over scalars or arrays, one module per topic.

absorption (chromophore tables), scattering (power laws, glucose), beer_lambert
(modified Beer-Lambert law), diffusion (dipole diffusion theory), skin (layers),
tissue (band-integrated tissue properties), forward (forward models by name),
layers (the three-layer skin model), lut (the ``rte-lut`` look-up table: grid, build,
cache, interpolate), kernels (compiled: mc_white, the white Monte Carlo behind the table;
lut_kernel and band_kernel, the simulator's fast path).
The validation solvers (the NumPy photon engine with its front ends ``mc_slab``,
``mc_layers``, ``mc_detected_paths``, adding-doubling ``slab_rt``, the table's checks)
are not part of the installed package since 0.2: they live in a source checkout's
``validation/nirglucose_reference`` (for the tests, benchmarks and studies).
"""

from __future__ import annotations

from .diffusion import (
    differential_pathlength_factor,
    effective_attenuation_per_cm,
    farrell_reflectance,
)
from .forward import FORWARD_MODELS, detected_fraction

_LAZY = {
    "three_layer_reflectance": "layers",
}
#: The validation solvers that left the installed package in 0.2, by their module in
#: ``validation/nirglucose_reference`` (a source checkout).
_VALIDATION = {
    "slab_rt": "adding_doubling",
    "mc_slab": "monte_carlo",
    "mc_layers": "monte_carlo",
    "mc_detected_paths": "mc_paths",
    "reweight_detected": "mc_paths",
}


def __getattr__(name: str):
    if name in _LAZY:
        import importlib

        return getattr(importlib.import_module(f"{__name__}.{_LAZY[name]}"), name)
    if name in _VALIDATION:
        raise AttributeError(
            f"nirglucose.optics.{name} is a validation solver, no longer installed with the "
            f"package: in a source checkout, put validation/ on sys.path and use "
            f"nirglucose_reference.{_VALIDATION[name]}.{name}")
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


__all__ = [
    *_LAZY,
    "FORWARD_MODELS",
    "detected_fraction",
    "differential_pathlength_factor",
    "effective_attenuation_per_cm",
    "farrell_reflectance",
]
