"""Designing a device: the bound each design allows (:mod:`.bound`), the search
over LED sets ranked by it (:mod:`.search`), and a fleet of units drawn from the parts'
tolerances (:mod:`~nirglucose.design.fleet`).

The parts a design is made of (photodiodes, NIR LEDs) are in the config's catalogue,
:mod:`nirglucose.config.parts`.
"""

from __future__ import annotations

from .bound import (
    CONDITIONS,
    DesignBound,
    DesignTerms,
    design_bound,
    design_terms,
    noise_covariance,
)
from .fleet import FleetTolerances, Unit, draw_units, simulate_unit
from .search import (
    CANDIDATE_WAVELENGTHS_NM,
    SEARCH_DETECTORS,
    candidate_leds,
    drive_powers_mw,
    rank_designs,
    subset_bounds,
)

__all__ = [
    "CANDIDATE_WAVELENGTHS_NM",
    "SEARCH_DETECTORS",
    "candidate_leds",
    "drive_powers_mw",
    "rank_designs",
    "subset_bounds",
    "CONDITIONS",
    "DesignBound",
    "DesignTerms",
    "design_bound",
    "design_terms",
    "noise_covariance",
    "FleetTolerances",
    "Unit",
    "draw_units",
    "simulate_unit",
]
