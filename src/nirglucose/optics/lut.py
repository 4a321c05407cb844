"""Look-up table of layered-skin reflectance and per-layer path, for the fast path.

A radiative-transport (Monte Carlo) solution of three-layer skin costs far too much per
evaluation for the simulator, which needs tens of millions. The table holds, at the
probe's source-detector distance, the natural logarithms of the reflectance R(rho) and
of the mean path in the epidermis, dermis and subcutis over six axes, and interpolates
them multilinearly:

========================  ==========  ================  ====================================
axis                      coordinate  default box       what moves it in the simulator
========================  ==========  ================  ====================================
musp_dermis_per_cm        log         7 - 30 /cm        wavelength, glucose (Maier 1994)
musp_ratio                linear      0.48 - 0.85       subcutis / dermis mus' (wavelength)
mua_dermis_per_cm         sqrt        0.05 - 2 /cm      blood, saturation, water, glucose
mua_subcutis_per_cm       sqrt        0.01 - 2 /cm      fat (BMI), blood, water
mua_epidermis_per_cm      linear      0 - 35 /cm        melanin (Fitzpatrick type)
skin_transport_thickness  log         0.25 - 13         mus'_dermis x skin thickness
========================  ==========  ================  ====================================

Why these six: once the probe geometry (distance, epidermis thickness, refractive index;
the cache key) is fixed, the layered model has exactly these free inputs (the epidermis
scatters like the dermis: one skin power law, Jacques 2013). The coordinates make ln R
nearly linear along each axis: ln R ~ -rho sqrt(3 mua mus') in diffusion theory (hence
sqrt(mua)), ~ -mua_e L_e through the thin epidermis (linear), power laws in mus' (log).
Thickness is counted in transport mean free paths (tau = mus'_dermis x skin thickness)
because that is the Monte Carlo's own unit; the grid keeps a node line on tau = 1 (where
the diffusion model, kept as an independent comparison, has a kink). The default box
covers LEDs anywhere in 700-1300 nm, Fitzpatrick I-VI, every preset's physiology and
skin 0.4-4 mm.

Where the table comes from: a white Monte Carlo solution of the radiative transport
equation (:mod:`nirglucose.optics.mc_white`, MCML physics with Henyey-Greenstein g = 0.9
and Fresnel escape, compiled with numba): one run per (``musp_ratio``,
``skin_transport_thickness``) solve node, in transport units, gives R and the per-layer
mean paths at every ``musp_dermis_per_cm`` node by scaling and at every absorption node
by re-weighting (exact for the RTE; Kienle & Patterson 1996, Sassaroli & Fantini 2004).
Every run uses the same random numbers (:data:`LUT_MC_SETTINGS`), so the noise is
correlated between nodes. The point reflectance at rho is a fourth-order kernel estimate
over rho +- 0.75 mm. The default grid (36 runs of 3 200 000 photons) takes about 2
hours of CPU (about 70 minutes of wall time on 2 cores); its nodes carry a Monte Carlo
standard error of R of 0.3-0.7 %. Common random numbers do not make that noise smooth
along the scattering axes (a photon's path changes with the layer boundary and the
detector window), so the table stores the three-layer diffusion model
(:mod:`nirglucose.optics.layers`) plus a least-squares fit of the Monte Carlo minus
diffusion difference over the 252 scattering nodes, for every absorption node
(:func:`_residual_fit`; the diffusion model supplies the shape, the transport solution
the level; its degrees chosen by cross-validation between two independent halves of the
photons). The thickness and ratio axes are refined by solving the diffusion model at
their refined nodes and evaluating the fit there; every other axis by cubic splines.
Multilinear interpolation through node values errs with the sign of the curvature
everywhere (ln R is convex or concave along every axis), so the stored node values are
centred (:func:`_centre_nodes`: each less its second differences / 12, which makes the
interpolant's error zero on average over every cell; Blu, Thevenaz & Unser 2004); the
float32 table is interpolated multilinearly. It is therefore not exact at its nodes.

Accuracy (README, "Layered skin optics"): interpolation, noise-free (the diffusion
solver's table against the diffusion model at 3 000 random off-grid points), RMS 0.077 %,
maximum 0.41 % (0.17 % and 0.85 % through uncentred node values); the table's own Monte
Carlo noise, RMS 0.18 % (two tables from disjoint halves of the photons compared);
against independent references (the mean of four 4 000 000-photon solves with other
seeds, standard error 0.15 %) at 204 random off-grid points in three sets
(``benchmarks/optics_reference.py``) and 24 at the thin-skin weak spot: median 0.30 %,
RMS 0.40 %, maximum 0.98 %, none beyond 1 %.
Over the paper cohort the table is 0.90-1.05 x the diffusion model (median 0.98).
``optics.lut_solver = "diffusion"`` fills the table with the diffusion model alone
(about 40 s; for sweeps of the probe geometry, each of which needs its own table).

Cache: ``<cache dir>/lut-<key>.npz``, where the key hashes the geometry, the grid and the
solver settings; the directory is ``$NIRGLUCOSE_CACHE``, else
``$XDG_CACHE_HOME/nirglucose``, else ``~/.cache/nirglucose``. Files are written
atomically (temporary file + rename) and read with ``allow_pickle=False``. The grid is
``$NIRGLUCOSE_LUT_GRID`` (default ``"default"``) where none is named.

References
----------
.. [1] A. Liemert, A. Kienle, "Light diffusion in N-layered turbid media: steady-state
   domain", J. Biomed. Opt. 15, 025003 (2010), doi:10.1117/1.3368682
.. [2] L. Wang, S. L. Jacques, L. Zheng, "MCML - Monte Carlo modeling of light transport
   in multi-layered tissues", Comput. Methods Programs Biomed. 47, 131-146 (1995),
   doi:10.1016/0169-2607(95)01640-F
.. [3] S. L. Jacques, "Optical properties of biological tissues: a review",
   Phys. Med. Biol. 58, R37-R61 (2013), doi:10.1088/0031-9155/58/11/R37
.. [4] A. Kienle, M. S. Patterson, "Determination of the optical properties of turbid
   media from a single Monte Carlo simulation", Phys. Med. Biol. 41, 2221-2227 (1996),
   doi:10.1088/0031-9155/41/10/026
.. [5] A. Sassaroli, S. Fantini, Phys. Med. Biol. 49, N255-N257 (2004),
   doi:10.1088/0031-9155/49/14/N07
.. [6] T. Blu, P. Thevenaz, M. Unser, "Linear interpolation revitalized", IEEE Trans.
   Image Process. 13, 710-719 (2004), doi:10.1109/TIP.2004.826093
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import logging
import os
import tempfile
import time
from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..exceptions import ConfigError
from . import layers, mc_white

__all__ = [
    "LUT_AXES",
    "LUT_GRIDS",
    "SkinLUT",
    "NodeLUT",
    "build_lut",
    "cache_dir",
    "lut_key",
    "load_or_build_lut",
    "get_lut",
    "interpolate_lut",
    "node_lut",
    "interpolate_node_lut",
    "reflectance_from_tissue_optics",
    "random_lut_points",
    "direct_solve",
    "lut_errors",
    "LUT_MC_PHOTONS",
    "LUT_MC_SETTINGS",
]

_log = logging.getLogger(__name__)

#: Bump when the solver or the file layout changes: old cache files are then ignored.
_FORMAT_VERSION = 5

#: Axis names, in table order, with their coordinate and unit. The thickness axis is
#: the skin (epidermis + dermis) thickness in transport mean free paths,
#: tau = mus'_dermis * skin thickness: the model's point source (one transport mean free
#: path deep) crosses into the subcutis at tau = 1, where R has a kink, and the grid
#: always has a node line there, so the kink never falls inside a cell.
LUT_AXES: dict[str, tuple[str, str]] = {
    "musp_dermis_per_cm": ("log", "1/cm"),
    "musp_ratio": ("linear", "-"),
    "mua_dermis_per_cm": ("sqrt", "1/cm"),
    "mua_subcutis_per_cm": ("sqrt", "1/cm"),
    "mua_epidermis_per_cm": ("linear", "1/cm"),
    "skin_transport_thickness": ("log", "-"),
}

#: Grids by name: per axis ``(low, high, n_solve, upsample)``. The model is solved at
#: ``n_solve`` nodes uniform in the axis' coordinate, then each axis is refined
#: ``upsample`` times by a cubic spline through the solved nodes, and the refined table,
#: its node values centred (:func:`_centre_nodes`), is what is interpolated
#: multilinearly. The thickness axis (uniform on either side of
#: tau = 1) and the ratio axis are not splined (:data:`_SOLVED_AXES`): the diffusion
#: model is solved at each of their refined nodes, and the Monte Carlo correction
#: (:func:`_residual_fit`) evaluated there. The
#: ``default`` box covers every LED in 700-1300 nm, Fitzpatrick I-VI, the physiology
#: presets and skin 0.4-4.2 mm; ``tiny`` covers the same box coarsely, for tests.
LUT_GRIDS: dict[str, dict[str, tuple[float, float, int, int]]] = {
    "default": {
        "musp_dermis_per_cm": (7.0, 30.0, 7, 3),
        "musp_ratio": (0.48, 0.85, 3, 3),
        "mua_dermis_per_cm": (0.05, 2.0, 7, 2),
        "mua_subcutis_per_cm": (0.01, 2.0, 7, 2),
        "mua_epidermis_per_cm": (0.0, 35.0, 6, 2),
        "skin_transport_thickness": (0.25, 13.0, 12, 2),
    },
    "tiny": {
        "musp_dermis_per_cm": (7.0, 30.0, 2, 1),
        "musp_ratio": (0.48, 0.85, 2, 1),
        "mua_dermis_per_cm": (0.05, 2.0, 2, 1),
        "mua_subcutis_per_cm": (0.01, 2.0, 2, 1),
        "mua_epidermis_per_cm": (0.0, 35.0, 2, 1),
        "skin_transport_thickness": (0.25, 13.0, 3, 1),
    },
}

#: Monte Carlo photons per (musp_ratio, skin_transport_thickness) node, by grid name
#: (a custom grid takes the default grid's unless :func:`build_lut` is told). The
#: default's 3.2 million: at 1.6 million the table's own noise exceeds 1 % at about 1 %
#: of random points of the box (0.13 % at 3.2 million; two tables from disjoint halves
#: of the photons compared, README). [-]
LUT_MC_PHOTONS: dict[str, int] = {"default": 3_200_000, "tiny": 8_000}

#: Settings of the white Monte Carlo behind the table (:mod:`nirglucose.optics.mc_white`;
#: all in the cache key). ``seed``: the common random numbers of every run;
#: ``half_width_cm``: the detector kernel's half-width about rho (fourth-order kernel,
#: bias O(h^4): below 0.2 % at 0.75 mm for the most absorbing skin of the box);
#: ``path_split``: path (transport mean free paths) past which each doubling of a
#: photon's path plays Russian roulette (3x faster; 3-4x the mean path of the light
#: detected at the farthest rho* of the box); ``anisotropy``: Henyey-Greenstein g;
#: ``residual_fit_degrees``: degrees (ln mus'_dermis, musp_ratio, ln tau) of the fit that
#: removes the node noise along the scattering axes (:func:`_residual_fit`;
#: None keeps the raw Monte Carlo nodes); chosen by cross-validation between two
#: disjoint halves of the default build's photons (fit one half, predict the other's
#: nodes, and along ln tau its nodes left out one at a time): 4 in ln mus' (3 leaves
#: a 0.3 % bias at the nodes), 5 along ln tau (6 or more oscillate between the nodes).
LUT_MC_SETTINGS: dict = {
    "seed": 9,
    "half_width_cm": 0.075,
    "path_split": 300.0,
    "anisotropy": mc_white.SKIN_ANISOTROPY,
    "residual_fit_degrees": (4, 2, 5),
}

#: What solves the model at the table's nodes. ``"monte-carlo"`` (default): the white
#: Monte Carlo of the RTE above, about 2 CPU-hours for the default grid, with 0.3-0.7 %
#: noise per node. ``"diffusion"``: the three-layer diffusion model
#: (:func:`nirglucose.optics.layers.three_layer_reflectance`), about 40 s, smooth, within
#: 1.5-3 % of Monte Carlo for most skin (``nirglucose.optics.mc_paths``) and 0.90-1.05 x
#: the Monte Carlo table over the paper cohort: for quick sweeps of the probe geometry.
LUT_SOLVERS = ("monte-carlo", "diffusion")

#: Scattering axes (table positions): those the white Monte Carlo runs or scales over,
#: along which :func:`_residual_fit` smooths the Monte Carlo noise.
_SCATTERING = tuple(list(LUT_AXES).index(k) for k in
                    ("musp_dermis_per_cm", "musp_ratio", "skin_transport_thickness"))

#: Axes at whose refined nodes the diffusion model is solved (and the Monte Carlo fit
#: evaluated) instead of splined through the solve nodes: the thickness axis, where R
#: has the kink at tau = 1, and the ratio axis, whose 3 solve nodes give only a
#: quadratic spline where thin skin makes R depend strongly on the subcutis.
_SOLVED_AXES = ("musp_ratio", "skin_transport_thickness")

#: Output channels of :attr:`SkinLUT.values`.
_CHANNELS = ("ln_reflectance", "ln_path_epidermis", "ln_path_dermis", "ln_path_subcutis")

#: Paths below this are stored as this (a layer the detected light hardly reaches; the
#: finite-difference path there is rounding noise). [cm]
_PATH_FLOOR_CM = 1e-6

#: On every grid node the skin is at least this many times thicker than the epidermis.
_MIN_SKIN_OVER_EPIDERMIS = 1.25


def _forward(kind: str, x: np.ndarray) -> np.ndarray:
    # a negative input becomes NaN here, which the range check then reports by axis name
    with np.errstate(invalid="ignore", divide="ignore"):
        if kind == "log":
            return np.log(x)
        if kind == "sqrt":
            return np.sqrt(x)
    return x


def _inverse(kind: str, u: np.ndarray) -> np.ndarray:
    if kind == "log":
        return np.exp(u)
    if kind == "sqrt":
        return u * u
    return u


@dataclass(frozen=True)
class SkinLUT:
    """A tabulated three-layer skin model at one probe geometry.

    Attributes
    ----------
    values : ndarray
        (*shape, 4), float32: ln R [ln(1/cm^2)] and ln of the epidermis, dermis and
        subcutis paths [ln cm] at the (refined) grid nodes; paths below 1e-6 cm are
        stored as 1e-6 cm.
    nodes : tuple of ndarray
        Node coordinates of each axis (in the axis' coordinate: log, sqrt or linear);
        uniform, except the thickness axis, uniform on either side of tau = 1.
    shape : tuple of int
        Nodes per axis.
    grid : dict
        The grid spec (axis -> (low, high, n_solve, upsample)).
    geometry : dict
        ``rho_cm``, ``epidermis_thickness_cm``, ``n_tissue``, ``n_ambient``.
    key : str
        Cache key (hash of geometry, grid and solver settings).
    build_seconds : float
        Wall-clock time the build took (0 when loaded from the cache). [s]
    n_solves : int
        Grid nodes at which the model was solved. [-]
    solver : str
        What solved the nodes, one of :data:`LUT_SOLVERS`.
    """

    values: NDArray[np.float32] = field(repr=False)
    nodes: tuple[NDArray[np.float64], ...] = field(repr=False)
    shape: tuple[int, ...]
    grid: dict
    geometry: dict
    key: str
    build_seconds: float = 0.0
    n_solves: int = 0
    solver: str = "monte-carlo"

    def axis_nodes(self, name: str) -> NDArray[np.float64]:
        """Physical values of the nodes of one axis."""
        i = list(LUT_AXES).index(name)
        return _inverse(LUT_AXES[name][0], self.nodes[i])

    @property
    def box(self) -> dict[str, tuple[float, float]]:
        """Physical (low, high) of each axis actually covered by the nodes."""
        return {k: (float(v[0]), float(v[-1]))
                for k, v in ((k, self.axis_nodes(k)) for k in LUT_AXES)}


def _check_grid(grid: dict) -> None:
    if set(grid) != set(LUT_AXES):
        raise ConfigError(f"a LUT grid needs exactly the axes {list(LUT_AXES)}, got {list(grid)}")
    for name, (lo, hi, n, m) in grid.items():
        kind, unit = LUT_AXES[name]
        if not (np.isfinite(hi) and hi > lo and n >= 2 and m >= 1):
            raise ConfigError(
                f"LUT axis {name}: (low, high, n_solve, upsample) = {(lo, hi, n, m)} needs "
                f"low < high, n_solve >= 2 and upsample >= 1 [{unit}]"
            )
        if lo < 0 or (kind == "log" and lo == 0):
            raise ConfigError(
                f"LUT axis {name}: low = {lo!r} is out of range; valid range is "
                f"{'(0' if kind == 'log' else '[0'}, high) [{unit}]"
            )


def _resolve_grid(grid: str | dict) -> dict:
    if isinstance(grid, str):
        if grid not in LUT_GRIDS:
            raise ConfigError(f"unknown LUT grid {grid!r}; valid: {', '.join(LUT_GRIDS)}")
        grid = LUT_GRIDS[grid]
    grid = {k: (float(v[0]), float(v[1]), int(v[2]), int(v[3])) for k, v in grid.items()}
    _check_grid(grid)
    return grid


def _geometry(separation_cm, epidermis_thickness_cm, n_tissue, n_ambient) -> dict:
    geo = {
        "rho_cm": float(separation_cm),
        "epidermis_thickness_cm": float(epidermis_thickness_cm),
        "n_tissue": float(n_tissue),
        "n_ambient": float(n_ambient),
    }
    for name, v in geo.items():
        if not (np.isfinite(v) and v > 0):
            raise ConfigError(f"{name} = {v!r} is out of range; valid range is (0, inf)")
    return geo


def lut_key(
    separation_cm: float,
    epidermis_thickness_cm: float,
    n_tissue: float = 1.4,
    n_ambient: float = 1.0,
    grid: str | dict = "default",
    *,
    n_photons: int | None = None,
    solver: str = "monte-carlo",
) -> str:
    """Hash of everything a table depends on: geometry, grid, solver and its settings.

    Examples
    --------
    >>> len(lut_key(0.3, 0.008))
    20
    """
    _check_solver(solver)
    payload = {
        "version": _FORMAT_VERSION,
        "geometry": _geometry(separation_cm, epidermis_thickness_cm, n_tissue, n_ambient),
        "grid": _resolve_grid(grid),
        "solver": {
            "diffusion": "layered-hankel-1",  # layers.py's solver; bump when it changes
            "min_skin_over_epidermis": _MIN_SKIN_OVER_EPIDERMIS,
            "path_floor_cm": _PATH_FLOOR_CM,
        } if solver == "diffusion" else {
            "monte_carlo": "white-mc-1",  # mc_white's algorithm; bump when it changes
            "n_photons": _mc_photons(grid, n_photons),
            **LUT_MC_SETTINGS,
            "batch_photons": mc_white._BATCH_PHOTONS,
            "split_survival": mc_white._SPLIT_SURVIVAL,
            "min_skin_over_epidermis": _MIN_SKIN_OVER_EPIDERMIS,
            "path_floor_cm": _PATH_FLOOR_CM,
        },
    }
    text = json.dumps(payload, sort_keys=True)
    return hashlib.sha256(text.encode()).hexdigest()[:20]


def _check_solver(solver: str) -> None:
    if solver not in LUT_SOLVERS:
        raise ConfigError(f"unknown look-up table solver {solver!r}; valid: "
                          f"{', '.join(LUT_SOLVERS)}")


def _mc_photons(grid: str | dict, n_photons: int | None) -> int:
    """Photons per Monte Carlo run: given, else the grid's, else the default grid's."""
    if n_photons is None:
        name = grid if isinstance(grid, str) else "default"
        n_photons = LUT_MC_PHOTONS.get(name, LUT_MC_PHOTONS["default"])
    if isinstance(n_photons, bool) or not isinstance(n_photons, int | np.integer) \
            or n_photons < 1:
        raise ConfigError(f"n_photons = {n_photons!r} is invalid; expected an integer >= 1 [-]")
    return int(n_photons)


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
    """Keyword arguments of :func:`~nirglucose.optics.mc_white.white_mc_run` for a table."""
    return {
        "n_photons": n_photons,
        "seed": int(LUT_MC_SETTINGS["seed"]),
        "mua_ref": _mua_ref(grid),
        "g": float(LUT_MC_SETTINGS["anisotropy"]),
        "n_tissue": geo["n_tissue"],
        "n_ambient": geo["n_ambient"],
        "path_split": float(LUT_MC_SETTINGS["path_split"]),
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
    One run of :func:`~nirglucose.optics.mc_white.white_mc_run` per
    (``musp_ratio``, ``skin_transport_thickness``) solve node, in transport units;
    :func:`~nirglucose.optics.mc_white.white_mc_tally` turns it into R and the mean
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
    degrees = LUT_MC_SETTINGS["residual_fit_degrees"]
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
    run (:func:`~nirglucose.optics.mc_white.white_mc_run`); disjoint ranges give
    independent node values (``benchmarks/optics_fit_degrees.py``).
    """
    musp = ax["musp_dermis_per_cm"]
    rho, half = geo["rho_cm"], float(LUT_MC_SETTINGS["half_width_cm"])
    if not half < rho:
        raise ConfigError(f"separation_cm = {rho!r} must exceed the detector kernel's "
                          f"half-width {half!r} [cm]")
    band = ((rho - half) * float(musp.min()), (rho + half) * float(musp.max()))
    run_kw = _mc_run_kwargs(grid, geo, photons)
    shape = tuple(a.size for a in ax.values())
    values = np.empty(shape + (4,))
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


# ------------------------------------------------------------------------------- cache


def cache_dir() -> Path:
    """``$NIRGLUCOSE_CACHE``, else ``$XDG_CACHE_HOME/nirglucose``, else ``~/.cache/nirglucose``."""
    env = os.environ.get("NIRGLUCOSE_CACHE")
    if env:
        return Path(env)
    xdg = os.environ.get("XDG_CACHE_HOME")
    return (Path(xdg) if xdg else Path.home() / ".cache") / "nirglucose"


def _save(lut: SkinLUT, path: Path) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=path.name, suffix=".tmp")
    try:
        with os.fdopen(fd, "wb") as fh:
            np.savez(
                fh,
                values=lut.values,
                nodes=np.concatenate(lut.nodes),
                shape=np.array(lut.shape, dtype=np.int64),
                grid=np.array(json.dumps(lut.grid, sort_keys=True)),
                geometry=np.array(json.dumps(lut.geometry, sort_keys=True)),
                key=np.array(lut.key),
                n_solves=np.array(lut.n_solves, dtype=np.int64),
                solver=np.array(lut.solver),
            )
        os.chmod(tmp, 0o644)  # mkstemp makes it private; a cache is for every reader
        os.replace(tmp, path)  # atomic on POSIX: readers see the old file or the new one
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise


