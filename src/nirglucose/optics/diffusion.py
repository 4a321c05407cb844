"""Diffusion-theory light transport in a semi-infinite turbid medium.

Closed-form results of the steady-state diffusion approximation to the radiative
transport equation for a semi-infinite, homogeneous medium illuminated by a
pencil beam: the spatially resolved diffuse reflectance of the dipole model
(Farrell, Patterson & Wilson 1992), the effective attenuation coefficient and the
differential pathlength factor (Arridge et al. 1992; Fantini et al. 1999).

Every function here is written with plain arithmetic operators and a tiny private
namespace dispatch for ``sqrt``/``exp``, so that it works unchanged on NumPy arrays
and on :class:`torch.Tensor` objects (autograd flows through it). The simulator and
the RTE-inspired neural networks therefore evaluate the *same* physics. Inputs
broadcast against each other; a mix of tensors and array-likes is promoted to
tensors of the first tensor's dtype and device.

Validation: out-of-range physical input raises :class:`~nirglucose.exceptions.ConfigError`
naming the value, the valid range and the unit. On tensors the check runs on
``tensor.detach()`` (it never touches the autograd graph) but it does read the values
back to the host, which synchronises a GPU; pass ``validate=False`` on a hot
training path where the inputs are guaranteed valid by construction (e.g. produced
by a softplus).
"""

from __future__ import annotations

import sys
from types import ModuleType
from typing import Any

import numpy as np

from nirglucose import portable as pm
from nirglucose.exceptions import ConfigError

__all__ = [
    "boundary_coefficient",
    "differential_pathlength_factor",
    "effective_attenuation_per_cm",
    "farrell_reflectance",
]

#: Valid range of the relative refractive index n_tissue / n_ambient for the
#: Groenhuis (Egan & Hilgeman) fit of the internal diffuse reflectance.
_N_REL_RANGE = (1.0, 2.0)


# --------------------------------------------------------------------------- dispatch


def _torch_module() -> ModuleType | None:
    """Return the torch module if it has already been imported, else ``None``.

    torch is never imported here: if the caller has no torch loaded, no argument can
    be a tensor.
    """
    return sys.modules.get("torch")


def _is_tensor(x: Any) -> bool:
    torch = _torch_module()
    return torch is not None and isinstance(x, torch.Tensor)


def _xp(*arrays: Any) -> ModuleType:
    """Return ``torch`` if any argument is a tensor, else ``numpy``."""
    torch = _torch_module()
    if torch is not None and any(isinstance(a, torch.Tensor) for a in arrays):
        return torch
    return np


def _as_arrays(*arrays: Any) -> tuple[ModuleType, tuple[Any, ...]]:
    """Convert all arguments to one array type (tensors win) and return its namespace."""
    xp = _xp(*arrays)
    if xp is np:
        return np, tuple(np.asarray(a, dtype=np.float64) for a in arrays)
    ref = next(a for a in arrays if _is_tensor(a))
    dtype = ref.dtype if ref.is_floating_point() else xp.get_default_dtype()
    out = tuple(
        a.to(dtype=dtype) if _is_tensor(a) else xp.as_tensor(a, dtype=dtype, device=ref.device)
        for a in arrays
    )
    return xp, out


def _exp(xp: ModuleType, x: Any) -> Any:
    """``exp`` in the arrays' namespace; NumPy's through :mod:`nirglucose.portable` (the same
    bits on every CPU), torch's as it is (autograd)."""
    return pm.exp(x) if xp is np else xp.exp(x)


def _host(x: Any) -> np.ndarray:
    """Detached host copy of ``x`` as a float64 NumPy array (for validation only)."""
    if _is_tensor(x):
        return x.detach().to("cpu").double().numpy()
    return np.asarray(x, dtype=np.float64)


def _check(
    name: str,
    x: Any,
    unit: str,
    *,
    low: float = -np.inf,
    high: float = np.inf,
    low_inclusive: bool = True,
) -> None:
    """Raise :class:`ConfigError` unless every element of ``x`` is finite and in range."""
    v = _host(x)
    if v.size == 0:
        return
    above = v >= low if low_inclusive else v > low
    ok = np.isfinite(v) & above & (v <= high)
    if not np.all(ok):
        bad = v[~ok].flat[0]
        bracket = "[" if low_inclusive else "("
        raise ConfigError(
            f"{name} = {bad!r} is out of range; valid range is "
            f"{bracket}{low:g}, {high:g}] (finite) [{unit}]"
        )


