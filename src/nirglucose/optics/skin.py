"""Layered skin: epidermal transmission and the share of the photon path in each layer.

The fast forward models treat skin as an epidermis (melanin) over a semi-infinite
medium whose optical properties mix the dermis and the subcutis in proportion to the
share of the photon path spent in each. That share follows from the mean photon
penetration depth of diffuse reflectance at a source-detector separation rho
(Weiss, Nossal & Bonner 1989): z ~ sqrt(rho / mu_eff) / (2 sqrt 2). The
``rte-lut`` model replaces this approximation with a Monte Carlo solution of light
transport in three layers (:mod:`nirglucose.optics.lut`).

References
----------
.. [1] G. H. Weiss, R. Nossal, R. F. Bonner, "Statistics of penetration depth of photons
   re-emitted from irradiated tissue", J. Mod. Opt. 36, 349-359 (1989),
   doi:10.1080/09500348914550381
.. [2] S. L. Jacques, "Skin optics", Oregon Medical Laser Center News (1998).
.. [3] I. V. Meglinski, S. J. Matcher, "Quantitative assessment of skin layers absorption
   and skin reflectance spectra simulation in the visible and near-infrared spectral
   regions", Physiol. Meas. 23, 741-753 (2002), doi:10.1088/0967-3334/23/4/312
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from .. import portable as pm

__all__ = [
    "epidermis_mua_per_cm",
    "epidermis_transmittance",
    "mean_penetration_depth_cm",
    "dermis_path_fraction",
]


def epidermis_mua_per_cm(
    melanin_fraction: ArrayLike, melanosome_mua: ArrayLike, baseline_mua: ArrayLike
) -> np.ndarray:
    """Epidermal absorption mua = f_mel mua_mel + (1 - f_mel) mua_baseline (Jacques 1998 [2]_).

    Parameters
    ----------
    melanin_fraction : array_like
        Melanosome volume fraction. [-]
    melanosome_mua : array_like
        mua inside a melanosome. [1/cm]
    baseline_mua : array_like
        mua of melanin-free skin. [1/cm]

    Returns
    -------
    numpy.ndarray
        Epidermal mua. [1/cm]

    Examples
    --------
    >>> round(float(epidermis_mua_per_cm(0.1, 116.0, 0.244)), 2)
    11.82
    """
    f = np.asarray(melanin_fraction, dtype=float)
    return f * np.asarray(melanosome_mua) + (1.0 - f) * np.asarray(baseline_mua)


def epidermis_transmittance(mua_epi_per_cm: ArrayLike, thickness_cm: ArrayLike) -> np.ndarray:
    """Two diffuse passes through the epidermis: T = exp(-2 * 2 t mua).

    Diffuse (Lambertian) light crosses a thin slab along a mean path of 2 t, and the
    detected light crosses the epidermis twice, in and out.

    Parameters
    ----------
    mua_epi_per_cm : array_like
        Epidermal absorption. [1/cm]
    thickness_cm : array_like
        Epidermal thickness. [cm]

    Returns
    -------
    numpy.ndarray
        Transmittance of the round trip. [-]

    Examples
    --------
    >>> round(float(epidermis_transmittance(10.0, 0.008)), 4)
    0.7261
    """
    return pm.exp(-4.0 * np.asarray(mua_epi_per_cm) * np.asarray(thickness_cm))


def mean_penetration_depth_cm(separation_cm: ArrayLike, mu_eff_per_cm: ArrayLike) -> np.ndarray:
    """Mean depth of detected photons, sqrt(rho / mu_eff) / (2 sqrt 2) (Weiss 1989 [1]_).

    Parameters
    ----------
    separation_cm : array_like
        Source-detector separation. [cm]
    mu_eff_per_cm : array_like
        Effective attenuation coefficient. [1/cm]

    Returns
    -------
    numpy.ndarray
        Depth. [cm]

    Examples
    --------
    >>> round(float(mean_penetration_depth_cm(0.3, 3.0)), 3)
    0.112
    """
    return np.sqrt(np.asarray(separation_cm) / np.asarray(mu_eff_per_cm)) / (2.0 * np.sqrt(2.0))


def dermis_path_fraction(skin_thickness_cm: ArrayLike, depth_cm: ArrayLike) -> np.ndarray:
    """Share of the photon path inside a skin layer of given thickness: 1 - exp(-t / z).

    An exponential depth distribution of mean z (Weiss 1989 [1]_) puts a share
    1 - exp(-t/z) of the photon path above depth t.

    Parameters
    ----------
    skin_thickness_cm : array_like
        Epidermis + dermis thickness. [cm]
    depth_cm : array_like
        Mean penetration depth. [cm]

    Returns
    -------
    numpy.ndarray
        Fraction in (0, 1). [-]

    Examples
    --------
    >>> round(float(dermis_path_fraction(0.1, 0.1)), 4)
    0.6321
    """
    return 1.0 - pm.exp(-np.asarray(skin_thickness_cm) / np.asarray(depth_cm))
