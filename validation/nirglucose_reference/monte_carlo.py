"""MCML Monte Carlo of layered turbid media: reflectance, transmittance, absorption.

The front end of the photon engine (:mod:`~nirglucose_reference.photon_engine`)
with MCML's own physics (discrete absorption, Fresnel reflection and refraction at every
interface; Wang, Jacques & Zheng 1995) and a tally of the classic MCML outputs. It exists
to validate the deterministic solvers
(:mod:`~nirglucose_reference.adding_doubling`, :mod:`~nirglucose.optics.diffusion`)
in tests and scripts; it is not on any hot path.

Packet bookkeeping
------------------
* The specular reflection at the top surface is deterministic and removed from the
  launched weight (``1 - R_sp``).
* At the outer surfaces the packet is split: the Fresnel-transmitted fraction of the
  weight escapes and is tallied, the rest is reflected back (MCML's "partial
  reflection" option; lower variance than all-or-none). At internal interfaces
  between layers the packet is reflected or refracted as a whole with the Fresnel
  probability.
* Standard errors of the scalar tallies come from the per-packet totals (packets are
  independent); those of the radial profile from 20 interleaved batches of packets.

References
----------
.. [1] L. Wang, S. L. Jacques, L. Zheng, "MCML - Monte Carlo modeling of light transport
   in multi-layered tissues", Comput. Methods Programs Biomed. 47, 131-146 (1995),
   doi:10.1016/0169-2607(95)01640-F
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from nirglucose.exceptions import ConfigError
from nirglucose.optics._inputs import as_generator

from .photon_engine import (
    N_BATCHES,
    Packets,
    Stack,
    as_layers,
    check_range,
    check_run,
    run_photons,
)

__all__ = ["MCResult", "mc_layers", "mc_slab"]

_MAX_STEPS = 1_000_000


@dataclass(frozen=True)
class MCResult:
    """Tallies of a Monte Carlo run, all per incident photon.

    Attributes
    ----------
    n_photons : int
        Number of launched packets. [-]
    specular : float
        Specular reflectance of the top surface (deterministic). [-]
    specular_se : float
        Its standard error (0: not sampled). [-]
    diffuse_reflectance : float
        Weight escaping through the top surface after entering the medium. [-]
    diffuse_reflectance_se : float
        Standard error of ``diffuse_reflectance``. [-]
    total_transmittance : float
        Weight escaping through the bottom surface, unscattered beam included. [-]
    total_transmittance_se : float
        Standard error of ``total_transmittance``. [-]
    unscattered_transmittance : float
        Part of ``total_transmittance`` that never scattered. [-]
    absorbed_per_layer : ndarray
        Weight absorbed in each layer. [-]
    mean_pathlength_cm : ndarray
        Mean path length travelled in each layer by the diffusely reflected light
        (escaping-weight weighted). [cm]
    rho_cm : ndarray or None
        Centres of the radial bins of the reflectance profile. [cm]
    reflectance_per_cm2 : ndarray or None
        Spatially resolved diffuse reflectance R(rho). [1/cm^2]
    reflectance_per_cm2_se : ndarray or None
        Standard error of ``reflectance_per_cm2`` (batch estimate). [1/cm^2]
    pathlength_at_rho_cm : ndarray or None
        Mean total path length of the light reflected in each radial bin. [cm]
    """

    n_photons: int
    specular: float
    specular_se: float
    diffuse_reflectance: float
    diffuse_reflectance_se: float
    total_transmittance: float
    total_transmittance_se: float
    unscattered_transmittance: float
    absorbed_per_layer: NDArray[np.float64] = field(repr=False)
    mean_pathlength_cm: NDArray[np.float64] = field(repr=False)
    rho_cm: NDArray[np.float64] | None = field(default=None, repr=False)
    reflectance_per_cm2: NDArray[np.float64] | None = field(default=None, repr=False)
    reflectance_per_cm2_se: NDArray[np.float64] | None = field(default=None, repr=False)
    pathlength_at_rho_cm: NDArray[np.float64] | None = field(default=None, repr=False)

    @property
    def total_reflectance(self) -> float:
        """Specular plus diffuse reflectance. [-]"""
        return self.specular + self.diffuse_reflectance

    @property
    def total_reflectance_se(self) -> float:
        """Standard error of ``total_reflectance`` (that of the diffuse part). [-]"""
        return self.diffuse_reflectance_se


def mc_layers(
    mua_per_cm: ArrayLike,
    mus_per_cm: ArrayLike,
    g: ArrayLike,
    thickness_cm: ArrayLike,
    n_layers: ArrayLike,
    n_ambient: float = 1.0,
    n_photons: int = 100_000,
    *,
    rng: np.random.Generator | int,
    rho_edges_cm: ArrayLike | None = None,
    weight_threshold: float = 1e-4,
    roulette_chance: float = 0.1,
) -> MCResult:
    r"""Monte Carlo photon transport in a stack of layers (MCML algorithm).

    A pencil beam hits the top of the stack at normal incidence; the same ambient
    medium lies above and below. The last layer may be semi-infinite.

    Parameters
    ----------
    mua_per_cm : array_like
        Absorption coefficient of each layer (top first), ``>= 0``. [1/cm]
    mus_per_cm : array_like
        Scattering coefficient of each layer, ``>= 0``. [1/cm]
    g : array_like
        Henyey-Greenstein anisotropy of each layer, ``-1 < g < 1``. [-]
    thickness_cm : array_like
        Thickness of each layer, ``> 0``; only the last may be ``inf``, and then it
        must absorb (``mua > 0``). [cm]
    n_layers : array_like
        Refractive index of each layer, ``> 0``. [-]
    n_ambient : float, optional
        Refractive index above and below the stack. Default 1.0. [-]
    n_photons : int, optional
        Number of photon packets, ``>= 1``. Default 100 000. [-]
    rng : numpy.random.Generator or int
        Random generator, or a seed for :func:`numpy.random.default_rng`. [-]
    rho_edges_cm : array_like, optional
        Increasing edges of radial bins (first ``>= 0``) for the spatially resolved
        reflectance; None (default) skips that tally. [cm]
    weight_threshold : float, optional
        Packets lighter than this enter Russian roulette. Default 1e-4. [-]
    roulette_chance : float, optional
        Survival probability in the roulette; survivors' weight is divided by it.
        Default 0.1. [-]

    Returns
    -------
    MCResult
        Reflectance, transmittance, absorption, path lengths and their standard
        errors, per incident photon.

    Raises
    ------
    ConfigError
        If an input is out of range.

    Notes
    -----
    Free path :math:`s = -\ln\xi/\mu_t`; at each interaction the weight drops by
    :math:`w\,\mu_a/\mu_t` and the direction turns by the Henyey-Greenstein angle

    .. math::

        \cos\theta = \frac{1}{2g}\Big[1 + g^2
        - \Big(\frac{1 - g^2}{1 - g + 2g\xi}\Big)^2\Big],
        \qquad \psi = 2\pi\xi'.

    At an interface with incidence cosine :math:`c_i` the unpolarised Fresnel
    reflectance is :math:`R = (r_s^2 + r_p^2)/2`, :math:`r_s = (n_1c_i -
    n_2c_t)/(n_1c_i + n_2c_t)`, :math:`r_p = (n_1c_t - n_2c_i)/(n_1c_t + n_2c_i)`,
    and 1 beyond the critical angle. The specular reflectance is
    :math:`((n_0 - n_1)/(n_0 + n_1))^2`.

    References
    ----------
    .. [1] L. Wang, S. L. Jacques and L. Zheng, "MCML - Monte Carlo modeling of light
       transport in multi-layered tissues", Comput. Methods Programs Biomed. 47,
       131-146 (1995). :doi:`10.1016/0169-2607(95)01640-F`

    Examples
    --------
    >>> res = mc_layers([10.0], [90.0], [0.75], [0.02], [1.0], n_photons=20_000, rng=1)
    >>> abs(res.diffuse_reflectance - 0.0973) < 5 * res.diffuse_reflectance_se
    True
    """
    stack, edges = _validated_stack(mua_per_cm, mus_per_cm, g, thickness_cm, n_layers,
                                    n_ambient, rho_edges_cm)
    n_photons = check_run(n_photons, weight_threshold, roulette_chance)  # sizes the tally
    gen = as_generator(rng)
    tally = _LayerTally(n_photons, stack.n_layers, edges)
    run_photons(stack, tally, n_photons, gen, absorption="discrete",
                weight_threshold=weight_threshold, roulette_chance=roulette_chance,
                max_steps=_MAX_STEPS)
    return tally.result(stack.specular)


def _validated_stack(mua_per_cm, mus_per_cm, g, thickness_cm, n_layers, n_ambient,
                     rho_edges_cm) -> tuple[Stack, NDArray[np.float64] | None]:
    """The engine's :class:`Stack` and the radial bin edges, or ConfigError (one line)."""
    mua0 = np.atleast_1d(np.asarray(mua_per_cm, dtype=np.float64))
    if mua0.ndim != 1 or mua0.size == 0:
        raise ConfigError("mua_per_cm must be a scalar or a 1-D sequence with one value per layer")
    nl = mua0.size
    mua = as_layers("mua_per_cm", mua0, nl)
    mus = as_layers("mus_per_cm", mus_per_cm, nl)
    gl = as_layers("g", g, nl)
    d = as_layers("thickness_cm", thickness_cm, nl)
    nidx = as_layers("n_layers", n_layers, nl)
    check_range("mua_per_cm", mua, "1/cm", 0.0, np.inf)
    check_range("mus_per_cm", mus, "1/cm", 0.0, np.inf)
    check_range("g", gl, "-", -1.0, 1.0, low_open=True, high_open=True)
    check_range("thickness_cm", d[:-1], "cm", 0.0, np.inf, low_open=True)
    check_range("thickness_cm", d[-1:], "cm", 0.0, np.inf, low_open=True, finite=False)
    check_range("n_layers", nidx, "-", 0.0, np.inf, low_open=True)
    check_range("n_ambient", np.atleast_1d(float(n_ambient)), "-", 0.0, np.inf, low_open=True)
    if np.isinf(d[-1]) and mua[-1] <= 0.0:
        raise ConfigError(
            f"mua_per_cm = {mua[-1]!r} of the semi-infinite last layer is out of range; "
            "valid range is (0, inf) [1/cm]"
        )
    edges = None
    if rho_edges_cm is not None:
        edges = np.asarray(rho_edges_cm, dtype=np.float64)
        if edges.ndim != 1 or edges.size < 2 or edges[0] < 0 or np.any(np.diff(edges) <= 0):
            raise ConfigError("rho_edges_cm must be >= 2 increasing edges starting at >= 0 [cm]")
    return Stack.from_layers(mua, mus, gl, d, nidx, n_ambient), edges


