"""The modified Beer-Lambert law.

References
----------
.. [1] D. T. Delpy et al., "Estimation of optical pathlength through tissue from direct
   time of flight measurement", Phys. Med. Biol. 33, 1433-1442 (1988),
   doi:10.1088/0031-9155/33/12/008
.. [2] L. Kocsis, P. Herman, A. Eke, "The modified Beer-Lambert law revisited",
   Phys. Med. Biol. 51, N91-N98 (2006), doi:10.1088/0031-9155/51/5/N02
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from .. import portable as pm

__all__ = ["mbll_transmittance", "absorbance", "LN10"]

LN10 = float(pm.log(10.0))


def mbll_transmittance(
    mua_per_cm: ArrayLike,
    dpf: ArrayLike,
    separation_cm: ArrayLike,
    geometry_factor: ArrayLike = 1.0,
) -> np.ndarray:
    """Detected fraction I/I0 = G exp(-mua DPF rho) (modified Beer-Lambert law).

    Parameters
    ----------
    mua_per_cm : array_like
        Absorption coefficient. [1/cm]
    dpf : array_like
        Differential path-length factor. [-]
    separation_cm : array_like
        Source-detector separation rho. [cm]
    geometry_factor : array_like
        exp(-G), the scattering/geometry loss independent of absorption. [-]

    Returns
    -------
    numpy.ndarray
        I / I0. [-]

    Notes
    -----
    OD = mua DPF rho + G (natural log), Delpy et al. 1988 [1]_, Kocsis 2006 [2]_.

    Examples
    --------
    >>> round(float(mbll_transmittance(0.1, 5.0, 0.3)), 4)
    0.8607
    """
    mua = np.asarray(mua_per_cm, dtype=float)
    return np.asarray(geometry_factor) * pm.exp(-mua * np.asarray(dpf) * np.asarray(separation_cm))


def absorbance(intensity: ArrayLike, reference: ArrayLike) -> np.ndarray:
    """Decadic absorbance A = log10(I0 / I) (DESIGN.md physics notes).

    Parameters
    ----------
    intensity : array_like
        Detected intensity I (e.g. ADC code). [any]
    reference : array_like
        Reference intensity I0, same units. [any]

    Returns
    -------
    numpy.ndarray
        A. [-]

    Examples
    --------
    >>> float(absorbance(100.0, 1000.0))
    1.0
    """
    return pm.log10(np.asarray(reference, dtype=float) / np.asarray(intensity, dtype=float))