def _load(path: Path, key: str) -> SkinLUT | None:
    try:
        with np.load(path, allow_pickle=False) as f:
            if str(f["key"]) != key:
                return None
            return SkinLUT(
                values=f["values"].copy(),
                nodes=tuple(np.split(f["nodes"].copy(), np.cumsum(f["shape"])[:-1])),
                shape=tuple(int(v) for v in f["shape"]),
                grid={k: tuple(v) for k, v in json.loads(str(f["grid"])).items()},
                geometry=json.loads(str(f["geometry"])),
                key=key,
                n_solves=int(f["n_solves"]),
                solver=str(f["solver"]) if "solver" in f.files else "monte-carlo",
            )
    except (OSError, ValueError, KeyError) as exc:
        _log.warning("ignoring unreadable LUT cache file %s (%s)", path, exc)
        return None


def load_or_build_lut(
    separation_cm: float,
    epidermis_thickness_cm: float,
    n_tissue: float = 1.4,
    n_ambient: float = 1.0,
    *,
    grid: str | dict = "default",
    directory: str | os.PathLike | None = None,
    solver: str = "monte-carlo",
) -> SkinLUT:
    """The table for a geometry: read from the disk cache, or built and written there.

    Parameters
    ----------
    separation_cm, epidermis_thickness_cm, n_tissue, n_ambient
        See :func:`build_lut`.
    grid : str or dict, optional
        Grid name or spec. Default "default".
    solver : {'monte-carlo', 'diffusion'}, optional
        What solves the nodes (:data:`LUT_SOLVERS`). Default "monte-carlo".
    directory : path, optional
        Cache directory; :func:`cache_dir` when omitted.

    Returns
    -------
    SkinLUT
        ``build_seconds`` is 0 when it came from the cache.
    """
    key = lut_key(separation_cm, epidermis_thickness_cm, n_tissue, n_ambient, grid,
                  solver=solver)
    path = Path(directory) if directory is not None else cache_dir()
    path = path / f"lut-{key}.npz"
    if path.exists():
        lut = _load(path, key)
        if lut is not None:
            return lut
    if solver == "monte-carlo":  # minutes to hours: say so where it shows
        spec = _resolve_grid(grid)
        runs = spec["musp_ratio"][2] * spec["skin_transport_thickness"][2]
        _log.warning("building the rte-lut skin table %s by Monte Carlo: %d runs of %d "
                     "photons (the default grid: about 2 hours of CPU), once per probe "
                     "geometry, cached in %s; optics.lut_solver=diffusion builds one in "
                     "about 40 s", key, runs, _mc_photons(grid, None), path.parent)
    else:
        _log.info("building the skin LUT %s (grid %s, solver %s)", key,
                  grid if isinstance(grid, str) else "custom", solver)
    lut = build_lut(separation_cm, epidermis_thickness_cm, n_tissue, n_ambient, grid=grid,
                    solver=solver)
    try:
        _save(lut, path)
    except OSError as exc:  # a read-only home still simulates, it just rebuilds next time
        _log.warning("could not write the LUT cache %s (%s)", path, exc)
    return lut


