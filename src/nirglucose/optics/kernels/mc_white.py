"""White Monte Carlo of three-layer skin in transport units, compiled, for the look-up table.

One run traces photons through "skin" (epidermis and dermis, which scatter alike:
one skin power law, Jacques 2013) of thickness ``tau`` over a semi-infinite subcutis,
with no absorption of their own, and records, for every photon that escapes the top
surface within a band of radii, its exit radius and the path it travelled above each
of several depths (the epidermis), in the rest of the skin and in the subcutis. From
that record, any absorption and any dermal scattering follow without another run:

* **Scaling** (the RTE has no length scale of its own): with the anisotropy g fixed,
  lengths counted in transport mean free paths of the dermis (x* = mus'_dermis x) make
  the problem depend on mus'_dermis only through the source-detector distance
  rho* = mus'_dermis rho and the epidermis depth d* = mus'_dermis d_epi, and
  R(rho) = mus'_dermis^2 R*(rho*) (Graaff et al. 1993; Kienle & Patterson 1996).
* **Absorption by re-weighting**: a photon's trajectory does not depend on absorption
  (the microscopic Beer-Lambert law), so R = <exp(-sum_k mua_k L_k)> over the detected
  photons, and the mean path per layer is the same weighted mean of L_k, exactly
  (Sassaroli & Fantini 2004; Alerstam et al. 2008).

So one run per (subcutis/dermis scattering ratio q, skin thickness tau) covers every
mus'_dermis and every absorption of the table.

Design choices, each for low or smooth noise:

* **Common random numbers.** Photon i draws its random numbers from its own
  counter-based stream (SplitMix64, Steele et al. 2014) seeded by (seed, i), and flight
  f of photon i always takes the same slots of it (optical depth, polar and azimuthal
  angle, escape decision). The step is drawn as an optical depth and carried across
  the skin/subcutis interface (MCML), so a trajectory moves continuously with tau and
  q; the noise of neighbouring table nodes is correlated and the interpolant smooth.
* **Analog reference absorption.** Each photon carries a path budget drawn once,
  Lambda ~ Exp(mua_ref*), and stops when it is spent: that is absorption mua_ref* in
  every layer, simulated analogously (no weight, no roulette, no discontinuity). Tallies
  re-weight by exp(-sum_k (mua_k* - mua_ref*) L_k*); mua_ref* is the smallest absorption
  of the table's box in transport units, so the re-weighting factor stays <= 1 but in
  the epidermis (where it exceeds 1 by at most exp(mua_ref* L_epi*), a 1e-4 effect).
* **All-or-none Fresnel escape** at the top surface (probability 1 - R_F, n_tissue
  against n_ambient; the same partial-reflection physics as MCML in expectation): every
  photon carries weight 1 and has at most one record.
* **Kernel estimate of the point reflectance.** The ring average over
  rho +- h is biased by h^2 R''/6 (up to 8 % at h = 0.5 mm for the most absorbing skin);
  the tally uses the fourth-order kernel K(u) = 15/32 (3 - 10 u^2 + 7 u^4) on |u| < 1,
  which cancels the u^2 term (bias O(h^4 R'''')) and vanishes at its edges (a photon's
  weight is continuous in its exit radius, for smooth common-random-number noise).

Relation to the NumPy photon engine (``nirglucose_reference.photon_engine``,
the one reference engine, with pluggable tallies): same MCML physics, but this kernel
stays separate and compiled because its random numbers are counter-based per photon and
flight (common random numbers across the table's nodes), its optical depth is carried
across the interface and its absorption is analog -- none of which a vectorised
all-packets-per-step loop can give -- and because it must be tens of times faster (a few
tens of microseconds per photon, against about 2 ms for the NumPy engine in skin). The
reference engine validates it (``tests/optics/test_optics_mc_white.py``).

Speed: about 0.3 us per scattering event on one core (numba), a few tens of
microseconds per photon; :func:`white_mc_run` splits the photons into batches run on
threads (the kernel releases the GIL) and joins them in batch order, so the result is
bit-identical for any number of threads.

References
----------
.. [1] L. Wang, S. L. Jacques, L. Zheng, "MCML - Monte Carlo modeling of light transport
   in multi-layered tissues", Comput. Methods Programs Biomed. 47, 131-146 (1995),
   doi:10.1016/0169-2607(95)01640-F
.. [2] A. Sassaroli, S. Fantini, "Comment on the modified Beer-Lambert law for
   scattering media", Phys. Med. Biol. 49, N255-N257 (2004),
   doi:10.1088/0031-9155/49/14/N07
.. [3] E. Alerstam, S. Andersson-Engels, T. Svensson, "White Monte Carlo for
   time-resolved photon migration", J. Biomed. Opt. 13, 041304 (2008),
   doi:10.1117/1.2950319
.. [4] R. Graaff, M. H. Koelink, F. F. M. de Mul, W. G. Zijlstra, A. C. M. Dassel,
   J. G. Aarnoudse, "Condensed Monte Carlo simulations for the description of light
   transport", Appl. Opt. 32, 426-434 (1993), doi:10.1364/AO.32.000426
.. [5] A. Kienle, M. S. Patterson, "Determination of the optical properties of turbid
   media from a single Monte Carlo simulation", Phys. Med. Biol. 41, 2221-2227 (1996),
   doi:10.1088/0031-9155/41/10/026
.. [6] S. L. Jacques, "Optical properties of biological tissues: a review",
   Phys. Med. Biol. 58, R37-R61 (2013), doi:10.1088/0031-9155/58/11/R37
.. [7] G. L. Steele, D. Lea, C. H. Flood, "Fast splittable pseudorandom number
   generators", OOPSLA 2014, 453-472, doi:10.1145/2660193.2660195
"""

