"""Forward optical models: the fraction of LED power that reaches the photodiode.

Selected by name (``optics.model``), listed in :data:`FORWARD_MODELS`:

``"beer-lambert"`` (default, fast)
    Modified Beer-Lambert law, I/I0 = G exp(-mua DPF rho), with the diffusion-theory
    DPF (Fantini 1999) evaluated at each sample's own optical properties, so glucose's
    effect on scattering changes the path. G is fixed per wavelength so that the model
    equals the diffusion model at nominal skin.
``"diffusion"``
    Farrell-Patterson-Wilson dipole reflectance R(rho) times the detector area.
``"rte-lut"``
    Three-layer skin (epidermis, dermis, semi-infinite subcutis) solved as layered
    transport (:mod:`nirglucose.optics.layers`), read from a cached look-up table
    (:mod:`nirglucose.optics.lut`); R(rho) times the detector area.

The first two put the epidermis (melanin) in front as a round-trip transmittance and mix
dermis and subcutis by the share of the path in each (:mod:`nirglucose.optics.skin`).
"""

from __future__ import annotations

import numpy as np

from .. import portable as pm
from ..exceptions import ConfigError
from . import skin
from .diffusion import (
    differential_pathlength_factor,
    effective_attenuation_per_cm,
    farrell_reflectance,
)

__all__ = ["FORWARD_MODELS", "detected_fraction", "geometry_factor", "mixed_optics"]

FORWARD_MODELS = ("beer-lambert", "diffusion", "rte-lut")


def mixed_optics(optics: dict, skin_thickness_cm: np.ndarray, separation_cm: float):
    """Mix dermis and subcutis by the share of the photon path in the skin layer.

    Returns ``(mua, musp, dermis_share)``, each (n, n_led, n_pts).
    """
    mu_eff = effective_attenuation_per_cm(
        optics["mua_dermis"], optics["musp_dermis"], validate=False
    )
    depth = skin.mean_penetration_depth_cm(separation_cm, mu_eff)
    share = skin.dermis_path_fraction(np.asarray(skin_thickness_cm)[:, None, None], depth)
    mua = share * optics["mua_dermis"] + (1.0 - share) * optics["mua_subcutis"]
    musp = share * optics["musp_dermis"] + (1.0 - share) * optics["musp_subcutis"]
    return mua, musp, share


def detected_fraction(
    model: str,
    optics: dict,
    *,
    melanin_fraction: np.ndarray,
    skin_thickness_cm: np.ndarray,
    epidermis_thickness_cm: float,
    separation_cm: float,
    detector_area_cm2: float,
    n_tissue: float,
    geometry_factor: np.ndarray | None = None,
    lut=None,
) -> np.ndarray:
    """Fraction of emitted power detected, per sample and band node, (n, n_led, n_pts).

    Parameters
    ----------
    model : {'beer-lambert', 'diffusion', 'rte-lut'}
        Forward model.
    optics : dict
        Output of :func:`nirglucose.optics.tissue.tissue_optics`.
    melanin_fraction : array_like
        Epidermal melanosome fraction, (n,). [-]
    skin_thickness_cm : array_like
        Epidermis + dermis thickness, (n,). [cm]
    epidermis_thickness_cm : float
        Living epidermis thickness. [cm]
    separation_cm : float
        Source-detector separation. [cm]
    detector_area_cm2 : float
        Photodiode area. [cm^2]
    n_tissue : float
        Tissue refractive index. [-]
    geometry_factor : array_like, optional
        G of the Beer-Lambert model per (n_led, n_pts); from :func:`geometry_factor`
        when omitted.
    lut : SkinLUT or NodeLUT, optional
        Table of the ``rte-lut`` model (:mod:`nirglucose.optics.lut`); the cached
        default table for this geometry when omitted.

    Returns
    -------
    numpy.ndarray
        Detected fraction. [-]
    """
    if model not in FORWARD_MODELS:
        raise ConfigError(f"unknown forward model {model!r}; valid: {', '.join(FORWARD_MODELS)}")
    if model == "rte-lut":
        from .lut import reflectance_from_tissue_optics

        return detector_area_cm2 * reflectance_from_tissue_optics(
            optics, melanin_fraction=melanin_fraction, skin_thickness_cm=skin_thickness_cm,
            epidermis_thickness_cm=epidermis_thickness_cm, separation_cm=separation_cm,
            n_tissue=n_tissue, lut=lut,
        )
    if model == "beer-lambert":
        if geometry_factor is None:
            raise ConfigError("the beer-lambert model needs its geometry_factor (see simulator)")
        return _beer_lambert(
            optics, melanin_fraction, skin_thickness_cm, epidermis_thickness_cm,
            separation_cm, geometry_factor,
        )
    mua, musp, _ = mixed_optics(optics, skin_thickness_cm, separation_cm)
    mel = np.asarray(melanin_fraction)[:, None, None]
    mua_epi = skin.epidermis_mua_per_cm(mel, optics["melanosome"], optics["baseline"])
    t_epi = skin.epidermis_transmittance(mua_epi, epidermis_thickness_cm)
    r = farrell_reflectance(separation_cm, mua, musp, n_tissue, validate=False)
    return t_epi * r * detector_area_cm2


