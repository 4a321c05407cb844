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
.. [6] K. B. Bec, J. Grabska, C. W. Huck, "Near-infrared spectroscopy in
   bio-applications", Molecules 25, 2948 (2020), doi:10.3390/molecules25122948, Table 1
.. [7] M. Golic, K. Walsh, P. Lawson, "Short-wavelength near-infrared spectra of
   sucrose, glucose, and fructose with respect to sugar concentration and temperature",
   Appl. Spectrosc. 57, 139-145 (2003)
.. [8] R. Nachabe et al., "Estimation of biological chromophores using diffuse optical
   spectroscopy: benefit of extending the UV-VIS wavelength range to include 1000 to
   1600 nm", Biomed. Opt. Express 1, 1432-1442 (2010), doi:10.1364/BOE.1.001432
.. [9] R. Röttgers, D. McKee, C. Utschig, "Temperature and salinity correction
   coefficients for light absorption by water in the visible to infrared spectral
   region", Opt. Express 22, 25093-25108 (2014), doi:10.1364/OE.22.025093; tabulated in
   the WOPP v3 pure-water file (R. Röttgers, HZG, 2016; SOURCES.md)
.. [10] G. M. Hale, M. R. Querry, "Optical constants of water in the 200-nm to 200-um
   wavelength region", Appl. Opt. 12, 555-563 (1973), doi:10.1364/AO.12.000555
"""

from __future__ import annotations

import warnings

import numpy as np
from numpy.typing import ArrayLike

from .. import portable as pm
from ..data import load_spectrum
from ..exceptions import ConfigError

__all__ = [
    "WATER_SOURCES",
    "WATER_TABLE_TEMPERATURE_C",
    "WAVELENGTH_RANGE_NM",
    "water_mua_per_cm",
    "water_dmua_dt_per_cm_per_c",
    "water_mua_at_temperature_per_cm",
    "blood_mua_per_cm",
    "lipid_mua_per_cm",
    "melanosome_mua_per_cm",
    "skin_baseline_mua_per_cm",
    "glucose_mua_per_cm_per_mm",
    "GLUCOSE_BANDS_NM",
    "GLUCOSE_FIRST_OVERTONE_RELATIVE_PEAK",
    "LIPID_TABLE_END_NM",
]

#: Valid ``source`` names of :func:`water_mua_per_cm` -> packaged table.
WATER_SOURCES = {
    "kou1993": "water_kou1993",
    "segelstein1981": "water_segelstein1981",
    "hale_querry1973": "water_hale_querry1973",
    "palmer_williams1974": "water_palmer_williams1974",
}

#: Temperature of the water in each table of :data:`WATER_SOURCES` (the reference of
#: :func:`water_mua_at_temperature_per_cm`). [degC] Kou et al.: 22 degC (their abstract,
#: [1]_); Hale & Querry: 25 degC (their abstract, [10]_); Palmer & Williams: 27 degC (as
#: Kou et al. give it, their Fig. 1); Segelstein's compilation states none found here:
#: 25 degC is an assumption (SOURCES.md).
WATER_TABLE_TEMPERATURE_C = {
    "kou1993": 22.0,
    "segelstein1981": 25.0,
    "hale_querry1973": 25.0,
    "palmer_williams1974": 27.0,
}

#: Wavelength range the chromophore functions accept (every table covers it, except
#: the lipid table above :data:`LIPID_TABLE_END_NM`). [nm]
WAVELENGTH_RANGE_NM = (700.0, 1700.0)

#: van Veen's fat table ends here; above it the provisional digitised curve is used. [nm]
_LIPID_SWITCH_NM = 1098.0

#: The provisional lipid curve, the only lipid table above 1098 nm, ends here; above it
#: lipid mua is held at its value here (:func:`lipid_mua_per_cm`). [nm]
LIPID_TABLE_END_NM = 1597.85


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
        Wavelength, 700-1700. [nm]
    source : {'kou1993', 'segelstein1981', 'hale_querry1973', 'palmer_williams1974'}
        Which published table to use (they differ by up to 40 % at 940 nm; at
        1450-1650 nm Kou, Segelstein and Palmer-Williams agree within about 10 % and
        Hale-Querry is up to 23 % lower).

    Returns
    -------
    numpy.ndarray
        mua of water. [1/cm]

    References
    ----------
    Kou et al. 1993 [1]_, tabulated by S. Prahl (OMLC); Segelstein 1981; Hale & Querry
    1973 (Appl. Opt. 12, 555, doi:10.1364/AO.12.000555); Palmer & Williams 1974
    (J. Opt. Soc. Am. 64, 1107, doi:10.1364/JOSA.64.001107).

    Examples
    --------
    >>> round(float(water_mua_per_cm(1150.0)), 2)
    0.98
    >>> round(float(water_mua_per_cm(1550.0)), 1)
    11.9
    """
    if source not in WATER_SOURCES:
        raise ConfigError(f"unknown water source {source!r}; valid: {', '.join(WATER_SOURCES)}")
    return _interp(WATER_SOURCES[source], _check_wavelength(wavelength_nm))


