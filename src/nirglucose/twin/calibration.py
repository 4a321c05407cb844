"""Simulation-based calibration of a twin's posterior estimator.

Talts et al. (arXiv:1804.06788, 2018): draw parameters from the prior, simulate a device
with each, and ask the posterior estimator for the posterior of each simulated device.
For a calibrated posterior the rank of the true value among the posterior draws is
uniform, and a central 90 % interval covers the truth 90 % of the time. The devices here
have seeds apart from the training simulations' (:func:`calibrate`).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .device import TwinDevice
from .inference import PosteriorEstimator
from .parameters import IDENTIFIED_WIDTH_RATIO, Parameter
from .simulate import device_seeds, simulate_summaries

__all__ = ["calibrate", "COVERAGE_TARGET", "COVERAGE_BAND"]

#: The interval whose coverage is checked, and the band its coverage must lie in.
COVERAGE_TARGET = 0.9
COVERAGE_BAND = (0.85, 0.95)
#: Seed offset of the calibration devices (apart from the training simulations').
_SEED_OFFSET = 1_000_003


def calibrate(device: TwinDevice, params: list[Parameter], est: PosteriorEstimator, *,
              n_devices: int = 100, n_draws: int = 500, seed: int = 0,
              n_jobs: int = 1) -> dict[str, Any]:
    """SBC over ``n_devices`` synthetic devices with known parameters.

    Returns
    -------
    dict
        Per parameter key: ``coverage`` of the central 90 % interval, ``identified_share``
        (devices on which it was identified, :data:`~.parameters.IDENTIFIED_WIDTH_RATIO`),
        ``identified`` (in most devices), ``meets_band`` (coverage within
        :data:`COVERAGE_BAND`), ``ranks`` (rank of the truth among ``n_draws`` draws, per
        device); and ``n_devices``, ``n_draws``.
    """
    bounds = np.array([p.fit_bounds for p in params])
    rng = np.random.default_rng(np.random.SeedSequence([seed, 4]))
    z_true = rng.uniform(bounds[:, 0], bounds[:, 1], size=(n_devices, len(params)))
    values = np.column_stack([p.from_fit(z_true[:, i]) for i, p in enumerate(params)])
    x = simulate_summaries(device, [p.key for p in params], values,
                           device_seeds(seed + _SEED_OFFSET, n_devices), n_jobs)
    ok = np.flatnonzero(np.isfinite(x).all(axis=1))
    half = (1.0 - COVERAGE_TARGET) / 2.0
    ranks, covered, identified = [], [], []
    for j in ok:
        z = est.sample(x[j], n_draws, seed + int(j))
        ranks.append((z < z_true[j]).sum(axis=0))
        lo, hi = np.quantile(z, [half, 1.0 - half], axis=0)
        covered.append((lo <= z_true[j]) & (z_true[j] <= hi))
        identified.append((hi - lo) / (COVERAGE_TARGET * (bounds[:, 1] - bounds[:, 0]))
                          < IDENTIFIED_WIDTH_RATIO)
    ranks, covered, identified = (np.asarray(a) for a in (ranks, covered, identified))
    out: dict[str, Any] = {"n_devices": int(len(ok)), "n_draws": int(n_draws),
                           "parameters": {}}
    for i, p in enumerate(params):
        cov = float(covered[:, i].mean())
        out["parameters"][p.key] = {
            "coverage": round(cov, 3),
            "identified_share": round(float(identified[:, i].mean()), 3),
            "identified": bool(identified[:, i].mean() > 0.5),
            "meets_band": bool(COVERAGE_BAND[0] <= cov <= COVERAGE_BAND[1]),
            "ranks": ranks[:, i].astype(int).tolist(),
        }
    return out
