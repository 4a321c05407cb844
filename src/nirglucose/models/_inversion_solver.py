"""The physics inversion's batched MAP solver over the simulator's forward model.

The forward model, :class:`~nirglucose.simulation.forward_model.ForwardModel` (the
noise-free log ratio ln(fraction / T_ref) of each reading for any glucose and any tissue
and probe state), lives beside the simulator (:mod:`nirglucose.simulation.forward_model`)
and is re-exported here with its :data:`NUISANCES` and :data:`PHYSICAL_BOUNDS`.

:func:`map_estimate` minimises, for all rows at once,

    || R (y - a - b * m(theta(z))) ||^2 + || z ||^2

over whitened unknowns z (theta = mu + s z: a Gaussian prior N(mu, s^2) per unknown),
by Levenberg-Marquardt with a forward-difference Jacobian [1]_ [2]_; ``R`` is the
Cholesky factor of the inverse noise covariance, ``a`` and ``b`` the per-channel
calibration. The damping of each row adapts on its own (a step that raises that row's
cost is refused and the row's damping grows tenfold), so rows never wait on each other.

References
----------
.. [1] D. W. Marquardt, "An algorithm for least-squares estimation of nonlinear
   parameters", J. SIAM 11, 431-441 (1963), doi:10.1137/0111030
.. [2] Å. Björck, "Numerical Methods for Least Squares Problems", SIAM (1996), ch. 9.
"""

from __future__ import annotations

import numpy as np

from ..dataset.adc import quantisation_variance_ln
from ..simulation.forward_model import NUISANCES, PHYSICAL_BOUNDS, ForwardModel

__all__ = [
    "NUISANCES", "PHYSICAL_BOUNDS", "ForwardModel", "map_estimate", "posterior_variance",
    "model_jacobian", "VAR_FLOOR_12BIT", "residual_var_floor",
]

#: The residual-variance floor at 12 bits of the privileged estimators (the oracle and
#: physics-inversion): a 12-bit code's quantisation at mid-scale, (1/2048)^2 / 12 =
#: 1.99e-8 (:func:`~nirglucose.dataset.adc.quantisation_variance_ln`), as first set,
#: rounded to 2e-8 -- kept so that every 12-bit result stays byte-identical. [-]
VAR_FLOOR_12BIT = 2e-8


def residual_var_floor(adc_bits: int) -> float:
    """The privileged estimators' residual-variance floor at ``adc_bits``. [-]

    :data:`VAR_FLOOR_12BIT` scaled as the quantisation variance LSB^2 / 12 scales
    (:func:`~nirglucose.dataset.adc.quantisation_variance_ln`, Bennett 1948): a quarter
    per bit above 12, four times per bit below. The bits are the data's declared ones,
    which the averaging emulation raises by log4 of the readings averaged
    (:func:`~nirglucose.design.averaging.averaging_overrides`), so an estimator can use
    the resolution a quieter design has. The ratio of two powers of two is exact: at
    12 bits the floor is 2e-8 to the last bit.

    Examples
    --------
    >>> residual_var_floor(12)
    2e-08
    >>> residual_var_floor(14)
    1.25e-09
    """
    return VAR_FLOOR_12BIT * (quantisation_variance_ln(adc_bits) / quantisation_variance_ln(12))

#: Forward-difference step of the Jacobian, in prior standard deviations. [-]
_STEP_SD = 1e-4
#: Levenberg-Marquardt damping: start, growth on a refused step, shrink on an accepted
#: one (Marquardt 1963's factor 10).
_DAMP_START, _DAMP_UP, _DAMP_DOWN = 1e-3, 10.0, 0.1


def _residuals(fm, y, calib, root_w, mean, sd, z):
    """Whitened data residuals (n, k) and the model's log ratio, at whitened ``z``."""
    theta = mean + sd * z
    # a trial state the optics cannot take (e.g. volume fractions summing past 1) gives
    # non-finite residuals; the solver refuses such steps, so they need no warning
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        m = fm.log_ratio(theta[:, 0], theta[:, 1:])
        r = (y - calib[0] - calib[1] * m) @ root_w.T
    return r, m