from __future__ import annotations

import os
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field

import numpy as np
from numba import njit
from numpy.typing import ArrayLike, NDArray

from ...exceptions import ConfigError
from .._environment import mc_threads_from_env
from .._inputs import check_n_photons

__all__ = [
    "SKIN_ANISOTROPY",
    "WhiteRun",
    "white_mc_run",
    "white_mc_tally",
    "white_mc_points",
    "kernel_weight",
]

#: Henyey-Greenstein anisotropy of skin and subcutis in the near infrared (Jacques 2013
#: [6]_: g ~ 0.9 for dermis; the MC check of the diffusion model uses the same). [-]
SKIN_ANISOTROPY = 0.9

#: Photons per batch: the unit of threading and of the standard errors. [-]
_BATCH_PHOTONS = 1 << 12

#: Flights per photon above which the kernel gives up (the path budget ends every
#: photon long before: a photon that has not escaped by 1/mua_ref* is rare). [-]
_MAX_FLIGHTS = 50_000_000

# SplitMix64 constants (Steele et al. 2014 [7]_)
_GOLDEN = np.uint64(0x9E3779B97F4A7C15)
_MIX1 = np.uint64(0xBF58476D1CE4E5B9)
_MIX2 = np.uint64(0x94D049BB133111EB)
_TO_UNIT = 1.0 / 9007199254740992.0  # 2^-53
_S30, _S27, _S31, _S11 = np.uint64(30), np.uint64(27), np.uint64(31), np.uint64(11)
#: Survival chance of the path-length roulette, played each time a photon's path
#: doubles past ``path_split`` (its weight is divided by it: unbiased). [-]
_SPLIT_SURVIVAL = 0.25
#: Stands for infinity inside the kernel (compiled with fastmath, which assumes finite
#: numbers): an unreachable boundary, an endless budget. [-]
_BIG = 1e300
#: random-number slots per flight: optical depth, cos(theta), azimuth, escape decision
_SLOTS = 4


@njit(cache=True, nogil=True, inline="always")
def _mix(z):
    z = (z ^ (z >> _S30)) * _MIX1
    z = (z ^ (z >> _S27)) * _MIX2
    return z ^ (z >> _S31)


@njit(cache=True, nogil=True, inline="always")
def _uniform(base, slot):
    """Uniform [0, 1) number ``slot`` of the stream starting at ``base`` (SplitMix64)."""
    return np.float64(_mix(base + (np.uint64(slot) + np.uint64(1)) * _GOLDEN) >> _S11) * _TO_UNIT


