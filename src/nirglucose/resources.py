"""Up-front resource checks: refuse a run that cannot fit in memory before it starts.

A request such as 10^12 subjects would otherwise allocate until the operating
system kills the process (or a neighbour's); one line now is better.

Examples
--------
>>> check_simulation_size(80, 3)
>>> simulation_bytes(80, 3)
960000
"""

from __future__ import annotations

import os

from .exceptions import ConfigError

__all__ = ["SIM_BYTES_PER_SNAPSHOT", "check_simulation_size", "physical_memory_bytes",
           "simulation_bytes"]

#: Memory a simulated snapshot needs: ``simulate_frame`` peaks at 1,125 B per snapshot
#: (``tools/cli_memory.py``, slope of peak RSS between 9,000 and 90,000
#: snapshots), times about 3.5 for the copies made on saving, summarising and
#: benchmarking. Only used to refuse runs that cannot fit, before they start. [B]
SIM_BYTES_PER_SNAPSHOT = 4_000


def physical_memory_bytes() -> int | None:
    """Physical memory of this machine, None where it cannot be read. [B]"""
    try:
        return int(os.sysconf("SC_PHYS_PAGES") * os.sysconf("SC_PAGE_SIZE"))
    except (ValueError, OSError, AttributeError):  # pragma: no cover - not POSIX
        return None


def simulation_bytes(n_subjects: int, per_subject: int) -> int:
    """Estimated peak memory of simulating ``n_subjects x per_subject`` in memory. [B]"""
    return int(n_subjects) * int(per_subject) * SIM_BYTES_PER_SNAPSHOT


def check_simulation_size(n_subjects: int, per_subject: int) -> None:
    """Raise if an in-memory simulation of this size cannot fit in physical memory.

    Raises
    ------
    ConfigError
        The estimate (:func:`simulation_bytes`) exceeds :func:`physical_memory_bytes`;
        the message gives both in GiB and the way out.
    """
    total = physical_memory_bytes()
    need = simulation_bytes(n_subjects, per_subject)
    if total is not None and need > total:
        raise ConfigError(
            f"{n_subjects} subjects x {per_subject} measurements need about "
            f"{need / 2**30:,.0f} GiB of memory, more than this machine's "
            f"{total / 2**30:,.0f} GiB; simulate fewer, or write a directory "
            "(partitioned Parquet) with `nirglucose simulate`"
        )
