"""The forward model seen by the physics inversion, and its batched MAP solver.

:class:`ForwardModel` evaluates the noise-free log ratio ln(fraction / T_ref) of each
reading for any glucose and any tissue and probe state (the simulator's optics through
its band integral, :mod:`nirglucose.optics.forward`), with the forward model chosen by
name. :func:`map_estimate` minimises, for all rows at once,

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

from ..config import ScenarioConfig
from ..constants import MGDL_PER_MMOLL_GLUCOSE
from ..optics import tissue
from ..optics.forward import FORWARD_MODELS
from ..simulation.simulator import _band_detected_fraction, _tables

__all__ = [
    "NUISANCES", "PHYSICAL_BOUNDS", "ForwardModel", "map_estimate", "posterior_variance",
    "model_jacobian",
]

#: The unknowns besides glucose, in column order: ln of the detected dermal blood
#: fraction, saturation, dermal water fraction, subcutis fat fraction, epidermal
#: melanosome fraction, skin thickness under the probe [mm], the LEDs' common thermal
#: peak shift [nm], ln of the optical coupling.
NUISANCES = (
    "log_blood_fraction",
    "saturation",
    "water_fraction",
    "subcutis_fat_fraction",
    "melanin_fraction",
    "skin_thickness_mm",
    "led_shift_nm",
    "log_coupling",
)
#: Where the forward model is evaluated, per unknown: volume fractions inside (0, 1),
#: a thickness inside the configured skin range's order of magnitude (0.1-10 mm), LED
#: shifts within +/- 30 nm (a 100 degC swing at the datasheets' 0.3 nm/degC). The
#: estimate itself is never clipped; only the model's argument is.
PHYSICAL_BOUNDS = {
    "log_blood_fraction": (np.log(1e-4), np.log(0.5)),
    "saturation": (0.01, 0.999),
    "water_fraction": (0.05, 0.95),
    "subcutis_fat_fraction": (0.05, 0.95),
    "melanin_fraction": (0.0, 0.6),
    "skin_thickness_mm": (0.1, 10.0),
    "led_shift_nm": (-30.0, 30.0),
    "log_coupling": (-2.0, 2.0),
}
#: Forward-difference step of the Jacobian, in prior standard deviations. [-]
_STEP_SD = 1e-4
#: Levenberg-Marquardt damping: start, growth on a refused step, shrink on an accepted
#: one (Marquardt 1963's factor 10).
_DAMP_START, _DAMP_UP, _DAMP_DOWN = 1e-3, 10.0, 0.1


class ForwardModel:
    """ln(fraction / T_ref) per LED for given glucose and nuisance state.

    Parameters
    ----------
    cfg : ScenarioConfig
        The device and optics (LED bands, geometry, tables, glucose's optical signal).
    model : str
        The forward model assumed, one of :data:`nirglucose.optics.forward.FORWARD_MODELS`
        (may differ from the one that made the data).
    """

    def __init__(self, cfg: ScenarioConfig, model: str):
        if model not in FORWARD_MODELS:
            raise ValueError(f"unknown forward model {model!r}")
        optics = cfg.optics.model_copy(update={"model": model})
        self.cfg = cfg.model_copy(update={"optics": optics})
        self.tables = _tables(self.cfg)

    def log_ratio(self, glucose_mgdl: np.ndarray, theta: np.ndarray) -> np.ndarray:
        """(n, n_led) noise-free ln(adc / adc_ref) at glucose [mg/dL] and ``theta``
        ((n, len(NUISANCES)), columns as :data:`NUISANCES`)."""
        cfg = self.cfg
        th = _clip_physical(theta)
        state = tissue.TissueState(
            np.exp(th[:, 0]),
            th[:, 1],
            th[:, 2],
            th[:, 3],
            cfg.glucose.signal_gain * np.asarray(glucose_mgdl, float) / MGDL_PER_MMOLL_GLUCOSE,
        )
        n_led = len(cfg.leds.wavelengths_nm)
        shift = np.repeat(th[:, 6:7], n_led, axis=1)
        frac = _band_detected_fraction(cfg, self.tables, state, th[:, 4], th[:, 5], shift)
        return np.log(frac / cfg.hardware.reference_transmission) + th[:, 7:8]


def _clip_physical(theta: np.ndarray) -> np.ndarray:
    lo = np.array([PHYSICAL_BOUNDS[k][0] for k in NUISANCES])
    hi = np.array([PHYSICAL_BOUNDS[k][1] for k in NUISANCES])
    return np.clip(theta, lo, hi)


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
