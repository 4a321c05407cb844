"""Compiled contact layer: coupling, blanched blood and compressed skin in one pass.

:func:`nirglucose.simulation.contact.apply_contact` computes the humidity's position in
its range, the optical coupling exp(a z - b w), the blanched blood f_b exp(c p) and the
compressed thickness d exp(e p) as about a dozen NumPy passes with three ``exp``.
:func:`contact` does the same operations, in the same order per value, in one compiled
pass: + - x / are IEEE 754 basic operations, ``exp`` the C library's through
:mod:`math` (what :mod:`nirglucose.portable` calls), and numba neither fuses a
multiply-add nor reorders without ``fastmath``; so the values equal the NumPy
reference's bit for bit (a test holds them so). The physics and its sources live in
:mod:`nirglucose.simulation.contact`, which stays the reference; the caller makes the
draws and forms the scalar factors as the reference does.
"""

from __future__ import annotations

import math

from numba import njit

__all__ = ["contact"]


@njit(cache=True, nogil=True, error_model="numpy")
def contact(pressure, coupling_z, humidity, measured_humidity, blood, thickness, k,
            compensate, coupling, blood_out, thickness_out):  # pragma: no cover - compiled
    """The contact layer's outputs into ``coupling``, ``blood_out``, ``thickness_out``.

    ``k``: the RH range's low end and width, the coupling's a and b (exp(a z - b w)),
    the blanching's and the compression's exponent factors (exp(c p), exp(e p));
    ``compensate``: subtract the measured humidity's position (``measured_humidity``).
    """
    lo, width, a, b, c, e = k
    for i in range(pressure.shape[0]):
        w = (humidity[i] - lo) / width
        if compensate:
            w = w - (measured_humidity[i] - lo) / width
        coupling[i] = math.exp(a * coupling_z[i] - b * w)
        p = pressure[i]
        blood_out[i] = blood[i] * math.exp(c * p)
        thickness_out[i] = thickness[i] * math.exp(e * p)
