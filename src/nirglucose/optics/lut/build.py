"""Building the table: solve the model at the nodes, refine, smooth, centre.

:func:`build_lut` solves the layered-skin model at the grid's solve nodes (the white
Monte Carlo of :mod:`nirglucose.optics.kernels.mc_white` plus a least-squares fit of its
difference to the three-layer diffusion model, or the diffusion model alone), refines
each axis and centres the node values for multilinear interpolation. No caching here
(:mod:`nirglucose.optics.lut.cache`); the package docstring gives the method and its
references (Wang et al. 1995; Kienle & Patterson 1996; Sassaroli & Fantini 2004;
Blu, Thevenaz & Unser 2004).
"""

from __future__ import annotations

import logging
import time

import numpy as np

from ...exceptions import ConfigError
from .. import layers
from ..kernels import mc_white
from .grid import (
    _CHANNELS,
    _MIN_SKIN_OVER_EPIDERMIS,
    _PATH_FLOOR_CM,
    _SCATTERING,
    _SOLVED_AXES,
    LUT_AXES,
    SkinLUT,
    _check_solver,
    _forward,
    _geometry,
    _inverse,
    _mc_photons,
    _resolve_grid,
    grid_mc_settings,
    lut_key,
)

__all__ = ["build_lut"]

_log = logging.getLogger(__name__)


def _mua_ref(grid: dict) -> float:
    """Reference absorption of the runs, in transport units: the box's smallest mua*.

    mua* = mua / mus'_dermis over the dermis and subcutis boxes (the epidermis, where
    mua may be 0, is a thin layer the re-weighting handles exactly).
    """
    lo = min(grid["mua_dermis_per_cm"][0], grid["mua_subcutis_per_cm"][0])
    if not lo > 0:
        raise ConfigError(f"the dermis and subcutis absorption boxes must start above 0 for "
                          f"the Monte Carlo table, got {lo!r} [1/cm]")
    return float(lo / grid["musp_dermis_per_cm"][1])


def _mc_run_kwargs(grid: dict, geo: dict, n_photons: int) -> dict:
    """Keyword arguments of :func:`~nirglucose.optics.kernels.mc_white.white_mc_run` for a table."""
    settings = grid_mc_settings(grid)
    return {
        "n_photons": n_photons,
        "seed": int(settings["seed"]),
        "mua_ref": _mua_ref(grid),
        "g": float(settings["anisotropy"]),
        "n_tissue": geo["n_tissue"],
        "n_ambient": geo["n_ambient"],
        "path_split": float(settings["path_split"]),
    }


def _solve_axes(grid: dict, geo: dict) -> tuple[list[np.ndarray], list[int | None]]:
    """Solve-grid coordinates of each axis, and the index of the tau = 1 node (or None)."""
    coords, splits = [], []
    for name, (lo, hi, n, _m) in grid.items():
        kind = LUT_AXES[name][0]
        if name == "skin_transport_thickness":
            # keep the skin thicker than the epidermis on every node ...
            lo = max(lo, _MIN_SKIN_OVER_EPIDERMIS * geo["epidermis_thickness_cm"]
                     * grid["musp_dermis_per_cm"][1])
            if not hi > lo:
                raise ConfigError(
                    f"epidermis_thickness_cm = {geo['epidermis_thickness_cm']!r} leaves no "
                    f"room for a dermis in the grid's skin_transport_thickness box "
                    f"(up to {hi:g}) [-]"
                )
            u_lo, u_hi = np.log(lo), np.log(hi)
            if u_lo < 0.0 < u_hi:  # ... and a node on tau = 1 (u = 0), uniform either side
                n_lo = int(np.clip(round((n - 1) * -u_lo / (u_hi - u_lo)), 1, n - 2))
                u = np.concatenate([np.linspace(u_lo, 0.0, n_lo + 1)[:-1],
                                    np.linspace(0.0, u_hi, n - n_lo)])
                coords.append(u)
                splits.append(n_lo)
                continue
            coords.append(np.linspace(u_lo, u_hi, n))
            splits.append(None)
            continue
        u_lo, u_hi = _forward(kind, np.float64(lo)), _forward(kind, np.float64(hi))
        coords.append(np.linspace(u_lo, u_hi, n))
        splits.append(None)
    return coords, splits


def _pieces(n: int, split: int | None) -> list[tuple[int, int]]:
    """First and last node of each piece of an axis of n nodes (two when split at tau = 1)."""
    return [(0, n - 1)] if split is None else [(0, split), (split, n - 1)]