@njit(cache=True, nogil=True)
def _fresnel_r(cos_i, n_rel):
    """Unpolarised Fresnel reflectance from inside (index ratio n_rel = n_in / n_out)."""
    sin_t2 = n_rel * n_rel * (1.0 - cos_i * cos_i)
    if sin_t2 >= 1.0:
        return 1.0
    cos_t = np.sqrt(1.0 - sin_t2)
    rs = (n_rel * cos_i - cos_t) / (n_rel * cos_i + cos_t)
    rp = (n_rel * cos_t - cos_i) / (n_rel * cos_t + cos_i)
    return 0.5 * (rs * rs + rp * rp)


@njit(cache=True, nogil=True, fastmath=True)
def _trace(seed, first, count, tau, q, g, n_rel, mua_ref, depths, r_lo, r_hi,  # noqa: C901
           path_split):
    """Trace photons ``first .. first + count - 1``; see :func:`white_mc_run`.

    Returns the exit radius (m,), the photon index (m,) and the paths (m, K + 2) --
    above each of the K ``depths`` (all inside the skin), in the skin, in the subcutis --
    of the photons escaping at ``r_lo <= r < r_hi``, and the numbers of photons escaping
    anywhere and transmitted (only when q = 0: the bottom layer is then empty space).
    Lengths in transport mean free paths of the skin.

    One long function on purpose: it is the compiled per-photon loop (flight, boundary,
    Fresnel escape, scattering, roulette, tally), and keeping the state in local
    variables of one numba function is what makes it fast (helpers that return several
    values allocate tuples inside the innermost loop).
    """
    n_dep = depths.size
    cap = 1024
    out_r = np.empty(cap)
    out_i = np.empty(cap, dtype=np.int64)
    out_p = np.empty((cap, n_dep + 2))
    out_w = np.empty(cap)
    m = 0
    n_escaped = 0.0
    n_transmitted = 0.0
    depth_max = depths.max()
    mus_skin = 1.0 / (1.0 - g)  # scattering per transport length: mus / mus' = 1 / (1 - g)
    mus_sub = q / (1.0 - g)
    path = np.empty(n_dep + 2)
    seed_key = _mix(np.uint64(seed) * _GOLDEN + np.uint64(0x632BE59BD9B4E019))
    for i in range(first, first + count):
        base = _mix(seed_key + np.uint64(i) * _GOLDEN)
        split_key = _mix(base ^ np.uint64(0xD1B54A32D192ED03))
        x = 0.0
        y = 0.0
        z = 0.0
        ux = 0.0
        uy = 0.0
        uz = 1.0
        layer = 0
        path[:] = 0.0
        walked = 0.0
        weight = 1.0
        next_split = path_split
        n_split = 0
        budget = -np.log(1.0 - _uniform(base, 0)) / mua_ref if mua_ref > 0 else _BIG
        alive = True
        flight = 0
        while alive and flight < _MAX_FLIGHTS:
            slot = 1 + _SLOTS * flight
            depth_left = -np.log(1.0 - _uniform(base, slot))  # optical depth of the flight
            hits = 0
            while True:
                mus = mus_skin if layer == 0 else mus_sub
                if uz < 0.0:
                    dist_b = (-z if layer == 0 else tau - z) / uz
                elif uz > 0.0 and layer == 0:
                    dist_b = (tau - z) / uz
                else:
                    dist_b = _BIG
                step = depth_left / mus if mus > 0.0 else _BIG
                boundary = step >= dist_b
                if boundary:
                    step = dist_b
                if step >= _BIG:  # q = 0: straight down through empty space
                    n_transmitted += weight
                    alive = False
                    break
                if walked + step >= budget:  # the reference absorption ends the photon
                    alive = False
                    break
                z1 = z + step * uz
                if layer == 0:
                    path[n_dep] += step
                    lo_z = min(z, z1)
                    hi_z = max(z, z1)
                    if lo_z < depth_max:
                        for k in range(n_dep):
                            d = depths[k]
                            if hi_z <= d:
                                path[k] += step
                            elif lo_z < d:
                                path[k] += step * (d - lo_z) / (hi_z - lo_z)
                else:
                    path[n_dep + 1] += step
                x += step * ux
                y += step * uy
                z = z1
                walked += step
                if not boundary:
                    break
                depth_left -= step * mus
                if layer == 0 and uz < 0.0:  # the top surface
                    z = 0.0
                    r_f = _fresnel_r(-uz, n_rel)
                    u = (_uniform(base, slot + 3) if hits == 0
                         else _uniform(_mix(base ^ np.uint64(flight + 1)), hits))
                    hits += 1
                    if u >= r_f:  # escapes
                        n_escaped += weight
                        r = np.sqrt(x * x + y * y)
                        if r_lo <= r < r_hi:
                            if m == cap:
                                cap *= 2
                                nr = np.empty(cap)
                                nr[:m] = out_r[:m]
                                out_r = nr
                                ni = np.empty(cap, dtype=np.int64)
                                ni[:m] = out_i[:m]
                                out_i = ni
                                npth = np.empty((cap, n_dep + 2))
                                npth[:m] = out_p[:m]
                                out_p = npth
                                nw = np.empty(cap)
                                nw[:m] = out_w[:m]
                                out_w = nw
                            out_r[m] = r
                            out_i[m] = i
                            out_p[m] = path
                            out_w[m] = weight
                            m += 1
                        alive = False
                        break
                    uz = -uz  # Fresnel (or total internal) reflection
                else:  # the skin/subcutis interface: same refractive index, crosses
                    z = tau
                    layer = 1 if uz > 0.0 else 0
            if not alive:
                break
            if walked >= next_split:  # path-length roulette (unbiased: weight / chance)
                if _uniform(split_key, n_split) >= _SPLIT_SURVIVAL:
                    break
                weight /= _SPLIT_SURVIVAL
                n_split += 1
                next_split *= 2.0
            # Henyey-Greenstein scattering (MCML [1]_, Eqs. 3.28-3.31)
            xi = _uniform(base, slot + 1)
            if g == 0.0:
                cos_t = 2.0 * xi - 1.0
            else:
                tmp = (1.0 - g * g) / (1.0 - g + 2.0 * g * xi)
                cos_t = min(1.0, max(-1.0, (1.0 + g * g - tmp * tmp) / (2.0 * g)))
            sin_t = np.sqrt(1.0 - cos_t * cos_t)
            psi = 2.0 * np.pi * _uniform(base, slot + 2)
            cp = np.cos(psi)
            sp = np.sin(psi)
            if abs(uz) > 1.0 - 1e-12:
                nx = sin_t * cp
                ny = sin_t * sp
                nz = cos_t if uz > 0.0 else -cos_t
            else:
                tmp = np.sqrt(1.0 - uz * uz)
                nx = sin_t * (ux * uz * cp - uy * sp) / tmp + ux * cos_t
                ny = sin_t * (uy * uz * cp + ux * sp) / tmp + uy * cos_t
                nz = -sin_t * cp * tmp + uz * cos_t
            norm = np.sqrt(nx * nx + ny * ny + nz * nz)
            ux = nx / norm
            uy = ny / norm
            uz = nz / norm
            flight += 1
    return (out_r[:m].copy(), out_i[:m].copy(), out_p[:m].copy(), out_w[:m].copy(),
            n_escaped, n_transmitted)


