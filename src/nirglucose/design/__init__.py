"""Designing a device: the bound each design allows (:mod:`.bound`, and the per-state
form :mod:`.state_bound`), the search over LED sets ranked by it (:mod:`.search`), a
fleet of units drawn from the parts' tolerances (:mod:`~nirglucose.design.fleet`), and
what it takes to read glucose at published magnitudes (:mod:`nirglucose.design.requirements`,
:mod:`.levers`, exposure limits :mod:`.exposure`, averaging :mod:`.averaging`; the
study that confirms its designs by simulation is a sweep study,
:mod:`nirglucose.evaluation.sweep.requirements`).

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
from .exposure import max_led_power_mw
from .fleet import FleetTolerances, Unit, draw_units, simulate_unit
from .search import (
    CANDIDATE_WAVELENGTHS_NM,
    SEARCH_DETECTORS,
    candidate_leds,
    drive_powers_mw,
    rank_designs,
    subset_bounds,
)
from .state_bound import state_bound, state_bounds

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
    "max_led_power_mw",
    "state_bound",
    "state_bounds",
]
