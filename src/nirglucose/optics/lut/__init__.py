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
skin 0.4-4 mm. It stops at a dermal mua of 2 /cm, which nominal skin reaches at about
1343 nm (water), and at a subcutis/dermis mus' ratio of 0.85, which the fat and skin
power laws reach at 1368 nm: LED bands above about 1340 nm fall outside it and raise a
ConfigError naming the axis (``data/optics/SOURCES.md``, "Above 1300 nm").

Above it, the ``swir`` grid: LED bands in 1160-1700 nm (:data:`LUT_GRID_WAVELENGTHS_NM`),
dermal mua 0.5-26 /cm (the 1450 nm water peak included), subcutis 0.25-8 /cm,
epidermis 0-10 /cm, skin mus' 5.5-14.5 /cm, fat/skin mus' ratio 0.74-1.03. Its own
table per probe geometry, built the same way with a narrower detector kernel (rho +-
0.35 mm: R falls about 50 times faster per cm at 26 /cm than at 2 /cm) and 12.8 million
photons per run (:data:`LUT_MC_GRID_SETTINGS`, :data:`LUT_MC_PHOTONS`). The more the
dermis absorbs, the fewer photons reach rho with a path short enough to count, so the
table's own Monte Carlo noise grows with absorption; its errors against independent
references are given per dermal absorption in the README. ``optics.lut_grid = "auto"``
(the default) gives each LED the table that covers its band, so a device may have LEDs
on both sides of 1320 nm.

Where the table comes from: a white Monte Carlo solution of the radiative transport
equation (:mod:`nirglucose.optics.kernels.mc_white`, MCML physics with Henyey-Greenstein g = 0.9
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
(``studies/optics_reference.py``) and 24 at the thin-skin weak spot: median 0.30 %,
RMS 0.40 %, maximum 0.98 %, none beyond 1 %.
Over the paper cohort the table is 0.90-1.05 x the diffusion model (median 0.98).
``optics.lut_solver = "diffusion"`` fills the table with the diffusion model alone
(about 40 s; for sweeps of the probe geometry, each of which needs its own table).

Modules, by job: :mod:`.grid` (axes, named grids, Monte Carlo settings, :class:`SkinLUT`,
the cache key), :mod:`.build` (:func:`build_lut`: solve, refine, smooth, centre),
:mod:`.cache` (the disk cache, ``$NIRGLUCOSE_CACHE``, ``$NIRGLUCOSE_LUT_GRID``: the only
environment variables the optics read), :mod:`.interpolate` (:func:`interpolate_lut`,
:func:`node_lut`, :func:`interpolate_node_lut`, :func:`reflectance_from_tissue_optics`).
The checks against direct solves (``random_lut_points``, ``direct_solve``,
``lut_errors``) are validation references: import them from
``nirglucose_reference.lut_checks``.

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

from .build import build_lut
from .cache import cache_dir, get_lut, load_or_build_lut, lut_grid_named_in_env
from .grid import (
    LUT_AXES,
    LUT_GRID_WAVELENGTHS_NM,
    LUT_GRIDS,
    LUT_MC_GRID_SETTINGS,
    LUT_MC_PHOTONS,
    LUT_MC_SETTINGS,
    LUT_SOLVERS,
    SkinLUT,
    grid_mc_settings,
    grid_name,
    lut_grids_for_bands,
    lut_key,
)
from .interpolate import (
    NodeLUT,
    interpolate_lut,
    interpolate_node_lut,
    node_lut,
    reflectance_from_tissue_optics,
)

__all__ = [
    "LUT_AXES",
    "LUT_GRIDS",
    "LUT_GRID_WAVELENGTHS_NM",
    "lut_grids_for_bands",
    "SkinLUT",
    "NodeLUT",
    "build_lut",
    "cache_dir",
    "lut_grid_named_in_env",
    "lut_key",
    "load_or_build_lut",
    "get_lut",
    "interpolate_lut",
    "node_lut",
    "interpolate_node_lut",
    "reflectance_from_tissue_optics",
    "LUT_MC_PHOTONS",
    "LUT_MC_SETTINGS",
    "LUT_MC_GRID_SETTINGS",
    "grid_mc_settings",
    "grid_name",
    "LUT_SOLVERS",
]