@dataclass(frozen=True)
class WhiteRun:
    """Photons of one white Monte Carlo run that escaped within the recorded band.

    Lengths are in transport mean free paths of the skin (x* = mus'_skin x). [-]

    Attributes
    ----------
    radius : ndarray
        Exit radius of each recorded photon, (m,). [-]
    path : ndarray
        (m, K + 2): path above each of the K ``depths``, in the whole skin (those
        included), in the subcutis. [-]
    weight : ndarray
        Weight of each recorded photon (1, or a power of 4 after path roulette), (m,). [-]
    batch : ndarray
        Batch of each recorded photon (for standard errors), (m,). [-]
    depths : ndarray
        The K depths, (K,). [-]
    n_photons, n_batches : int
        Launched photons and batches. [-]
    escaped, transmitted : float
        Weight escaping the top anywhere, and lost through the bottom (only when q = 0),
        per launched photon, with the reference absorption (no specular term). [-]
    settings : dict
        Everything the run depends on (seed, tau, q, g, refractive indices, mua_ref*).
    """

    radius: NDArray[np.float64] = field(repr=False)
    path: NDArray[np.float64] = field(repr=False)
    weight: NDArray[np.float64] = field(repr=False)
    batch: NDArray[np.int64] = field(repr=False)
    depths: NDArray[np.float64] = field(repr=False)
    n_photons: int
    n_batches: int
    escaped: float
    transmitted: float
    settings: dict