def water_dmua_dt_per_cm_per_c(wavelength_nm: ArrayLike) -> np.ndarray:
    """Temperature coefficient of pure water's absorption coefficient, d(mua)/dT.

    Parameters
    ----------
    wavelength_nm : array_like
        Wavelength, 700-1700. [nm]

    Returns
    -------
    numpy.ndarray
        d(mua)/dT of liquid water. [1/(cm degC)]

    Notes
    -----
    Röttgers et al. [9]_ measured it spectrophotometrically over 400-2700 nm; the table is
    the WOPP v3 column (2 nm steps), linear in temperature. Warmer water's O-H bands move
    to shorter wavelengths: the coefficient is positive on their short-wavelength flanks
    (about 1306-1442 nm, 1104-1190 nm, 908-994 nm) and negative on the long ones
    (about -0.11 /(cm degC) at 1490 nm, -0.064 at 1550 nm, -0.029 at 1650 nm: -0.46,
    -0.57 and -0.49 % per degC of the same file's mua at 20 degC). An independent
    measurement at 2014 and 2090 nm (-0.259 and -0.104 /(cm K), 20-100 degC) agrees
    within 7 % (SOURCES.md).

    Examples
    --------
    >>> round(float(water_dmua_dt_per_cm_per_c(1450.0)), 4)
    -0.0366
    >>> round(float(water_dmua_dt_per_cm_per_c(1412.0)), 3)
    0.14
    """
    return _interp("water_dmua_dt_rottgers2014", _check_wavelength(wavelength_nm))


