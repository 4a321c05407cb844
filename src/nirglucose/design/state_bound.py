"""The per-state bound: glucose's posterior error of a design linearised at each state.

:func:`~nirglucose.design.bound.design_bound`'s ``"device"`` condition is the Bayesian
(van Trees) bound [1]_ with the Fisher information averaged over the population's
states, ``[(E F + P)^-1]_gg``. It is a valid lower bound, but where one state's
information F(theta) has lower rank than the unknowns (fewer LEDs than glucose plus the
eight nuisances), averaging F over states of different Jacobians fills in the missing
directions: the average credits the device with information from states it is not in.
At published glucose magnitudes (preset ``physical``) this makes it uninformative: one
LED at 850 nm with a monitor photodiode, a 16-bit ADC and 4,096 readings averaged has a
van Trees bound of 0.5 mg/dL, although one reading of one LED cannot separate glucose
from eight unknown nuisances (tests/design/test_state_bound.py shows it).

This module gives the error of the Bayesian estimator of the model linearised at each
state, averaged over states:

    MSE = E_theta [ ((F(theta) + P)^-1)_gg ],    F = J^T S^-1 J,

with the same Jacobians J, noise covariance S, glucose prior and nuisance prior P as
the van Trees bound (:class:`~nirglucose.design.bound.DesignTerms`). For each state it
is the exact posterior variance of glucose of the locally linear Gaussian model, so it
is what a Gauss-Newton or MAP inversion whose linearisation is right reaches; by
Jensen's inequality for the matrix inverse it is never below the van Trees bound. It is
not a strict lower bound of the nonlinear problem (an estimator might exploit the
Jacobian's change within the prior's spread; van Trees & Bell [1]_ discuss this
"expected" form of the CRB), but it does not credit a state with other states'
information. The oracle condition of :mod:`~nirglucose.design.bound` is the same
per-state form with the nuisances known.

References
----------
.. [1] H. L. Van Trees, K. L. Bell, "Bayesian Bounds for Parameter Estimation and
   Nonlinear Filtering/Tracking", Wiley-IEEE (2007), ch. 1 (the Bayesian CRB and the
   expected CRB).
.. [2] S. M. Kay, "Fundamentals of Statistical Signal Processing, Vol. I: Estimation
   Theory", Prentice Hall (1993), ch. 10-11 (the posterior covariance of the Bayesian
   linear model).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from ..exceptions import ConfigError
from .bound import DesignTerms

__all__ = ["state_bound", "state_bounds"]

#: Subsets evaluated together (memory: n_states x batch x p^2 doubles, about 40 MB at
#: 256 states). [-]
_BATCH = 256


def _incidence(subsets, n_led: int) -> np.ndarray:
    """(n_subsets, n_led) 0/1 matrix of LED subsets (rows may differ in size)."""
    rows = [np.asarray(list(s), dtype=int) for s in subsets]
    if not rows:
        raise ConfigError("give at least one LED subset")
    out = np.zeros((len(rows), n_led))
    for i, r in enumerate(rows):
        if r.size == 0 or r.min() < 0 or r.max() >= n_led or len(set(r.tolist())) != r.size:
            raise ConfigError(f"LED subsets must be non-empty distinct indices into the "
                              f"{n_led} LEDs of the set, got {r.tolist()}")
        out[i, r] = 1.0
    return out


def state_bounds(terms: DesignTerms, subsets: Sequence[Sequence[int]], *,
                 prior: bool = True) -> np.ndarray:
    """The per-state bound of many LED subsets of one set of terms.

    Parameters
    ----------
    terms : DesignTerms
        Jacobians, noise and priors of the candidate LEDs
        (:func:`~nirglucose.design.design_terms`).
    subsets : sequence of sequence of int
        Each row one design: indices into the candidate LEDs (rows may differ in size).
    prior : bool
        Include the Gaussian glucose prior (without it a design with no information
        has an infinite bound).

    Returns
    -------
    numpy.ndarray
        (n_subsets,) root mean over states of glucose's linearised posterior variance.
        [mg/dL]

    Notes
    -----
    Per state, with S = D + c 1 1^T (independent variances D, common variance c),
    F = sum_k w_k J_k J_k^T - c u u^T / (1 + c sum_k w_k), w = 1 / D, u = sum_k w_k J_k
    (Sherman-Morrison, as :func:`~nirglucose.design.search.subset_bounds`); a saturated
    channel keeps its variance with a zero Jacobian row (as the bound). Then
    ((F + P)^-1)_gg solved per state, P = diag(1 / var g, Sigma_theta^-1).
    """
    n, n_led, p = terms.jacobian.shape
    m = _incidence(subsets, n_led)
    jac = np.where(terms.saturated[:, :, None], 0.0, terms.jacobian)
    with np.errstate(divide="ignore"):
        w = np.where(np.isfinite(terms.noise_var), 1.0 / terms.noise_var, 0.0)
    wj = w[:, :, None] * jac
    outer = np.einsum("nlp,nlq->nlpq", wj, jac).reshape(n, n_led, p * p)  # w J J^T
    prec = np.zeros((p, p))
    prec[0, 0] = 1.0 / terms.glucose_var if prior else 0.0
    prec[1:, 1:] = np.linalg.inv(terms.nuisance_cov)
    c = terms.common_var
    e0 = np.zeros(p)
    e0[0] = 1.0
    out = np.empty(len(m))
    for start in range(0, len(m), _BATCH):
        mb = m[start:start + _BATCH]
        info = np.matmul(mb, outer).reshape(n, len(mb), p, p) + prec
        if c > 0:
            u = np.matmul(mb, wj)  # (n, B, p)
            s = w @ mb.T  # (n, B)
            info -= (c / (1.0 + c * s))[:, :, None, None] * u[:, :, :, None] * u[:, :, None, :]
        try:
            var_g = np.linalg.solve(info, np.broadcast_to(e0, info.shape[:-1])[..., None])
            var_g = var_g[..., 0, 0]
        except np.linalg.LinAlgError:
            var_g = np.full(info.shape[:2], np.inf)
        out[start:start + len(mb)] = np.sqrt(np.mean(var_g, axis=0))
    return out


def state_bound(terms: DesignTerms, leds: Sequence[int] | None = None, *,
                prior: bool = True) -> float:
    """The per-state bound of one LED subset (all LEDs when ``leds`` is None). [mg/dL]

    Examples
    --------
    >>> from nirglucose.design import design_terms
    >>> t = design_terms("paper", n_states=32)
    >>> bool(state_bound(t) >= t.bound().rmse_mgdl)  # never below van Trees
    True
    """
    n_led = terms.jacobian.shape[1]
    idx = list(range(n_led)) if leds is None else list(leds)
    return float(state_bounds(terms, [idx], prior=prior)[0])
