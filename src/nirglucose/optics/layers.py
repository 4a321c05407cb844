"""Three-layer skin: layer optical properties and layered light transport.

Skin is modelled as an epidermis (melanin) over a dermis (blood, water) over a
semi-infinite subcutis (fat), with the thicknesses and volume fractions of the
SOURCES.md layer table (Meglinski & Matcher 2002; Jacques 1998, 2013). The optical
properties of each layer are built from the same chromophore tables the simulator uses
(:mod:`nirglucose.optics.tissue`), so the layered model and the fast forward models
see the same tissue.

Light transport: steady-state diffusion in N plane-parallel layers, solved exactly in
the spatial-frequency (Hankel) domain (Kienle et al. 1998; Liemert & Kienle 2010) and
transformed back by a fixed Gauss-Legendre quadrature. Every layer shares the
refractive index ``n_tissue``; the top surface has the partial-current (Robin) boundary
condition with the Groenhuis coefficient A, the bottom layer is semi-infinite. The
pencil beam is an isotropic point source one transport mean free path deep, attenuated
on its way there. The mean partial path length in each layer follows from the
microscopic Beer-Lambert law, L_i = -d ln R / d mua_i (exact for this model because the
diffusion coefficient D = 1/(3 mus') does not depend on mua), computed by a forward
finite difference, so the partial paths sum to the total mean path by construction.

Accuracy against Monte Carlo (the radiative transport equation), measured with
``nirglucose_reference.mc_paths.mc_detected_paths``, is given in the README section
"Layered skin optics" and checked by the slow tests.

References
----------
.. [1] I. V. Meglinski, S. J. Matcher, "Quantitative assessment of skin layers absorption
   and skin reflectance spectra simulation in the visible and near-infrared spectral
   regions", Physiol. Meas. 23, 741-753 (2002), doi:10.1088/0967-3334/23/4/312
.. [2] S. L. Jacques, "Optical properties of biological tissues: a review",
   Phys. Med. Biol. 58, R37-R61 (2013), doi:10.1088/0031-9155/58/11/R37
.. [3] A. Kienle, M. S. Patterson, N. Dognitz, R. Bays, G. Wagnieres, H. van den Bergh,
   "Noninvasive determination of the optical properties of two-layered turbid media",
   Appl. Opt. 37, 779-791 (1998), doi:10.1364/AO.37.000779
.. [4] A. Liemert, A. Kienle, "Light diffusion in N-layered turbid media: steady-state
   domain", J. Biomed. Opt. 15, 025003 (2010), doi:10.1117/1.3368682
.. [5] L. Wang, S. L. Jacques, L. Zheng, "MCML - Monte Carlo modeling of light transport
   in multi-layered tissues", Comput. Methods Programs Biomed. 47, 131-146 (1995),
   doi:10.1016/0169-2607(95)01640-F
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.special import j0

from .. import portable as pm
from ..exceptions import ConfigError
from . import skin, tissue
from .diffusion import boundary_coefficient

__all__ = [
    "LAYER_NAMES",
    "SKIN_LAYERS",
    "skin_layer_optics",
    "layers_from_tissue_optics",
    "layered_diffusion_reflectance",
    "three_layer_reflectance",
]

#: Layer names, top first; the order of every per-layer axis in this package.
LAYER_NAMES = ("epidermis", "dermis", "subcutis")

#: Typical layer geometry and composition (SOURCES.md layer table: Meglinski & Matcher
#: 2002 [1]_, Jacques 1998 and 2013 [2]_). Ranges are (low, high); ``typical`` values
#: are the ones this package uses when a caller gives none. Thickness in mm, fractions
#: are volume fractions. The subcutis is modelled as semi-infinite (it is 1-30 mm thick,
#: deeper than the light detected a few mm from the source reaches).
SKIN_LAYERS: dict[str, dict[str, object]] = {
    "epidermis": {
        "thickness_mm": (0.05, 0.10),
        "thickness_mm_typical": 0.08,
        "melanosome_fraction": {"light": (0.01, 0.03), "moderate": (0.11, 0.16),
                                "dark": (0.18, 0.43)},
        "blood_fraction": 0.0,
        "refractive_index": 1.4,
    },
    "dermis": {
        "thickness_mm": (1.0, 2.0),
        "thickness_mm_typical": 1.5,
        "blood_fraction": (0.002, 0.05),
        "blood_fraction_typical": 0.02,
        "saturation": (0.6, 0.8),
        "saturation_typical": 0.7,
        "water_fraction": (0.6, 0.7),
        "water_fraction_typical": 0.65,
        "refractive_index": 1.4,
    },
    "subcutis": {
        "thickness_mm": (1.0, 30.0),
        "blood_fraction": (0.01, 0.05),
        "water_fraction": (0.1, 0.3),
        "fat_fraction": (0.7, 0.9),
        "fat_fraction_typical": 0.8,
        "refractive_index": 1.44,
    },
}

#: Gauss-Legendre points per half period of J0(k rho) in the inverse Hankel transform.
_GAUSS_POINTS = 8
#: The transform is truncated at k_max = _K_MAX_PER_MUSP * mus' of the top layer, where
#: the integrand has decayed by about exp(-k / mus') = exp(-15). With 8 points per half
#: period the quadrature error is below 3e-5 (relative) over the LUT's parameter box.
_K_MAX_PER_MUSP = 15.0
#: Finite-difference step in mua for the partial paths (truncation error ~ step x the
#: path variance, below 1e-4 cm; rounding error below 1e-8 cm). [1/cm]
_MUA_STEP_PER_CM = 1e-4
#: Points x k-nodes per block of the vectorised solve (bounds the temporaries' memory).
_BLOCK_ELEMENTS = 1 << 20


def skin_layer_optics(
    wavelength_nm: ArrayLike,
    *,
    melanin_fraction: ArrayLike,
    blood_fraction: ArrayLike = 0.02,
    saturation: ArrayLike = 0.7,
    water_fraction: ArrayLike = 0.65,
    subcutis_fat_fraction: ArrayLike = 0.8,
    glucose_mm: ArrayLike = 0.0,
    water_source: str = "kou1993",
) -> dict[str, NDArray[np.float64]]:
    """Absorption and reduced scattering of the three skin layers at given wavelengths.

    Uses the chromophore tables and composition rules of the simulator
    (:func:`nirglucose.optics.tissue.tissue_optics`, Jacques 2013 [2]_ Eq. 12); the
    epidermis is f_mel mua_melanosome + (1 - f_mel) mua_baseline and scatters like the
    dermis (Jacques 2013 skin power law), the subcutis like fat.

    Parameters
    ----------
    wavelength_nm : array_like
        Wavelengths, 1-D, within 700-1700 nm. [nm]
    melanin_fraction : array_like
        Epidermal melanosome volume fraction per sample, scalar or (n,). [-]
    blood_fraction, saturation, water_fraction : array_like, optional
        Dermal blood volume fraction, its oxygen saturation and the dermal water
        fraction, scalar or (n,). [-]
    subcutis_fat_fraction : array_like, optional
        Fat volume fraction of the subcutis, scalar or (n,). [-]
    glucose_mm : array_like, optional
        Interstitial glucose, scalar or (n,). [mM]
    water_source : str, optional
        Water absorption table (see :data:`nirglucose.optics.absorption.WATER_SOURCES`).

    Returns
    -------
    dict
        ``mua_epidermis``, ``mua_dermis``, ``musp_dermis``, ``mua_subcutis``,
        ``musp_subcutis``, each (n, n_wavelengths). [1/cm]

    References
    ----------
    .. [1] I. V. Meglinski, S. J. Matcher, Physiol. Meas. 23, 741-753 (2002),
       doi:10.1088/0967-3334/23/4/312
    .. [2] S. L. Jacques, Phys. Med. Biol. 58, R37-R61 (2013),
       doi:10.1088/0031-9155/58/11/R37

    Examples
    --------
    >>> o = skin_layer_optics([850.0], melanin_fraction=0.02)
    >>> round(float(o["musp_dermis"][0, 0]), 1), round(float(o["mua_epidermis"][0, 0]), 2)
    (21.6, 2.56)
    """
    wl = np.atleast_1d(np.asarray(wavelength_nm, dtype=float))
    if wl.ndim != 1:
        raise ConfigError(f"wavelength_nm must be 1-D, got shape {wl.shape}")
    spectra = tissue.band_spectra(wl, np.ones_like(wl), 1, water_source)
    cols = np.broadcast_arrays(
        *(np.atleast_1d(np.asarray(v, dtype=float)) for v in (
            melanin_fraction, blood_fraction, saturation, water_fraction,
            subcutis_fat_fraction, glucose_mm))
    )
    mel, blood, sat, water, fat, glc = cols
    state = tissue.TissueState(blood, sat, water, fat, glc)
    optics = tissue.tissue_optics(
        spectra, state, water_displacement_per_mm=1.1e-4, scattering_rel_per_mm=-1.25e-3
    )
    out = layers_from_tissue_optics(optics, mel)
    return {k: v[..., 0] for k, v in out.items()}


def layers_from_tissue_optics(
    optics: dict, melanin_fraction: ArrayLike
) -> dict[str, NDArray[np.float64]]:
    """The three layers' optical properties from the simulator's tissue optics.

    Parameters
    ----------
    optics : dict
        Output of :func:`nirglucose.optics.tissue.tissue_optics`, arrays (n, ...). [1/cm]
    melanin_fraction : array_like
        Epidermal melanosome fraction, (n,). [-]

    Returns
    -------
    dict
        ``mua_epidermis`` (Jacques 1998, via :func:`nirglucose.optics.skin.epidermis_mua_per_cm`),
        ``mua_dermis``, ``musp_dermis``, ``mua_subcutis``, ``musp_subcutis``, each of
        the shape of ``optics["mua_dermis"]``. [1/cm]

    References
    ----------
    .. [1] S. L. Jacques, Phys. Med. Biol. 58, R37-R61 (2013),
       doi:10.1088/0031-9155/58/11/R37
    """
    mua_d = np.asarray(optics["mua_dermis"])
    mel = np.asarray(melanin_fraction, dtype=float)
    mel = mel.reshape(mel.shape + (1,) * (mua_d.ndim - mel.ndim))
    mua_e = skin.epidermis_mua_per_cm(mel, optics["melanosome"], optics["baseline"])
    return {
        "mua_epidermis": np.broadcast_to(mua_e, mua_d.shape),
        "mua_dermis": mua_d,
        "musp_dermis": np.asarray(optics["musp_dermis"]),
        "mua_subcutis": np.asarray(optics["mua_subcutis"]),
        "musp_subcutis": np.asarray(optics["musp_subcutis"]),
    }


# ----------------------------------------------------------------------------- transport


@lru_cache(maxsize=32)
def _hankel_rule(rho_cm: float, k_max: float) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Nodes k and weights w with sum(w f(k)) = (1/2 pi) int_0^k_max f(k) J0(k rho) k dk."""
    panel = np.pi / rho_cm
    n_panels = max(int(np.ceil(k_max / panel)), 4)
    x, w = np.polynomial.legendre.leggauss(_GAUSS_POINTS)
    a = panel * np.arange(n_panels)[:, None]
    k = (a + 0.5 * panel * (x + 1.0)).ravel()
    wk = np.tile(0.5 * panel * w, n_panels)
    return k, wk * k * j0(k * rho_cm) / (2.0 * np.pi)