def _check_optics(mua: Any, musp: Any, *, mua_strictly_positive: bool = False) -> None:
    _check("mua_per_cm", mua, "1/cm", low=0.0, low_inclusive=not mua_strictly_positive)
    _check("musp_per_cm", musp, "1/cm", low=0.0, low_inclusive=False)


# --------------------------------------------------------------------------- physics


def _groenhuis_a(n_rel: Any) -> Any:
    """Boundary coefficient A of a relative index (no validation)."""
    r_id = -1.440 / n_rel**2 + 0.710 / n_rel + 0.668 + 0.0636 * n_rel
    return (1.0 + r_id) / (1.0 - r_id)


def boundary_coefficient(n_tissue: Any = 1.4, n_ambient: Any = 1.0) -> Any:
    r"""Internal-reflection boundary coefficient A of the extrapolated boundary.

    Parameters
    ----------
    n_tissue : float or array_like or torch.Tensor
        Refractive index of the turbid medium. [-]
    n_ambient : float or array_like or torch.Tensor
        Refractive index of the medium above the surface. [-]

    Returns
    -------
    A : float or ndarray or torch.Tensor
        Boundary coefficient, ``A >= 1`` (about 1.0 for matched indices). [-]

    Raises
    ------
    ConfigError
        If ``n_tissue / n_ambient`` is outside [1, 2], the range of the fit.

    Notes
    -----
    With the relative index :math:`n = n_\mathrm{tissue}/n_\mathrm{ambient}` the
    internal diffuse reflectance is the polynomial fit (Egan & Hilgeman) quoted by
    Groenhuis et al.

    .. math::

        r_{id} = -1.440\,n^{-2} + 0.710\,n^{-1} + 0.668 + 0.0636\,n,
        \qquad A = \frac{1 + r_{id}}{1 - r_{id}}.

    The fit gives :math:`A = 1.003` at :math:`n = 1` and :math:`A = 3.25` at
    :math:`n = 1.4`.

    References
    ----------
    .. [1] R. A. J. Groenhuis, H. A. Ferwerda and J. J. Ten Bosch, "Scattering and
       absorption of turbid materials determined from reflection measurements.
       1: Theory", Appl. Opt. 22, 2456-2462 (1983). :doi:`10.1364/AO.22.002456`

    Examples
    --------
    >>> round(float(boundary_coefficient(1.4, 1.0)), 3)
    3.251
    """
    xp, (nt, na) = _as_arrays(n_tissue, n_ambient)
    n_rel = nt / na
    _check("n_tissue / n_ambient", n_rel, "-", low=_N_REL_RANGE[0], high=_N_REL_RANGE[1])
    return _groenhuis_a(n_rel)


def effective_attenuation_per_cm(
    mua_per_cm: Any, musp_per_cm: Any, *, validate: bool = True
) -> Any:
    r"""Effective attenuation coefficient of the diffusion approximation.

    Parameters
    ----------
    mua_per_cm : float or array_like or torch.Tensor
        Absorption coefficient, ``>= 0``. [1/cm]
    musp_per_cm : float or array_like or torch.Tensor
        Reduced scattering coefficient, ``> 0``. [1/cm]
    validate : bool, optional
        Check the ranges (on a detached host copy for tensors). Default True. [-]

    Returns
    -------
    mu_eff : ndarray or torch.Tensor
        Effective attenuation coefficient, broadcast shape of the inputs. [1/cm]

    Raises
    ------
    ConfigError
        If ``mua_per_cm < 0``, ``musp_per_cm <= 0`` or any value is not finite.

    Notes
    -----
    .. math:: \mu_\mathrm{eff} = \sqrt{3\,\mu_a\,(\mu_a + \mu_s')}

    The fluence far from a point source decays as
    :math:`\exp(-\mu_\mathrm{eff} r)/r`.

    References
    ----------
    .. [1] T. J. Farrell, M. S. Patterson and B. Wilson, "A diffusion theory model of
       spatially resolved, steady-state diffuse reflectance for the noninvasive
       determination of tissue optical properties in vivo", Med. Phys. 19, 879-888
       (1992). :doi:`10.1118/1.596777`

    Examples
    --------
    >>> round(float(effective_attenuation_per_cm(0.1, 10.0)), 4)
    1.7407
    """
    xp, (mua, musp) = _as_arrays(mua_per_cm, musp_per_cm)
    if validate:
        _check_optics(mua, musp)
    return xp.sqrt(3.0 * mua * (mua + musp))