@lru_cache(maxsize=8)
def _get_lut(separation_cm, epidermis_thickness_cm, n_tissue, n_ambient, grid, directory,
             solver):
    return load_or_build_lut(separation_cm, epidermis_thickness_cm, n_tissue, n_ambient,
                             grid=grid, directory=directory, solver=solver)


def get_lut(
    separation_cm: float,
    epidermis_thickness_cm: float,
    n_tissue: float = 1.4,
    n_ambient: float = 1.0,
    *,
    grid: str | None = None,
    solver: str = "monte-carlo",
) -> SkinLUT:
    """:func:`load_or_build_lut`, memoised per process, for the current cache directory.

    ``grid`` defaults to ``$NIRGLUCOSE_LUT_GRID``, else ``"default"``.
    """
    grid = grid or os.environ.get("NIRGLUCOSE_LUT_GRID", "default")
    return _get_lut(float(separation_cm), float(epidermis_thickness_cm), float(n_tissue),
                    float(n_ambient), grid, str(cache_dir()), solver)


# ------------------------------------------------------------------------ interpolation


@lru_cache(maxsize=256)
def _axis_map(nodes_bytes: bytes) -> tuple[float, float, int, float]:
    """(u0, h_low, n_low, h_high): node i at u0 + i h_low up to n_low, then h_high after."""
    u = np.frombuffer(nodes_bytes, dtype=np.float64)
    d = np.diff(u)
    if np.allclose(d, d[0], rtol=1e-9, atol=0.0):
        return float(u[0]), float(d[0]), u.size - 1, float(d[0])
    n_low = int(np.argmax(~np.isclose(d, d[0], rtol=1e-9, atol=0.0)))
    if not np.allclose(d[n_low:], d[n_low], rtol=1e-9, atol=0.0):  # pragma: no cover
        raise ConfigError("LUT axes must be uniform, or uniform on either side of one node")
    return float(u[0]), float(d[0]), n_low, float(d[n_low])