def _refined_coords(u: np.ndarray, m: int, split: int | None) -> np.ndarray:
    """An axis' solve coordinates refined m times (uniformly on each side of ``split``).

    Solve node j is refined node j * m.
    """
    fine = [np.linspace(u[a], u[b], (b - a) * m + 1)[(1 if k else 0):]
            for k, (a, b) in enumerate(_pieces(u.size, split))]
    return np.concatenate(fine)


def _upsample(values: np.ndarray, axis: int, u: np.ndarray, m: int,
              split: int | None) -> tuple[np.ndarray, np.ndarray]:
    """Refine one axis m times with cubic splines (separately on each side of ``split``)."""
    from scipy.interpolate import make_interp_spline

    fine_u = _refined_coords(u, m, split)
    out = []
    for k, (a, b) in enumerate(_pieces(u.size, split)):
        spline = make_interp_spline(u[a:b + 1], values.take(range(a, b + 1), axis=axis),
                                    k=min(3, b - a), axis=axis)
        at = fine_u[a * m + (1 if k else 0):b * m + 1]
        out.append(spline(at))
    return np.concatenate(out, axis=axis), fine_u


def build_lut(
    separation_cm: float,
    epidermis_thickness_cm: float,
    n_tissue: float = 1.4,
    n_ambient: float = 1.0,
    *,
    grid: str | dict = "default",
    n_photons: int | None = None,
    solver: str = "monte-carlo",
) -> SkinLUT:
    """Tabulate three-layer skin by white Monte Carlo (no caching; see :func:`load_or_build_lut`).

    Parameters
    ----------
    separation_cm : float
        Source-detector distance. [cm]
    epidermis_thickness_cm : float
        Living epidermis thickness. [cm]
    n_tissue, n_ambient : float, optional
        Refractive indices of the skin and of the medium above it. [-]
    grid : str or dict, optional
        A name of :data:`LUT_GRIDS` or a spec with the same axes. Default "default".
    n_photons : int, optional
        Photons per Monte Carlo run; default :data:`LUT_MC_PHOTONS` of the grid.
    solver : {'monte-carlo', 'diffusion'}, optional
        What solves the nodes (:data:`LUT_SOLVERS`). Default "monte-carlo".

    Returns
    -------
    SkinLUT

    Notes
    -----
    One run of :func:`~nirglucose.optics.kernels.mc_white.white_mc_run` per
    (``musp_ratio``, ``skin_transport_thickness``) solve node, in transport units;
    :func:`~nirglucose.optics.kernels.mc_white.white_mc_tally` turns it into R and the mean
    paths at every ``musp_dermis_per_cm`` node (scaling) and every absorption node
    (re-weighting), exactly for the RTE up to Monte Carlo noise. Every run uses the
    same random numbers (:data:`LUT_MC_SETTINGS` ``seed``). The table holds the
    three-layer diffusion model plus a smooth fit of the Monte Carlo minus diffusion
    difference (:func:`_residual_fit`); on the axes of :data:`_SOLVED_AXES` both are
    evaluated at every refined node, the other axes whose ``upsample`` exceeds 1 are
    refined by cubic splines. Last, the refined node values are centred for multilinear
    interpolation (:func:`_centre_nodes`).

    References
    ----------
    .. [1] A. Kienle, M. S. Patterson, Phys. Med. Biol. 41, 2221-2227 (1996),
       doi:10.1088/0031-9155/41/10/026
    .. [2] A. Sassaroli, S. Fantini, Phys. Med. Biol. 49, N255-N257 (2004),
       doi:10.1088/0031-9155/49/14/N07

    Examples
    --------
    >>> lut = build_lut(0.3, 0.008, grid="tiny", n_photons=2000)
    >>> lut.values.shape
    (2, 2, 2, 2, 2, 3, 4)
    """
    _check_solver(solver)
    photons = _mc_photons(grid, n_photons)
    grid = _resolve_grid(grid)
    geo = _geometry(separation_cm, epidermis_thickness_cm, n_tissue, n_ambient)
    start = time.perf_counter()
    names = list(LUT_AXES)
    coords, splits = _solve_axes(grid, geo)
    ax = {k: _inverse(LUT_AXES[k][0], coords[i]) for i, k in enumerate(names)}
    values, solved = _node_values(solver, grid, geo, coords, splits, ax, photons)
    # model solves: the Monte Carlo runs' nodes, or every diffusion node of the table
    solved_nodes = solved if solver == "diffusion" else {}
    n_solves = int(np.prod([solved_nodes.get(i, c).size for i, c in enumerate(coords)]))
    nodes = []
    for i, name in enumerate(names):
        m = grid[name][3]
        u = coords[i]
        if i in solved:
            u = solved[i]
        elif m > 1:
            values, u = _upsample(values, i, u, m, splits[i])
        nodes.append(u)
    # solve node j is refined node j * upsample: the tau = 1 node of the refined axis
    values = _centre_nodes(values, [None if s is None else s * grid[k][3]
                                    for s, k in zip(splits, names, strict=True)])
    key = lut_key(geo["rho_cm"], geo["epidermis_thickness_cm"], geo["n_tissue"],
                  geo["n_ambient"], grid, n_photons=photons, solver=solver)
    return SkinLUT(
        np.ascontiguousarray(values, dtype=np.float32), tuple(nodes), values.shape[:-1],
        grid, geo, key, time.perf_counter() - start, n_solves, solver,
    )