class _LayerTally:
    """MCML's tallies: per-packet reflectance and transmittance, absorption per layer,
    mean paths of the reflected light, and optionally the radial profile R(rho) in
    20 interleaved batches (Wang et al. 1995, section 4)."""

    def __init__(self, n_photons: int, n_layers: int, edges: NDArray[np.float64] | None):
        self.n_photons, self.edges = n_photons, edges
        self.rd_ph = np.zeros(n_photons)
        self.tt_ph = np.zeros(n_photons)
        self.tu_total = 0.0
        self.absorbed_w = np.zeros(n_layers)
        self.path_w = np.zeros(n_layers)  # sum over reflected weight of w * path in layer
        if edges is not None:
            self.r_rho = np.zeros((N_BATCHES, edges.size - 1))
            self.lw_rho = np.zeros(edges.size - 1)

    def absorbed(self, layer, weight) -> None:
        self.absorbed_w += np.bincount(layer, weights=weight, minlength=self.absorbed_w.size)

    def escaped(self, pk: Packets, ob, esc, top) -> None:
        self.rd_ph[pk.pid[ob[top]]] += esc[top]
        bot = ~top
        self.tt_ph[pk.pid[ob[bot]]] += esc[bot]
        self.tu_total += float(np.sum(esc[bot & ~pk.scattered[ob]]))
        self.path_w += (esc[top, None] * pk.path[ob[top]]).sum(axis=0)
        if self.edges is not None and np.any(top):
            nb = self.edges.size - 1
            ot = ob[top]
            rr = np.hypot(pk.x[ot], pk.y[ot])
            k = np.searchsorted(self.edges, rr, side="right") - 1
            inb = (k >= 0) & (k < nb)
            np.add.at(self.r_rho, (pk.pid[ot[inb]] % N_BATCHES, k[inb]), esc[top][inb])
            self.lw_rho += np.bincount(
                k[inb], weights=esc[top][inb] * pk.path[ot[inb]].sum(axis=1), minlength=nb
            )

    def result(self, specular: float) -> MCResult:
        """The run's :class:`MCResult`, per incident photon."""
        n_photons, edges = self.n_photons, self.edges
        ddof = 1 if n_photons > 1 else 0
        rd_total = float(self.rd_ph.sum())
        nl = self.path_w.size
        rho_c = r_prof = r_prof_se = l_rho = None
        if edges is not None:
            area = np.pi * (edges[1:] ** 2 - edges[:-1] ** 2)
            per_batch = self.r_rho / (n_photons / N_BATCHES) / area
            r_prof = self.r_rho.sum(axis=0) / n_photons / area
            r_prof_se = per_batch.std(axis=0, ddof=1) / np.sqrt(N_BATCHES)
            with np.errstate(invalid="ignore", divide="ignore"):
                l_rho = self.lw_rho / self.r_rho.sum(axis=0)
            rho_c = 0.5 * (edges[1:] + edges[:-1])
        return MCResult(
            n_photons=n_photons,
            specular=float(specular),
            specular_se=0.0,
            diffuse_reflectance=float(self.rd_ph.mean()),
            diffuse_reflectance_se=float(np.std(self.rd_ph, ddof=ddof) / np.sqrt(n_photons)),
            total_transmittance=float(self.tt_ph.mean()),
            total_transmittance_se=float(np.std(self.tt_ph, ddof=ddof) / np.sqrt(n_photons)),
            unscattered_transmittance=self.tu_total / n_photons,
            absorbed_per_layer=self.absorbed_w / n_photons,
            mean_pathlength_cm=self.path_w / rd_total if rd_total > 0 else np.full(nl, np.nan),
            rho_cm=rho_c,
            reflectance_per_cm2=r_prof,
            reflectance_per_cm2_se=r_prof_se,
            pathlength_at_rho_cm=l_rho,
        )