def _cell_coords(
    nodes: list[np.ndarray], names: list[str], inputs: list[np.ndarray],
) -> tuple[list[np.ndarray], list[np.ndarray]]:
    """Cell index and fraction along each axis; raises for points outside the nodes."""
    idx, frac = [], []
    for u_nodes, name, x in zip(nodes, names, inputs, strict=True):
        kind, unit = LUT_AXES[name]
        n = u_nodes.size
        u0, h_lo, n_lo, h_hi = _axis_map(np.ascontiguousarray(u_nodes, dtype=np.float64).tobytes())
        pos = _forward(kind, x) - u0
        pos /= h_lo
        if n_lo < n - 1:  # two-piece axis: past node n_lo the spacing changes
            hi_part = pos > n_lo
            pos[hi_part] = n_lo + (pos[hi_part] - n_lo) * (h_lo / h_hi)
        pmin, pmax = np.min(pos, initial=np.inf), np.max(pos, initial=-np.inf)
        tol = 1e-9 * n
        if not (pmin >= -tol and pmax <= n - 1 + tol):  # also catches NaN
            lo, hi = _inverse(kind, u_nodes[0]), _inverse(kind, u_nodes[-1])
            bad = x.flat[int(np.argmin(pos))] if not pmin >= -tol else x.flat[int(np.argmax(pos))]
            if np.isnan(pmin) or np.isnan(pmax):
                bad = float("nan")
            hint = " (mus'_dermis x skin thickness)" if name == "skin_transport_thickness" else ""
            raise ConfigError(
                f"{name}{hint} = {bad!r} is outside the look-up table; valid range is "
                f"[{lo:.6g}, {hi:.6g}] [{unit}] (use another grid or forward model)"
            )
        j = pos.astype(np.intp)
        np.clip(j, 0, n - 2, out=j)
        pos -= j
        idx.append(j)
        frac.append(pos)
    return idx, frac


