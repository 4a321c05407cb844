"""The photodiode as a part: material, responsivity curve, dark current, shunt, area.

A :class:`Detector` record names its responsivity table (a packaged file under
``data/parts/``, see its SOURCES.md) and carries the datasheet's scalars. With a
detector in the scenario (``detector="G17190-005K"``, :mod:`.parts`), each LED's
responsivity is the curve averaged over the LED's emission band
(:func:`band_responsivity_a_per_w`), its dark current and temperature law replace
``hardware.dark_current_*``, its active area ``optics.detector_area_mm2``, and its shunt
resistance adds Johnson noise beside the feedback resistor's. Without one (the default)
every value is as before.
"""

from __future__ import annotations

import csv
from functools import cache
from importlib import resources
from typing import Literal

import numpy as np
from pydantic import Field, field_validator

from .. import portable as pm
from ..exceptions import ConfigError
from ._base import _Model

__all__ = [
    "Detector",
    "RESPONSIVITY_TABLES",
    "band_responsivity_a_per_w",
    "responsivity_curve",
]

#: Packaged responsivity tables (``data/parts/``, SOURCES.md): file -> what it is.
RESPONSIVITY_TABLES = {
    "responsivity_ingaas_hamamatsu_g17190.csv": "Hamamatsu G17190 series InGaAs, typ.",
    "responsivity_ingaas_thorlabs_fga01.csv": "Thorlabs FGA01 InGaAs, typ.",
    "responsivity_si_vishay_bpw34.csv": "Vishay BPW34 Si, derived",
}
#: Share of an LED band's emission that may fall below a responsivity table's start
#: before the band is refused (beyond its long end the detector is blind, SOURCES.md). [-]
_MAX_WEIGHT_BELOW_TABLE = 0.01
#: Band integration: points over +-4 standard deviations of the emission. [-]
_BAND_GRID_POINTS = 161
_BAND_HALF_WIDTH_SD = 4.0


class Detector(_Model):
    """One photodiode: a catalogue row (``data/parts/detectors.csv``) or a user's record."""

    part: str = Field(..., min_length=1, description="Part name, e.g. G17190-005K. [-]")
    vendor: str = Field("", description="Maker. [-]")
    material: Literal["Si", "InGaAs"] = Field(..., description="Detector material. [-]")
    responsivity_table: str = Field(
        ...,
        description="Packaged responsivity table (data/parts/SOURCES.md), one of "
        f"{tuple(RESPONSIVITY_TABLES)}. [-]",
    )
    active_area_mm2: float = Field(
        ..., gt=0, le=100, description="Active area; replaces optics.detector_area_mm2. [mm^2]"
    )
    dark_current_25c_na: float = Field(
        ..., ge=0, le=1000, description="Typical dark current at 25 degC. [nA]"
    )
    dark_current_per_c: float = Field(
        ...,
        ge=0,
        le=0.2,
        description="k of the dark-current law I25 exp(k (T - 25)): ln of the datasheet's "
        "growth per degC (G17190: ln 1.09). [1/degC]",
    )
    shunt_resistance_mohm: float | None = Field(
        None,
        gt=0,
        le=1e6,
        description="Typical shunt resistance, its Johnson noise added to the feedback "
        "resistor's; None where the datasheet states none (no added noise). [MOhm]",
    )
    capacitance_pf: float | None = Field(
        None, gt=0, le=1e5, description="Typical terminal capacitance (recorded only). [pF]"
    )

    @field_validator("responsivity_table")
    @classmethod
    def _known_table(cls, v: str) -> str:
        if v not in RESPONSIVITY_TABLES:
            raise ValueError(
                f"unknown responsivity table {v!r}; valid: {', '.join(RESPONSIVITY_TABLES)}"
            )
        return v


@cache
def _read_table(filename: str) -> tuple[np.ndarray, np.ndarray]:
    text = resources.files("nirglucose.data").joinpath("parts", filename).read_text()
    rows = list(csv.reader(text.splitlines()))[1:]
    data = np.array([[float(a), float(b)] for a, b in rows if a.strip()])
    wl, r = data[:, 0].copy(), data[:, 1].copy()
    wl.setflags(write=False)
    r.setflags(write=False)
    return wl, r


def responsivity_curve(detector: Detector) -> tuple[np.ndarray, np.ndarray]:
    """``(wavelength_nm, responsivity_a_per_w)`` of a detector's packaged table.

    Examples
    --------
    >>> from nirglucose.config.parts import detector_part
    >>> wl, r = responsivity_curve(detector_part("BPW34"))
    >>> round(float(np.interp(950.0, wl, r)), 3)
    0.627
    """
    return _read_table(detector.responsivity_table)


def band_responsivity_a_per_w(
    wavelength_nm: float, fwhm_nm: float, curve: tuple[np.ndarray, np.ndarray]
) -> float:
    """Responsivity seen by an LED: the curve averaged over its Gaussian emission band.

    R_LED = int R(lambda) S(lambda) d lambda / int S(lambda) d lambda, S a Gaussian of the
    LED's FWHM (sigma = FWHM / (2 sqrt(2 ln 2))), R interpolated linearly in the table and
    zero beyond its long-wavelength end (the material's cut-off, data/parts/SOURCES.md).
    The photocurrent of a broadband source is the responsivity-weighted integral of its
    spectral power (Hamamatsu, "Photodiode technical information", spectral response;
    Horowitz & Hill, "The Art of Electronics", 3rd ed., 12.6).

    Parameters
    ----------
    wavelength_nm : float
        LED centre wavelength. [nm]
    fwhm_nm : float
        Emission full width at half maximum. [nm]
    curve : tuple of numpy.ndarray
        ``(wavelength_nm, responsivity_a_per_w)`` of the detector. [nm, A/W]

    Returns
    -------
    float
        Band-averaged responsivity. [A/W]

    Raises
    ------
    ConfigError
        More than 1 % of the band lies below the table's first wavelength.

    Examples
    --------
    A flat curve gives its value; a narrow band the value at the centre:

    >>> flat = (np.array([700.0, 1300.0]), np.array([0.5, 0.5]))
    >>> round(band_responsivity_a_per_w(900.0, 40.0, flat), 12)
    0.5
    >>> ramp = (np.array([700.0, 1300.0]), np.array([0.0, 0.6]))
    >>> round(band_responsivity_a_per_w(1000.0, 40.0, ramp), 9)
    0.3
    """
    wl, r = curve
    sigma = float(fwhm_nm) / (2.0 * np.sqrt(2.0 * float(pm.log(2.0))))
    x = np.linspace(-_BAND_HALF_WIDTH_SD, _BAND_HALF_WIDTH_SD, _BAND_GRID_POINTS)
    grid = float(wavelength_nm) + sigma * x
    weight = pm.exp(-0.5 * x * x)
    weight = weight / np.sum(weight)
    below = float(np.sum(weight[grid < wl[0]]))
    if below > _MAX_WEIGHT_BELOW_TABLE:
        raise ConfigError(
            f"the LED at {wavelength_nm:g} nm (FWHM {fwhm_nm:g} nm) emits {100 * below:.0f} % "
            f"of its power below {wl[0]:g} nm, where the detector's responsivity table starts; "
            "choose an LED within the detector's range or give responsivity_a_per_w"
        )
    resp = np.interp(grid, wl, r, left=float(r[0]), right=0.0)
    return float(pm.dot_last(resp, weight))