def water_mua_at_temperature_per_cm(
    wavelength_nm: ArrayLike, temperature_c: ArrayLike, source: str = "kou1993"
) -> np.ndarray:
    """Absorption coefficient of pure water at a temperature.

    mua(lambda, T) = mua_table(lambda) + d(mua)/dT (lambda) (T - T_table), with T_table
    the temperature of the chosen table (:data:`WATER_TABLE_TEMPERATURE_C`) and
    d(mua)/dT from Röttgers et al. [9]_ (:func:`water_dmua_dt_per_cm_per_c`).

    Parameters
    ----------
    wavelength_nm : array_like
        Wavelength, 700-1700. [nm]
    temperature_c : array_like
        Water temperature, 0-60 (the linear model's range, about the measurements'). [degC]
    source : str
        Water table (:data:`WATER_SOURCES`).

    Returns
    -------
    numpy.ndarray
        mua of water at ``temperature_c``. [1/cm]

    Examples
    --------
    >>> a22 = water_mua_at_temperature_per_cm(1550.0, 22.0)
    >>> bool(a22 == water_mua_per_cm(1550.0))
    True
    >>> round(float(water_mua_at_temperature_per_cm(1550.0, 33.0) / a22 - 1), 3)
    -0.059
    """
    t = np.asarray(temperature_c, dtype=float)
    bad = ~((t >= 0.0) & (t <= 60.0))
    if np.any(bad):
        first = float(t.flat[int(np.flatnonzero(bad.ravel())[0])])
        raise ConfigError(f"water temperature {first} degC is outside 0-60 degC, the "
                          "linear model's range")
    mua = water_mua_per_cm(wavelength_nm, source)
    return mua + water_dmua_dt_per_cm_per_c(wavelength_nm) * (
        t - WATER_TABLE_TEMPERATURE_C[source])


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
    for consistency (SOURCES.md); they need no molar extinction of haemoglobin (Prahl's
    compilation stops at 1000 nm). Above about 1400 nm whole blood absorbs like water
    (0.74-1.02 x pure water's mua at 1450-1700 nm; oxy and deoxy within 10 %); above
    1200 nm the compilation rests mainly on one data set (Friebel et al.; SOURCES.md).
    Linear mixing in S follows Jacques 2013 [5]_, Eq. 12.

    Examples
    --------
    >>> round(float(blood_mua_per_cm(850.0, 1.0)), 1)
    4.9
    >>> round(float(blood_mua_per_cm(1450.0, 1.0)), 1)
    24.1
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
    only table that covers the 1210 nm lipid band; probably from Nachabe et al. [8]_,
    not verified; see SOURCES.md) up to its end at 1597.85 nm
    (:data:`LIPID_TABLE_END_NM`).

    Above 1597.85 nm no lipid table was found. There lipid mua is **held at the curve's
    last value, 0.165 /cm** -- a stated assumption and a known underestimate: fat's
    absorption rises towards its CH2 first-overtone band at about 1720 nm (Bec et al.
    [6]_, Table 1: first C-H overtone of lipids 1610-1725 nm). Lipid enters the model
    only through the subcutis, under a dermis absorbing about 4 /cm (water) at
    1600-1700 nm, yet it still matters for thin skin: were fat's true mua at 1650 nm
    10 x the held value, the three-layer diffusion model's R at 3 mm would be 11 % lower
    for 1.58 mm skin and 31 % lower for 0.8 mm (SOURCES.md). A call that reaches above
    1597.85 nm warns (UserWarning).

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
    >>> import warnings
    >>> with warnings.catch_warnings():
    ...     warnings.simplefilter("ignore")
    ...     float(lipid_mua_per_cm(1650.0)) == float(lipid_mua_per_cm(1597.85))
    True
    """
    wl = _check_wavelength(wavelength_nm)
    if np.any(wl > LIPID_TABLE_END_NM):
        warnings.warn(
            f"lipid absorption above {LIPID_TABLE_END_NM:g} nm is not tabulated; it is held "
            f"at its {LIPID_TABLE_END_NM:g} nm value, "
            f"{float(load_spectrum('lipid_provisional')[1][-1]):.3g} /cm, an underestimate "
            "near the 1720 nm fat band (nirglucose/data/optics/SOURCES.md)",
            UserWarning,
            stacklevel=2,
        )
    # np.interp holds the last tabulated value beyond the table's end (the stated
    # assumption above LIPID_TABLE_END_NM)
    return np.where(
        wl <= _LIPID_SWITCH_NM,
        _interp("lipid_vanveen2004", wl),
        _interp("lipid_provisional", wl),
    )


def melanosome_mua_per_cm(wavelength_nm: ArrayLike) -> np.ndarray:
    """Absorption coefficient inside a melanosome, 6.6e11 lambda^-3.33 (Jacques 1998 [4]_).

    Above about 1100 nm the power law is an extrapolation of a fit to shorter
    wavelengths (no melanin table beyond it was found).

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
    0.244 /cm, held up to 1700 nm (an extrapolation; collagen's own NIR absorption was
    not found as a table, SOURCES.md).

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


#: Default peak of glucose's 1st C-H overtone band relative to the 2nd-overtone peak: an
#: assumption (a factor of 10 per overtone order), no published absorptivity having been
#: found (SOURCES.md); ``glucose.first_overtone_relative_peak`` moves it. [-]
GLUCOSE_FIRST_OVERTONE_RELATIVE_PEAK = 10.0