def _multilinear(flat: np.ndarray, strides: np.ndarray, idx, frac, base=None) -> np.ndarray:
    """Multilinear interpolation on a flattened (n_nodes, C) table; returns (M, C)."""
    d = len(idx)
    offsets = np.zeros(1, dtype=np.intp)
    for k in reversed(range(d)):  # dimension 0 ends as the most significant corner bit
        offsets = np.concatenate([offsets, offsets + strides[k]])
    lin = idx[0] * strides[0] if base is None else base + idx[0] * strides[0]
    for k in range(1, d):
        lin = lin + idx[k] * strides[k]
    vals = flat[lin[:, None] + offsets[None, :]]  # (M, 2^d, C)
    for k in range(d):
        half = vals.shape[1] // 2
        a = vals[:, :half]
        vals = a + frac[k][:, None, None] * (vals[:, half:] - a)
    return vals[:, 0]


def _multilinear_1d(flat: np.ndarray, strides: np.ndarray, lin: np.ndarray, frac) -> np.ndarray:
    """Multilinear interpolation on a 1-D table (the hot path), depth first.

    ``lin`` is the flat index of each point's lower corner; one ``take`` per corner and
    one lerp per pair keep every temporary at (M,), which stays in the CPU cache.
    """
    d = len(frac)

    def corner(level: int, offset: int) -> np.ndarray:
        if level == d:
            return flat.take(lin + offset if offset else lin)
        a = corner(level + 1, offset)
        b = corner(level + 1, offset + int(strides[level]))
        b -= a
        b *= frac[level]
        b += a
        return b

    return corner(0, 0)


