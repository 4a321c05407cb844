"""Compiled hot path of the ``beer-lambert`` model: tissue optics to band-averaged signal.

The simulator needs, for every snapshot and LED, the detected fraction of the LED's
power integrated over its emission band. The NumPy composition of
:func:`nirglucose.optics.tissue.tissue_optics`, the ``beer-lambert`` branch of
:func:`nirglucose.optics.forward.detected_fraction` and the band weights makes about 40
passes over (snapshots x LEDs x band nodes) arrays; this module does the same algebra in
one compiled pass per snapshot (numba), with no temporaries. It is an implementation
detail of :mod:`nirglucose.simulation.simulator`: the physics, units and citations live in
the NumPy functions above, which stay the reference (a test holds the two equal to
1e-12 relative).

Per snapshot i, LED l and band node p, with the node's peak shift s = shift[i, l] and
each tabulated spectrum X taken as X + s dX/dlambda (first-order Taylor, as
:func:`~nirglucose.optics.tissue.tissue_optics` does; the flat baseline is not shifted):

* dermis mua = B S oxy + B (1 - S) deoxy + W D water + W C glucose + (1 - B - W) base
  + W D dT water_dt, subcutis mua likewise with B/2, water 0.2, fat F and the rest
  baseline (Jacques 2013); dT the water's temperature offset from its table's and
  water_dt the (scaled) d(mua)/dT of water (Röttgers 2014), zero when the switch is off;
* mus' = table x exp(k C) (Maier 1994);
* dermal share of the path 1 - exp(-t 2 sqrt(2 / rho) mu_eff^(1/2)) (Weiss 1989),
  mua and mus' mixed by it;
* optical depth 4 d mua_epi + x^2 / (2 (1 + x)), x = rho sqrt(3 mua mus') (Fantini 1999);
* fraction = sum_p w_lp G_lp exp(-optical depth).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ... import portable as pm
from ...exceptions import ConfigError
from ...libm import exp_into
from ..lut import interpolate as lut_mod
from ..tissue import SUBCUTIS, BandSpectra

__all__ = ["band_detected_fraction", "band_detected_fraction_lut"]

#: Chromophore order of the stacked tables passed to the kernel.
_ORDER = ("blood_oxy", "blood_deoxy", "water", "glucose", "fat", "baseline",
          "musp_skin", "musp_fat", "melanosome", "water_dt")


@njit(cache=True, inline="always")
def _coefficients(b, s, w, f, c, x_disp_per_mm, k_scat_per_mm, blood_sub_ratio, water_sub):
    """Mixture coefficients of one snapshot: dermis (oxy, deoxy, water, glucose,
    baseline), subcutis (oxy, deoxy, water, glucose, fat, baseline), and the glucose
    scattering factor exp(k C) (see :func:`nirglucose.optics.tissue.tissue_optics`)."""
    disp = max(1.0 - x_disp_per_mm * c, 0.0)
    b_oxy = b * s
    bs = blood_sub_ratio * b
    bs_oxy = bs * s
    return (b_oxy, b - b_oxy, w * disp, w * c, 1.0 - b - w,
            bs_oxy, bs - bs_oxy, water_sub * disp, water_sub * c, f,
            max(1.0 - bs - water_sub - f, 0.0), np.exp(k_scat_per_mm * c))


@njit(cache=True, nogil=True)
def _coefficient_rows(blood, sat, water, fat_sub, glucose_mm, water_dt_c, x_disp_per_mm,
                      k_scat_per_mm, blood_sub_ratio, water_sub):  # pragma: no cover - compiled
    """Per snapshot, (14, n): the mixture coefficients (dermis rows 0-4, subcutis 5-10,
    see :func:`_coefficients`), water's temperature term (row 11 dermis: water's
    coefficient x dT; row 12 subcutis) and the glucose scattering factor (row 13)."""
    n = blood.shape[0]
    c = np.empty((14, n))
    for i in range(n):
        (c[0, i], c[1, i], c[2, i], c[3, i], c[4, i], c[5, i], c[6, i], c[7, i], c[8, i],
         c[9, i], c[10, i], c[13, i]) = _coefficients(
            blood[i], sat[i], water[i], fat_sub[i], glucose_mm[i], x_disp_per_mm,
            k_scat_per_mm, blood_sub_ratio, water_sub)
        c[11, i] = c[2, i] * water_dt_c[i]
        c[12, i] = c[7, i] * water_dt_c[i]
    return c


@njit(cache=True, inline="always")
def _node_spectra(tab, der, led, p):
    """One band node's tabulated spectra and wavelength derivatives, in :data:`_ORDER`
    (the flat baseline without one)."""
    return (tab[0, led, p], der[0, led, p], tab[1, led, p], der[1, led, p],
            tab[2, led, p], der[2, led, p], tab[3, led, p], der[3, led, p],
            tab[4, led, p], der[4, led, p], tab[5, led, p], tab[6, led, p], der[6, led, p],
            tab[7, led, p], der[7, led, p], tab[8, led, p], der[8, led, p],
            tab[9, led, p], der[9, led, p])


# error_model="numpy": a division by zero gives inf or NaN, as in NumPy, instead of
# raising, so the loops carry no check per value and vectorise (no divisor here is zero;
# the values are the same bits either way)
@njit(cache=True, nogil=True, error_model="numpy")
def _kernel(blood, sat, water, fat_sub, glucose_mm, water_dt_c, shift_t, melanin, skin_cm,
            tab, der, weight_geometry, x_disp_per_mm, k_scat_per_mm, rho_cm, epi_cm,
            blood_sub_ratio, water_sub, out_t):  # pragma: no cover - compiled
    n_led, n = out_t.shape
    n_pts = tab.shape[2]
    share_k = -2.0 * np.sqrt(2.0 / rho_cm)
    x2_k = 3.0 * rho_cm * rho_cm
    epi_k = 4.0 * epi_cm
    # Per snapshot: coefficients (:func:`_coefficient_rows`) and the share exponent's
    # thickness factor.
    c = _coefficient_rows(blood, sat, water, fat_sub, glucose_mm, water_dt_c, x_disp_per_mm,
                          k_scat_per_mm, blood_sub_ratio, water_sub)
    c0, c1, c2, c3, c4, c5, c6 = c[0], c[1], c[2], c[3], c[4], c[5], c[6]
    c7, c8, c9, c10, c11, c12, glc_scatter = c[7], c[8], c[9], c[10], c[11], c[12], c[13]
    t_k = share_k * skin_cm
    has_dt = np.any(water_dt_c != 0.0)
    out_t[:] = 0.0
    mua_d, mua_s, musp_d = np.empty(n), np.empty(n), np.empty(n)
    musp_s, epi, arg, e = np.empty(n), np.empty(n), np.empty(n), np.empty(n)
    work_r, work_t, work_k = np.empty(n), np.empty(n), np.empty(n, np.int64)
    # Node by node, in loops free of calls (which the compiler vectorises) around two
    # exponentials of the row (the C library's exp, vectorised: libm.exp_into).
    for led in range(n_led):
        sh_l = shift_t[led]
        out_l = out_t[led]
        for p in range(n_pts):
            (t_oxy, d_oxy, t_deo, d_deo, t_wat, d_wat, t_glc, d_glc, t_fat, d_fat, base,
             t_msd, d_msd, t_mss, d_mss, t_mel, d_mel, t_wdt, d_wdt) = _node_spectra(
                tab, der, led, p)
            wg = weight_geometry[led, p]
            for i in range(n):
                sh = sh_l[i]
                oxy = t_oxy + sh * d_oxy
                deoxy = t_deo + sh * d_deo
                wat = t_wat + sh * d_wat
                glc = t_glc + sh * d_glc
                md = c0[i] * oxy + c1[i] * deoxy + c2[i] * wat + c3[i] * glc + c4[i] * base
                ms = (c5[i] * oxy + c6[i] * deoxy + c7[i] * wat + c8[i] * glc
                      + c9[i] * (t_fat + sh * d_fat) + c10[i] * base)
                if has_dt:  # loop-invariant: the compiler makes two loops of this one
                    wdt = t_wdt + sh * d_wdt
                    md += c11[i] * wdt
                    ms += c12[i] * wdt
                mua_d[i] = md
                mua_s[i] = ms
                msd = (t_msd + sh * d_msd) * glc_scatter[i]
                musp_d[i] = msd
                musp_s[i] = (t_mss + sh * d_mss) * glc_scatter[i]
                epi[i] = epi_k * (base + melanin[i] * ((t_mel + sh * d_mel) - base))
                arg[i] = t_k[i] * np.sqrt(np.sqrt(3.0 * md * (md + msd)))
            exp_into(arg, e, work_r, work_t, work_k)
            for i in range(n):
                share = 1.0 - e[i]
                mua = mua_s[i] + share * (mua_d[i] - mua_s[i])
                musp = musp_s[i] + share * (musp_d[i] - musp_s[i])
                x2 = x2_k * mua * musp
                arg[i] = -(0.5 * x2 / (1.0 + np.sqrt(x2)) + epi[i])
            exp_into(arg, e, work_r, work_t, work_k)
            for i in range(n):
                out_l[i] += wg * e[i]


@njit(cache=True, nogil=True)
def _layers_kernel(blood, sat, water, fat_sub, glucose_mm, water_dt_c, shift_t, melanin, tab,
                   der, x_disp_per_mm, k_scat_per_mm, blood_sub_ratio, water_sub,
                   mua_d, mua_s, mua_e, musp_d, musp_s):  # pragma: no cover - compiled
    """The three layers' optics at every (node, snapshot), node-major (n_led * n_pts, n):
    :func:`nirglucose.optics.tissue.tissue_optics` then
    :func:`nirglucose.optics.layers.layers_from_tissue_optics`, in one pass."""
    n_led, n = shift_t.shape
    n_pts = tab.shape[2]
    c = _coefficient_rows(blood, sat, water, fat_sub, glucose_mm, water_dt_c, x_disp_per_mm,
                          k_scat_per_mm, blood_sub_ratio, water_sub)
    c0, c1, c2, c3, c4, c5, c6 = c[0], c[1], c[2], c[3], c[4], c[5], c[6]
    c7, c8, c9, c10, c11, c12, glc_scatter = c[7], c[8], c[9], c[10], c[11], c[12], c[13]
    for led in range(n_led):
        sh_l = shift_t[led]
        for p in range(n_pts):
            (t_oxy, d_oxy, t_deo, d_deo, t_wat, d_wat, t_glc, d_glc, t_fat, d_fat, base,
             t_msd, d_msd, t_mss, d_mss, t_mel, d_mel, t_wdt, d_wdt) = _node_spectra(
                tab, der, led, p)
            first = (led * n_pts + p) * n
            for i in range(n):  # a loop free of calls: vectorised
                sh = sh_l[i]
                oxy = t_oxy + sh * d_oxy
                deoxy = t_deo + sh * d_deo
                wat = t_wat + sh * d_wat
                glc = t_glc + sh * d_glc
                wdt = t_wdt + sh * d_wdt
                g = first + i
                mua_d[g] = (c0[i] * oxy + c1[i] * deoxy + c2[i] * wat + c3[i] * glc
                            + c4[i] * base + c11[i] * wdt)
                mua_s[g] = (c5[i] * oxy + c6[i] * deoxy + c7[i] * wat + c8[i] * glc
                            + c9[i] * (t_fat + sh * d_fat) + c10[i] * base + c12[i] * wdt)
                musp_d[g] = (t_msd + sh * d_msd) * glc_scatter[i]
                musp_s[g] = (t_mss + sh * d_mss) * glc_scatter[i]
                mua_e[g] = base + melanin[i] * ((t_mel + sh * d_mel) - base)


def _stacked(spectra: BandSpectra) -> tuple[np.ndarray, np.ndarray]:
    cached = spectra.__dict__.get("_kernel_tables")
    if cached is None:
        tab = np.ascontiguousarray(np.stack([spectra.spectra[k] for k in _ORDER]), dtype=float)
        der = np.ascontiguousarray(
            np.stack([np.zeros_like(spectra.spectra[k]) if k == "baseline"
                      else spectra.derivatives[k] for k in _ORDER]), dtype=float)
        cached = (tab, der)
        object.__setattr__(spectra, "_kernel_tables", cached)  # frozen dataclass: cache slot
    return cached


def _water_dt(state, n: int) -> np.ndarray:
    """The water's temperature offset per snapshot, (n,) [degC]; zeros where the state
    has none (its term then adds exactly 0 to each absorption)."""
    dt = getattr(state, "water_temperature_delta_c", None)
    if dt is None:
        return np.zeros(n)
    return np.ascontiguousarray(np.broadcast_to(np.asarray(dt, dtype=np.float64), (n,)))


def band_detected_fraction(
    spectra: BandSpectra,
    state,
    *,
    shift_nm: np.ndarray,
    melanin_fraction: np.ndarray,
    skin_thickness_cm: np.ndarray,
    epidermis_thickness_cm: float,
    separation_cm: float,
    geometry_factor: np.ndarray,
    water_displacement_per_mm: float,
    scattering_rel_per_mm: float,
) -> np.ndarray:
    """Band-averaged detected fraction of the ``beer-lambert`` model, (n, n_led).

    Equals ``einsum('nlp,lp->nl', detected_fraction('beer-lambert', tissue_optics(...)),
    spectra.weights)`` (to rounding).

    Parameters
    ----------
    spectra : BandSpectra
        Chromophore tables over the LED bands.
    state : TissueState
        Composition per snapshot, each (n,).
    shift_nm : array_like
        LED peak shift per snapshot and LED, broadcastable to (n, n_led). [nm]
    melanin_fraction : array_like
        Epidermal melanosome fraction, (n,). [-]
    skin_thickness_cm : array_like
        Epidermis + dermis thickness, (n,). [cm]
    epidermis_thickness_cm, separation_cm : float
        Probe geometry. [cm]
    geometry_factor : array_like
        G of the Beer-Lambert model, (n_led, n_pts). [-]
    water_displacement_per_mm, scattering_rel_per_mm : float
        Glucose's effect on water and on mus'. [1/mM]

    Returns
    -------
    numpy.ndarray
        Detected fraction. [-]
    """
    n_led = spectra.nodes_nm.shape[0]

    def vec(a, n=None):
        a = np.asarray(a, dtype=np.float64)
        if n is not None and a.shape != n:  # broadcast only what needs it (the inversions
            a = np.broadcast_to(a, n)  # call this ~10^4 times a fit: the call costs)
        return np.ascontiguousarray(a)

    glucose = vec(state.glucose_mm)
    n = glucose.shape[0]
    shift = np.asarray(shift_nm, dtype=np.float64)
    if shift.ndim == 1:
        shift = shift[:, None]
    tab, der = _stacked(spectra)
    out_t = np.empty((n_led, n))
    _kernel(
        vec(state.blood_fraction, (n,)), vec(state.saturation, (n,)),
        vec(state.water_fraction, (n,)), vec(state.subcutis_fat_fraction, (n,)), glucose,
        _water_dt(state, n), vec(np.broadcast_to(shift, (n, n_led)).T),
        vec(melanin_fraction, (n,)),
        vec(skin_thickness_cm, (n,)),
        tab, der, vec(np.asarray(spectra.weights) * np.asarray(geometry_factor)),
        float(water_displacement_per_mm), float(scattering_rel_per_mm), float(separation_cm),
        float(epidermis_thickness_cm), float(SUBCUTIS["blood_ratio_to_dermis"]),
        float(SUBCUTIS["water_fraction"]), out_t,
    )
    return out_t.T


def band_detected_fraction_lut(
    spectra: BandSpectra,
    state,
    *,
    shift_nm: np.ndarray,
    melanin_fraction: np.ndarray,
    skin_thickness_cm: np.ndarray,
    node_lut,
    detector_area_cm2: float,
    water_displacement_per_mm: float,
    scattering_rel_per_mm: float,
) -> np.ndarray:
    """Band-averaged detected fraction of the ``rte-lut`` model, (n, n_led).

    The layer optics in one compiled pass, then the table kernel
    (:func:`nirglucose.optics.kernels.lut_kernel.node_reflectance`), then the band weights:
    equal (to rounding) to weighting ``detected_fraction('rte-lut', tissue_optics(...))``
    over each band. Parameters as :func:`band_detected_fraction`, with ``node_lut`` the
    :class:`~nirglucose.optics.lut.NodeLUT` of the scenario's band nodes (or a tuple of
    one per LED, each for that LED's nodes, where the bands need different grids) and
    ``detector_area_cm2`` the photodiode area [cm^2].

    Raises
    ------
    ConfigError
        If a snapshot's optics fall outside the table (the message names the axis).
    """
    n_led, n_pts = spectra.nodes_nm.shape
    tables = node_lut if isinstance(node_lut, tuple) else (node_lut,)
    want = [(1, n_pts)] * n_led if isinstance(node_lut, tuple) else [(n_led, n_pts)]
    if [tuple(t.node_shape) for t in tables] != want:
        raise ConfigError(f"the node tables are for nodes "
                          f"{[tuple(t.node_shape) for t in tables]}, the LED bands have "
                          f"{(n_led, n_pts)}")

    def vec(a, shape):
        return np.ascontiguousarray(np.broadcast_to(np.asarray(a, dtype=np.float64), shape))

    glucose = np.ascontiguousarray(state.glucose_mm, dtype=np.float64)
    n = glucose.shape[0]
    shift = np.asarray(shift_nm, dtype=np.float64)
    if shift.ndim == 1:
        shift = shift[:, None]
    tab, der = _stacked(spectra)
    k = n_led * n_pts
    mua_d, mua_s, mua_e, musp_d, musp_s = (np.empty(n * k) for _ in range(5))
    _layers_kernel(
        vec(state.blood_fraction, (n,)), vec(state.saturation, (n,)),
        vec(state.water_fraction, (n,)), vec(state.subcutis_fat_fraction, (n,)), glucose,
        _water_dt(state, n), vec(np.broadcast_to(shift, (n, n_led)).T, (n_led, n)),
        vec(melanin_fraction, (n,)),
        tab, der,
        float(water_displacement_per_mm), float(scattering_rel_per_mm),
        float(SUBCUTIS["blood_ratio_to_dermis"]), float(SUBCUTIS["water_fraction"]),
        mua_d, mua_s, mua_e, musp_d, musp_s,
    )
    t_cm = vec(skin_thickness_cm, (n,))
    # one table for every LED, or one per LED (node-major inputs: LED i's rows are one
    # contiguous block)
    shape = (n_led, n_pts, n) if len(tables) == 1 else (1, n_pts, n)
    per = k * n // len(tables)
    out = np.concatenate([
        _table_reflectance(t, shape, t_cm, *(a[i * per:(i + 1) * per] for a in (
            mua_d, mua_s, mua_e, musp_d, musp_s)))
        for i, t in enumerate(tables)])
    weights = np.asarray(spectra.weights) * float(detector_area_cm2)
    return (weights.reshape(k, 1) * out.reshape(k, n)).reshape(n_led, n_pts, n).sum(axis=1).T


def _table_reflectance(node_lut, shape, t_cm, mua_d, mua_s, mua_e, musp_d, musp_s):
    """R(rho) of every (node, row) from the node table, node-major, (n_led * n_pts * n,).

    Outside the table the NumPy reference path names the axis and raises ConfigError.
    """
    from .lut_kernel import node_reflectance

    n_led, n_pts, n = shape
    ln_t = pm.log(t_cm)  # once per call: every node's kernel call reads the same rows
    k = n_led * n_pts
    out = np.empty(n * k)
    # node by node: each call reads one node's table (a few MB, cache-resident), where
    # row-major points would jump between all the nodes' tables
    table, n_cells, ratio, axis_f, axis_i = lut_mod._node_kernel_args(node_lut)
    bad = -1
    for node in range(k):
        rows = slice(node * n, (node + 1) * n)
        bad = node_reflectance(table[node * n_cells:(node + 1) * n_cells], n_cells,
                               ratio[node:node + 1], axis_f, axis_i, mua_d[rows], mua_s[rows],
                               mua_e[rows], ln_t, musp_s[rows], musp_d[rows], out[rows])
        if bad >= 0:
            break
    if bad >= 0:  # outside the table: the reference path names the axis and raises
        def rowmajor(a):
            return a.reshape(n_led, n_pts, n).transpose(2, 0, 1)

        lut_mod._interpolate_node_lut_numpy(
            node_lut, mua_epidermis_per_cm=rowmajor(mua_e), mua_dermis_per_cm=rowmajor(mua_d),
            musp_dermis_per_cm=rowmajor(musp_d), mua_subcutis_per_cm=rowmajor(mua_s),
            musp_subcutis_per_cm=rowmajor(musp_s), skin_thickness_cm=t_cm,
        )
        raise ConfigError("the skin optics fall outside the look-up table")  # pragma: no cover
    return out
