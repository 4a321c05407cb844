"""Reduced scattering of skin and fat, and glucose's effect on it.

References
----------
.. [1] S. L. Jacques, "Optical properties of biological tissues: a review",
   Phys. Med. Biol. 58, R37-R61 (2013), doi:10.1088/0031-9155/58/11/R37
.. [2] J. S. Maier, S. A. Walker, S. Fantini, M. A. Franceschini, E. Gratton,
   "Possible correlation between blood glucose concentration and the reduced scattering
   coefficient of tissues in the near infrared", Opt. Lett. 19, 2062-2064 (1994),
   doi:10.1364/OL.19.002062
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from .. import portable as pm
from ..exceptions import ConfigError

__all__ = ["SKIN_MUSP", "FAT_MUSP", "power_law_musp_per_cm", "glucose_scattering_factor"]

#: Jacques 2013 [1]_ Table 2 averages: mus' = a (lambda / 500 nm)^-b. (a [1/cm], b [-])
SKIN_MUSP = (46.0, 1.421)
FAT_MUSP = (18.4, 0.672)


def power_law_musp_per_cm(
    wavelength_nm: ArrayLike, a_per_cm: float = SKIN_MUSP[0], b: float = SKIN_MUSP[1]
) -> np.ndarray:
    """Reduced scattering coefficient mus' = a (lambda / 500 nm)^-b.

    Parameters
    ----------
    wavelength_nm : array_like
        Wavelength. [nm]
    a_per_cm : float
        mus' at 500 nm. [1/cm]
    b : float
        Scattering power. [-]

    Returns
    -------
    numpy.ndarray
        mus'. [1/cm]

    References
    ----------
    Jacques 2013 [1]_, Eq. 2 and Table 2.

    Examples
    --------
    >>> round(float(power_law_musp_per_cm(850.0)), 1)
    21.6
    """
    wl = np.asarray(wavelength_nm, dtype=float)
    if np.any(wl <= 0):
        raise ConfigError("wavelength must be positive [nm]")
    return a_per_cm * pm.power(wl / 500.0, -b)  # [1], Eq. 2


def glucose_scattering_factor(glucose_mm: ArrayLike, rel_per_mm: float) -> np.ndarray:
    """Relative change of mus' with glucose: exp(k C), i.e. 1 + k C to first order.

    Glucose raises the refractive index of the interstitial fluid towards that of the
    scatterers, lowering mus' (Maier et al. 1994 [2]_); k = d ln(mus')/dC is about
    -2 (dn/dC) / (n_s - n_ecf).

    Parameters
    ----------
    glucose_mm : array_like
        Glucose concentration. [mM]
    rel_per_mm : float
        k, negative. [1/mM]

    Returns
    -------
    numpy.ndarray
        Factor multiplying mus'. [-]

    Notes
    -----
    The exponential keeps mus' positive when a scenario amplifies the glucose signal
    far beyond literature magnitudes (the ``paper`` preset); at literature magnitudes
    (k C of order 1e-2) it equals the linear law within 1e-4.

    Examples
    --------
    >>> round(float(glucose_scattering_factor(10.0, -1e-3)), 5)
    0.99005
    """
    return pm.exp(rel_per_mm * np.asarray(glucose_mm, dtype=float))