def _strides(shape: tuple[int, ...]) -> np.ndarray:
    return np.array([int(np.prod(shape[k + 1:])) for k in range(len(shape))], dtype=np.intp)


def interpolate_lut(
    lut: SkinLUT,
    *,
    mua_epidermis_per_cm: ArrayLike,
    mua_dermis_per_cm: ArrayLike,
    musp_dermis_per_cm: ArrayLike,
    mua_subcutis_per_cm: ArrayLike,
    musp_subcutis_per_cm: ArrayLike,
    skin_thickness_cm: ArrayLike,
    pathlengths: bool = False,
) -> tuple[NDArray[np.float64], NDArray[np.float64] | None]:
    """Reflectance (and per-layer path) of three-layer skin, from the table.

    Same inputs and outputs as :func:`nirglucose.optics.layers.three_layer_reflectance`
    at the table's geometry; multilinear in the axes' coordinates, in log of the outputs.

    Parameters
    ----------
    lut : SkinLUT
        The table.
    mua_epidermis_per_cm, mua_dermis_per_cm, mua_subcutis_per_cm : array_like
        Absorption of each layer. [1/cm]
    musp_dermis_per_cm, musp_subcutis_per_cm : array_like
        Reduced scattering of the skin and of the subcutis. [1/cm]
    skin_thickness_cm : array_like
        Epidermis + dermis thickness. [cm]
    pathlengths : bool, optional
        Also return the paths. Default False.

    Returns
    -------
    reflectance_per_cm2 : ndarray
        R(rho). [1/cm^2]
    pathlength_cm : ndarray or None
        Mean path per layer (last axis: epidermis, dermis, subcutis). [cm]

    Raises
    ------
    ConfigError
        If a point lies outside the table's box (the message names the axis and range).

    References
    ----------
    .. [1] A. Liemert, A. Kienle, J. Biomed. Opt. 15, 025003 (2010),
       doi:10.1117/1.3368682

    Examples
    --------
    >>> lut = build_lut(0.3, 0.008, grid="tiny")
    >>> r, _ = interpolate_lut(lut, mua_epidermis_per_cm=2.0, mua_dermis_per_cm=0.3,
    ...     musp_dermis_per_cm=20.0, mua_subcutis_per_cm=0.1, musp_subcutis_per_cm=12.0,
    ...     skin_thickness_cm=0.18)
    >>> bool(0.1 < r < 1.0)
    True
    """
    arrays = np.broadcast_arrays(*(np.asarray(v, dtype=float) for v in (
        mua_epidermis_per_cm, mua_dermis_per_cm, musp_dermis_per_cm, mua_subcutis_per_cm,
        musp_subcutis_per_cm, skin_thickness_cm)))
    shape = arrays[0].shape
    mua_e, mua_d, musp_d, mua_s, musp_s, t_skin = (a.ravel() for a in arrays)
    inputs = [musp_d, musp_s / musp_d, mua_d, mua_s, mua_e, musp_d * t_skin]
    idx, frac = _cell_coords(list(lut.nodes), list(LUT_AXES), inputs)
    n_ch = 4 if pathlengths else 1
    flat = lut.values.reshape(-1, 4)[:, :n_ch]
    out = np.exp(_multilinear(flat, _strides(lut.shape), idx, frac).astype(np.float64))
    refl = out[:, 0].reshape(shape)
    paths = out[:, 1:].reshape(shape + (3,)) if pathlengths else None
    return refl, paths


@dataclass(frozen=True)
class NodeLUT:
    """A :class:`SkinLUT` specialised to fixed wavelength nodes (the simulator's fast path).

    Along ``musp_ratio`` (the subcutis/dermis scattering ratio, which depends on
    wavelength only) the table is replaced, per node, by its value and slope at the
    node's ratio: exact for the multilinear interpolant while the ratio stays in the
    node's cell. Only ln R is kept. ``values`` has shape (n_nodes, *other axes), complex64:
    ln R + 1j d(ln R)/d(ratio) (one gather fetches both, and the multilinear weights are
    real, so complex arithmetic interpolates the two channels at once).
    """

    values: NDArray[np.float32] = field(repr=False)
    musp_ratio: NDArray[np.float64] = field(repr=False)
    node_shape: tuple[int, ...]
    lut: SkinLUT = field(repr=False)

    def __reduce__(self):
        # pickle the recipe, not the arrays: a worker process rebuilds the node table
        # from its own disk cache (simulate_block's tables travel to Dask/joblib workers)
        geo = self.lut.geometry
        return (_node_lut_from_recipe, (
            geo["rho_cm"], geo["epidermis_thickness_cm"], geo["n_tissue"], geo["n_ambient"],
            self.lut.grid, self.musp_ratio.tolist(), self.lut.solver,
        ))


_Q = list(LUT_AXES).index("musp_ratio")
_NOT_Q = [i for i in range(len(LUT_AXES)) if i != _Q]


_NODE_CACHE: dict[tuple, NodeLUT] = {}
_NODE_CACHE_SIZE = 8


def node_lut(lut: SkinLUT, musp_ratio: ArrayLike) -> NodeLUT:
    """Specialise a table to fixed subcutis/dermis scattering ratios, one per node.

    Memoised per process on the table's key and the ratios (the simulator asks for the
    same one at every call of its tables).

    Parameters
    ----------
    lut : SkinLUT
        The table.
    musp_ratio : array_like
        mus'_subcutis / mus'_dermis at each node, any shape (e.g. (n_led, n_pts)). [-]

    Returns
    -------
    NodeLUT
    """
    q = np.ascontiguousarray(musp_ratio, dtype=float)
    memo = (lut.key, q.shape, q.tobytes())
    if memo in _NODE_CACHE:
        return _NODE_CACHE[memo]
    (j,), (f,) = _cell_coords([lut.nodes[_Q]], ["musp_ratio"], [q.ravel()])
    v = np.moveaxis(lut.values[..., 0], _Q, 0)  # (n_q, ...) view, float32
    v0 = v[j].astype(np.float64)  # (n_nodes, ...)
    v1 = v[j + 1].astype(np.float64)
    ff = f.reshape((-1,) + (1,) * (v0.ndim - 1))
    slope = v1 - v0
    value = v0 + ff * slope
    slope /= np.diff(lut.nodes[_Q])[j].reshape(ff.shape)
    values = np.ascontiguousarray((value + 1j * slope).astype(np.complex64))
    out = NodeLUT(values, q.copy(), q.shape, lut)
    if len(_NODE_CACHE) >= _NODE_CACHE_SIZE:
        _NODE_CACHE.pop(next(iter(_NODE_CACHE)))
    _NODE_CACHE[memo] = out
    return out


