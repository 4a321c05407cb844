"""Optics: pure functions over scalars or arrays, one module per topic.

absorption (chromophore tables), scattering (power laws, glucose), beer_lambert
(modified Beer-Lambert law), diffusion (dipole diffusion theory), skin (layers),
tissue (band-integrated tissue properties), forward (forward models by name).
"""

from __future__ import annotations

from .diffusion import (
    differential_pathlength_factor,
    effective_attenuation_per_cm,
    farrell_reflectance,
)
from .forward import FORWARD_MODELS, detected_fraction

__all__ = [
    "FORWARD_MODELS",
    "detected_fraction",
    "differential_pathlength_factor",
    "effective_attenuation_per_cm",
    "farrell_reflectance",
]