#: Glucose C-H overtone bands: (centre nm, 1/e half-width nm, peak relative to the
#: 2nd-overtone peak, C-H overtone order). Below 1300 nm (unchanged since the first
#: model): the 2nd C-H overtone about 1100-1200 nm and a weaker 3rd overtone about
#: 900-950 nm (SOURCES.md, Glucose section; Golic et al. [7]_ place the sugar C-H bands
#: at 910 nm). Added with the 1700 nm range: the 1st C-H overtone at 1670 nm, the middle
#: of the published 1610-1725 nm first-overtone C-H range of carbohydrates (Bec et al.
#: [6]_, Table 1), with the 2nd overtone's width. Positions are published
#: (``data/optics/glucose_band_positions.csv``; a test holds each centre within one
#: FWHM of one of them); shapes and magnitudes are assumptions: no public table of
#: glucose absorptivity was found. The relative peaks assume a factor of 10 per overtone
#: order (3rd : 2nd : 1st = 0.1 : 1 : 10), the factor the first model chose for 3rd : 2nd.
GLUCOSE_BANDS_NM = (
    (1150.0, 45.0, 1.0, 2),
    (920.0, 30.0, 0.1, 3),
    (1670.0, 45.0, GLUCOSE_FIRST_OVERTONE_RELATIVE_PEAK, 1),
)


def glucose_mua_per_cm_per_mm(
    wavelength_nm: ArrayLike,
    peak_per_cm_per_mm: float = 1.0e-4,
    first_overtone_relative_peak: float = GLUCOSE_FIRST_OVERTONE_RELATIVE_PEAK,
) -> np.ndarray:
    """Glucose's own absorption per mM, as Gaussian C-H overtone bands.

    Parameters
    ----------
    wavelength_nm : array_like
        Wavelength, 700-1700. [nm]
    peak_per_cm_per_mm : float
        Absorption at the 2nd C-H overtone peak (1150 nm) per mM. [1/(cm mM)]
    first_overtone_relative_peak : float
        Peak of the 1st C-H overtone band (1670 nm) relative to the 2nd-overtone peak
        (:data:`GLUCOSE_FIRST_OVERTONE_RELATIVE_PEAK`, an assumption). [-]

    Returns
    -------
    numpy.ndarray
        Specific absorption of glucose. [1/(cm mM)]

    Notes
    -----
    Order-of-magnitude model only (SOURCES.md: in the 1050-1150 nm window glucose's
    absorption per mM is of order 1e-4 of water's mua or smaller); the magnitude is a
    config parameter (``glucose.absorptivity_per_cm_per_mm``). The band positions are
    published (:data:`GLUCOSE_BANDS_NM`, [6]_, [7]_); the 1st-overtone band at 1670 nm,
    by default 10 x the 2nd-overtone peak, is an assumption (a factor of 10 per overtone
    order), not a measured absorptivity: none was found (SOURCES.md), so its height is a
    parameter (``first_overtone_relative_peak``, config
    ``glucose.first_overtone_relative_peak``) a study can move. Glucose's O-H overtones
    (about 1480-1540 nm, [6]_) are not modelled as bands: in water they act mainly
    through water displacement, which the tissue model carries separately.

    Examples
    --------
    >>> round(float(glucose_mua_per_cm_per_mm(1670.0, 1e-4)), 6)
    0.001
    >>> round(float(glucose_mua_per_cm_per_mm(1670.0, 1e-4, 3.0)), 6)
    0.0003
    """
    wl = _check_wavelength(wavelength_nm)
    if not first_overtone_relative_peak >= 0:
        raise ConfigError("first_overtone_relative_peak must be >= 0, got "
                          f"{first_overtone_relative_peak}")
    out = np.zeros_like(wl)
    for centre, width, rel, order in GLUCOSE_BANDS_NM:
        if order == 1:
            rel = float(first_overtone_relative_peak)
        out = out + rel * pm.exp(-(((wl - centre) / width) ** 2))
    return peak_per_cm_per_mm * out