def _node_lut_from_recipe(rho_cm, epidermis_thickness_cm, n_tissue, n_ambient, grid, ratio,
                          solver="monte-carlo"):
    grid = {k: tuple(v) for k, v in grid.items()}
    named = [k for k, v in LUT_GRIDS.items() if _resolve_grid(v) == _resolve_grid(grid)]
    lut = (get_lut(rho_cm, epidermis_thickness_cm, n_tissue, n_ambient, grid=named[0],
                   solver=solver)
           if named else load_or_build_lut(rho_cm, epidermis_thickness_cm, n_tissue,
                                           n_ambient, grid=grid, solver=solver))
    return node_lut(lut, np.asarray(ratio))


def _node_kernel_args(nlut: NodeLUT) -> tuple:
    """The table arguments of :func:`._lut_kernel.node_reflectance`, cached on the table.

    ``(table words, cells per node, node ratios, axis_f, axis_i)``; see the kernel.
    """
    cached = nlut.__dict__.get("_kernel_args")
    if cached is not None:
        return cached
    from ._lut_kernel import KERNEL_AXES

    lut = nlut.lut
    kinds = tuple(LUT_AXES[list(LUT_AXES)[i]][0] for i in _NOT_Q)
    if kinds != KERNEL_AXES:  # pragma: no cover - a guard for whoever edits LUT_AXES
        raise ConfigError(f"the LUT kernel expects axes {KERNEL_AXES}, the table has {kinds}")
    strides = [*_strides(tuple(lut.shape[i] for i in _NOT_Q)), 0]
    axis_f = np.empty((6, 4))
    axis_i = np.empty((6, 3), dtype=np.int64)
    for row, (i, stride) in enumerate(zip([*_NOT_Q, _Q], strides, strict=True)):
        u = np.ascontiguousarray(lut.nodes[i], dtype=np.float64)
        u0, h_lo, n_lo, h_hi = _axis_map(u.tobytes())  # the map _cell_coords uses
        axis_f[row] = (u0, 1.0 / h_lo, h_lo / h_hi, 1e-9 * u.size)
        axis_i[row] = (n_lo, u.size, stride)
    values = np.ascontiguousarray(nlut.values, dtype=np.complex64)
    cached = (values.reshape(-1).view(np.int64), values[0].size,
              np.ascontiguousarray(nlut.musp_ratio, dtype=np.float64).ravel(), axis_f, axis_i)
    object.__setattr__(nlut, "_kernel_args", cached)  # frozen dataclass: a cache slot
    return cached


def interpolate_node_lut(
    nlut: NodeLUT,
    *,
    mua_epidermis_per_cm: np.ndarray,
    mua_dermis_per_cm: np.ndarray,
    musp_dermis_per_cm: np.ndarray,
    mua_subcutis_per_cm: np.ndarray,
    musp_subcutis_per_cm: np.ndarray,
    skin_thickness_cm: np.ndarray,
) -> NDArray[np.float64]:
    """Reflectance R(rho) from a :class:`NodeLUT`, as :func:`interpolate_lut` gives it.

    One call of a compiled kernel (:mod:`nirglucose.optics._lut_kernel`): coordinates,
    cells, the 32-corner multilinear interpolation and the ``musp_ratio`` slope in one
    pass over the points; equal to the numpy reference (``_interpolate_node_lut_numpy``)
    to float32 rounding of ln R.

    Parameters
    ----------
    nlut : NodeLUT
        The node table.
    mua_epidermis_per_cm, mua_dermis_per_cm, mua_subcutis_per_cm : array_like
        Absorption of each layer, (n, *node_shape). [1/cm]
    musp_dermis_per_cm, musp_subcutis_per_cm : array_like
        Reduced scattering of the skin and of the subcutis, (n, *node_shape). [1/cm]
    skin_thickness_cm : array_like
        Epidermis + dermis thickness, (n,) or (n, *node_shape). [cm]

    Returns
    -------
    ndarray
        R(rho), (n, *node_shape). [1/cm^2]

    Raises
    ------
    ConfigError
        If a point lies outside the table's box (the message names the axis and range).
    """
    from ._lut_kernel import node_reflectance

    mua_d = np.asarray(mua_dermis_per_cm, dtype=float)
    full = mua_d.shape
    k = len(nlut.node_shape)
    if full[len(full) - k:] != nlut.node_shape:
        raise ConfigError(
            f"inputs of shape {full} do not end with the node shape {nlut.node_shape}"
        )

    def flat(a: ArrayLike) -> np.ndarray:  # C order, 1-D; a view where it can be
        return np.ascontiguousarray(np.broadcast_to(np.asarray(a, dtype=float), full)).ravel()

    t = np.asarray(skin_thickness_cm, dtype=float)
    ln_t = np.log(t.reshape(t.shape + (1,) * (len(full) - t.ndim)))  # one log per row
    out = np.empty(mua_d.size)
    bad = node_reflectance(
        *_node_kernel_args(nlut), flat(mua_d), flat(mua_subcutis_per_cm),
        flat(mua_epidermis_per_cm), flat(ln_t), flat(musp_subcutis_per_cm),
        flat(musp_dermis_per_cm), out,
    )
    if bad >= 0:  # the reference names the axis and the range, and raises
        return _interpolate_node_lut_numpy(
            nlut, mua_epidermis_per_cm=mua_epidermis_per_cm, mua_dermis_per_cm=mua_d,
            musp_dermis_per_cm=musp_dermis_per_cm, mua_subcutis_per_cm=mua_subcutis_per_cm,
            musp_subcutis_per_cm=musp_subcutis_per_cm, skin_thickness_cm=skin_thickness_cm,
        )
    return out.reshape(full)


