"""The NumPy photon engine: MCML photon-packet transport with pluggable tallies.

One vectorised implementation of the MCML algorithm (Wang, Jacques & Zheng 1995): a
pencil beam normally incident on a stack of plane-parallel layers, exponential free
paths, Henyey-Greenstein scattering, Fresnel splitting at the outer surfaces and Russian
roulette. All live packets advance together, one step per loop iteration (no Python loop
over photons). What is recorded is not the engine's business: a :class:`Tally` receives
the absorbed weight and every packet that escapes, and the front ends build their
results from their tallies (:func:`~nirglucose_reference.monte_carlo.mc_layers`:
reflectance, transmittance, absorption, radial profile;
:func:`~nirglucose_reference.mc_paths.mc_detected_paths`: the packets detected in
a ring with their path per layer).

Two absorption models (:data:`ABSORPTION_MODELS`):

* ``"discrete"`` (MCML proper): free paths from mu_t = mu_a + mu_s; at each interaction
  the weight drops by w mu_a/mu_t (the tally's ``absorbed``); at an internal interface
  the whole packet is reflected or refracted with the Fresnel probability.
* ``"continuous"``: free paths from mu_s and w <- w exp(-mu_a s) along every step (the
  microscopic Beer-Lambert law; Sassaroli & Fantini 2004), so a trajectory does not
  depend on mu_a and a run can be re-weighted to other absorptions. The layers share one
  refractive index: internal interfaces are crossed without reflection.

Because free paths are exponential (memoryless), a fresh path is drawn after every
boundary crossing instead of carrying the remaining step: the two are statistically
identical. The random numbers are drawn in a fixed order per step (free paths, polar and
azimuthal angles of the scattered packets, internal-interface decisions, roulette), so a
seed gives the same bytes.

Relation to :mod:`nirglucose.optics.kernels.mc_white`: that is the production engine behind the
``rte-lut`` table and stays a separate, compiled (numba) per-photon kernel, because its
design is what this engine cannot give: counter-based random numbers per photon and per
flight (common random numbers across table nodes), an optical depth carried across the
skin/subcutis interface, analog (path-budget) absorption and a kernel detector, run on
threads at about 0.3 us per scattering event. This engine is the readable reference that
validates it and the deterministic solvers; it is on no hot path.

References
----------
.. [1] L. Wang, S. L. Jacques, L. Zheng, "MCML - Monte Carlo modeling of light transport
   in multi-layered tissues", Comput. Methods Programs Biomed. 47, 131-146 (1995),
   doi:10.1016/0169-2607(95)01640-F
.. [2] A. Sassaroli, S. Fantini, "Comment on the modified Beer-Lambert law for
   scattering media", Phys. Med. Biol. 49, N255-N257 (2004),
   doi:10.1088/0031-9155/49/14/N07
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

import numpy as np
from numpy.typing import ArrayLike, NDArray

from nirglucose import portable as pm
from nirglucose.exceptions import ConfigError
from nirglucose.optics._inputs import check_n_photons

__all__ = ["ABSORPTION_MODELS", "N_BATCHES", "Packets", "Stack", "Tally", "as_layers",
           "check_range", "check_run", "fresnel", "hg_cos", "run_photons"]

#: Absorption models of :func:`run_photons` (module docstring).
ABSORPTION_MODELS = ("discrete", "continuous")

#: Interleaved batches of photons (photon index modulo this) from which the front ends'
#: standard errors of binned tallies are estimated. [-]
N_BATCHES = 20

#: A direction this close to the z axis is treated as vertical in the scattering
#: rotation (MCML's own cut-off, Wang et al. 1995, Eq. 3.25). [-]
_VERTICAL_COS = 1.0 - 1e-12


def as_layers(name: str, v: ArrayLike, n_layers: int) -> NDArray[np.float64]:
    """``v`` as one float per layer, (n_layers,): a scalar is repeated; else ConfigError."""
    a = np.atleast_1d(np.asarray(v, dtype=np.float64))
    if a.ndim != 1 or a.size not in (1, n_layers):
        raise ConfigError(f"{name} must be a scalar or have one value per layer ({n_layers})")
    return np.broadcast_to(a, (n_layers,)).copy()


def check_range(
    name: str,
    v: NDArray[np.float64],
    unit: str,
    low: float,
    high: float,
    *,
    low_open: bool = False,
    high_open: bool = False,
    finite: bool = True,
) -> None:
    """Raise a one-line ConfigError naming the first value of ``v`` outside the range.

    ``nan`` is always out of range, and so is ``inf`` when ``finite``.
    """
    ok = ~np.isnan(v)
    if finite:
        ok &= np.isfinite(v)
    ok &= (v > low) if low_open else (v >= low)
    ok &= (v < high) if high_open else (v <= high)
    if not np.all(ok):
        bad = float(v[~ok].flat[0])  # not np.float64(...) in the message
        lb, hb = ("(" if low_open else "["), (")" if high_open else "]")
        raise ConfigError(
            f"{name} = {bad!r} is out of range; valid range is {lb}{low:g}, {high:g}{hb} [{unit}]"
        )


def check_run(n_photons: int, weight_threshold: float, roulette_chance: float) -> int:
    """The run settings of :func:`run_photons`, checked; returns ``n_photons`` as an int.

    ``weight_threshold`` and ``roulette_chance`` must lie in (0, 1): a chance above 1
    would make the roulette inflate weights (biased), 0 would divide by zero (Wang et
    al. 1995, section 3.7). Front ends that size a tally by ``n_photons`` call this
    before building it; :func:`run_photons` calls it again.
    """
    for name, v in (("weight_threshold", weight_threshold), ("roulette_chance", roulette_chance)):
        try:
            arr = np.atleast_1d(np.asarray(v, dtype=np.float64))
        except (TypeError, ValueError):
            raise ConfigError(f"{name} = {v!r} is not a number [-]") from None
        if arr.shape != (1,):
            raise ConfigError(f"{name} = {v!r} must be a scalar [-]")
        check_range(name, arr, "-", 0.0, 1.0, low_open=True, high_open=True)
    return check_n_photons(n_photons)


@dataclass(frozen=True)
class Stack:
    """Validated layers, top first (build with :meth:`from_layers`).

    Attributes
    ----------
    mua_per_cm, mus_per_cm, g : ndarray
        Absorption, scattering coefficient [1/cm] and anisotropy [-] per layer, (L,).
    z_top_cm, z_bot_cm : ndarray
        Depth of each layer's top and bottom (the last may be ``inf``), (L,). [cm]
    n_ext : ndarray
        Refractive indices of ambient, the L layers and ambient again, (L + 2,). [-]
    specular : float
        Specular reflectance of the top surface, removed at launch. [-]
    """

    mua_per_cm: NDArray[np.float64]
    mus_per_cm: NDArray[np.float64]
    g: NDArray[np.float64]
    z_top_cm: NDArray[np.float64]
    z_bot_cm: NDArray[np.float64]
    n_ext: NDArray[np.float64]
    specular: float

    @classmethod
    def from_layers(cls, mua_per_cm, mus_per_cm, g, thickness_cm, n_layers,
                    n_ambient: float) -> Stack:
        """Stack from per-layer arrays (already validated; ``thickness_cm`` (L,)).

        The specular reflectance is ((n_0 - n_1)/(n_0 + n_1))^2 (Wang et al. 1995,
        Eq. 3.1).
        """
        d = np.asarray(thickness_cm, dtype=np.float64)
        nidx = np.asarray(n_layers, dtype=np.float64)
        return cls(
            mua_per_cm=np.asarray(mua_per_cm, dtype=np.float64),
            mus_per_cm=np.asarray(mus_per_cm, dtype=np.float64),
            g=np.asarray(g, dtype=np.float64),
            z_top_cm=np.concatenate([[0.0], np.cumsum(d)[:-1]]),
            z_bot_cm=np.cumsum(d),
            n_ext=np.concatenate([[n_ambient], nidx, [n_ambient]]),
            specular=float(((n_ambient - nidx[0]) / (n_ambient + nidx[0])) ** 2),
        )

    @property
    def n_layers(self) -> int:
        """Number of layers. [-]"""
        return self.mua_per_cm.size


class Packets:
    """State of the live packets, compacted to them after every step.

    ``pid`` is each packet's photon index; position [cm], direction cosines [-],
    weight [-], layer, whether it has scattered, and its path per layer (n, L) [cm].
    """

    _FIELDS = ("pid", "x", "y", "z", "ux", "uy", "uz", "w", "lay", "scattered", "path")

    def __init__(self, n_photons: int, n_layers: int, weight: float) -> None:
        n = n_photons
        self.pid = np.arange(n)
        self.x, self.y, self.z = np.zeros(n), np.zeros(n), np.zeros(n)
        self.ux, self.uy, self.uz = np.zeros(n), np.zeros(n), np.ones(n)
        self.w = np.full(n, weight)
        self.lay = np.zeros(n, dtype=np.intp)
        self.scattered = np.zeros(n, dtype=bool)
        self.path = np.zeros((n, n_layers))

    def keep(self, mask: NDArray[np.bool_]) -> None:
        """Drop the packets where ``mask`` is False."""
        for name in self._FIELDS:
            setattr(self, name, getattr(self, name)[mask])


class Tally(Protocol):
    """What a front end records. Both hooks see the packets before their update."""

    def absorbed(self, layer: NDArray[np.intp], weight: NDArray[np.float64]) -> None:
        """Weight absorbed at interactions (discrete model only), by layer index."""

    def escaped(self, packets: Packets, idx: NDArray[np.intp], weight: NDArray[np.float64],
                top: NDArray[np.bool_]) -> None:
        """Weight ``weight`` of packets ``idx`` leaving the stack, through the top if ``top``."""


def fresnel(
    cos_i: NDArray[np.float64], n1: NDArray[np.float64], n2: NDArray[np.float64]
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    r"""Unpolarised Fresnel reflectance and cosine of the refracted ray.

    :math:`R = (r_s^2 + r_p^2)/2`, :math:`r_s = (n_1c_i - n_2c_t)/(n_1c_i + n_2c_t)`,
    :math:`r_p = (n_1c_t - n_2c_i)/(n_1c_t + n_2c_i)`, and 1 beyond the critical angle
    (Wang et al. 1995, Eq. 3.36).
    """
    ratio = n1 / n2
    sin_t2 = ratio * ratio * (1.0 - cos_i * cos_i)
    tir = sin_t2 >= 1.0
    cos_t = np.sqrt(np.clip(1.0 - sin_t2, 0.0, None))
    with np.errstate(invalid="ignore", divide="ignore"):
        rs = (n1 * cos_i - n2 * cos_t) / (n1 * cos_i + n2 * cos_t)
        rp = (n1 * cos_t - n2 * cos_i) / (n1 * cos_t + n2 * cos_i)
        r = 0.5 * (rs * rs + rp * rp)
    return np.where(tir, 1.0, r), cos_t


def hg_cos(g: NDArray[np.float64], xi: NDArray[np.float64]) -> NDArray[np.float64]:
    """Sample cos(theta) from the Henyey-Greenstein phase function (Wang et al. 1995, Eq. 3.28)."""
    # this code's guard, not MCML's (MCML tests g == 0 exactly): as g -> 0 the
    # quotient (1 + g^2 - tmp^2)/(2g) loses its precision, so below this |g| the
    # isotropic cos(theta) = 2 xi - 1 is used, the limit of the formula
    iso = np.abs(g) < 1e-6
    gs = np.where(iso, 0.5, g)
    tmp = (1.0 - gs * gs) / (1.0 - gs + 2.0 * gs * xi)
    mu = (1.0 + gs * gs - tmp * tmp) / (2.0 * gs)
    return np.clip(np.where(iso, 2.0 * xi - 1.0, mu), -1.0, 1.0)


def _move(stack: Stack, pk: Packets, mu_free: NDArray[np.float64],
          gen: np.random.Generator, continuous: bool) -> NDArray[np.bool_]:
    """Draw each packet's free path, move it (at most to its layer's boundary).

    Returns where the boundary was hit. [1], Eqs. 3.19-3.21; continuous absorption [2].
    """
    n, lay, uz = pk.pid.size, pk.lay, pk.uz
    with np.errstate(divide="ignore", invalid="ignore"):
        s = -pm.log1p(-gen.random(n)) / mu_free[lay]  # inf in a clear layer
        db = np.where(uz > 0, (stack.z_bot_cm[lay] - pk.z) / uz,
                      np.where(uz < 0, (stack.z_top_cm[lay] - pk.z) / uz, np.inf))
    hit = s >= db
    step = np.where(hit, db, s)
    pk.x += step * pk.ux
    pk.y += step * pk.uy
    pk.z += step * uz
    pk.path[np.arange(n), lay] += step
    if continuous:
        pk.w *= pm.exp(-stack.mua_per_cm[lay] * step)  # [2]
    return hit


def _scatter(stack: Stack, pk: Packets, it: NDArray[np.intp], gen: np.random.Generator) -> None:
    """Turn packets ``it`` by a Henyey-Greenstein angle ([1], Eqs. 3.22-3.26)."""
    cos_t = hg_cos(stack.g[pk.lay[it]], gen.random(it.size))
    psi = 2.0 * np.pi * gen.random(it.size)
    sin_t = np.sqrt(1.0 - cos_t * cos_t)
    cp, sp = pm.cos(psi), pm.sin(psi)
    ux0, uy0, uz0 = pk.ux[it], pk.uy[it], pk.uz[it]
    vert = np.abs(uz0) > _VERTICAL_COS
    tmp = np.sqrt(np.where(vert, 1.0, 1.0 - uz0 * uz0))
    nx = np.where(vert, sin_t * cp, sin_t * (ux0 * uz0 * cp - uy0 * sp) / tmp + ux0 * cos_t)
    ny = np.where(vert, sin_t * sp, sin_t * (uy0 * uz0 * cp + ux0 * sp) / tmp + uy0 * cos_t)
    nz = np.where(vert, np.sign(uz0) * cos_t, -sin_t * cp * tmp + uz0 * cos_t)
    norm = np.sqrt(nx * nx + ny * ny + nz * nz)
    pk.ux[it], pk.uy[it], pk.uz[it] = nx / norm, ny / norm, nz / norm
    pk.scattered[it] = True


def _boundaries(stack: Stack, pk: Packets, hb: NDArray[np.intp], gen: np.random.Generator,
                tally: Tally, continuous: bool) -> None:
    """Packets ``hb`` at a boundary: escape in part, reflect, refract or cross ([1], 3.5)."""
    lb = pk.lay[hb]
    down = pk.uz[hb] > 0
    pk.z[hb] = np.where(down, stack.z_bot_cm[lb], stack.z_top_cm[lb])
    nxt = lb + np.where(down, 1, -1)
    n1 = stack.n_ext[lb + 1]
    n2 = stack.n_ext[nxt + 1]
    refl, cos_tr = fresnel(np.abs(pk.uz[hb]), n1, n2)
    outside = (nxt < 0) | (nxt >= stack.n_layers)
    ob = hb[outside]  # outer surface: split the packet (MCML partial reflection)
    if ob.size:
        r_o = refl[outside]
        tally.escaped(pk, ob, pk.w[ob] * (1.0 - r_o), ~down[outside])
        pk.w[ob] *= r_o
        pk.uz[ob] = -pk.uz[ob]
    ib = hb[~outside]
    if not ib.size:
        return
    if continuous:  # one refractive index: cross
        pk.lay[ib] = nxt[~outside]
        return
    back = gen.random(ib.size) < refl[~outside]  # reflect or refract the whole packet
    ibr, ibt = ib[back], ib[~back]
    pk.uz[ibr] = -pk.uz[ibr]
    ratio = (n1 / n2)[~outside][~back]
    pk.ux[ibt] *= ratio
    pk.uy[ibt] *= ratio
    pk.uz[ibt] = np.sign(pk.uz[ibt]) * cos_tr[~outside][~back]
    pk.lay[ibt] = nxt[~outside][~back]


def run_photons(
    stack: Stack,
    tally: Tally,
    n_photons: int,
    gen: np.random.Generator,
    *,
    absorption: str,
    weight_threshold: float,
    roulette_chance: float,
    max_steps: int,
) -> None:
    """Trace ``n_photons`` packets through ``stack`` until every one has left or died.

    Parameters
    ----------
    stack : Stack
        The layers (validated by the front end).
    tally : Tally
        Receives the absorbed and the escaping weight.
    n_photons : int
        Packets launched, each with weight ``1 - stack.specular``. [-]
    gen : numpy.random.Generator
        The run's random numbers. [-]
    absorption : {'discrete', 'continuous'}
        Absorption model (:data:`ABSORPTION_MODELS`).
    weight_threshold, roulette_chance : float
        Russian roulette below this weight; survival probability (survivors' weight is
        divided by it). [-]
    max_steps : int
        Steps after which a run that has not finished raises RuntimeError. [-]

    Raises
    ------
    ConfigError
        If ``absorption`` is not one of :data:`ABSORPTION_MODELS`, ``n_photons`` is not
        an integer >= 1, ``weight_threshold`` or ``roulette_chance`` is outside (0, 1)
        (:func:`check_run`), or a refractive index of ``stack`` is not finite and > 0.

    Notes
    -----
    Per step: free path :math:`s = -\\ln\\xi/\\mu` (:math:`\\mu = \\mu_t` or
    :math:`\\mu_s`), move, absorb, scatter, boundaries, roulette ([1]; [2] for the
    continuous absorption).

    References
    ----------
    .. [1] L. Wang, S. L. Jacques, L. Zheng, Comput. Methods Programs Biomed. 47,
       131-146 (1995), doi:10.1016/0169-2607(95)01640-F
    .. [2] A. Sassaroli, S. Fantini, Phys. Med. Biol. 49, N255-N257 (2004),
       doi:10.1088/0031-9155/49/14/N07
    """
    if absorption not in ABSORPTION_MODELS:
        raise ConfigError(f"absorption = {absorption!r} is unknown; valid: {ABSORPTION_MODELS}")
    n_photons = check_run(n_photons, weight_threshold, roulette_chance)
    check_range("refractive index", stack.n_ext, "-", 0.0, np.inf, low_open=True, high_open=True)
    continuous = absorption == "continuous"
    mua, mus = stack.mua_per_cm, stack.mus_per_cm
    mut = mua + mus
    with np.errstate(invalid="ignore", divide="ignore"):
        frac_abs = np.where(mut > 0, mua / mut, 0.0)
    mu_free = mus if continuous else mut
    pk = Packets(n_photons, stack.n_layers, 1.0 - stack.specular)
    for _ in range(max_steps):
        if pk.pid.size == 0:
            return
        hit = _move(stack, pk, mu_free, gen, continuous)
        it = np.flatnonzero(~hit)  # interaction: absorption + scattering
        if it.size:
            if not continuous:
                li = pk.lay[it]
                dw = pk.w[it] * frac_abs[li]
                pk.w[it] -= dw
                tally.absorbed(li, dw)
            _scatter(stack, pk, it, gen)
        hb = np.flatnonzero(hit)
        if hb.size:
            _boundaries(stack, pk, hb, gen, tally, continuous)
        # Russian roulette ([1], 3.7); a continuous run's weights stay > 0 (but for
        # underflow), and its roulette has always taken every light packet
        light = pk.w < weight_threshold
        low = np.flatnonzero(light if continuous else light & (pk.w > 0.0))
        if low.size:
            survive = gen.random(low.size) < roulette_chance
            pk.w[low] = np.where(survive, pk.w[low] / roulette_chance, 0.0)
        keep = pk.w > 0.0
        if not np.all(keep):
            pk.keep(keep)
    raise RuntimeError(f"Monte Carlo did not finish within {max_steps} steps")