def _tanh_sech(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """tanh and sech of x >= 0, overflow-free."""
    e = pm.exp(-x)
    e2 = e * e
    return (1.0 - e2) / (1.0 + e2), 2.0 * e / (1.0 + e2)


def _surface_flux_hat(
    k: np.ndarray,
    mua: np.ndarray,
    musp: np.ndarray,
    ztop: np.ndarray,
    zbot: np.ndarray,
    a_coef: float,
    r_specular: float,
) -> np.ndarray:
    """Hankel transform of the surface flux, (N, K), for N stacks of L layers.

    ``mua``, ``musp``, ``ztop``, ``zbot``: (N, L), with ``zbot[:, -1] = inf``.
    """
    n_layers = mua.shape[1]
    d = 1.0 / (3.0 * musp)  # [4], D = 1/(3 mus') (absorption-independent)
    z0 = 1.0 / musp[:, 0]  # source one transport mean free path deep
    seg = np.clip(np.minimum(zbot, z0[:, None]) - ztop, 0.0, None)
    source = (1.0 - r_specular) * pm.exp(-(mua * seg).sum(axis=1))  # ballistic leg
    kk = (k * k)[None, :]
    # downward from the Robin boundary, Y = D phi'/phi = 1/(2A) at z = 0, to the source
    y = np.full((mua.shape[0], k.size), 1.0 / (2.0 * a_coef))
    ratio = np.ones_like(y)  # phi(0) / phi(z0)
    alphas = []
    for i in range(n_layers):
        alpha = np.sqrt(kk + (mua[:, i] / d[:, i])[:, None])
        alphas.append(alpha)
        da = d[:, i, None] * alpha
        h = np.clip(np.minimum(zbot[:, i], z0) - ztop[:, i], 0.0, None)[:, None]
        if not np.any(h):
            continue
        th, sh = _tanh_sech(alpha * h)
        c = y / da
        den = 1.0 + c * th
        ratio = ratio * sh / den
        y = da * (c + th) / den
    y_up = y
    # upward from the semi-infinite bottom, Y = -D alpha, to the source
    y = -d[:, -1, None] * alphas[-1]
    for i in range(n_layers - 2, -1, -1):
        h = np.clip(zbot[:, i] - np.maximum(ztop[:, i], z0), 0.0, None)[:, None]
        if not np.any(h):
            continue
        da = d[:, i, None] * alphas[i]
        th, _ = _tanh_sech(alphas[i] * h)
        c = y / da
        y = da * (c - th) / (1.0 - c * th)
    phi_source = source[:, None] / (y_up - y)  # flux jump of the unit point source
    return phi_source * ratio / (2.0 * a_coef)  # flux D phi'(0) = phi(0) / (2A)


def _check(name: str, v: np.ndarray, unit: str, low: float, *, strict: bool) -> None:
    ok = np.isfinite(v) & ((v > low) if strict else (v >= low))
    if not np.all(ok):
        bad = v[~ok].flat[0]
        lb = "(" if strict else "["
        raise ConfigError(
            f"{name} = {bad!r} is out of range; valid range is {lb}{low:g}, inf) [{unit}]"
        )


def layered_diffusion_reflectance(
    rho_cm: float,
    mua_per_cm: ArrayLike,
    musp_per_cm: ArrayLike,
    thickness_cm: ArrayLike,
    n_tissue: float = 1.4,
    n_ambient: float = 1.0,
    *,
    pathlengths: bool = True,
    validate: bool = True,
) -> tuple[NDArray[np.float64], NDArray[np.float64] | None]:
    r"""Diffuse reflectance at one distance, and the path in each layer, of layered tissue.

    Parameters
    ----------
    rho_cm : float
        Source-detector distance on the surface, ``> 0``. [cm]
    mua_per_cm : array_like
        Absorption coefficient of each layer, top first, shape (..., L), ``>= 0``. [1/cm]
    musp_per_cm : array_like
        Reduced scattering coefficient of each layer, (..., L), ``> 0``. [1/cm]
    thickness_cm : array_like
        Thickness of the first L - 1 layers, (..., L - 1), ``> 0``; the last layer is
        semi-infinite. [cm]
    n_tissue : float, optional
        Refractive index of every layer. Default 1.4. [-]
    n_ambient : float, optional
        Refractive index above the surface; ``n_tissue / n_ambient`` in [1, 2].
        Default 1.0. [-]
    pathlengths : bool, optional
        Also return the mean path of the detected light in each layer (one more
        solve per layer). Default True.
    validate : bool, optional
        Check the ranges. Default True.

    Returns
    -------
    reflectance_per_cm2 : ndarray
        Diffuse reflectance R(rho) per incident photon, shape (...). [1/cm^2]
    pathlength_cm : ndarray or None
        Mean partial path length in each layer, (..., L); None unless ``pathlengths``. [cm]

    Raises
    ------
    ConfigError
        If an input is out of range.

    Notes
    -----
    In layer i the Hankel transform of the fluence obeys
    :math:`D_i(\partial_z^2 - \alpha_i^2)\hat\phi = -S\,\delta(z - z_0)` with
    :math:`\alpha_i^2 = k^2 + \mu_{a,i}/D_i`, :math:`D_i = 1/(3\mu'_{s,i})`; fluence and
    flux are continuous at the interfaces, :math:`\hat\phi = 2AD_1\partial_z\hat\phi`
    at the surface, and :math:`\hat\phi \to 0` at depth [3]_ [4]_. The admittance
    :math:`Y = D\partial_z\hat\phi/\hat\phi` is carried through each layer of
    thickness h with :math:`Y \mapsto D\alpha\,(Y/D\alpha \pm \tanh\alpha h)/(1 \pm
    (Y/D\alpha)\tanh\alpha h)` from the surface down and from the bottom up to the
    source at :math:`z_0 = 1/\mu'_{s,1}`, where :math:`\hat\phi(z_0) = S/(Y_\uparrow -
    Y_\downarrow)`; the source strength :math:`S = (1 - R_{sp})\exp(-\sum_i \mu_{a,i}
    \ell_i)` counts the specular loss and the absorption along the ballistic leg
    :math:`\ell_i` in each layer. The reflectance is the surface flux

    .. math:: R(\rho) = \frac{1}{2\pi}\int_0^\infty \frac{\hat\phi(k, 0)}{2A}
              J_0(k\rho)\,k\,dk,

    integrated with 8 Gauss-Legendre points per half period of :math:`J_0` up to
    :math:`k = 15\,\mu'_{s,1}` (relative error below 3e-5). Partial paths:
    :math:`L_i = -\partial\ln R/\partial\mu_{a,i}` (microscopic Beer-Lambert law [4]_),
    by a forward difference of step 1e-4 /cm. For identical layers
    this is the homogeneous semi-infinite solution with the partial-current boundary
    (about 15-20 % above Farrell's extrapolated-boundary dipole at 3 mm, and closer to
    Monte Carlo).

    References
    ----------
    .. [1] A. Kienle et al., Appl. Opt. 37, 779-791 (1998), doi:10.1364/AO.37.000779
    .. [2] A. Liemert, A. Kienle, J. Biomed. Opt. 15, 025003 (2010),
       doi:10.1117/1.3368682
    .. [3] R. C. Haskell, L. O. Svaasand, T.-T. Tsay, T.-C. Feng, M. S. McAdams,
       B. J. Tromberg, "Boundary conditions for the diffusion equation in radiative
       transfer", J. Opt. Soc. Am. A 11, 2727-2741 (1994), doi:10.1364/JOSAA.11.002727
    .. [4] A. Sassaroli, S. Fantini, "Comment on the modified Beer-Lambert law for
       scattering media", Phys. Med. Biol. 49, N255-N257 (2004),
       doi:10.1088/0031-9155/49/14/N07

    Examples
    --------
    >>> r, path = layered_diffusion_reflectance(0.3, [0.3, 0.3], [20.0, 20.0], [0.1])
    >>> round(float(r), 4), round(float(path.sum()), 3)
    (0.2836, 1.504)
    """
    rho = float(rho_cm)
    mua = np.asarray(mua_per_cm, dtype=float)
    musp = np.asarray(musp_per_cm, dtype=float)
    thick = np.asarray(thickness_cm, dtype=float)
    if mua.ndim == 0 or mua.shape[-1] < 1:
        raise ConfigError("mua_per_cm needs a last axis with one value per layer")
    n_layers = mua.shape[-1]
    batch = np.broadcast_shapes(mua.shape[:-1], musp.shape[:-1] if musp.ndim else (),
                                thick.shape[:-1] if thick.ndim else ())
    n_points = int(np.prod(batch))
    mua = np.broadcast_to(mua, batch + (n_layers,)).reshape(n_points, n_layers)
    musp = np.broadcast_to(musp, batch + (n_layers,)).reshape(n_points, n_layers)
    thick = np.broadcast_to(thick, batch + (n_layers - 1,)).reshape(n_points, n_layers - 1)
    n_rel = float(n_tissue) / float(n_ambient)
    if validate:
        _check("rho_cm", np.atleast_1d(rho), "cm", 0.0, strict=True)
        _check("mua_per_cm", mua, "1/cm", 0.0, strict=False)
        _check("musp_per_cm", musp, "1/cm", 0.0, strict=True)
        _check("thickness_cm", thick, "cm", 0.0, strict=True)
    a_coef = float(boundary_coefficient(n_rel, 1.0))  # validates 1 <= n_rel <= 2
    r_sp = ((n_rel - 1.0) / (n_rel + 1.0)) ** 2
    bounds = np.cumsum(thick, axis=1)
    n = mua.shape[0]
    ztop = np.concatenate([np.zeros((n, 1)), bounds], axis=1)
    zbot = np.concatenate([bounds, np.full((n, 1), np.inf)], axis=1)
    k, w = _hankel_rule(rho, float(_K_MAX_PER_MUSP * np.max(musp[:, 0], initial=1.0)))
    n_var = n_layers + 1 if pathlengths else 1
    refl = np.empty((n_var, n))
    step = max(1, _BLOCK_ELEMENTS // (k.size * n_var))
    for lo in range(0, n, step):
        sl = slice(lo, min(lo + step, n))
        m = np.repeat(mua[None, sl], n_var, axis=0)  # base, then one layer perturbed each
        for i in range(1, n_var):
            m[i, :, i - 1] += _MUA_STEP_PER_CM
        rep = (n_var, 1)
        flux = _surface_flux_hat(
            k, m.reshape(-1, n_layers), np.tile(musp[sl], rep), np.tile(ztop[sl], rep),
            np.tile(zbot[sl], rep), a_coef, r_sp,
        )
        refl[:, sl] = pm.matmul(flux, w).reshape(n_var, -1)
    paths = None
    if pathlengths:
        paths = (pm.log(refl[0])[:, None] - pm.log(refl[1:].T)) / _MUA_STEP_PER_CM
        paths = paths.reshape(batch + (n_layers,))
    refl = refl[0]
    return refl.reshape(batch), paths


def three_layer_reflectance(
    rho_cm: float,
    *,
    mua_epidermis_per_cm: ArrayLike,
    mua_dermis_per_cm: ArrayLike,
    musp_dermis_per_cm: ArrayLike,
    mua_subcutis_per_cm: ArrayLike,
    musp_subcutis_per_cm: ArrayLike,
    epidermis_thickness_cm: ArrayLike,
    skin_thickness_cm: ArrayLike,
    n_tissue: float = 1.4,
    n_ambient: float = 1.0,
    pathlengths: bool = True,
) -> tuple[NDArray[np.float64], NDArray[np.float64] | None]:
    """Diffuse reflectance and per-layer path of three-layer skin (the direct solve).

    The epidermis scatters like the dermis (one skin power law, Jacques 2013 [2]_);
    ``skin_thickness_cm`` is epidermis + dermis, as in the simulator. Inputs broadcast.

    Parameters
    ----------
    rho_cm : float
        Source-detector distance. [cm]
    mua_epidermis_per_cm, mua_dermis_per_cm, mua_subcutis_per_cm : array_like
        Absorption of each layer. [1/cm]
    musp_dermis_per_cm, musp_subcutis_per_cm : array_like
        Reduced scattering of the skin (epidermis and dermis) and of the subcutis. [1/cm]
    epidermis_thickness_cm : array_like
        Living epidermis thickness. [cm]
    skin_thickness_cm : array_like
        Epidermis + dermis thickness, ``> epidermis_thickness_cm``. [cm]
    n_tissue, n_ambient : float, optional
        Refractive indices of the tissue and of the medium above. [-]
    pathlengths : bool, optional
        Also return the per-layer mean paths. Default True.

    Returns
    -------
    reflectance_per_cm2 : ndarray
        R(rho) per incident photon. [1/cm^2]
    pathlength_cm : ndarray or None
        Mean path in the epidermis, dermis and subcutis (last axis, :data:`LAYER_NAMES`). [cm]

    Raises
    ------
    ConfigError
        If an input is out of range, or the skin is not thicker than the epidermis.

    References
    ----------
    .. [1] I. V. Meglinski, S. J. Matcher, Physiol. Meas. 23, 741-753 (2002),
       doi:10.1088/0967-3334/23/4/312
    .. [2] S. L. Jacques, Phys. Med. Biol. 58, R37-R61 (2013),
       doi:10.1088/0031-9155/58/11/R37
    .. [3] A. Liemert, A. Kienle, J. Biomed. Opt. 15, 025003 (2010),
       doi:10.1117/1.3368682

    Examples
    --------
    >>> r, path = three_layer_reflectance(
    ...     0.3, mua_epidermis_per_cm=2.0, mua_dermis_per_cm=0.3, musp_dermis_per_cm=20.0,
    ...     mua_subcutis_per_cm=0.1, musp_subcutis_per_cm=12.0,
    ...     epidermis_thickness_cm=0.008, skin_thickness_cm=0.18)
    >>> round(float(r), 4), np.round(path, 3).tolist()
    (0.2523, [0.057, 1.088, 0.497])
    """
    t_e = np.asarray(epidermis_thickness_cm, dtype=float)
    t_s = np.asarray(skin_thickness_cm, dtype=float)
    if np.any(~(t_s > t_e)):
        bad = np.broadcast_to(t_s, np.broadcast_shapes(t_s.shape, t_e.shape))[
            ~(np.broadcast_to(t_s > t_e, np.broadcast_shapes(t_s.shape, t_e.shape)))].flat[0]
        raise ConfigError(
            f"skin_thickness_cm = {bad!r} must exceed epidermis_thickness_cm "
            f"(valid range: (epidermis, inf) [cm])"
        )
    mua_d = np.asarray(mua_dermis_per_cm, dtype=float)
    musp_d = np.asarray(musp_dermis_per_cm, dtype=float)
    arrays = np.broadcast_arrays(
        np.asarray(mua_epidermis_per_cm, dtype=float), mua_d,
        np.asarray(mua_subcutis_per_cm, dtype=float),
        musp_d, np.asarray(musp_subcutis_per_cm, dtype=float), t_e, t_s,
    )
    mua_e, mua_d, mua_s, musp_d, musp_s, t_e, t_s = arrays
    return layered_diffusion_reflectance(
        rho_cm,
        np.stack([mua_e, mua_d, mua_s], axis=-1),
        np.stack([musp_d, musp_d, musp_s], axis=-1),
        np.stack([t_e, t_s - t_e], axis=-1),
        n_tissue,
        n_ambient,
        pathlengths=pathlengths,
    )