def _interpolate_node_lut_numpy(
    nlut: NodeLUT,
    *,
    mua_epidermis_per_cm: np.ndarray,
    mua_dermis_per_cm: np.ndarray,
    musp_dermis_per_cm: np.ndarray,
    mua_subcutis_per_cm: np.ndarray,
    musp_subcutis_per_cm: np.ndarray,
    skin_thickness_cm: np.ndarray,
) -> NDArray[np.float64]:
    """Numpy reference of :func:`interpolate_node_lut` (the tests compare the two)."""
    lut = nlut.lut
    mua_d = np.asarray(mua_dermis_per_cm, dtype=float)
    full = mua_d.shape
    k = len(nlut.node_shape)
    if full[len(full) - k:] != nlut.node_shape:
        raise ConfigError(
            f"inputs of shape {full} do not end with the node shape {nlut.node_shape}"
        )
    lead = len(full) - k
    # node-major order: consecutive points read the same node's slab (cache locality)
    perm = tuple(range(lead, len(full))) + tuple(range(lead))

    def flat(a: ArrayLike) -> np.ndarray:
        return np.broadcast_to(a, full).transpose(perm).ravel()

    t = np.asarray(skin_thickness_cm, dtype=float)
    t = t.reshape(t.shape + (1,) * (len(full) - t.ndim))
    musp_d = flat(musp_dermis_per_cm)
    q = flat(musp_subcutis_per_cm) / musp_d
    inputs = [musp_d, flat(mua_d), flat(mua_subcutis_per_cm), flat(mua_epidermis_per_cm),
              musp_d * flat(t)]
    names = [n for n in LUT_AXES if n != "musp_ratio"]
    shape = tuple(lut.shape[i] for i in _NOT_Q)
    idx, frac = _cell_coords([lut.nodes[i] for i in _NOT_Q], names, inputs)
    _cell_coords([lut.nodes[_Q]], ["musp_ratio"], [q])
    strides = _strides(shape)
    n_nodes = int(np.prod(nlut.node_shape))
    n_rows = q.size // n_nodes
    lin = np.repeat(np.arange(n_nodes, dtype=np.intp) * int(np.prod(shape)), n_rows)
    for j, s in zip(idx, strides, strict=True):
        lin += j * s
    out = _multilinear_1d(nlut.values.ravel(), strides, lin,
                          [f.astype(np.float32) for f in frac])
    dq = q - np.repeat(nlut.musp_ratio.ravel(), n_rows)
    ln_r = out.real.astype(np.float64) + dq * out.imag
    return np.exp(ln_r).reshape(tuple(full[i] for i in perm)).transpose(np.argsort(perm))


def reflectance_from_tissue_optics(
    optics: dict,
    *,
    melanin_fraction: ArrayLike,
    skin_thickness_cm: ArrayLike,
    epidermis_thickness_cm: float,
    separation_cm: float,
    n_tissue: float,
    lut: SkinLUT | NodeLUT | None = None,
) -> NDArray[np.float64]:
    """R(rho) of three-layer skin for the simulator's tissue optics, from the table.

    Parameters
    ----------
    optics : dict
        Output of :func:`nirglucose.optics.tissue.tissue_optics`, (n, n_led, n_pts). [1/cm]
    melanin_fraction : array_like
        Epidermal melanosome fraction, (n,). [-]
    skin_thickness_cm : array_like
        Epidermis + dermis thickness, (n,). [cm]
    epidermis_thickness_cm, separation_cm : float
        Probe geometry; must match the table's. [cm]
    n_tissue : float
        Tissue refractive index; must match the table's. [-]
    lut : SkinLUT or NodeLUT, optional
        The table; :func:`get_lut` for this geometry when omitted.

    Returns
    -------
    ndarray
        R(rho), (n, n_led, n_pts). [1/cm^2]
    """
    if lut is None:
        lut = get_lut(separation_cm, epidermis_thickness_cm, n_tissue)
    geo = (lut.lut if isinstance(lut, NodeLUT) else lut).geometry
    want = {"rho_cm": separation_cm, "epidermis_thickness_cm": epidermis_thickness_cm,
            "n_tissue": n_tissue}
    for name, v in want.items():
        if not np.isclose(geo[name], float(v), rtol=1e-12, atol=0.0):
            raise ConfigError(f"the look-up table was built for {name} = {geo[name]!r}, "
                              f"not {float(v)!r}")
    lay = layers.layers_from_tissue_optics(optics, melanin_fraction)
    t = np.asarray(skin_thickness_cm, dtype=float)
    args = {
        "mua_epidermis_per_cm": lay["mua_epidermis"],
        "mua_dermis_per_cm": lay["mua_dermis"],
        "musp_dermis_per_cm": lay["musp_dermis"],
        "mua_subcutis_per_cm": lay["mua_subcutis"],
        "musp_subcutis_per_cm": lay["musp_subcutis"],
    }
    if isinstance(lut, NodeLUT):
        return interpolate_node_lut(lut, skin_thickness_cm=t, **args)
    t = t.reshape(t.shape + (1,) * (lay["mua_dermis"].ndim - t.ndim))
    return interpolate_lut(lut, skin_thickness_cm=t, **args)[0]


# --------------------------------------------------------------------------- validation


def random_lut_points(lut: SkinLUT, n_points: int, *, rng: np.random.Generator | int = 0,
                      groups: int | None = None) -> dict[str, NDArray[np.float64]]:
    """Points uniform in each axis' coordinate over the table's box, as solver inputs.

    Returns keyword arguments for :func:`interpolate_lut` and
    :func:`~nirglucose.optics.layers.three_layer_reflectance`. With ``groups``, the
    points come in that many consecutive groups that share ``musp_ratio`` and
    ``skin_transport_thickness`` (so one Monte Carlo run solves a group: see
    :func:`lut_errors`); every other coordinate is drawn per point.
    """
    gen = rng if isinstance(rng, np.random.Generator) else np.random.default_rng(rng)
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
    named = [k for k, v in LUT_GRIDS.items() if _resolve_grid(v) == grid]
    photons = _mc_photons(named[0] if named else grid, n_photons)
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
            geo["rho_cm"], float(LUT_MC_SETTINGS["half_width_cm"]),
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