def _node_values(solver: str, grid: dict, geo: dict, coords: list, splits: list, ax: dict,
                 photons: int) -> tuple[np.ndarray, dict]:
    """The model's values at the solve nodes, and the refined coordinates of the axes
    solved at every refined node (:data:`_SOLVED_AXES`; none for raw Monte Carlo nodes).

    The diffusion model (:func:`_diffusion_nodes`), plus for the Monte Carlo solver the
    smooth fit of Monte Carlo minus diffusion (:func:`_residual_fit`; Kienle & Patterson
    1996 for the scaled white runs behind :func:`_monte_carlo_nodes`).
    """
    names = list(LUT_AXES)
    degrees = grid_mc_settings(grid)["residual_fit_degrees"]
    if solver == "monte-carlo" and degrees is None:  # raw Monte Carlo nodes, splined
        values = _monte_carlo_nodes(ax, grid, geo, photons)
        solved = {}
    else:
        # the diffusion model is solved at every refined node of the scattering axes
        # that it resolves better than a spline (_SOLVED_AXES); the Monte Carlo
        # correction is a smooth fit over the scattering axes, evaluated there directly
        solved = {i: _refined_coords(coords[i], grid[k][3], splits[i])
                  for i, k in enumerate(names) if k in _SOLVED_AXES}
        values = _diffusion_nodes(
            {k: _inverse(LUT_AXES[k][0], solved[i]) if i in solved else ax[k]
             for i, k in enumerate(names)}, geo)
        if solver == "monte-carlo":
            at_solve = values
            for i in solved:  # solve node j is refined node j * upsample
                at_solve = at_solve.take(np.arange(coords[i].size) * grid[names[i]][3],
                                         axis=i)
            at = tuple(solved.get(i, coords[i]) for i in _SCATTERING)
            values += _residual_fit(_monte_carlo_nodes(ax, grid, geo, photons), at_solve,
                                    coords, splits[-1], degrees, at=at)
    return values, solved


def _centre_nodes(values: np.ndarray, splits: list[int | None]) -> np.ndarray:
    """Node values whose multilinear interpolant is unbiased over each cell.

    Multilinear interpolation of a smooth f through its node values errs by
    sum_k f_kk h_k^2 t_k (1 - t_k) / 2 inside a cell (t_k in [0, 1] the position along
    axis k, h_k the node spacing): always with the sign of the curvature, on average
    f_kk h_k^2 / 12 over the cell, at most f_kk h_k^2 / 8 at its middle. Storing
    f - sum_k delta_k^2 f / 12 instead (delta_k^2 f = f_(i+1) - 2 f_i + f_(i-1) ~ f_kk h_k^2,
    the second difference along axis k) makes each term's mean over the cell zero, the
    least-squares choice of a constant shift, and its largest value f_kk h_k^2 / 12 (at
    the nodes; f_kk h_k^2 / 24 at the middle): the idea of quasi-interpolation and
    of "linear interpolation revitalized" (Blu, Thevenaz & Unser 2004), at no cost at
    interpolation time. The table is then no longer exact at its nodes, by design.

    Second differences are taken within each piece of an axis (split at tau = 1 on the
    thickness axis, where the diffusion model has a kink: the node there takes the mean
    of the two sides), and the end nodes of a piece take their neighbour's; a piece of
    two nodes (no curvature to see) is left as it is.

    Parameters
    ----------
    values : ndarray
        Node values, the last axis the channels.
    splits : list of int or None
        Per axis, the node index where its two pieces meet (or None).

    References
    ----------
    .. [1] T. Blu, P. Thevenaz, M. Unser, "Linear interpolation revitalized", IEEE Trans.
       Image Process. 13, 710-719 (2004), doi:10.1109/TIP.2004.826093
    """
    shift = np.zeros(values.shape)
    for axis in range(values.ndim - 1):
        n = values.shape[axis]
        total = np.zeros((n,) + tuple(np.delete(values.shape, axis)))
        count = np.zeros(n)
        for a, b in _pieces(n, splits[axis]):
            count[a:b + 1] += 1.0
            if b - a < 2:
                continue
            d2 = np.diff(np.moveaxis(values[(slice(None),) * axis + (slice(a, b + 1),)],
                                     axis, 0), n=2, axis=0)
            total[a:b + 1] += np.concatenate([d2[:1], d2, d2[-1:]])
        shift += np.moveaxis(total / count.reshape((n,) + (1,) * (values.ndim - 1)), 0, axis)
    return values - shift / 12.0


