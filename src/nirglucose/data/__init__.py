"""Packaged data tables (optical spectra with their sources; see optics/SOURCES.md)."""

from __future__ import annotations

import csv
from functools import cache
from importlib import resources

import numpy as np

__all__ = ["load_spectrum", "OPTICS_TABLES"]

#: Name -> (file, value unit) of every packaged optical table.
OPTICS_TABLES = {
    "water_kou1993": ("water_mua_kou1993.csv", "1/cm"),
    "water_segelstein1981": ("water_mua_segelstein1981.csv", "1/cm"),
    "water_hale_querry1973": ("water_mua_hale_querry1973.csv", "1/cm"),
    "water_palmer_williams1974": ("water_mua_palmer_williams1974.csv", "1/cm"),
    "hbo2_eps_prahl": ("hbo2_molar_extinction_prahl.csv", "cm^-1/M"),
    "hb_eps_prahl": ("hb_molar_extinction_prahl.csv", "cm^-1/M"),
    "blood_oxy_bosschaart2014": ("blood_oxy_mua_bosschaart2014.csv", "1/cm"),
    "blood_deoxy_bosschaart2014": ("blood_deoxy_mua_bosschaart2014.csv", "1/cm"),
    "lipid_vanveen2004": ("lipid_mua_vanveen2004.csv", "1/cm"),
    "lipid_provisional": ("lipid_mua_provisional_unattributed_digitized.csv", "1/cm"),
    "melanosome_jacques": ("melanosome_mua_jacques_powerlaw.csv", "1/cm"),
    "skin_musp_jacques2013": ("skin_musp_jacques2013.csv", "1/cm"),
    "water_dmua_dt_rottgers2014": ("water_dmua_dt_rottgers2014.csv", "1/(cm degC)"),
}


@cache
def load_spectrum(name: str) -> tuple[np.ndarray, np.ndarray]:
    """Return ``(wavelength_nm, value)`` of a packaged optical table.

    Parameters
    ----------
    name : str
        A key of :data:`OPTICS_TABLES`.

    Returns
    -------
    wavelength_nm, value : numpy.ndarray
        Read-only arrays, sorted by wavelength. Units of ``value`` are in
        :data:`OPTICS_TABLES`. Lines of the file that start with ``#`` (a table's
        source, written into the file) are skipped.

    Examples
    --------
    >>> wl, mua = load_spectrum("water_kou1993")
    >>> bool(wl[0] < 700 < 1700 < wl[-1])
    True
    """
    if name not in OPTICS_TABLES:
        valid = ", ".join(sorted(OPTICS_TABLES))
        raise KeyError(f"unknown optical table {name!r}; valid: {valid}")
    filename = OPTICS_TABLES[name][0]
    text = resources.files(__package__).joinpath("optics", filename).read_text()
    # lines starting with '#' carry a table's source; the first other line is the header
    lines = [line for line in text.splitlines() if not line.startswith("#")]
    rows = list(csv.reader(lines))[1:]
    data = np.array([[float(a), float(b)] for a, b in rows if a.strip()])
    wavelength_nm, value = data[:, 0].copy(), data[:, 1].copy()
    wavelength_nm.setflags(write=False)
    value.setflags(write=False)
    return wavelength_nm, value
