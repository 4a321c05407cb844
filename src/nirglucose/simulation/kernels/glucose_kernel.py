"""Compiled glucose of each snapshot: one pass instead of about twenty.

:func:`nirglucose.simulation.glucose.sample_glucose` sums each snapshot's fasting
baseline, postprandial excursion, stress rise and dawn rise and reflects the sum into the
reported range as about twenty NumPy passes (and gathers by status). :func:`snapshots`
does the same operations, in the same order per value, in one compiled pass: + - x / are
IEEE 754 basic operations, ``exp`` the C library's through :mod:`math` (what
:mod:`nirglucose.portable` calls), NumPy's ``mod`` is ``fmod`` (exact) moved to the
divisor's sign, and numba neither fuses a multiply-add nor reorders without
``fastmath``; so the values equal the NumPy reference's bit for bit (a test holds them so).
The physics and its sources live in :mod:`nirglucose.simulation.glucose`, which stays the
reference; the caller makes the draws.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

__all__ = ["snapshots"]


@njit(cache=True, inline="always")
def _mod(a, b):
    """``np.mod(a, b)`` for b > 0: fmod (IEEE 754 remainder toward zero, exact, so the
    same bits from any correct implementation; numba's is LLVM's ``frem``), moved to
    b's sign (NumPy's ``npy_remainder``), a zero as +0.0."""
    m = np.fmod(a, b)
    if m != 0.0:
        if m < 0.0:
            m += b
    else:
        m = 0.0
    return m


@njit(cache=True, nogil=True, error_model="numpy")
def snapshots(baseline, status, subject, peak, dawn, hours_since_meal, meal_size, stressed,
              stress_u, hour, k, out):  # pragma: no cover - compiled
    """Each snapshot's glucose into ``out`` (n,) [mg/dL].

    ``baseline`` (n_sub,) and ``status`` (n_sub,) per subject, ``subject`` (n,) each
    snapshot's subject; ``peak``, ``dawn``: the meal peak and dawn rise per status; the
    draws per snapshot; ``k``: meal peak time, dawn peak hour and width, range low, high.
    """
    peak_h, dawn_hour, dawn_width, low, high = k
    width = high - low
    two_width = 2.0 * width
    for i in range(out.shape[0]):
        s = subject[i]
        st = status[s]
        x = hours_since_meal[i] / peak_h
        excursion = x * math.exp(1.0 - x)
        d = (hour[i] - dawn_hour) / dawn_width
        rise = stress_u[i] if stressed[i] else 0.0
        raw = (baseline[s] + peak[st] * meal_size[i] * excursion + rise
               + dawn[st] * math.exp(-(d * d)))
        y = _mod(raw - low, two_width)
        out[i] = low + (two_width - y if y > width else y)
