"""Designing a device: the bound each design allows (:mod:`.bound`).

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

__all__ = [
    "CONDITIONS",
    "DesignBound",
    "DesignTerms",
    "design_bound",
    "design_terms",
    "noise_covariance",
]
