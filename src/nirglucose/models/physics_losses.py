"""Physics residuals of the PINNs as pure loss functions.

Each function maps tensors to a scalar tensor (differentiable) and holds no state: the
estimators in :mod:`nirglucose.models.pinn` add them to the data loss in their
``get_loss`` override. Every loss is zero exactly when its relation holds and positive
otherwise.

* :func:`beer_lambert_loss` — the Original and Optimized PINNs' residual
  ``A(lambda) - eps(lambda) c l`` (study's form) [1]_.
* :func:`diffusion_absorbance` / :func:`diffusion_reflectance_loss` — the RTE PINNs'
  tie between predicted optical properties and measured absorbance through the
  Farrell-Patterson-Wilson dipole reflectance, the same function the simulator's
  'diffusion' forward model evaluates [2]_.
* :func:`scattering_prior_loss` — the RTE PINNs' stability term: ``mus'`` near the
  Jacques (2013) power law [3]_.
* :func:`forward_likelihood_loss` — the Beer-Lambert PINNs' ``'forward'`` term: the
  negative log-likelihood of the measured log ratios given the predicted glucose under
  the package's forward model, nuisances marginalised (Laplace) [4]_.
* :func:`state_mode_loss` — the RTE PINNs' ``'forward'`` state term: predicted tissue
  state against each reading's posterior mode under the forward model [4]_.

References
----------
.. [1] R. Gani, "Physics-Informed Neural Networks vs. Physics Models for Non-Invasive
   Glucose Monitoring: A Comparative Study Under Noise-Stressed Synthetic Conditions",
   University College London (the reference study).
.. [2] T. J. Farrell, M. S. Patterson and B. Wilson, "A diffusion theory model of
   spatially resolved, steady-state diffuse reflectance for the noninvasive
   determination of tissue optical properties in vivo", Med. Phys. 19, 879-888 (1992).
   :doi:`10.1118/1.596777`
.. [3] S. L. Jacques, "Optical properties of biological tissues: a review",
   Phys. Med. Biol. 58, R37-R61 (2013). :doi:`10.1088/0031-9155/58/11/R37`
.. [4] C. M. Bishop, "Pattern Recognition and Machine Learning", Springer (2006),
   sec. 4.4 (the Laplace approximation) and 2.3.3 (linear-Gaussian marginals).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
import torch
from numpy.typing import ArrayLike

from ..constants import MGDL_PER_MMOLL_GLUCOSE
from ..optics.absorption import glucose_mua_per_cm_per_mm
from ..optics.diffusion import farrell_reflectance

__all__ = [
    "glucose_absorptivity_per_cm_per_mgdl",
    "beer_lambert_residual",
    "beer_lambert_loss",
    "diffusion_absorbance",
    "diffusion_reflectance_loss",
    "scattering_prior_loss",
    "forward_likelihood_loss",
    "state_mode_loss",
]

_LN10 = math.log(10.0)


def glucose_absorptivity_per_cm_per_mgdl(
    wavelength_nm: ArrayLike,
    peak_per_cm_per_mm: float = 1.0e-4,
    signal_gain: float = 1.0,
) -> np.ndarray:
    r"""Decadic absorptivity of glucose per mg/dL, as the simulator models it.

    Parameters
    ----------
    wavelength_nm : array_like
        Wavelengths, 700-1700. [nm]
    peak_per_cm_per_mm : float
        Natural-log absorption at the 2nd C-H overtone peak per mM
        (``glucose.absorptivity_per_cm_per_mm`` of the scenario). [1/(cm mM)]
    signal_gain : float
        The scenario's ``glucose.signal_gain`` (the ``paper`` preset's value is
        :data:`nirglucose.config.PAPER_SIGNAL_GAIN`), which the simulator applies to
        glucose's optical effects. [-]

    Returns
    -------
    numpy.ndarray
        :math:`\varepsilon(\lambda)`, decadic absorbance per cm of path per mg/dL.
        [1/(cm mg/dL)]

    Notes
    -----
    .. math::

        \varepsilon(\lambda) = \frac{g\,\mu_{a,\mathrm{glc}}(\lambda)}
                                    {\ln 10 \cdot 18.016\ \mathrm{mg/dL\,per\,mM}}

    with :math:`\mu_{a,\mathrm{glc}}` from
    :func:`~nirglucose.optics.absorption.glucose_mua_per_cm_per_mm` (natural log, per mM)
    and :math:`g` the signal gain: the simulator multiplies glucose in mM by :math:`g`
    before it enters the tissue optics, and absorbance here is decadic
    (:math:`A = \log_{10} I_0/I`, DESIGN.md).

    Examples
    --------
    >>> from nirglucose.config import PAPER_SIGNAL_GAIN
    >>> eps = glucose_absorptivity_per_cm_per_mgdl([1150.0], 1e-4, PAPER_SIGNAL_GAIN)
    >>> float(eps[0]) > 0
    True
    """
    mua = glucose_mua_per_cm_per_mm(wavelength_nm, peak_per_cm_per_mm)
    return signal_gain * mua / (_LN10 * MGDL_PER_MMOLL_GLUCOSE)


def beer_lambert_residual(
    absorbance: torch.Tensor,
    glucose_mgdl: torch.Tensor,
    absorptivity_per_cm_per_mgdl: torch.Tensor,
    pathlength_cm: float = 1.0,
    *,
    absorbance_ref: torch.Tensor | float = 0.0,
    glucose_ref_mgdl: torch.Tensor | float = 0.0,
) -> torch.Tensor:
    r"""Beer-Lambert residual per sample and wavelength.

    Parameters
    ----------
    absorbance : torch.Tensor
        Measured decadic absorbance :math:`\log_{10}(I_0/I)`, (n, k). [-]
    glucose_mgdl : torch.Tensor
        Predicted glucose, (n,). [mg/dL]
    absorptivity_per_cm_per_mgdl : torch.Tensor
        :math:`\varepsilon(\lambda)`, (k,). [1/(cm mg/dL)]
    pathlength_cm : float
        Optical path :math:`l` (the study takes 1). [cm]
    absorbance_ref, glucose_ref_mgdl : torch.Tensor or float
        Reference absorbance (k,) and glucose subtracted from both sides (the
        differential form); 0 gives the study's absolute form. [-], [mg/dL]

    Returns
    -------
    torch.Tensor
        :math:`(A_\lambda - A_\mathrm{ref}) - \varepsilon(\lambda)(\hat c - c_\mathrm{ref})\,l`,
        (n, k). [-]
    """
    dc = (glucose_mgdl - glucose_ref_mgdl).unsqueeze(-1)
    return (absorbance - absorbance_ref) - absorptivity_per_cm_per_mgdl * dc * pathlength_cm


def beer_lambert_loss(
    absorbance: torch.Tensor,
    glucose_mgdl: torch.Tensor,
    absorptivity_per_cm_per_mgdl: torch.Tensor,
    pathlength_cm: float = 1.0,
    *,
    absorbance_ref: torch.Tensor | float = 0.0,
    glucose_ref_mgdl: torch.Tensor | float = 0.0,
) -> torch.Tensor:
    r"""The study's physics loss: mean over samples of :math:`\sum_\lambda r_\lambda^2`.

    Parameters
    ----------
    absorbance, glucose_mgdl, absorptivity_per_cm_per_mgdl, pathlength_cm,
    absorbance_ref, glucose_ref_mgdl
        As in :func:`beer_lambert_residual`.

    Returns
    -------
    torch.Tensor
        Scalar :math:`\frac1n\sum_i\sum_\lambda |\log(I_0/I_\lambda) -
        \varepsilon(\lambda)\hat c_i l|^2`; zero iff every residual is zero. [-]

    Examples
    --------
    >>> import torch
    >>> eps = torch.tensor([1e-4, 2e-4])
    >>> c = torch.tensor([100.0, 200.0])
    >>> a = eps * c[:, None]
    >>> float(beer_lambert_loss(a, c, eps))
    0.0
    """
    r = beer_lambert_residual(
        absorbance,
        glucose_mgdl,
        absorptivity_per_cm_per_mgdl,
        pathlength_cm,
        absorbance_ref=absorbance_ref,
        glucose_ref_mgdl=glucose_ref_mgdl,
    )
    return (r * r).sum(dim=-1).mean()


def diffusion_absorbance(
    mua_per_cm: torch.Tensor,
    musp_per_cm: torch.Tensor,
    offset: torch.Tensor | float,
    *,
    rho_cm: float,
    detector_area_cm2: float,
    n_tissue: float = 1.4,
) -> torch.Tensor:
    r"""Absorbance the diffusion model predicts from optical properties.

    Parameters
    ----------
    mua_per_cm, musp_per_cm : torch.Tensor
        Absorption and reduced scattering coefficients, (n, k), positive. [1/cm]
    offset : torch.Tensor or float
        Per-wavelength instrument constant :math:`b_\lambda`, (k,): the log ratio of
        reference to source power and gains that the absorbance also contains. [-]
    rho_cm : float
        Source-detector separation. [cm]
    detector_area_cm2 : float
        Photodiode area. [cm^2]
    n_tissue : float
        Tissue refractive index. [-]

    Returns
    -------
    torch.Tensor
        :math:`A = -\log_{10}[R(\rho;\mu_a,\mu_s')\,A_\mathrm{det}] + b_\lambda`,
        (n, k). [-]

    Notes
    -----
    :math:`R` is :func:`~nirglucose.optics.diffusion.farrell_reflectance` (Farrell et
    al. 1992 [2]_), evaluated on tensors so gradients flow to the optical-property
    heads; the simulator's 'diffusion' forward model uses the same function. Range
    checks are off (``validate=False``): the heads' softplus keeps the inputs positive.
    """
    r = farrell_reflectance(rho_cm, mua_per_cm, musp_per_cm, n_tissue, validate=False)
    return -torch.log10(r * detector_area_cm2) + offset


def diffusion_reflectance_loss(
    absorbance: torch.Tensor,
    mua_per_cm: torch.Tensor,
    musp_per_cm: torch.Tensor,
    offset: torch.Tensor | float,
    *,
    rho_cm: float,
    detector_area_cm2: float,
    n_tissue: float = 1.4,
    scale: torch.Tensor | float = 1.0,
) -> torch.Tensor:
    r"""Light-transport residual of the RTE PINNs: measured vs diffusion absorbance.

    Parameters
    ----------
    absorbance : torch.Tensor
        Measured decadic absorbance at the regularised wavelengths, (n, k). [-]
    mua_per_cm, musp_per_cm, offset, rho_cm, detector_area_cm2, n_tissue
        As in :func:`diffusion_absorbance`.
    scale : torch.Tensor or float
        Divides each wavelength's residual, (k,) (e.g. the training spread of the
        absorbance, so every wavelength weighs alike). [-]

    Returns
    -------
    torch.Tensor
        Scalar :math:`\frac1n\sum_i\sum_\lambda [(A_{i\lambda} - \hat A_{i\lambda})/s_\lambda]^2`;
        zero iff the predicted optics reproduce every absorbance. [-]
    """
    pred = diffusion_absorbance(
        mua_per_cm,
        musp_per_cm,
        offset,
        rho_cm=rho_cm,
        detector_area_cm2=detector_area_cm2,
        n_tissue=n_tissue,
    )
    r = (absorbance - pred) / scale
    return (r * r).sum(dim=-1).mean()


def scattering_prior_loss(
    musp_per_cm: torch.Tensor,
    prior_musp_per_cm: torch.Tensor | Sequence[float],
) -> torch.Tensor:
    r"""Stability term: squared log distance of :math:`\mu_s'` from its prior.

    Parameters
    ----------
    musp_per_cm : torch.Tensor
        Predicted reduced scattering, (n, k), positive. [1/cm]
    prior_musp_per_cm : torch.Tensor or sequence of float
        Prior at the same wavelengths, (k,), e.g. the Jacques (2013) power law
        :math:`a(\lambda/500\,\mathrm{nm})^{-b}` for skin [3]_. [1/cm]

    Returns
    -------
    torch.Tensor
        Scalar :math:`\frac1n\sum_i\sum_\lambda [\ln\mu'_{s,i\lambda} -
        \ln\mu'_{s,\mathrm{prior},\lambda}]^2`; zero iff every prediction equals the
        prior. [-]

    Notes
    -----
    One absorbance per wavelength cannot determine both :math:`\mu_a` and
    :math:`\mu_s'`; the prior removes that degeneracy and keeps the scattering
    spectrum smooth (a power law has no jumps between neighbouring LEDs).
    """
    prior = torch.as_tensor(prior_musp_per_cm, dtype=musp_per_cm.dtype, device=musp_per_cm.device)
    d = torch.log(musp_per_cm) - torch.log(prior)
    return (d * d).sum(dim=-1).mean()


def forward_likelihood_loss(
    glucose_mgdl: torch.Tensor,
    likelihood_mode_mgdl: torch.Tensor,
    information_per_mgdl2: torch.Tensor,
) -> torch.Tensor:
    r"""Forward-model term: the readings' negative log-likelihood at the predicted glucose.

    Parameters
    ----------
    glucose_mgdl : torch.Tensor
        Predicted glucose :math:`\hat c_i`, (n,). [mg/dL]
    likelihood_mode_mgdl : torch.Tensor
        Mode :math:`\hat g_i` of each reading's glucose likelihood under the forward
        model, (n,) (:meth:`~nirglucose.models.inversion.PhysicsInversion.glucose_likelihood`).
        [mg/dL]
    information_per_mgdl2 : torch.Tensor
        Its curvature :math:`w_i = J_g^T\Sigma_i^{-1}J_g`, (n,), >= 0. [1/(mg/dL)^2]

    Returns
    -------
    torch.Tensor
        Scalar :math:`\frac1n\sum_i w_i(\hat c_i - \hat g_i)^2`; zero iff every
        prediction with :math:`w_i > 0` is its likelihood's mode. [-]

    Notes
    -----
    With the forward model linearised in glucose and the nuisances marginalised under
    their prior (Laplace [4]_), the measured log ratios :math:`y_i` of a reading are
    Gaussian, :math:`y_i \sim N(\bar y_i + J_{g,i}(c - c_{0,i}), \Sigma_i)`, and

    .. math::

        r_i^T\Sigma_i^{-1}r_i - \min_c r_i^T\Sigma_i^{-1}r_i = w_i(c - \hat g_i)^2,
        \qquad r_i = y_i - \bar y_i - J_{g,i}(c - c_{0,i}),

    so this loss is :math:`-2\ln p(y_i \mid \hat c_i)` averaged over readings, less
    its minimum (a constant: the gradients are those of the likelihood). Each reading
    weighs by how much its absorbances say about glucose: little on a device whose
    nuisances swamp glucose's signal.

    Examples
    --------
    >>> import torch
    >>> g = torch.tensor([100.0, 150.0])
    >>> float(forward_likelihood_loss(g, g, torch.tensor([0.5, 0.1])))
    0.0
    >>> float(forward_likelihood_loss(g + 2.0, g, torch.tensor([0.5, 0.1])))
    1.2000000476837158
    """
    d = glucose_mgdl - likelihood_mode_mgdl
    return (information_per_mgdl2 * d * d).mean()



def state_mode_loss(
    state: torch.Tensor, mode: torch.Tensor, scale: torch.Tensor
) -> torch.Tensor:
    r"""Distance of predicted tissue state from the forward model's posterior mode.

    Parameters
    ----------
    state : torch.Tensor
        (n, p) predicted nuisances (their units).
    mode : torch.Tensor
        (n, p) each reading's posterior mode under the forward model at its reference
        glucose (:meth:`~nirglucose.models.inversion.PhysicsInversion.linearise`).
        [units]
    scale : torch.Tensor
        (p,) the modes' training spread. [units]

    Returns
    -------
    torch.Tensor
        Scalar :math:`\frac{1}{np}\sum_{i,j}[(\hat\theta_{ij} - \theta^*_{ij})/\sigma_j]^2`;
        zero iff every prediction is its mode. [-]

    Notes
    -----
    The reading's negative log-posterior, linearised at its mode, is the quadratic
    :math:`(\hat\theta - \theta^*)^T H (\hat\theta - \theta^*)` with H the posterior
    precision [4]_. This keeps its minimiser and weighs departures by the population's
    spread instead of H: on a quiet device H is thousands of times larger, no network
    matches a per-reading mode to that precision, and the term would swamp the MSE at
    any weight.

    Examples
    --------
    >>> import torch
    >>> m = torch.tensor([[0.02, 0.7]])
    >>> float(state_mode_loss(m, m, torch.tensor([0.01, 0.05])))
    0.0
    >>> float(state_mode_loss(m + torch.tensor([[0.01, 0.0]]), m, torch.tensor([0.01, 0.05])))
    0.5
    """
    d = (state - mode) / scale
    return (d * d).mean()