def _n_threads(n_threads: int | None) -> int:
    if n_threads is not None:
        return max(1, int(n_threads))
    env = mc_threads_from_env()
    if env is not None:
        return env
    return max(1, min(len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity")
                      else (os.cpu_count() or 1), 8))


def _checked_run_args(skin_transport_thickness, musp_ratio, depths, radius_band, n_photons,
                      mua_ref, g, first_photon) -> tuple:
    """:func:`white_mc_run`'s inputs as (tau, q, depths, r_lo, r_hi), or ConfigError."""
    tau = float(skin_transport_thickness)
    q = float(musp_ratio)
    dep = np.ascontiguousarray(np.atleast_1d(np.asarray(depths, dtype=float)))
    r_lo, r_hi = (float(v) for v in radius_band)
    checks = (
        ("skin_transport_thickness", tau, np.isfinite(tau) and tau > 0, "(0, inf)"),
        ("musp_ratio", q, np.isfinite(q) and q >= 0, "[0, inf)"),
        ("mua_ref", float(mua_ref), float(mua_ref) >= 0, "[0, inf)"),
        ("g", float(g), abs(float(g)) < 1, "(-1, 1)"),
        ("depths", dep.tolist(), dep.ndim == 1 and bool(np.all((dep > 0) & (dep < tau))),
         f"(0, {tau:g})"),
        ("radius_band", (r_lo, r_hi), 0 <= r_lo < r_hi, "0 <= low < high"),
    )
    for name, v, ok, valid in checks:
        if not ok:
            raise ConfigError(f"{name} = {v!r} is out of range; valid range is {valid} [-]")
    check_n_photons(n_photons)
    if isinstance(first_photon, bool) or not isinstance(first_photon, int | np.integer) \
            or first_photon < 0:
        raise ConfigError(f"first_photon = {first_photon!r} is invalid; expected an integer "
                          f">= 0 [-]")
    if float(mua_ref) == 0.0 and q > 0.0:
        raise ConfigError("mua_ref = 0 never ends a photon in a semi-infinite medium; "
                          "valid range is (0, inf) when musp_ratio > 0 [-]")
    return tau, q, dep, r_lo, r_hi