def _residual_basis(coords: list[np.ndarray], split: int | None,
                    degrees: tuple[int, int, int],
                    at: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None) -> np.ndarray:
    """Least-squares basis over the scattering axes (mus'_dermis, musp_ratio, thickness).

    Tensor products of polynomials in ln mus'_dermis and musp_ratio with, along ln tau,
    a polynomial plus truncated powers (u - u_1)_+^k at tau = 1 (u_1), where the
    diffusion model's point source crosses into the subcutis and its R has a kink that
    the transport solution does not have. Coordinates scaled to [-1, 1] over the solve
    nodes ``coords``; each degree capped at the axis' node count - 1, along ln tau on
    each side of tau = 1 (so the basis has full rank at the solve nodes, and the fit
    is unique between them). Evaluated at the solve nodes, or at the coordinates ``at``
    (mus'_dermis, musp_ratio, thickness). Returns (n_musp * n_q * n_tau, n_terms).
    """
    axes = (coords[0], coords[1], coords[-1])
    points = axes if at is None else at

    def scaled(u, nodes):
        half = np.ptp(nodes) / 2.0
        mid = (nodes.max() + nodes.min()) / 2.0
        return (u - mid) / half if half > 0 else np.zeros_like(u)

    x, q, y = (scaled(p, n) for p, n in zip(points, axes, strict=True))
    dx, dq, dy = (min(int(d), n.size - 1) for d, n in zip(degrees, axes, strict=True))
    gx, gq, gy = np.meshgrid(x, q, y, indexing="ij")
    if split is None:
        along_tau = [gy**k for k in range(dy + 1)]
    else:  # the degree on either side of the knot capped by that side's nodes (full rank)
        knot = scaled(axes[2][split], axes[2])
        along_tau = [gy**k for k in range(min(dy, split) + 1)]
        along_tau += [np.maximum(gy - knot, 0.0)**k
                      for k in range(1, min(dy, axes[2].size - 1 - split) + 1)]
    cols = [gx**i * gq**j * t for i in range(dx + 1) for j in range(dq + 1) for t in along_tau]
    return np.stack([c.ravel() for c in cols], axis=1)


def _residual_fit(mc: np.ndarray, diffusion: np.ndarray, coords: list, split: int | None,
                  degrees, at: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None,
                  ) -> np.ndarray:
    """Monte Carlo minus diffusion, with its noise along the scattering axes fitted away.

    The table stores ln R and ln paths of the diffusion model plus a least-squares fit
    (:func:`_residual_basis`) of the Monte Carlo minus diffusion difference over the
    scattering nodes, separately for every absorption node and channel. Along the
    absorption axes the Monte Carlo values are already smooth (one run re-weighted);
    along the scattering axes every node has its own ~1 % noise, and the difference
    to diffusion is a slowly varying function (0.6-1.3 in R over the default box)
    that a few dozen terms describe: the fit averages the noise over the 252 scattering
    nodes of the default grid. A control-variate use of the diffusion model (it only
    supplies the shape; the level comes from the transport solution).

    Returns the fitted difference at the solve nodes, or, with ``at``, at the
    coordinates (ln mus'_dermis, musp_ratio, ln tau) given there (the fit is a smooth
    function of them, so the table's refined scattering axes need no spline through
    the Monte Carlo nodes).
    """
    basis = _residual_basis(coords, split, tuple(degrees))
    # (musp, q, tau, mua_d, mua_s, mua_e, C): the scattering axes first
    d = np.moveaxis(mc - diffusion, -2, 2)
    coef, *_ = np.linalg.lstsq(basis, d.reshape(basis.shape[0], -1), rcond=None)
    if at is None:
        return np.moveaxis((basis @ coef).reshape(d.shape), 2, -2)
    basis = _residual_basis(coords, split, tuple(degrees), at=at)
    shape = tuple(a.size for a in at) + d.shape[3:]
    return np.moveaxis((basis @ coef).reshape(shape), 2, -2)


