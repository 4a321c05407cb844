"""Input checks shared by the optics' Monte Carlo front ends (no physics here).

One place for what the photon engine's front ends
(``nirglucose_reference.monte_carlo``,
``nirglucose_reference.mc_paths``), the white Monte Carlo
(:mod:`~nirglucose.optics.kernels.mc_white`) and the table grid
(:mod:`~nirglucose.optics.lut.grid`) all ask of their inputs: a photon count and a
random generator. Imports NumPy only, so any of them may use it.
"""

from __future__ import annotations

import numpy as np

from ..exceptions import ConfigError

__all__ = ["as_generator", "check_n_photons"]


def check_n_photons(n_photons: object) -> int:
    """``n_photons`` as an int, or a one-line ConfigError unless it is an integer >= 1.

    Parameters
    ----------
    n_photons : object
        Photon count to check; ``bool`` is refused. [-]

    Returns
    -------
    int
        The count. [-]

    Raises
    ------
    ConfigError
        If it is not an integer >= 1.
    """
    if isinstance(n_photons, bool) or not isinstance(n_photons, int | np.integer) or n_photons < 1:
        raise ConfigError(f"n_photons = {n_photons!r} is invalid; expected an integer >= 1 [-]")
    return int(n_photons)


def as_generator(rng: np.random.Generator | int | None) -> np.random.Generator:
    """The generator itself, or a fresh one seeded with ``rng``.

    :func:`numpy.random.default_rng` returns a Generator it is given unchanged, so a
    caller's generator is consumed, not copied.

    Parameters
    ----------
    rng : numpy.random.Generator or int or None
        Random generator or seed. [-]

    Returns
    -------
    numpy.random.Generator
    """
    return np.random.default_rng(rng)