def white_mc_run(
    skin_transport_thickness: float,
    musp_ratio: float,
    depths: ArrayLike,
    radius_band: tuple[float, float],
    *,
    n_photons: int,
    seed: int,
    mua_ref: float,
    g: float = SKIN_ANISOTROPY,
    n_tissue: float = 1.4,
    n_ambient: float = 1.0,
    path_split: float = np.inf,
    n_threads: int | None = None,
    first_photon: int = 0,
) -> WhiteRun:
    r"""Trace photons through skin over subcutis, in transport units, without absorption.

    Parameters
    ----------
    skin_transport_thickness : float
        Skin (epidermis + dermis) thickness tau* = mus'_skin t, ``> 0``. [-]
    musp_ratio : float
        mus'_subcutis / mus'_skin, ``>= 0`` (0: nothing below the skin, a finite slab
        over a matched empty half-space). [-]
    depths : array_like
        Depths above which the path is recorded separately (epidermis bottoms, one per
        mus'_skin of interest), in ``(0, tau*)``. [-]
    radius_band : tuple of float
        Exit radii recorded, ``[low, high)``. [-]
    n_photons : int
        Photons launched, ``>= 1``. [-]
    seed : int
        Seed of the common random numbers (photon i always draws the same stream). [-]
    mua_ref : float
        Reference absorption in every layer, simulated analogously (path budget),
        ``>= 0``; tallies hold for any absorption near or above it. [-]
    g : float, optional
        Henyey-Greenstein anisotropy of every layer. Default :data:`SKIN_ANISOTROPY`. [-]
    n_tissue, n_ambient : float, optional
        Refractive indices of the tissue and of the medium above. [-]
    n_threads : int, optional
        Threads; default ``$NIRGLUCOSE_MC_THREADS`` or the available cores (at most 8).
        The result does not depend on it. [-]
    first_photon : int, optional
        Index of the first photon: the run traces photons ``first_photon`` to
        ``first_photon + n_photons - 1`` of the seed's streams, so runs over disjoint
        ranges are independent, and their tallies' photon-weighted mean is the run over
        the union (a build extended, or split in two for cross-validation). Default 0. [-]

    Returns
    -------
    WhiteRun

    Notes
    -----
    MCML [1]_ with continuous (here analog, as a path budget) absorption: free optical
    depth :math:`-\ln\xi` carried across the internal interface, Henyey-Greenstein
    scattering, escape through the top with probability :math:`1 - R_F(\theta)`
    (Fresnel, unpolarised), else specular reflection.

    References
    ----------
    .. [1] L. Wang, S. L. Jacques, L. Zheng, Comput. Methods Programs Biomed. 47,
       131-146 (1995), doi:10.1016/0169-2607(95)01640-F
    .. [2] E. Alerstam, S. Andersson-Engels, T. Svensson, J. Biomed. Opt. 13, 041304
       (2008), doi:10.1117/1.2950319

    Examples
    --------
    >>> run = white_mc_run(2.0, 0.7, [0.2], (1.0, 3.0), n_photons=2000, seed=0,
    ...                    mua_ref=0.01)
    >>> run.path.shape[1]
    3
    """
    tau, q, dep, r_lo, r_hi = _checked_run_args(skin_transport_thickness, musp_ratio,
                                                depths, radius_band, n_photons, mua_ref, g,
                                                first_photon)
    n_rel = float(n_tissue) / float(n_ambient)
    n, first = int(n_photons), int(first_photon)
    starts = list(range(first, first + n, _BATCH_PHOTONS))

    def one(start: int):
        return _trace(int(seed), start, min(_BATCH_PHOTONS, first + n - start), tau, q,
                      float(g), n_rel, float(mua_ref), dep, r_lo, r_hi,
                      min(float(path_split), _BIG))

    threads = min(_n_threads(n_threads), len(starts))
    if threads > 1:
        with ThreadPoolExecutor(threads) as pool:
            parts = list(pool.map(one, starts))
    else:
        parts = [one(s) for s in starts]
    n_batches = len(starts)
    return WhiteRun(
        radius=np.concatenate([p[0] for p in parts]),
        path=np.concatenate([p[2] for p in parts]),
        weight=np.concatenate([p[3] for p in parts]),
        batch=(np.concatenate([p[1] for p in parts]) - first) // _BATCH_PHOTONS,
        depths=dep,
        n_photons=n,
        n_batches=n_batches,
        escaped=float(sum(p[4] for p in parts)) / n,
        transmitted=float(sum(p[5] for p in parts)) / n,
        settings={"seed": int(seed), "tau": tau, "q": q, "g": float(g),
                  "n_tissue": float(n_tissue), "n_ambient": float(n_ambient),
                  "mua_ref": float(mua_ref), "path_split": float(path_split),
                  "first_photon": first},
    )


def kernel_weight(u: NDArray[np.float64]) -> NDArray[np.float64]:
    """Fourth-order kernel 15/32 (3 - 10 u^2 + 7 u^4) on |u| < 1 (zero outside).

    Integrates to 1, with zero first, second and third moments, so a kernel estimate of
    a smooth profile is unbiased to O(h^4); it vanishes at |u| = 1 (Gasser, Mueller &
    Mammitzsch 1985, the order-(0, 4) kernel of minimum variance with continuity).

    References
    ----------
    .. [1] T. Gasser, H.-G. Mueller, V. Mammitzsch, "Kernels for nonparametric curve
       estimation", J. R. Stat. Soc. B 47, 238-252 (1985),
       doi:10.1111/j.2517-6161.1985.tb01350.x
    """
    u2 = u * u
    return np.where(u2 < 1.0, (15.0 / 32.0) * (3.0 - 10.0 * u2 + 7.0 * u2 * u2), 0.0)


