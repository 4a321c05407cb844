"""Interpolating the table: multilinear in the axes' coordinates, three variants.

:func:`interpolate_lut` (the full table, reflectance and per-layer paths, NumPy),
:func:`node_lut` + :func:`interpolate_node_lut` (the simulator's fast path: the table
specialised to fixed wavelength nodes, interpolated by the compiled kernel of
:mod:`nirglucose.optics.kernels.lut_kernel`; ``_interpolate_node_lut_numpy`` is its NumPy
reference) and :func:`reflectance_from_tissue_optics` (the simulator's entry). The node
values are centred at build time (Blu, Thevenaz & Unser 2004), so multilinear
interpolation errs by zero on average over every cell.

References
----------
.. [1] T. Blu, P. Thevenaz, M. Unser, "Linear interpolation revitalized", IEEE Trans.
   Image Process. 13, 710-719 (2004), doi:10.1109/TIP.2004.826093
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import lru_cache

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ... import portable as pm
from ...exceptions import ConfigError
from .. import layers
from .cache import get_lut, load_or_build_lut
from .grid import (
    _CHANNELS,
    LUT_AXES,
    LUT_GRID_WAVELENGTHS_NM,
    SkinLUT,
    _forward,
    _inverse,
    grid_name,
)

__all__ = [
    "interpolate_lut",
    "NodeLUT",
    "node_lut",
    "interpolate_node_lut",
    "reflectance_from_tissue_optics",
]


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


#: Which named grid covers which LED bands, for the out-of-box message.
_GRID_BANDS = ", ".join(f"'{g}' covers {a:g}-{b:g} nm" for g, (a, b) in
                        LUT_GRID_WAVELENGTHS_NM.items())


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
                f"{name}{hint} = {float(bad):.6g} is outside the look-up table; valid range is "
                f"[{lo:.6g}, {hi:.6g}] [{unit}] (optics.lut_grid: {_GRID_BANDS} LED bands; "
                f"or use another forward model)"
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
    >>> from nirglucose.optics.lut import build_lut
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
    n_ch = len(_CHANNELS) if pathlengths else 1
    flat = lut.values.reshape(-1, len(_CHANNELS))[:, :n_ch]
    out = pm.exp(_multilinear(flat, _strides(lut.shape), idx, frac).astype(np.float64))
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
    named = grid_name(grid)
    lut = (get_lut(rho_cm, epidermis_thickness_cm, n_tissue, n_ambient, grid=named,
                   solver=solver)
           if named else load_or_build_lut(rho_cm, epidermis_thickness_cm, n_tissue,
                                           n_ambient, grid=grid, solver=solver))
    return node_lut(lut, np.asarray(ratio))


def _node_kernel_args(nlut: NodeLUT) -> tuple:
    """Arguments of :func:`~nirglucose.optics.kernels.lut_kernel.node_reflectance`.

    Cached on the table: ``(table words, cells per node, node ratios, axis_f,
    axis_i)``; see the kernel.
    """
    cached = nlut.__dict__.get("_kernel_args")
    if cached is not None:
        return cached
    from ..kernels.lut_kernel import KERNEL_AXES

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

    One call of a compiled kernel (:mod:`nirglucose.optics.kernels.lut_kernel`): coordinates,
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
    from ..kernels.lut_kernel import node_reflectance

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
    ln_t = pm.log(t.reshape(t.shape + (1,) * (len(full) - t.ndim)))  # one log per row
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
    return pm.exp(ln_r).reshape(tuple(full[i] for i in perm)).transpose(np.argsort(perm))


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
