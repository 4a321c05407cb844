"""The noise-stressed NIR sensor simulator: one module per layer, and the facade."""

from __future__ import annotations

from .simulator import block_ranges, iter_blocks, simulate_block, simulate_frame

__all__ = ["block_ranges", "iter_blocks", "simulate_block", "simulate_frame"]