def _detector_weights(run: WhiteRun, rho: float, half_width: float) -> NDArray[np.float64]:
    """Per-record weight v_j with R*(rho*) = sum_j v_j / N (before absorption)."""
    r = run.radius
    k = kernel_weight((r - rho) / half_width)
    return run.weight * k / (half_width * 2.0 * np.pi * r)


def white_mc_tally(
    run: WhiteRun,
    rho_cm: float,
    half_width_cm: float,
    musp_skin_per_cm: ArrayLike,
    mua_epidermis_per_cm: ArrayLike,
    mua_dermis_per_cm: ArrayLike,
    mua_subcutis_per_cm: ArrayLike,
    *,
    specular: bool = True,
) -> dict[str, NDArray[np.float64]]:
    r"""Reflectance and mean paths on a grid of scattering and absorptions, from one run.

    Parameters
    ----------
    run : WhiteRun
        The run; its k-th depth must be the epidermis depth mus'_skin[k] d_epi.
    rho_cm, half_width_cm : float
        Source-detector distance and the kernel's half-width. [cm]
    musp_skin_per_cm : array_like
        (K,): mus' of the skin, one per recorded depth. [1/cm]
    mua_epidermis_per_cm, mua_dermis_per_cm, mua_subcutis_per_cm : array_like
        (A,), (B,), (C,): absorption nodes of each layer (the output is their outer
        product). [1/cm]
    specular : bool, optional
        Remove the specular reflection at launch (pencil beam from the ambient
        medium). Default True.

    Returns
    -------
    dict
        ``reflectance_per_cm2`` (K, A, B, C) [1/cm^2]; ``reflectance_se_per_cm2`` (same;
        batch standard error) [1/cm^2]; ``pathlength_cm`` (K, A, B, C, 3), mean path in
        the epidermis, dermis and subcutis [cm].

    Notes
    -----
    :math:`R(\rho) = \mu_s'^2 (1 - R_{sp}) \frac{1}{N} \sum_j v_j
    \exp(-\sum_l (\mu_{a,l}/\mu_s' - \mu^*_{a,ref}) L^*_{lj})` with the kernel weight
    :math:`v_j = K((r^*_j - \rho^*)/h^*) / (2\pi r^*_j h^*)`;
    :math:`L_l = \sum_j v_j e_j L^*_{lj} / (\mu_s' \sum_j v_j e_j)` [1]_ [2]_.

    References
    ----------
    .. [1] A. Sassaroli, S. Fantini, Phys. Med. Biol. 49, N255-N257 (2004),
       doi:10.1088/0031-9155/49/14/N07
    .. [2] A. Kienle, M. S. Patterson, Phys. Med. Biol. 41, 2221-2227 (1996),
       doi:10.1088/0031-9155/41/10/026
    """
    musp = np.atleast_1d(np.asarray(musp_skin_per_cm, dtype=float))
    mua = [np.atleast_1d(np.asarray(v, dtype=float)) for v in
           (mua_epidermis_per_cm, mua_dermis_per_cm, mua_subcutis_per_cm)]
    if musp.size != run.depths.size:
        raise ConfigError(f"musp_skin_per_cm has {musp.size} values; the run recorded "
                          f"{run.depths.size} depths")
    st = run.settings
    r_sp = ((st["n_tissue"] - st["n_ambient"]) / (st["n_tissue"] + st["n_ambient"])) ** 2
    launch = (1.0 - r_sp) if specular else 1.0
    n_a, n_b, n_c = (v.size for v in mua)
    n_k = musp.size
    refl = np.empty((n_k, n_a, n_b, n_c))
    se = np.empty_like(refl)
    paths = np.empty((n_k, n_a, n_b, n_c, 3))
    nb = run.n_batches
    for k, m in enumerate(musp):
        v = _detector_weights(run, rho_cm * m, half_width_cm * m)
        sel = np.flatnonzero(v != 0.0)
        v = v[sel]
        p = run.path[sel]
        l_epi = p[:, k]
        l_derm = p[:, -2] - l_epi
        l_sub = p[:, -1]
        e_a = np.exp(-np.outer(l_epi, mua[0] / m - st["mua_ref"]))
        e_b = np.exp(-np.outer(l_derm, mua[1] / m - st["mua_ref"]))
        e_c = np.exp(-np.outer(l_sub, mua[2] / m - st["mua_ref"]))
        x = (v[:, None, None] * e_a[:, :, None] * e_b[:, None, :]).reshape(sel.size, -1)
        total = (x.T @ e_c).reshape(n_a, n_b, n_c)
        # batch sums for the standard error
        b = run.batch[sel]
        per_batch = np.stack([(x[b == j].T @ e_c[b == j]).reshape(n_a, n_b, n_c)
                              for j in range(nb)]) if nb > 1 else None
        scale = m * m * launch / run.n_photons
        refl[k] = total * scale
        if per_batch is not None:
            counts = np.array([min(_BATCH_PHOTONS, run.n_photons - j * _BATCH_PHOTONS)
                               for j in range(nb)], dtype=float)
            means = per_batch * (m * m * launch) / counts[:, None, None, None]
            w = counts / counts.sum()
            mean = np.tensordot(w, means, axes=1)
            var = np.tensordot(w, (means - mean) ** 2, axes=1) / (nb - 1)
            se[k] = np.sqrt(var)
        else:
            se[k] = np.nan
        with np.errstate(invalid="ignore", divide="ignore"):
            for col, ell in enumerate((l_epi, l_derm, l_sub)):
                paths[k, ..., col] = ((x * ell[:, None]).T @ e_c).reshape(n_a, n_b, n_c) \
                    / total / m
    return {"reflectance_per_cm2": refl, "reflectance_se_per_cm2": se, "pathlength_cm": paths}