def farrell_reflectance(
    rho_cm: Any,
    mua_per_cm: Any,
    musp_per_cm: Any,
    n_tissue: Any = 1.4,
    n_ambient: Any = 1.0,
    *,
    validate: bool = True,
) -> Any:
    r"""Spatially resolved diffuse reflectance of a semi-infinite medium (dipole model).

    Works on NumPy arrays and on torch tensors (differentiable); inputs broadcast.

    Parameters
    ----------
    rho_cm : float or array_like or torch.Tensor
        Source-detector distance on the surface, ``> 0``. [cm]
    mua_per_cm : float or array_like or torch.Tensor
        Absorption coefficient, ``>= 0``. [1/cm]
    musp_per_cm : float or array_like or torch.Tensor
        Reduced scattering coefficient ``mus * (1 - g)``, ``> 0``. [1/cm]
    n_tissue : float or array_like or torch.Tensor, optional
        Refractive index of the tissue. Default 1.4. [-]
    n_ambient : float or array_like or torch.Tensor, optional
        Refractive index above the surface; ``n_tissue / n_ambient`` must lie in
        [1, 2]. Default 1.0 (air). [-]
    validate : bool, optional
        Check the ranges (index included). For tensors the check uses ``detach()``
        (autograd is not affected) but synchronises the device; False skips every
        check, for a hot path whose inputs are valid by construction. Default True. [-]

    Returns
    -------
    R : ndarray or torch.Tensor
        Diffuse reflectance per unit area per incident photon, broadcast shape of
        the inputs. [1/cm^2]

    Raises
    ------
    ConfigError
        If ``rho_cm <= 0``, ``mua_per_cm < 0``, ``musp_per_cm <= 0``, a value is not
        finite, or the relative index is outside [1, 2].

    Notes
    -----
    The pencil beam is replaced by an isotropic point source of strength
    :math:`a' = \mu_s'/\mu_t'` at depth :math:`z_0 = 1/\mu_t'`
    (:math:`\mu_t' = \mu_a + \mu_s'`) and a negative image source at
    :math:`-(z_0 + 2 z_b)`, with the extrapolated boundary :math:`z_b = 2AD`,
    :math:`D = 1/(3\mu_t')` and :math:`A` from :func:`boundary_coefficient`. The
    reflectance is the diffuse flux through the surface (Farrell et al. 1992, eq. 5):

    .. math::

        R(\rho) = \frac{a'}{4\pi}\Big[
            z_0\Big(\mu_\mathrm{eff} + \frac{1}{r_1}\Big)
            \frac{e^{-\mu_\mathrm{eff} r_1}}{r_1^2}
          + (z_0 + 2z_b)\Big(\mu_\mathrm{eff} + \frac{1}{r_2}\Big)
            \frac{e^{-\mu_\mathrm{eff} r_2}}{r_2^2}\Big],

    :math:`r_1^2 = z_0^2 + \rho^2`, :math:`r_2^2 = (z_0 + 2z_b)^2 + \rho^2`,
    :math:`\mu_\mathrm{eff} = \sqrt{3\mu_a\mu_t'}`. Integrated over the surface it
    gives the total diffuse reflectance
    :math:`R_d = \tfrac{a'}{2}\,[e^{-\mu_\mathrm{eff} z_0}
    + e^{-\mu_\mathrm{eff}(z_0 + 2z_b)}]`.
    Valid for :math:`\mu_a \ll \mu_s'` and :math:`\rho` beyond about one transport
    mean free path :math:`1/\mu_t'`.

    References
    ----------
    .. [1] T. J. Farrell, M. S. Patterson and B. Wilson, "A diffusion theory model of
       spatially resolved, steady-state diffuse reflectance for the noninvasive
       determination of tissue optical properties in vivo", Med. Phys. 19, 879-888
       (1992). :doi:`10.1118/1.596777`
    .. [2] R. A. J. Groenhuis, H. A. Ferwerda and J. J. Ten Bosch, "Scattering and
       absorption of turbid materials determined from reflection measurements.
       1: Theory", Appl. Opt. 22, 2456-2462 (1983). :doi:`10.1364/AO.22.002456`

    Examples
    --------
    >>> import numpy as np
    >>> r = farrell_reflectance(np.array([0.5, 1.0, 2.0]), 0.1, 10.0)
    >>> np.round(r, 4)
    array([0.1149, 0.0156, 0.0007])
    """
    xp, (rho, mua, musp, nt, na) = _as_arrays(rho_cm, mua_per_cm, musp_per_cm, n_tissue, n_ambient)
    n_rel = nt / na
    if validate:
        _check("rho_cm", rho, "cm", low=0.0, low_inclusive=False)
        _check_optics(mua, musp)
        _check("n_tissue / n_ambient", n_rel, "-", low=_N_REL_RANGE[0], high=_N_REL_RANGE[1])
    a_coef = _groenhuis_a(n_rel)
    mutp = mua + musp
    albedo_p = musp / mutp
    z0 = 1.0 / mutp
    zb = 2.0 * a_coef / (3.0 * mutp)  # 2 A D
    zi = z0 + 2.0 * zb
    mu_eff = xp.sqrt(3.0 * mua * mutp)
    rho2 = rho * rho
    r1 = xp.sqrt(z0 * z0 + rho2)
    r2 = xp.sqrt(zi * zi + rho2)
    term1 = z0 * (mu_eff + 1.0 / r1) * _exp(xp, -mu_eff * r1) / (r1 * r1)
    term2 = zi * (mu_eff + 1.0 / r2) * _exp(xp, -mu_eff * r2) / (r2 * r2)
    return albedo_p / (4.0 * np.pi) * (term1 + term2)