def _diffusion_nodes(ax: dict, geo: dict) -> np.ndarray:
    """ln R and ln paths at the solve nodes from the three-layer diffusion model."""
    names = list(LUT_AXES)
    mesh = dict(zip(names, np.meshgrid(*(ax[k] for k in names), indexing="ij"), strict=True))
    musp_d = mesh["musp_dermis_per_cm"]
    refl, paths = layers.three_layer_reflectance(
        geo["rho_cm"],
        mua_epidermis_per_cm=mesh["mua_epidermis_per_cm"],
        mua_dermis_per_cm=mesh["mua_dermis_per_cm"],
        musp_dermis_per_cm=musp_d,
        mua_subcutis_per_cm=mesh["mua_subcutis_per_cm"],
        musp_subcutis_per_cm=musp_d * mesh["musp_ratio"],
        epidermis_thickness_cm=geo["epidermis_thickness_cm"],
        skin_thickness_cm=mesh["skin_transport_thickness"] / musp_d,
        n_tissue=geo["n_tissue"],
        n_ambient=geo["n_ambient"],
    )
    paths = np.maximum(paths, _PATH_FLOOR_CM)
    return np.concatenate([np.log(refl)[..., None], np.log(paths)], axis=-1)


def _monte_carlo_nodes(ax: dict, grid: dict, geo: dict, photons: int,
                       first_photon: int = 0) -> np.ndarray:
    """ln R and ln paths at the solve nodes from white Monte Carlo runs (see build_lut).

    ``first_photon``: trace photons ``first_photon .. first_photon + photons - 1`` of each
    run (:func:`~nirglucose.optics.kernels.mc_white.white_mc_run`); disjoint ranges give
    independent node values (``studies/optics_fit_degrees.py``).
    """
    musp = ax["musp_dermis_per_cm"]
    rho, half = geo["rho_cm"], float(grid_mc_settings(grid)["half_width_cm"])
    if not half < rho:
        raise ConfigError(f"separation_cm = {rho!r} must exceed the detector kernel's "
                          f"half-width {half!r} [cm]")
    band = ((rho - half) * float(musp.min()), (rho + half) * float(musp.max()))
    run_kw = _mc_run_kwargs(grid, geo, photons)
    shape = tuple(a.size for a in ax.values())
    values = np.empty(shape + (len(_CHANNELS),))
    worst_se = 0.0
    for iq, q in enumerate(ax["musp_ratio"]):
        for it, tau in enumerate(ax["skin_transport_thickness"]):
            run = mc_white.white_mc_run(tau, q, musp * geo["epidermis_thickness_cm"], band,
                                        first_photon=first_photon, **run_kw)
            t = mc_white.white_mc_tally(run, rho, half, musp, ax["mua_epidermis_per_cm"],
                                        ax["mua_dermis_per_cm"], ax["mua_subcutis_per_cm"])
            refl = t["reflectance_per_cm2"]  # (musp, mua_e, mua_d, mua_s)
            if not np.all(refl > 0):
                raise ConfigError(
                    f"{photons} photons per run leave R <= 0 at some node of the grid "
                    f"(musp_ratio {q:.3g}, skin_transport_thickness {tau:.3g}); use more "
                    f"photons [-]"
                )
            worst_se = max(worst_se, float(np.max(t["reflectance_se_per_cm2"] / refl)))
            paths = np.maximum(t["pathlength_cm"], _PATH_FLOOR_CM)
            block = np.concatenate([np.log(refl)[..., None], np.log(paths)], axis=-1)
            # (musp, mua_e, mua_d, mua_s, 4) -> the table's (musp, mua_d, mua_s, mua_e, 4)
            values[:, iq, :, :, :, it] = np.moveaxis(block, 1, 3)
    _log.info("LUT Monte Carlo: %d runs of %d photons, worst node standard error of R %.2g",
              shape[1] * shape[5], photons, worst_se)
    return values
