"""Compiled measurement layer: each measured column, and the PPG front end, in one pass.

:func:`nirglucose.simulation.measurement.measure_physiology` forms each measured column
as truth + f sd z clipped to the instrument's range (three NumPy passes a column, the
clip through NumPy's Python wrapper), :func:`~nirglucose.simulation.measurement.measure_ppg`
perfusion and saturation in about eight passes with one ``exp``. :func:`measured_row`
and :func:`ppg` do the same operations, in the same order per value, in one compiled
pass: + x are IEEE 754 basic operations, ``exp`` the C library's through :mod:`math`
(what :mod:`nirglucose.portable` calls), the clip and minimum NumPy's own comparisons
(NaN passed through), and numba neither fuses a multiply-add nor reorders without
``fastmath``; so the values equal the NumPy reference's bit for bit (a test holds them
so). The physics lives in :mod:`nirglucose.simulation.measurement`, which stays the
reference; the caller makes the draws and forms the scalar factors.
"""

from __future__ import annotations

import math

from numba import njit

__all__ = ["clip", "measured_row", "ppg"]


@njit(cache=True, inline="always")
def clip(x, lo, hi):
    """``np.clip(x, lo, hi)`` of one float: ``lo`` only below it, then ``hi`` only above
    it, NaN passed through (so ``x`` kept where it equals a limit: np.clip(-0.0, 0.0,
    1.0) is -0.0; a test holds it equal to np.clip, signed zeros and NaN included)."""
    if not math.isnan(x):
        x = lo if x < lo else x
    if not math.isnan(x):
        x = hi if x > hi else x
    return x


@njit(cache=True, nogil=True, error_model="numpy")
def measured_row(value, scale, truth, lo, hi):  # pragma: no cover - compiled
    """``value`` (the draws z) in place: clip(z x scale + truth, lo, hi)."""
    for i in range(value.shape[0]):
        v = value[i] * scale
        v += truth[i]
        value[i] = clip(v, lo, hi)


@njit(cache=True, nogil=True, error_model="numpy")
def ppg(blood_fraction, saturation, z, a, b, blood_out, spo2_out):  # pragma: no cover
    """min(100 f_b exp(a z0), 100) into ``blood_out``, clip(100 S + b z1, 0, 100) into
    ``spo2_out``; ``z`` (2, n) the draws."""
    for i in range(blood_out.shape[0]):
        v = 100.0 * blood_fraction[i] * math.exp(a * z[0, i])
        # np.minimum: the first if it is smaller or NaN
        blood_out[i] = v if (v < 100.0 or math.isnan(v)) else 100.0
        spo2_out[i] = clip(100.0 * saturation[i] + b * z[1, i], 0.0, 100.0)
