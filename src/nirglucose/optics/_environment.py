"""Where the Monte Carlo kernel reads the environment: ``$NIRGLUCOSE_MC_THREADS``.

A leaf module (it imports no other optics module), so that the white Monte Carlo kernel
and the look-up-table cache read the same variable without importing each other.
"""

from __future__ import annotations

import os

from ..exceptions import ConfigError

__all__ = ["mc_threads_from_env"]


def mc_threads_from_env() -> int | None:
    """Threads of the white Monte Carlo from ``$NIRGLUCOSE_MC_THREADS`` (None: unset).

    Read in this leaf module, so the kernel need not import the cache; used by
    :func:`nirglucose.optics.kernels.mc_white.white_mc_run` when it is given no ``n_threads``.

    Raises
    ------
    ConfigError
        If the variable is set but is not an integer >= 1.
    """
    env = os.environ.get("NIRGLUCOSE_MC_THREADS")
    if not env:
        return None
    try:
        n = int(env)
    except ValueError:
        n = 0
    if n < 1:
        raise ConfigError(f"NIRGLUCOSE_MC_THREADS = {env!r} is invalid; expected an integer "
                          "in [1, inf) [-]")
    return n

