"""Chromophore spectra over each LED's emission band, and tissue optical properties.

An LED emits a band, not a line: the detected power integrates the tissue's response
over the emission spectrum, modelled as a Gaussian of the LED's FWHM and integrated
with Gauss-Hermite quadrature. The chromophore spectra at the quadrature nodes (and
their wavelength derivatives, for the thermal shift of the LED's peak) are computed
once per scenario; the per-sample work is arithmetic on those small tables.

Tissue composition (Jacques 2013, Eq. 12; volume fractions from SOURCES.md):
mua = B [S mua_oxy + (1 - S) mua_deoxy] + W mua_water + F mua_fat
      + (1 - B - W - F) mua_baseline,
with glucose displacing water (-x_disp C of W), absorbing (W C eps_glc) and lowering
mus' (factor exp(k C)). Where the tissue state carries a water temperature, water's
absorption is taken at it: mua_water + s d(mua)/dT (T - T_table) (Röttgers et al. 2014,
:func:`~nirglucose.optics.absorption.water_mua_at_temperature_per_cm`), with s the
scale of the ``water_temperature`` switch folded into the ``water_dt`` table.

References
----------
.. [1] S. L. Jacques, "Optical properties of biological tissues: a review",
   Phys. Med. Biol. 58, R37-R61 (2013), doi:10.1088/0031-9155/58/11/R37
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from .. import portable as pm
from . import absorption, scattering

__all__ = ["BandSpectra", "band_spectra", "TissueState", "tissue_optics", "SUBCUTIS"]

#: Subcutis composition besides fat: water 0.1-0.3 and blood 0.01-0.05 (SOURCES.md
#: layer table); blood is taken as half the dermal fraction (an assumption).
SUBCUTIS = {"water_fraction": 0.2, "blood_ratio_to_dermis": 0.5}

_CHROMOPHORES = (
    "water",
    "blood_oxy",
    "blood_deoxy",
    "fat",
    "melanosome",
    "baseline",
    "glucose",
    "musp_skin",
    "musp_fat",
    "water_dt",
)


@dataclass(frozen=True)
class BandSpectra:
    """Chromophore spectra at the quadrature nodes of each LED band, shape (n_led, n_pts).

    ``weights`` sum to 1 over each LED's nodes; ``d_<name>`` is the derivative of
    ``<name>`` with respect to wavelength [per nm].
    """

    centre_nm: np.ndarray
    nodes_nm: np.ndarray
    weights: np.ndarray
    spectra: dict
    derivatives: dict


def band_spectra(
    centre_nm,
    fwhm_nm,
    n_points: int = 5,
    water_source: str = "kou1993",
    glucose_peak_per_cm_per_mm: float = 1.0e-4,
    *,
    glucose_first_overtone_relative_peak: float = absorption.GLUCOSE_FIRST_OVERTONE_RELATIVE_PEAK,
    water_temperature_scale: float = 0.0,
) -> BandSpectra:
    """Tabulate every chromophore over the LED bands.

    Parameters
    ----------
    centre_nm, fwhm_nm : sequence of float
        LED peak wavelengths and emission FWHM. [nm]
    n_points : int
        Gauss-Hermite nodes per LED. [-]
    water_source : str
        Water table (see :data:`absorption.WATER_SOURCES`).
    glucose_peak_per_cm_per_mm : float
        Glucose absorption at its 1150 nm band peak. [1/(cm mM)]
    glucose_first_overtone_relative_peak : float
        Glucose's 1670 nm band peak relative to the 1150 nm one. [-]
    water_temperature_scale : float
        Factor on water's temperature coefficient: the ``water_temperature`` switch
        (0: the table ``water_dt`` is zero). [-]

    Returns
    -------
    BandSpectra
        Its ``water_dt`` table is ``water_temperature_scale`` x d(mua)/dT of water
        [1/(cm degC)] (:func:`absorption.water_dmua_dt_per_cm_per_c`).
    """
    centre = np.asarray(centre_nm, dtype=float)[:, None]
    sigma = np.asarray(fwhm_nm, dtype=float)[:, None] / (2.0 * np.sqrt(2.0 * pm.log(2.0)))
    x, w = _hermgauss(int(n_points))
    nodes = centre + np.sqrt(2.0) * sigma * x[None, :]
    weights = np.broadcast_to(w / np.sqrt(np.pi), nodes.shape).copy()
    lo, hi = absorption.WAVELENGTH_RANGE_NM
    nodes = np.clip(nodes, lo + 1.0, hi - 1.0)  # tails of the band beyond the tables
    # the nodes and their +/- 1 nm neighbours (the derivatives) in one call per chromophore
    wl = np.stack([nodes, nodes + 1.0, nodes - 1.0])
    tab = {
        "water": absorption.water_mua_per_cm(wl, water_source),
        "blood_oxy": absorption.blood_mua_per_cm(wl, 1.0),
        "blood_deoxy": absorption.blood_mua_per_cm(wl, 0.0),
        "fat": absorption.lipid_mua_per_cm(wl),
        "melanosome": absorption.melanosome_mua_per_cm(wl),
        "baseline": absorption.skin_baseline_mua_per_cm(wl),
        "glucose": absorption.glucose_mua_per_cm_per_mm(
            wl, glucose_peak_per_cm_per_mm, glucose_first_overtone_relative_peak),
        "musp_skin": scattering.power_law_musp_per_cm(wl, *scattering.SKIN_MUSP),
        "musp_fat": scattering.power_law_musp_per_cm(wl, *scattering.FAT_MUSP),
        "water_dt": float(water_temperature_scale) * absorption.water_dmua_dt_per_cm_per_c(wl),
    }
    here = {k: v[0] for k, v in tab.items()}
    deriv = {k: 0.5 * (v[1] - v[2]) for k, v in tab.items()}
    return BandSpectra(np.asarray(centre_nm, float), nodes, weights, here, deriv)


@lru_cache(maxsize=8)
def _hermgauss(n_points: int) -> tuple[np.ndarray, np.ndarray]:
    """Gauss-Hermite nodes and weights (read-only; computed once per ``n_points``)."""
    x, w = np.polynomial.hermite.hermgauss(n_points)
    x.setflags(write=False)
    w.setflags(write=False)
    return x, w


@dataclass(frozen=True)
class TissueState:
    """Per-sample tissue composition, each an array of shape (n,).

    ``water_temperature_delta_c`` is the tissue water's temperature minus its table's
    (T - T_table, :data:`absorption.WATER_TABLE_TEMPERATURE_C`) [degC]; None (the
    default) takes water's absorption at the table's temperature.
    """

    blood_fraction: np.ndarray
    saturation: np.ndarray
    water_fraction: np.ndarray
    subcutis_fat_fraction: np.ndarray
    glucose_mm: np.ndarray
    water_temperature_delta_c: np.ndarray | None = None


def tissue_optics(
    spectra: BandSpectra,
    state: TissueState,
    *,
    water_displacement_per_mm: float,
    scattering_rel_per_mm: float,
    shift_nm: np.ndarray | float = 0.0,
) -> dict:
    """Absorption and reduced scattering of dermis and subcutis over the LED bands.

    Parameters
    ----------
    spectra : BandSpectra
        Tables from :func:`band_spectra`.
    state : TissueState
        Composition per sample.
    water_displacement_per_mm : float
        Fraction of water displaced per mM of glucose. [1/mM]
    scattering_rel_per_mm : float
        Relative change of mus' per mM of glucose. [1/mM]
    shift_nm : array_like
        Shift of each sample's LED peaks, shape (n,) or (n, n_led). [nm]

    Returns
    -------
    dict
        ``mua_dermis``, ``musp_dermis``, ``mua_subcutis``, ``musp_subcutis``, each
        (n, n_led, n_pts) [1/cm], ``melanosome`` (n, n_led, n_pts) and the flat
        ``baseline`` (1, n_led, n_pts) [1/cm].
    """
    n = np.shape(state.glucose_mm)[0]
    n_led, n_pts = spectra.nodes_nm.shape
    shift = _shift_per_node(shift_nm, n, n_led, n_pts)
    c = np.asarray(state.glucose_mm, dtype=float)
    b = np.asarray(state.blood_fraction, dtype=float)
    s = np.asarray(state.saturation, dtype=float)
    w = np.asarray(state.water_fraction, dtype=float)
    f_sub = np.asarray(state.subcutis_fat_fraction, dtype=float)
    # Each layer's mua is a per-sample mixture of the tabulated spectra: coefficients
    # (n, K) times the table (K, n_led * n_pts), plus the thermal-shift term
    # shift * (coefficients times the derivative table) -- two small matrix products
    # per layer instead of one broadcast pass per chromophore.
    disp = np.maximum(1.0 - water_displacement_per_mm * c, 0.0)  # water left [-]
    b_oxy = b * s
    coef_dermis = np.stack([b_oxy, b - b_oxy, w * disp, w * c, 1.0 - b - w], axis=1)
    b_sub = SUBCUTIS["blood_ratio_to_dermis"] * b
    w_sub = SUBCUTIS["water_fraction"]
    rest = np.maximum(1.0 - b_sub - w_sub - f_sub, 0.0)
    b_sub_oxy = b_sub * s
    coef_sub = np.stack(
        [b_sub_oxy, b_sub - b_sub_oxy, w_sub * disp, w_sub * c, f_sub, rest], axis=1
    )
    tables = _mixture_tables(spectra)
    mua_dermis = _mix(coef_dermis, *tables["dermis"], shift)
    mua_sub = _mix(coef_sub, *tables["subcutis"], shift)
    if state.water_temperature_delta_c is not None:
        # water at its temperature: + (water's coefficient) x delta T x d(mua)/dT
        dt = np.broadcast_to(np.asarray(state.water_temperature_delta_c, dtype=float), (n,))
        water_dt = _mix(None, *tables["water_dt"], shift, n)
        mua_dermis += (w * disp * dt)[:, None] * water_dt
        mua_sub += (w_sub * disp * dt)[:, None] * water_dt
    glc_scatter = scattering.glucose_scattering_factor(c, scattering_rel_per_mm)[:, None]
    musp_dermis = _mix(None, *tables["musp_skin"], shift, n)
    musp_dermis *= glc_scatter
    musp_sub = _mix(None, *tables["musp_fat"], shift, n)
    musp_sub *= glc_scatter
    shape = (n, n_led, n_pts)
    return {
        "mua_dermis": mua_dermis.reshape(shape),
        "musp_dermis": musp_dermis.reshape(shape),
        "mua_subcutis": mua_sub.reshape(shape),
        "musp_subcutis": musp_sub.reshape(shape),
        "melanosome": _mix(None, *tables["melanosome"], shift, n).reshape(shape),
        "baseline": spectra.spectra["baseline"][None],  # flat in the NIR: no shift
    }


#: Chromophores of each layer's absorption mixture, in the order of the coefficients
#: built in :func:`tissue_optics`.
_MIXTURES = {
    "dermis": ("blood_oxy", "blood_deoxy", "water", "glucose", "baseline"),
    "subcutis": ("blood_oxy", "blood_deoxy", "water", "glucose", "fat", "baseline"),
}


def _mixture_tables(spectra: BandSpectra) -> dict:
    """Per scenario: (table, derivative table) of each mixture, flattened over nodes.

    The baseline is flat in the NIR and is not shifted (zero derivative), as before.
    Memoised on the (immutable) spectra object.
    """
    cached = spectra.__dict__.get("_mixture_tables")
    if cached is not None:
        return cached
    tab, der = spectra.spectra, spectra.derivatives

    def rows(names):
        t = np.stack([np.ravel(tab[k]) for k in names])
        d = np.stack([np.zeros(t.shape[1]) if k == "baseline" else np.ravel(der[k])
                      for k in names])
        return np.ascontiguousarray(t), np.ascontiguousarray(d)

    out = {k: rows(v) for k, v in _MIXTURES.items()}
    for k in ("musp_skin", "musp_fat", "melanosome", "water_dt"):
        out[k] = (np.ravel(tab[k]).copy(), np.ravel(der[k]).copy())
    object.__setattr__(spectra, "_mixture_tables", out)  # frozen dataclass: a cache slot
    return out


def _shift_per_node(shift_nm, n: int, n_led: int, n_pts: int) -> np.ndarray | None:
    """The LED peak shift at every node, (n, n_led * n_pts), or None when zero."""
    shift = np.asarray(shift_nm, dtype=float)
    if shift.ndim == 0:
        return None if shift == 0.0 else np.full((n, n_led * n_pts), float(shift))
    if shift.ndim == 1:
        shift = shift[:, None]
    return np.repeat(np.broadcast_to(shift, (n, n_led)), n_pts, axis=1)


def _mix(coef, table, derivative, shift, n: int = 0) -> np.ndarray:
    """coef @ (table + shift * derivative), (n, n_nodes); ``coef`` None means one
    chromophore with coefficient 1 (first-order Taylor in the shift, a few nm at most)."""
    if coef is None:
        if shift is None:
            return np.broadcast_to(table, (n, table.size)).copy()
        out = shift * derivative
        out += table
        return out
    if shift is None:
        return pm.matmul(coef, table)
    # one product, (n, 2 n_nodes)
    both = pm.matmul(coef, np.concatenate([table, derivative], axis=1))
    m = table.shape[1]
    out = both[:, m:] * shift
    out += both[:, :m]
    return out