def differential_pathlength_factor(
    rho_cm: Any, mua_per_cm: Any, musp_per_cm: Any, *, validate: bool = True
) -> Any:
    r"""Differential pathlength factor of diffuse reflectance from a semi-infinite medium.

    Works on NumPy arrays and on torch tensors (differentiable); inputs broadcast.

    Parameters
    ----------
    rho_cm : float or array_like or torch.Tensor
        Source-detector distance, ``> 0``. [cm]
    mua_per_cm : float or array_like or torch.Tensor
        Absorption coefficient, ``> 0``. [1/cm]
    musp_per_cm : float or array_like or torch.Tensor
        Reduced scattering coefficient, ``> 0``. [1/cm]
    validate : bool, optional
        Check the ranges (detached host copy for tensors). Default True. [-]

    Returns
    -------
    dpf : ndarray or torch.Tensor
        Differential pathlength factor: mean optical path of the detected light
        divided by ``rho_cm``. [-]

    Raises
    ------
    ConfigError
        If ``rho_cm <= 0``, ``mua_per_cm <= 0``, ``musp_per_cm <= 0`` or a value is
        not finite.

    Notes
    -----
    .. math::

        \mathrm{DPF} = \frac{1}{2}\sqrt{\frac{3\mu_s'}{\mu_a}}
        \Big[1 - \frac{1}{1 + \rho\sqrt{3\mu_a\mu_s'}}\Big]

    It equals :math:`-\rho^{-1}\,\partial\ln R/\partial\mu_a` for the single-source
    far-field reflectance :math:`R \propto (\mu_\mathrm{eff} + 1/\rho)
    e^{-\mu_\mathrm{eff}\rho}/\rho^2` with :math:`\mu_\mathrm{eff} \approx
    \sqrt{3\mu_a\mu_s'}`, and tends to :math:`\tfrac12\sqrt{3\mu_s'/\mu_a}` for
    large :math:`\rho`. The modified Beer-Lambert law reads
    :math:`\Delta OD = \Delta\mu_a\,\rho\,\mathrm{DPF}` (natural log).

    References
    ----------
    .. [1] S. Fantini, D. Hueber, M. A. Franceschini, E. Gratton, W. Rosenfeld,
       P. G. Stubbs, A. E. Cerussi and S. Walker, "Non-invasive optical monitoring of
       the newborn piglet brain using continuous-wave and frequency-domain
       spectroscopy", Phys. Med. Biol. 44, 1543-1563 (1999).
       :doi:`10.1088/0031-9155/44/6/308`
    .. [2] S. R. Arridge, M. Cope and D. T. Delpy, "The theoretical basis for the
       determination of optical pathlengths in tissue: temporal and frequency
       analysis", Phys. Med. Biol. 37, 1531-1560 (1992).
       :doi:`10.1088/0031-9155/37/7/005`

    Examples
    --------
    >>> round(float(differential_pathlength_factor(3.0, 0.1, 10.0)), 4)
    7.2626
    """
    xp, (rho, mua, musp) = _as_arrays(rho_cm, mua_per_cm, musp_per_cm)
    if validate:
        _check("rho_cm", rho, "cm", low=0.0, low_inclusive=False)
        _check_optics(mua, musp, mua_strictly_positive=True)
    x = rho * xp.sqrt(3.0 * mua * musp)
    return 0.5 * xp.sqrt(3.0 * musp / mua) * (1.0 - 1.0 / (1.0 + x))
