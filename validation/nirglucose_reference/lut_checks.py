"""Checks of the look-up table against direct solves (validation only).

:func:`random_lut_points` draws off-grid points of a table's box, :func:`direct_solve`
solves the model there the way the table's nodes were solved (a white Monte Carlo run
per group of points, or the diffusion model), and :func:`lut_errors` compares the two.
Tests and ``benchmarks/optics*.py`` use them; the simulator never does.

References
----------
.. [1] A. Sassaroli, S. Fantini, Phys. Med. Biol. 49, N255-N257 (2004),
   doi:10.1088/0031-9155/49/14/N07
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from nirglucose.exceptions import ConfigError
from nirglucose.optics import layers
from nirglucose.optics._inputs import as_generator
from nirglucose.optics.kernels import mc_white
from nirglucose.optics.lut.build import _mc_run_kwargs
from nirglucose.optics.lut.grid import (
    LUT_AXES,
    SkinLUT,
    _inverse,
    _mc_photons,
    _resolve_grid,
    grid_mc_settings,
)
from nirglucose.optics.lut.interpolate import interpolate_lut

__all__ = ["random_lut_points", "direct_solve", "lut_errors"]


def random_lut_points(lut: SkinLUT, n_points: int, *, rng: np.random.Generator | int = 0,
                      groups: int | None = None) -> dict[str, NDArray[np.float64]]:
    """Points uniform in each axis' coordinate over the table's box, as solver inputs.

    Returns keyword arguments for :func:`interpolate_lut` and
    :func:`~nirglucose.optics.layers.three_layer_reflectance`. With ``groups``, the
    points come in that many consecutive groups that share ``musp_ratio`` and
    ``skin_transport_thickness`` (so one Monte Carlo run solves a group: see
    :func:`lut_errors`); every other coordinate is drawn per point.
    """
    gen = as_generator(rng)
    shared = ("musp_ratio", "skin_transport_thickness")
    if groups is not None and not 1 <= int(groups) <= n_points:
        raise ConfigError(f"groups = {groups!r} is out of range; valid range is "
                          f"[1, n_points = {n_points}]")
    sizes = np.diff(np.linspace(0, n_points, int(groups) + 1).round().astype(int)) \
        if groups is not None else None
    pts = {}
    for i, name in enumerate(LUT_AXES):
        kind = LUT_AXES[name][0]
        u_nodes = lut.nodes[i]
        if sizes is not None and name in shared:
            r = np.repeat(gen.random(sizes.size), sizes)
        else:
            r = gen.random(n_points)
        u = u_nodes[0] + (u_nodes[-1] - u_nodes[0]) * r
        lo, hi = lut.box[name]
        pts[name] = np.clip(_inverse(kind, u), lo, hi)  # round-off at the edges
    musp = pts["musp_dermis_per_cm"]
    return {
        "mua_epidermis_per_cm": pts["mua_epidermis_per_cm"],
        "mua_dermis_per_cm": pts["mua_dermis_per_cm"],
        "musp_dermis_per_cm": musp,
        "mua_subcutis_per_cm": pts["mua_subcutis_per_cm"],
        "musp_subcutis_per_cm": musp * pts["musp_ratio"],
        "skin_thickness_cm": pts["skin_transport_thickness"] / musp,
    }


def direct_solve(lut: SkinLUT, points: dict, *, n_photons: int | None = None,
                 seed: int | None = None,
                 ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """Monte Carlo solves at points, with the table's geometry and settings.

    For a table of the ``"diffusion"`` solver: the three-layer diffusion model at the
    points (standard error 0).

    One white Monte Carlo run per distinct (``musp_ratio``, ``skin_transport_thickness``)
    among the points (to 12 significant digits: the round-off of recovering them from
    the solver arguments does not split a group of :func:`random_lut_points`), with the
    table's seed (common random numbers), photons, reference absorption, roulette and
    detector kernel, so a solve differs from the table's nodes only by where it is.

    Parameters
    ----------
    lut : SkinLUT
        The table.
    points : dict
        Solver keyword arguments, (P,) arrays (:func:`random_lut_points`).
    n_photons : int, optional
        Photons per run; default the table's (:func:`lut_key`'s for its grid).
    seed : int, optional
        Random numbers of the runs; default the table's (common random numbers).
        Another seed and more photons make an independent reference.

    Returns
    -------
    reflectance_per_cm2 : ndarray
        R(rho), (P,). [1/cm^2]
    reflectance_se_per_cm2 : ndarray
        Its Monte Carlo standard error, (P,). [1/cm^2]
    pathlength_cm : ndarray
        Mean path in the epidermis, dermis and subcutis, (P, 3). [cm]

    References
    ----------
    .. [1] A. Kienle, M. S. Patterson, Phys. Med. Biol. 41, 2221-2227 (1996),
       doi:10.1088/0031-9155/41/10/026
    """
    geo, grid = lut.geometry, _resolve_grid(lut.grid)
    if lut.solver == "diffusion":  # the model the table interpolates, solved at the points
        p = {k: np.asarray(v, dtype=float) for k, v in points.items()}
        refl, paths = layers.three_layer_reflectance(
            geo["rho_cm"], epidermis_thickness_cm=geo["epidermis_thickness_cm"],
            n_tissue=geo["n_tissue"], n_ambient=geo["n_ambient"], **p)
        return refl, np.zeros_like(refl), paths
    photons = _mc_photons(grid, n_photons)
    p = {k: np.atleast_1d(np.asarray(v, dtype=float)) for k, v in points.items()}
    musp = p["musp_dermis_per_cm"]
    q = p["musp_subcutis_per_cm"] / musp
    tau = p["skin_thickness_cm"] * musp
    refl, se, paths = np.empty(musp.size), np.empty(musp.size), np.empty((musp.size, 3))
    # points that share (ratio, thickness) share a run; recovering both from the solver
    # arguments rounds (tau = skin x mus'), so they are matched to 12 significant digits
    pair = np.stack([q, tau], axis=1)
    scale = 10.0 ** np.floor(np.log10(np.where(pair > 0, np.abs(pair), 1.0)))
    _, first, which = np.unique(np.round(pair / scale, 11) * scale, axis=0,
                                return_index=True, return_inverse=True)
    for k, j in enumerate(first):
        sel = np.flatnonzero(which.ravel() == k)
        qq, tt = q[j], tau[j]
        refl[sel], se[sel], paths[sel] = mc_white.white_mc_points(
            geo["rho_cm"], float(grid_mc_settings(lut.grid)["half_width_cm"]),
            geo["epidermis_thickness_cm"],
            mua_epidermis_per_cm=p["mua_epidermis_per_cm"][sel],
            mua_dermis_per_cm=p["mua_dermis_per_cm"][sel],
            musp_dermis_per_cm=musp[sel],
            mua_subcutis_per_cm=p["mua_subcutis_per_cm"][sel],
            musp_ratio=float(qq), skin_transport_thickness=float(tt),
            **{**_mc_run_kwargs(grid, geo, photons),
               **({} if seed is None else {"seed": int(seed)})},
        )
    return refl, se, paths


def lut_errors(
    lut: SkinLUT, points: dict | None = None, n_points: int = 200, *,
    rng: np.random.Generator | int = 0, groups: int | None = 20,
    n_photons: int | None = None,
    seed: int | None = None,
) -> dict[str, NDArray[np.float64]]:
    """Relative errors of the table against direct solves at off-grid points.

    "Direct solve": :func:`direct_solve`, a white Monte Carlo run at the point with the
    table's settings and random numbers (the model the table is built from, so this
    measures the table: its interpolation and the part of the Monte Carlo noise that
    the common random numbers do not share between the point and the nodes).

    Parameters
    ----------
    lut : SkinLUT
        The table.
    points : dict, optional
        Solver keyword arguments (arrays); :func:`random_lut_points` when omitted.
    n_points : int, optional
        Number of random points when ``points`` is omitted. Default 200.
    rng : numpy.random.Generator or int, optional
        Random generator or seed. Default 0.
    groups : int or None, optional
        Random points share (``musp_ratio``, ``skin_transport_thickness``) in this many
        groups, one Monte Carlo run each (None: one run per point). Default 20.
    n_photons : int, optional
        Photons per direct run; default the table's.
    seed : int, optional
        Random numbers of the direct runs; default the table's.

    Returns
    -------
    dict
        ``reflectance`` (n,) and ``pathlength`` (n, 3): table / direct - 1;
        ``reflectance_se`` (n,): the direct solve's relative standard error.
    """
    args = points if points is not None else random_lut_points(
        lut, n_points, rng=rng, groups=groups)
    r_lut, p_lut = interpolate_lut(lut, pathlengths=True, **args)
    r_dir, se_dir, p_dir = direct_solve(lut, args, n_photons=n_photons, seed=seed)
    return {"reflectance": r_lut / r_dir - 1.0, "pathlength": p_lut / p_dir - 1.0,
            "reflectance_se": se_dir / r_dir}