def white_mc_points(
    rho_cm: float,
    half_width_cm: float,
    epidermis_thickness_cm: float,
    *,
    mua_epidermis_per_cm: ArrayLike,
    mua_dermis_per_cm: ArrayLike,
    musp_dermis_per_cm: ArrayLike,
    mua_subcutis_per_cm: ArrayLike,
    musp_ratio: float,
    skin_transport_thickness: float,
    n_photons: int,
    seed: int,
    mua_ref: float,
    g: float = SKIN_ANISOTROPY,
    n_tissue: float = 1.4,
    n_ambient: float = 1.0,
    path_split: float = np.inf,
    n_threads: int | None = None,
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """Direct Monte Carlo solves at points sharing one (musp_ratio, tau*): one run.

    Each point has its own mus'_dermis and absorptions ((P,) arrays); the run records
    the epidermis depth of each. Returns R [1/cm^2] (P,), its standard error [1/cm^2]
    (P,) and the mean paths [cm] (P, 3) (epidermis, dermis, subcutis).

    References
    ----------
    .. [1] A. Sassaroli, S. Fantini, Phys. Med. Biol. 49, N255-N257 (2004),
       doi:10.1088/0031-9155/49/14/N07
    """
    musp = np.atleast_1d(np.asarray(musp_dermis_per_cm, dtype=float))
    mua = np.broadcast_arrays(*(np.atleast_1d(np.asarray(v, dtype=float)) for v in (
        mua_epidermis_per_cm, mua_dermis_per_cm, mua_subcutis_per_cm, musp)))
    band = (float((rho_cm - half_width_cm) * musp.min()),
            float((rho_cm + half_width_cm) * musp.max()))
    run = white_mc_run(skin_transport_thickness, musp_ratio, musp * epidermis_thickness_cm,
                       band, n_photons=n_photons, seed=seed, mua_ref=mua_ref, g=g,
                       n_tissue=n_tissue, n_ambient=n_ambient, path_split=path_split,
                       n_threads=n_threads)
    refl = np.empty(musp.size)
    se = np.empty(musp.size)
    paths = np.empty((musp.size, 3))
    for k in range(musp.size):
        sub = WhiteRun(run.radius, run.path[:, [k, -2, -1]], run.weight, run.batch,
                       run.depths[k:k + 1], run.n_photons, run.n_batches, run.escaped,
                       run.transmitted, run.settings)
        t = white_mc_tally(sub, rho_cm, half_width_cm, musp[k], mua[0][k], mua[1][k],
                           mua[2][k])
        refl[k] = t["reflectance_per_cm2"].ravel()[0]
        se[k] = t["reflectance_se_per_cm2"].ravel()[0]
        paths[k] = t["pathlength_cm"].reshape(3)
    return refl, se, paths