def map_estimate(fm, y, calib, root_w, mean, sd, *, free, max_iter=30, tol=1e-6):
    """Posterior mode of every row's unknowns under Gaussian priors, all rows at once.

    Parameters
    ----------
    fm : ForwardModel
        The assumed forward model.
    y : numpy.ndarray
        (n, k) measured ln(adc / adc_ref). [-]
    calib : tuple of numpy.ndarray
        Per-channel offset ``a`` and gain ``b``, (k,) each. [-]
    root_w : numpy.ndarray
        (k, k) R with R^T R the inverse noise covariance. [-]
    mean, sd : numpy.ndarray
        (n, 1 + len(NUISANCES)) prior means and standard deviations: glucose [mg/dL]
        first, then :data:`NUISANCES` in their units.
    free : numpy.ndarray of bool
        (1 + len(NUISANCES),) which unknowns are estimated; the others stay at their
        prior mean (glucose is held at its reference value in calibration).
    max_iter : int
        Levenberg-Marquardt iterations at most. [-]
    tol : float
        Stop when no row's whitened step exceeds this. [-]

    Returns
    -------
    theta : numpy.ndarray
        (n, 1 + len(NUISANCES)) the estimates, in the units of ``mean``.
    m : numpy.ndarray
        (n, k) the model's log ratio there. [-]
    """
    n, p = mean.shape
    idx = np.flatnonzero(free)
    z = np.zeros((n, p))
    r, m = _residuals(fm, y, calib, root_w, mean, sd, z)
    cost = (r**2).sum(axis=1) + (z**2).sum(axis=1)
    damp = np.full(n, _DAMP_START)
    eye = np.eye(len(idx))
    for _ in range(int(max_iter)):
        J = np.empty((n, r.shape[1], len(idx)))
        for j, col in enumerate(idx):
            zp = z.copy()
            zp[:, col] += _STEP_SD
            J[:, :, j] = (_residuals(fm, y, calib, root_w, mean, sd, zp)[0] - r) / _STEP_SD
        zf = z[:, idx]
        A = np.einsum("nki,nkj->nij", J, J) + eye
        g = np.einsum("nki,nk->ni", J, r) + zf
        A += damp[:, None, None] * (eye * np.diagonal(A, axis1=1, axis2=2)[:, None, :])
        step = -np.linalg.solve(A, g[:, :, None])[:, :, 0]
        z_try = z.copy()
        z_try[:, idx] += step
        r_try, m_try = _residuals(fm, y, calib, root_w, mean, sd, z_try)
        cost_try = (r_try**2).sum(axis=1) + (z_try**2).sum(axis=1)
        ok = np.isfinite(cost_try) & (cost_try <= cost)
        z[ok], r[ok], m[ok], cost[ok] = z_try[ok], r_try[ok], m_try[ok], cost_try[ok]
        damp = np.where(ok, damp * _DAMP_DOWN, damp * _DAMP_UP)
        if np.abs(step).max(initial=0.0) < tol:  # refused steps count: they shrink
            break
    return mean + sd * z, m


def posterior_variance(fm, y, calib, root_w, mean, sd, theta, *, free):
    """Laplace approximation of each unknown's posterior variance at the mode ``theta``.

    Returns ``(var, edf)``: sd^2 diag((J^T J + I)^-1) in the units of ``mean`` (zero
    where not ``free``), (n, 1 + len(NUISANCES)), and each row's effective number of
    fitted parameters tr(J (J^T J + I)^-1 J^T) = p - tr((J^T J + I)^-1), (n,); J is the
    whitened residuals' Jacobian (Björck 1996, 9.1; Hastie et al. 2009, Eq. 3.50).
    """
    n, p = mean.shape
    idx = np.flatnonzero(free)
    z = (theta - mean) / sd
    r, _ = _residuals(fm, y, calib, root_w, mean, sd, z)
    J = np.empty((n, r.shape[1], len(idx)))
    for j, col in enumerate(idx):
        zp = z.copy()
        zp[:, col] += _STEP_SD
        J[:, :, j] = (_residuals(fm, y, calib, root_w, mean, sd, zp)[0] - r) / _STEP_SD
    A = np.einsum("nki,nkj->nij", J, J) + np.eye(len(idx))
    diag = np.diagonal(np.linalg.inv(A), axis1=1, axis2=2)
    out = np.zeros((n, p))
    out[:, idx] = diag * sd[:, idx] ** 2
    return out, len(idx) - diag.sum(axis=1)


def model_jacobian(fm, theta, sd):
    """Forward-difference Jacobian of the model's log ratio at ``theta``, unwhitened.

    Parameters
    ----------
    fm : ForwardModel
        The assumed forward model.
    theta : numpy.ndarray
        (n, 1 + len(NUISANCES)) glucose [mg/dL] then the nuisances in their units.
    sd : numpy.ndarray
        (n, 1 + len(NUISANCES)) scale of each unknown: the step is ``1e-4 sd`` (the
        solver's step in prior standard deviations). [units of ``theta``]

    Returns
    -------
    numpy.ndarray
        (n, k, 1 + len(NUISANCES)) d ln(adc / adc_ref) / d theta. [1/units of ``theta``]
    """
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        m0 = fm.log_ratio(theta[:, 0], theta[:, 1:])
        J = np.empty((*m0.shape, theta.shape[1]))
        for col in range(theta.shape[1]):
            h = _STEP_SD * sd[:, col]
            tp = theta.copy()
            tp[:, col] += h
            J[:, :, col] = (fm.log_ratio(tp[:, 0], tp[:, 1:]) - m0) / h[:, None]
    return J