def _beer_lambert(
    optics: dict,
    melanin_fraction,
    skin_thickness_cm,
    epidermis_thickness_cm: float,
    separation_cm: float,
    geometry_factor,
) -> np.ndarray:
    r"""The ``beer-lambert`` model, fused: the simulator's hot path.

    The same algebra as composing :func:`mixed_optics`,
    :func:`nirglucose.optics.skin.epidermis_mua_per_cm`,
    :func:`nirglucose.optics.skin.epidermis_transmittance`,
    :func:`nirglucose.optics.diffusion.differential_pathlength_factor` and
    :func:`nirglucose.optics.beer_lambert.mbll_transmittance` (a test holds them equal),
    rearranged so that each (sample, node) value is touched about 25 times, in place:

    * mean depth z = sqrt(rho / mu_eff) / (2 sqrt 2) (Weiss 1989), so the dermal share
      of the path 1 - exp(-t / z) = 1 - exp(-t 2 sqrt(2 / rho) mu_eff^(1/2));
    * with x = rho sqrt(3 mua mus'), the dermal optical depth mua DPF rho (Fantini
      1999) equals x^2 / (2 (1 + x)), one square root instead of three;
    * the epidermis round trip 4 d mua_epi and the dermal depth share one exponential.

    Returns the detected fraction, (n, n_led, n_pts). [-]
    """
    shape = optics["mua_dermis"].shape
    n = shape[0]

    def flat(name):
        return optics[name].reshape(n, -1)

    mua_d, musp_d = flat("mua_dermis"), flat("musp_dermis")
    mua_s, musp_s = flat("mua_subcutis"), flat("musp_subcutis")
    rho = float(separation_cm)
    # dermal share of the path (skin.dermis_path_fraction at skin.mean_penetration_depth_cm)
    share = mua_d + musp_d
    share *= mua_d
    share *= 3.0
    np.sqrt(share, out=share)  # mu_eff
    np.sqrt(share, out=share)
    t_cm = np.asarray(skin_thickness_cm, dtype=float)
    share *= (-2.0 * np.sqrt(2.0 / rho)) * (t_cm.reshape(-1, 1) if t_cm.ndim else t_cm)
    pm.exp(share, out=share)
    np.subtract(1.0, share, out=share)
    # mixed optics (mixed_optics)
    mua = mua_d - mua_s
    mua *= share
    mua += mua_s
    musp = musp_d - musp_s
    musp *= share
    musp += musp_s
    # dermal optical depth mua DPF rho = x^2 / (2 (1 + x)), x^2 = 3 rho^2 mua mus'
    x2 = mua
    x2 *= musp
    x2 *= 3.0 * rho * rho
    x = np.sqrt(x2, out=musp)
    x += 1.0
    x2 /= x
    x2 *= 0.5
    # epidermis round trip 4 d mua_epi, mua_epi = baseline + f_mel (mua_mel - baseline)
    base = np.ravel(optics["baseline"])
    mel_tab = optics["melanosome"]
    mel = mel_tab.reshape(mel_tab.shape[0], -1) - base
    f_mel = np.asarray(melanin_fraction, dtype=float)
    mel = mel * (f_mel.reshape(-1, 1) if f_mel.ndim else f_mel)
    mel += base
    mel *= 4.0 * float(epidermis_thickness_cm)
    x2 += mel
    np.negative(x2, out=x2)
    pm.exp(x2, out=x2)
    x2 *= np.ravel(geometry_factor)
    return x2.reshape(shape)


def geometry_factor(
    mua_per_cm: np.ndarray,
    musp_per_cm: np.ndarray,
    separation_cm: float,
    detector_area_cm2: float,
    n_tissue: float,
) -> np.ndarray:
    """G that makes the Beer-Lambert model equal the diffusion model at given optics.

    G = R_farrell(rho) A_det / exp(-mua DPF rho), evaluated at nominal properties.
    """
    r = farrell_reflectance(separation_cm, mua_per_cm, musp_per_cm, n_tissue) * detector_area_cm2
    dpf = differential_pathlength_factor(separation_cm, mua_per_cm, musp_per_cm)
    return r / pm.exp(-mua_per_cm * dpf * separation_cm)
