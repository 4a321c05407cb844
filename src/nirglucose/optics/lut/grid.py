"""The table's grid: axes, named grids, Monte Carlo settings, the table type and its key.

Everything a build, the cache and the interpolation agree on: :data:`LUT_AXES` (axis
names, coordinates, units), :data:`LUT_GRIDS`, :data:`LUT_MC_PHOTONS`,
:data:`LUT_MC_SETTINGS`, :data:`LUT_SOLVERS`, the axis coordinates (``_forward``,
``_inverse``), :class:`SkinLUT` and :func:`lut_key` (the hash of the geometry, the grid
and the solver settings). The package docstring (:mod:`nirglucose.optics.lut`) explains
the choices and gives the references.
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ... import portable as pm
from ...exceptions import ConfigError
from .._inputs import check_n_photons
from ..kernels import mc_white

__all__ = [
    "LUT_AXES",
    "LUT_GRIDS",
    "LUT_MC_PHOTONS",
    "LUT_MC_SETTINGS",
    "LUT_MC_GRID_SETTINGS",
    "LUT_SOLVERS",
    "LUT_GRID_WAVELENGTHS_NM",
    "SkinLUT",
    "grid_mc_settings",
    "grid_name",
    "lut_grids_for_bands",
    "lut_key",
]


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
#: ``default`` box covers every LED band in 700-1320 nm (not bands above about 1340 nm, where
#: the dermis absorbs more than 2 /cm and fat scatters more than 0.85 x skin),
#: Fitzpatrick I-VI, the physiology
#: presets and skin 0.4-4.2 mm; ``tiny`` covers the same box coarsely, for tests.
#: ``swir`` covers LED bands in 1160-1700 nm (``data/optics/SOURCES.md``, "Above 1300
#: nm"): the dermis absorbs 0.7-26 /cm there (water: the band tails of a 1350 or
#: 1550 nm LED reach into the 1450 nm peak), the subcutis 0.3-8 /cm (fat's 1210 nm band,
#: water), the epidermis at most about 7 /cm for the presets' melanin (melanosome
#: absorption falls as lambda^-3.5), skin mus' 5.8-14.3 /cm (glucose lowers it by up to
#: 29 % at 400 mg/dL under the presets' signal gain of 12.5) and the fat/skin mus' ratio
#: 0.75-1.00 (Jacques 2013's two power laws). :data:`LUT_GRID_WAVELENGTHS_NM` says which
#: grid covers which LED bands; every preset's skin through 100 nm wide bands at 1350,
#: 1450, 1550 and 1650 nm falls inside ``swir`` (``tests/optics/test_optics_lut_swir.py``).
#: ``tiny-swir`` is its coarse twin, for tests.
LUT_GRIDS: dict[str, dict[str, tuple[float, float, int, int]]] = {
    "default": {
        "musp_dermis_per_cm": (7.0, 30.0, 7, 3),
        "musp_ratio": (0.48, 0.85, 3, 3),
        "mua_dermis_per_cm": (0.05, 2.0, 7, 2),
        "mua_subcutis_per_cm": (0.01, 2.0, 7, 2),
        "mua_epidermis_per_cm": (0.0, 35.0, 6, 2),
        "skin_transport_thickness": (0.25, 13.0, 12, 2),
    },
    "swir": {
        "musp_dermis_per_cm": (5.5, 14.5, 5, 2),
        "musp_ratio": (0.74, 1.03, 3, 3),
        "mua_dermis_per_cm": (0.5, 26.0, 9, 2),
        "mua_subcutis_per_cm": (0.25, 8.0, 6, 2),
        "mua_epidermis_per_cm": (0.0, 10.0, 4, 2),
        "skin_transport_thickness": (0.25, 6.5, 9, 2),
    },
}


def _coarse(box: dict[str, tuple[float, float, int, int]]
            ) -> dict[str, tuple[float, float, int, int]]:
    """A box solved coarsely, for tests: two nodes an axis, three in tau (a node on tau =
    1 between its ends), no refinement."""
    return {k: (lo, hi, 3 if k == "skin_transport_thickness" else 2, 1)
            for k, (lo, hi, _n, _m) in box.items()}


LUT_GRIDS["tiny"] = _coarse(LUT_GRIDS["default"])
LUT_GRIDS["tiny-swir"] = _coarse(LUT_GRIDS["swir"])


#: LED band nodes each named grid covers [nm], for ``optics.lut_grid = "auto"``
#: (:func:`lut_grids_for_bands`). ``default`` ends below where nominal dermis reaches the
#: box's 2 /cm (1343 nm), ``swir`` starts above where skin mus' reaches its 14.5 /cm
#: (1140 nm); the 20 nm margins leave room for wetter skin, glucose and the LEDs'
#: thermal shift (every preset, ``tests/optics/test_optics_lut_swir.py``).
LUT_GRID_WAVELENGTHS_NM: dict[str, tuple[float, float]] = {
    "default": (700.0, 1320.0),
    "swir": (1160.0, 1700.0),
}


def lut_grids_for_bands(nodes_nm: ArrayLike) -> tuple[str, ...]:
    """The named grid of each LED band: the first of :data:`LUT_GRID_WAVELENGTHS_NM` whose
    wavelengths hold every node of the band.

    Parameters
    ----------
    nodes_nm : array_like
        (n_led, n_pts): the band nodes of each LED. [nm]

    Returns
    -------
    tuple of str
        One grid name per LED.

    Raises
    ------
    ConfigError
        If a band is wider than any one grid covers (one line naming the LED).

    Examples
    --------
    >>> lut_grids_for_bands([[830.0, 850.0, 870.0], [1500.0, 1550.0, 1600.0]])
    ('default', 'swir')
    """
    out = []
    for i, band in enumerate(np.atleast_2d(np.asarray(nodes_nm, dtype=float))):
        lo, hi = float(band.min()), float(band.max())
        name = next((g for g, (a, b) in LUT_GRID_WAVELENGTHS_NM.items()
                     if a <= lo and hi <= b), None)
        if name is None:
            spans = ", ".join(f"{g} {a:g}-{b:g} nm" for g, (a, b) in
                              LUT_GRID_WAVELENGTHS_NM.items())
            raise ConfigError(
                f"LED {i + 1}'s band spans {lo:.0f}-{hi:.0f} nm, wider than one rte-lut table "
                f"covers ({spans}); narrow its fwhm_nm or use optics.model = 'diffusion'")
        out.append(name)
    return tuple(out)


#: Monte Carlo photons per (musp_ratio, skin_transport_thickness) node, by grid name
#: (a custom grid takes the default grid's unless :func:`build_lut` is told). The
#: default's 3.2 million: at 1.6 million the table's own noise exceeds 1 % at about 1 %
#: of random points of the box (0.13 % at 3.2 million; two tables from disjoint halves
#: of the photons compared, README). ``swir``'s 12.8 million: its kernel is half as
#: wide (:data:`LUT_MC_GRID_SETTINGS`) and fewer photons reach rho the more the dermis
#: absorbs (a node's standard error of R, 3.2 million photons: 0.6 % at a dermal mua of
#: 4 /cm, 0.9 % at 8, 1.6 % at 12, 3.4 % at 16, 7.4 % at 20 /cm; halved by 4 x the
#: photons). [-]
LUT_MC_PHOTONS: dict[str, int] = {"default": 3_200_000, "tiny": 8_000,
                                   "swir": 12_800_000, "tiny-swir": 8_000}


#: Settings of the white Monte Carlo behind the table (:mod:`nirglucose.optics.kernels.mc_white`;
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


#: Settings of named grids that differ from :data:`LUT_MC_SETTINGS` (in their cache
#: key). ``swir``: R(rho) falls about 50 times faster per cm at a dermal mua of 26 /cm
#: than at 2 /cm, and the fourth-order kernel's O(h^4) bias grows with it: over
#: rho +- 0.75 mm it reads R 1.6 % low at 8 /cm, 3.6 % at 12 /cm and 8 % at 20 /cm
#: against rho +- 0.35 mm, which agrees with rho +- 0.25 mm within the noise (one
#: 3 200 000-photon run, mus' 9 /cm, tau 1.5, ratio 0.9; the noise grows as
#: h^-1/2). Its residual fit has degrees (3, 2, 4), one less than the default along
#: mus' (5 solve nodes instead of 7) and along ln tau (9 instead of 12), so the fit
#: still averages over more nodes than it has terms; not chosen by cross-validation.
LUT_MC_GRID_SETTINGS: dict[str, dict] = {
    name: {"half_width_cm": 0.035, "residual_fit_degrees": (3, 2, 4)}
    for name in ("swir", "tiny-swir")
}


#: What solves the model at the table's nodes. ``"monte-carlo"`` (default): the white
#: Monte Carlo of the RTE above, about 2 CPU-hours for the default grid, with 0.3-0.7 %
#: noise per node. ``"diffusion"``: the three-layer diffusion model
#: (:func:`nirglucose.optics.layers.three_layer_reflectance`), about 40 s, smooth, within
#: 1.5-3 % of Monte Carlo for most skin (``nirglucose_reference.mc_paths``) and 0.90-1.05 x
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
            return pm.log(x)
        if kind == "sqrt":
            return np.sqrt(x)
    return x


def _inverse(kind: str, u: np.ndarray) -> np.ndarray:
    if kind == "log":
        return pm.exp(u)
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


def grid_mc_settings(grid: str | dict) -> dict:
    """The Monte Carlo settings of a grid: :data:`LUT_MC_SETTINGS`, with a named grid's own
    (:data:`LUT_MC_GRID_SETTINGS`; a spec takes those of the named grid it equals)."""
    return {**LUT_MC_SETTINGS, **LUT_MC_GRID_SETTINGS.get(grid_name(grid) or "default", {})}


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


def grid_name(grid: str | dict) -> str | None:
    """The first name in :data:`LUT_GRIDS` of a grid with the same axes, or None: the one
    rule by which a spec takes a named grid's settings, photons and build cost."""
    axes = _resolve_grid(grid)
    return next((k for k, v in LUT_GRIDS.items() if _resolve_grid(v) == axes), None)


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
            **grid_mc_settings(grid),
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
    """Photons per Monte Carlo run: given, else the grid's (a spec takes those of the named
    grid it equals, as in :func:`grid_mc_settings`), else the default grid's."""
    if n_photons is None:
        n_photons = LUT_MC_PHOTONS.get(grid_name(grid) or "default", LUT_MC_PHOTONS["default"])
    return check_n_photons(n_photons)