def mc_slab(
    mua_per_cm: float,
    mus_per_cm: float,
    g: float,
    thickness_cm: float,
    n_slab: float,
    n_ambient: float = 1.0,
    n_photons: int = 100_000,
    *,
    rng: np.random.Generator | int,
    rho_edges_cm: Sequence[float] | NDArray[np.float64] | None = None,
) -> MCResult:
    r"""Monte Carlo reflectance and transmittance of one homogeneous slab.

    Same conventions as :func:`~nirglucose_reference.adding_doubling.slab_rt`: a normally
    incident pencil beam, the same ambient medium on both sides. ``thickness_cm =
    inf`` gives a semi-infinite medium (then ``mua_per_cm > 0``).

    Parameters
    ----------
    mua_per_cm : float
        Absorption coefficient, ``>= 0``. [1/cm]
    mus_per_cm : float
        Scattering coefficient, ``>= 0``. [1/cm]
    g : float
        Henyey-Greenstein anisotropy, ``-1 < g < 1``. [-]
    thickness_cm : float
        Slab thickness, ``> 0`` (``inf`` allowed). [cm]
    n_slab : float
        Refractive index of the slab. [-]
    n_ambient : float, optional
        Refractive index of the surrounding medium. Default 1.0. [-]
    n_photons : int, optional
        Number of photon packets. Default 100 000. [-]
    rng : numpy.random.Generator or int
        Random generator, or a seed. [-]
    rho_edges_cm : array_like, optional
        Radial bin edges for the spatially resolved reflectance. [cm]

    Returns
    -------
    MCResult
        ``specular``, ``diffuse_reflectance``, ``total_transmittance`` (diffuse +
        unscattered), their standard errors, and the optional radial profile.

    Raises
    ------
    ConfigError
        If an input is out of range.

    Notes
    -----
    See :func:`mc_layers` for the algorithm. Total reflectance
    :math:`R_t = R_{sp} + R_d` is comparable to the adding-doubling ``UR1``.

    References
    ----------
    .. [1] L. Wang, S. L. Jacques and L. Zheng, "MCML - Monte Carlo modeling of light
       transport in multi-layered tissues", Comput. Methods Programs Biomed. 47,
       131-146 (1995). :doi:`10.1016/0169-2607(95)01640-F`

    Examples
    --------
    >>> res = mc_slab(10.0, 90.0, 0.75, 0.02, 1.0, n_photons=20_000, rng=0)
    >>> abs(res.total_transmittance - 0.66096) < 5 * res.total_transmittance_se
    True
    """
    for name, v in (
        ("mua_per_cm", mua_per_cm),
        ("mus_per_cm", mus_per_cm),
        ("g", g),
        ("thickness_cm", thickness_cm),
        ("n_slab", n_slab),
    ):
        if np.ndim(v) != 0:
            raise ConfigError(f"{name} must be a scalar for mc_slab; use mc_layers for layers")
    return mc_layers(
        [mua_per_cm],
        [mus_per_cm],
        [g],
        [thickness_cm],
        [n_slab],
        n_ambient,
        n_photons,
        rng=rng,
        rho_edges_cm=rho_edges_cm,
    )
