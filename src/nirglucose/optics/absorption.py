"""Absorption coefficients of skin chromophores from published tables.

Every function returns a natural-log absorption coefficient mua [1/cm]
(I = I0 exp(-mua L)), interpolated linearly in the packaged tables
(``nirglucose/data/optics``; sources in its SOURCES.md).

References
----------
.. [1] L. Kou, D. Labrie, P. Chylek, "Refractive indices of water and ice in the
   0.65-2.5 um spectral range", Appl. Opt. 32, 3531-3540 (1993), doi:10.1364/AO.32.003531
.. [2] N. Bosschaart et al., "A literature review and novel theoretical approach on the
   optical properties of whole blood", Lasers Med. Sci. 29, 453-479 (2014),
   doi:10.1007/s10103-013-1446-7
.. [3] R. L. P. van Veen et al., "Determination of visible near-IR absorption
   coefficients of mammalian fat using time- and spatially resolved diffuse reflectance
   and transmission spectroscopy", J. Biomed. Opt. 10, 054004 (2005),
   doi:10.1117/1.2085149
.. [4] S. L. Jacques, "Skin optics", Oregon Medical Laser Center News (1998).
.. [5] S. L. Jacques, "Optical properties of biological tissues: a review",
   Phys. Med. Biol. 58, R37-R61 (2013), doi:10.1088/0031-9155/58/11/R37
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from .. import portable as pm
from ..data import load_spectrum
from ..exceptions import ConfigError

__all__ = [
    "WATER_SOURCES",
    "WAVELENGTH_RANGE_NM",
    "water_mua_per_cm",
    "blood_mua_per_cm",
    "lipid_mua_per_cm",
    "melanosome_mua_per_cm",
    "skin_baseline_mua_per_cm",
    "glucose_mua_per_cm_per_mm",
]

#: Valid ``source`` names of :func:`water_mua_per_cm` -> packaged table.
WATER_SOURCES = {
    "kou1993": "water_kou1993",
    "segelstein1981": "water_segelstein1981",
    "hale_querry1973": "water_hale_querry1973",
}

#: Wavelength range every table covers. [nm]
WAVELENGTH_RANGE_NM = (700.0, 1300.0)

#: van Veen's fat table ends here; above it the provisional digitised curve is used. [nm]
_LIPID_SWITCH_NM = 1098.0


def _check_wavelength(wavelength_nm: ArrayLike) -> np.ndarray:
    wl = np.asarray(wavelength_nm, dtype=float)
    low, high = WAVELENGTH_RANGE_NM
    bad = ~((wl >= low) & (wl <= high))
    if np.any(bad):
        first = float(wl.flat[int(np.flatnonzero(bad.ravel())[0])])
        raise ConfigError(
            f"wavelength {first} nm is outside the optics tables' range {low:g}-{high:g} nm"
        )
    return wl


def _interp(name: str, wl: np.ndarray) -> np.ndarray:
    x, y = load_spectrum(name)
    return np.interp(wl, x, y)


def water_mua_per_cm(wavelength_nm: ArrayLike, source: str = "kou1993") -> np.ndarray:
    """Absorption coefficient of pure water.

    Parameters
    ----------
    wavelength_nm : array_like
        Wavelength, 700-1300. [nm]
    source : {'kou1993', 'segelstein1981', 'hale_querry1973'}
        Which published table to use (they differ by up to 40 % at 940 nm).

    Returns
    -------
    numpy.ndarray
        mua of water. [1/cm]

    References
    ----------
    Kou et al. 1993 [1]_, tabulated by S. Prahl (OMLC); Segelstein 1981; Hale & Querry
    1973 (Appl. Opt. 12, 555, doi:10.1364/AO.12.000555).

    Examples
    --------
    >>> round(float(water_mua_per_cm(1150.0)), 2)
    0.98
    """
    if source not in WATER_SOURCES:
        raise ConfigError(f"unknown water source {source!r}; valid: {', '.join(WATER_SOURCES)}")
    return _interp(WATER_SOURCES[source], _check_wavelength(wavelength_nm))


def blood_mua_per_cm(wavelength_nm: ArrayLike, saturation: ArrayLike) -> np.ndarray:
    """Absorption coefficient of whole blood (haematocrit 45 %) at a given SO2.

    Parameters
    ----------
    wavelength_nm : array_like
        Wavelength. [nm]
    saturation : array_like
        Oxygen saturation SO2, 0-1. [-]

    Returns
    -------
    numpy.ndarray
        mua = S mua_oxy + (1 - S) mua_deoxy. [1/cm]

    Notes
    -----
    Bosschaart et al. 2014 [2]_ compiled whole-blood values, used over the whole range
    for consistency (SOURCES.md). Linear mixing in S follows Jacques 2013 [5]_, Eq. 12.

    Examples
    --------
    >>> round(float(blood_mua_per_cm(850.0, 1.0)), 1)
    4.9
    """
    wl = _check_wavelength(wavelength_nm)
    s = np.asarray(saturation, dtype=float)
    if np.any((s < 0) | (s > 1)):
        raise ConfigError("saturation must lie within 0-1 (a fraction, not %)")
    oxy = _interp("blood_oxy_bosschaart2014", wl)
    deoxy = _interp("blood_deoxy_bosschaart2014", wl)
    return s * oxy + (1.0 - s) * deoxy


def lipid_mua_per_cm(wavelength_nm: ArrayLike) -> np.ndarray:
    """Absorption coefficient of pure fat.

    van Veen et al. [3]_ up to 1098 nm; above it the provisional digitised curve (the
    only table that covers the 1210 nm lipid band; see SOURCES.md).

    Parameters
    ----------
    wavelength_nm : array_like
        Wavelength. [nm]

    Returns
    -------
    numpy.ndarray
        mua of fat. [1/cm]

    Examples
    --------
    >>> round(float(lipid_mua_per_cm(940.0)), 3)
    0.088
    """
    wl = _check_wavelength(wavelength_nm)
    return np.where(
        wl <= _LIPID_SWITCH_NM,
        _interp("lipid_vanveen2004", wl),
        _interp("lipid_provisional", wl),
    )


def melanosome_mua_per_cm(wavelength_nm: ArrayLike) -> np.ndarray:
    """Absorption coefficient inside a melanosome, 6.6e11 lambda^-3.33 (Jacques 1998 [4]_).

    Parameters
    ----------
    wavelength_nm : array_like
        Wavelength. [nm]

    Returns
    -------
    numpy.ndarray
        mua of melanosomes. [1/cm]

    Examples
    --------
    >>> round(float(melanosome_mua_per_cm(850.0)))
    116
    """
    wl = _check_wavelength(wavelength_nm)
    return 6.6e11 * pm.power(wl, -3.33)  # [4], power law fitted to melanosome data


def skin_baseline_mua_per_cm(wavelength_nm: ArrayLike) -> np.ndarray:
    """Baseline absorption of bloodless, melanin-free skin (Jacques 1998 [4]_).

    mua = 0.244 + 85.3 exp(-(lambda - 154) / 66.2) [1/cm]; in the NIR it is the constant
    0.244 /cm.

    Parameters
    ----------
    wavelength_nm : array_like
        Wavelength. [nm]

    Returns
    -------
    numpy.ndarray
        Baseline mua. [1/cm]
    """
    wl = _check_wavelength(wavelength_nm)
    return 0.244 + 85.3 * pm.exp(-(wl - 154.0) / 66.2)  # [4]


#: Glucose C-H overtone bands in the 700-1300 nm window: (centre nm, 1/e half-width nm,
#: peak relative to the 2nd-overtone peak). 2nd C-H overtone about 1100-1200 nm and a
#: weaker 3rd overtone about 900-950 nm (SOURCES.md, Glucose section). The shapes are
#: an assumption: no public table covers this window.
GLUCOSE_BANDS_NM = ((1150.0, 45.0, 1.0), (920.0, 30.0, 0.1))


def glucose_mua_per_cm_per_mm(
    wavelength_nm: ArrayLike, peak_per_cm_per_mm: float = 1.0e-4
) -> np.ndarray:
    """Glucose's own absorption per mM, as Gaussian overtone bands.

    Parameters
    ----------
    wavelength_nm : array_like
        Wavelength. [nm]
    peak_per_cm_per_mm : float
        Absorption at the 2nd C-H overtone peak per mM. [1/(cm mM)]

    Returns
    -------
    numpy.ndarray
        Specific absorption of glucose. [1/(cm mM)]

    Notes
    -----
    Order-of-magnitude model only (SOURCES.md: in the 1050-1150 nm window glucose's
    absorption per mM is of order 1e-4 of water's mua or smaller); the magnitude is a
    config parameter (``glucose.absorptivity_per_cm_per_mm``).
    """
    wl = _check_wavelength(wavelength_nm)
    out = np.zeros_like(wl)
    for centre, width, rel in GLUCOSE_BANDS_NM:
        out = out + rel * pm.exp(-(((wl - centre) / width) ** 2))
    return peak_per_cm_per_mm * out
