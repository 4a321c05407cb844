"""The one place the optics read environment variables.

``$NIRGLUCOSE_MC_THREADS`` (white Monte Carlo threads), ``$NIRGLUCOSE_CACHE`` and
``$XDG_CACHE_HOME`` (the table cache's directory) and ``$NIRGLUCOSE_LUT_GRID`` (the grid
used where none is named). A leaf module (it imports no other optics module), so that the
white Monte Carlo kernel and the look-up-table cache read them without importing each other.
"""

from __future__ import annotations

import os
from pathlib import Path

from ..exceptions import ConfigError

__all__ = ["mc_threads_from_env", "cache_dir_from_env", "lut_grid_from_env",
           "lut_grid_named_in_env"]


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



def cache_dir_from_env() -> Path:
    """``$NIRGLUCOSE_CACHE``, else ``$XDG_CACHE_HOME/nirglucose``, else ``~/.cache/nirglucose``."""
    env = os.environ.get("NIRGLUCOSE_CACHE")
    if env:
        return Path(env)
    xdg = os.environ.get("XDG_CACHE_HOME")
    return (Path(xdg) if xdg else Path.home() / ".cache") / "nirglucose"


def lut_grid_from_env() -> str:
    """The look-up-table grid named by ``$NIRGLUCOSE_LUT_GRID``, else ``"default"``."""
    return lut_grid_named_in_env() or "default"


def lut_grid_named_in_env() -> str | None:
    """The look-up-table grid named by ``$NIRGLUCOSE_LUT_GRID``, else None."""
    return os.environ.get("NIRGLUCOSE_LUT_GRID") or None
