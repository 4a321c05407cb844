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
    mua, musp, _ = mixed_optics(optics, skin_thickness_cm, separation_cm)
    mel = np.asarray(melanin_fraction)[:, None, None]
    mua_epi = skin.epidermis_mua_per_cm(mel, optics["melanosome"], optics["baseline"])
    if model == "diffusion":
        t_epi = skin.epidermis_transmittance(mua_epi, epidermis_thickness_cm)
        r = farrell_reflectance(separation_cm, mua, musp, n_tissue, validate=False)
        return t_epi * r * detector_area_cm2
    if geometry_factor is None:
        raise ConfigError("the beer-lambert model needs its geometry_factor (see simulator)")
    dpf = differential_pathlength_factor(separation_cm, mua, musp, validate=False)
    # epidermis round trip and dermal path in one exponential (skin.epidermis_transmittance
    # and beer_lambert.mbll_transmittance, fused: one pass over the arrays instead of two)
    optical_depth = 4.0 * epidermis_thickness_cm * mua_epi + mua * dpf * separation_cm
    return np.asarray(geometry_factor) * np.exp(-optical_depth)


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
    return r / np.exp(-mua_per_cm * dpf * separation_cm)
