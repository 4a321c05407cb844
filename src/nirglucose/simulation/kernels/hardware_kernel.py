"""Compiled hot path of the hardware layer: LED power to ADC codes in one pass.

:func:`nirglucose.simulation.hardware.apply_hardware` composes LED power, photocurrent,
dark current, ambient residual, shot and Johnson noise, the TIA and the converter (INL,
offset, rounding, saturation) as about 60 NumPy passes over (readings x LEDs) arrays.
This module does the same operations, in the same order per element, in one compiled
pass with no temporaries. Every step is an IEEE 754 basic operation (+ - x / sqrt,
correctly rounded: the same bits on every CPU) or the C library's ``exp`` / ``sin``
(``exp`` its algorithm inline, :func:`nirglucose.libm.exp1`; ``sin`` through
:mod:`math`, what :mod:`nirglucose.portable` calls), and numba neither fuses a
multiply-add nor reorders without ``fastmath``; so the codes, voltages and powers equal
the NumPy reference's bit for bit (a test holds them so). The physics, units and
citations live in :mod:`nirglucose.simulation.hardware`.

The random draws are made by the caller, in the reference's order, and passed in. The
kernels use numba's ``error_model="numpy"``: a division by zero gives inf or NaN, as in
NumPy (and the caller then raises), instead of raising inside the loop; so the loops
carry no check per value.
"""

from __future__ import annotations

import math
from collections import namedtuple

import numpy as np
from numba import njit

from ...libm import exp1

__all__ = ["FrontEnd", "convert", "reading_voltages", "reference_voltages"]

#: The scalars of the chain (each as the reference computes it; units of
#: :mod:`nirglucose.simulation.hardware`): the LED's thermal coefficient x its factor;
#: dark current at 25 degC [A] and its temperature coefficient [1/degC]; the factors of
#: the dark-current residual and the ambient light; the ambient share left after the
#: LED-off subtraction (1 - rejection); the shot-noise factor and 2 e [C]; the bandwidth
#: [Hz]; the Johnson factor, 4 k [J/K] and its resistance [Ohm]; the TIA gain [Ohm]; the
#: offset drift x its factor [LSB/degC]; the ADC's full-scale voltage [V], top code and
#: peak INL [LSB]; the reference path's transmission; whether read noise is added and
#: whether a monitor photodiode reads each pulse (1.0 or 0.0).
FrontEnd = namedtuple("FrontEnd", (
    "thermal", "i25", "dark_per_c", "f_dark", "f_ambient", "ambient_keep", "f_shot", "two_e",
    "bandwidth", "f_johnson", "four_k", "r_johnson", "gain", "offset_per_c", "vref", "full",
    "inl", "transmission", "read_noise", "monitor",
))

#: Reference temperature of the LED, dark-current and offset calibrations [degC] and
#: 0 degC in kelvin, as in :mod:`nirglucose.constants`.
_T_REF_C = 25.0
_ZERO_C_K = 273.15


@njit(cache=True, inline="always")
def _led_power(p0, thermal, ageing, led_c, age_h, flicker):
    """:func:`~nirglucose.simulation.hardware.led_power_w`. [W]"""
    return p0 * (1.0 - thermal * (led_c - _T_REF_C) - ageing * age_h / 1000.0 + flicker)


@njit(cache=True, inline="always")
def _dark(k, board_c):
    """:func:`~nirglucose.simulation.hardware.dark_current_a`. [A]"""
    return k.i25 * exp1(k.dark_per_c * (board_c - 25.0))


@njit(cache=True, inline="always")
def _shot(k, current_a, z):
    """Shot noise drawn: factor x :func:`~nirglucose.simulation.hardware.shot_noise_sd_a`
    x the standard-normal draw. [A]"""
    return k.f_shot * np.sqrt(k.two_e * abs(current_a) * k.bandwidth) * z


@njit(cache=True, inline="always")
def _johnson_sd(k, board_c):
    """Factor x :func:`~nirglucose.simulation.hardware.johnson_noise_sd_a`. [A]"""
    return k.f_johnson * np.sqrt(k.four_k * (board_c + _ZERO_C_K) * k.bandwidth / k.r_johnson)


#: cos(y) = sum_m (-1)^m y^(2m) / (2m)!, m = 0..7: for |y| <= pi/2 the first term left
#: out, (pi/2)^16 / 16!, is 6.6e-11, so the polynomial is within 1e-10 of sin(pi/2 + y).
_COS_TAYLOR = (1.0, -1.0 / 2, 1.0 / 24, -1.0 / 720, 1.0 / 40320, -1.0 / 3628800,
               1.0 / 479001600, -1.0 / 87178291200)


@njit(cache=True, inline="always")
def _sin_0_pi(x):
    """sin(x) for 0 <= x <= pi, within 1e-10 (not to the last bit: see :func:`convert`)."""
    y = x - 0.5 * math.pi
    y2 = y * y
    c = _COS_TAYLOR
    return c[0] + y2 * (c[1] + y2 * (c[2] + y2 * (c[3] + y2 * (c[4] + y2 * (
        c[5] + y2 * (c[6] + y2 * c[7]))))))


@njit(cache=True, inline="always")
def _quantise(rounded, full):
    """Clip a rounded code to [0, full], as an integer code."""
    c = rounded
    if c < 0.0:
        c = 0.0
    elif c > full:
        c = full
    return np.int64(c)


@njit(cache=True, nogil=True, error_model="numpy")
def convert(voltage_v, offset_lsb, k, out):  # pragma: no cover - compiled
    """:func:`~nirglucose.simulation.hardware.adc_convert` of 1-D arrays into ``out``
    (int64), clip(rint(V / Vref FS + INL + offset), 0, FS); returns False where a code is
    not finite.

    The INL bow needs sin(pi code / FS), a C-library call that costs more than all the
    rest; but only the rounded code is kept. So the sine is first taken from a
    polynomial within 1e-10 of it; where the code lands further than a tolerance
    (1e-9 |INL| + 1e-12 (1 + |ideal| + |offset|) LSB, above the polynomial's error and
    every rounding error of the sum by orders of magnitude) from a half-integer, the C
    library's sine would round to the same integer, which is kept. The others (about one
    code in 10^9), and any argument outside [0, pi] or not finite, are redone in a second
    pass with the C library's sine, exactly as the reference. (The first pass has no
    branch: LLVM would hoist the sine out of one and then compute it always.)
    """
    m = voltage_v.shape[0]
    n_unsure = 0
    for i in range(m):
        rounded, sure = _fast_code(k, voltage_v[i], offset_lsb[i])
        n_unsure += not sure
        out[i] = _quantise(rounded, k.full)
    ok = True
    if n_unsure:
        for i in range(m):
            if not _fast_code(k, voltage_v[i], offset_lsb[i])[1]:
                ideal = voltage_v[i] / k.vref * k.full
                code = ideal + k.inl * math.sin(math.pi * ideal / k.full) + offset_lsb[i]
                ok &= math.isfinite(code)
                out[i] = _quantise(np.rint(code), k.full)
    return ok


@njit(cache=True, inline="always")
def _fast_code(k, voltage_v, offset_lsb):
    """(rint of the code with the polynomial sine, whether the C library's would round
    it the same: see :func:`convert`)."""
    ideal = voltage_v / k.vref * k.full
    x = math.pi * ideal / k.full
    code = ideal + k.inl * _sin_0_pi(x) + offset_lsb
    rounded = np.rint(code)
    tol = 1e-9 * abs(k.inl) + 1e-12 * (1.0 + abs(ideal) + abs(offset_lsb))
    return rounded, (0.0 <= x) & (x <= math.pi) & (abs(code - rounded) < 0.5 - tol)


@njit(cache=True, nogil=True, error_model="numpy")
def reading_voltages(fraction, led_c, age_h, board_c, board_cal_c, subject_index, ambient_a,
                     ambient_flicker, z, led, k, signal_v, voltage_v, power_w, offset_lsb,
                     monitor_v):  # pragma: no cover - compiled
    """Each reading's TIA voltage [V] and converter offset [LSB] (read noise included),
    the monitor's voltage (with ``k.monitor``; its offset is the row's without read
    noise), the noise-free voltage [V] and the detected power [W], all (n, n_led).

    ``z``: the standard-normal draws (LED flicker, ambient, shot, Johnson, read noise,
    monitor shot, monitor Johnson), each (n, n_led) (the last three any array where
    ``k`` switches them off); ``led``: (5, n_led) P0 [W], responsivity [A/W], ageing
    [1/(1000 h)], flicker x factor and read-noise SD x scale [LSB].
    """
    n, n_led = fraction.shape
    z_flicker, z_ambient, z_shot, z_johnson, z_read, z_mon_shot, z_mon_johnson = z
    dark_cal = np.empty(board_cal_c.shape[0])  # once per subject, not per reading
    for s in range(board_cal_c.shape[0]):
        dark_cal[s] = _dark(k, board_cal_c[s])
    for i in range(n):
        dark_now = _dark(k, board_c[i])
        dark_res = k.f_dark * (dark_now - dark_cal[subject_index[i]])
        i_amb = k.f_ambient * ambient_a[i]
        amb = i_amb * k.ambient_keep * ambient_flicker[i]
        johnson = _johnson_sd(k, board_c[i])
        offset = k.offset_per_c * (board_c[i] - _T_REF_C)
        for j in range(n_led):
            frac = fraction[i, j]
            p_led = _led_power(led[0, j], k.thermal, led[2, j], led_c[i, j], age_h[i],
                               led[3, j] * z_flicker[i, j])
            power = p_led * frac
            power_w[i, j] = power
            i_sig = led[1, j] * power
            voltage_v[i, j] = (i_sig + dark_res + amb * z_ambient[i, j]
                               + _shot(k, i_sig + dark_now + i_amb, z_shot[i, j])
                               + johnson * z_johnson[i, j]) * k.gain
            offset_lsb[i, j] = offset + (led[4, j] * z_read[i, j] if k.read_noise else 0.0)
            signal_v[i, j] = led[1, j] * (led[0, j] * frac) * k.gain
            if k.monitor:
                i_mon = led[1, j] * p_led * k.transmission
                monitor_v[i, j] = (i_mon + dark_res + _shot(k, i_mon + dark_now, z_mon_shot[i, j])
                                   + johnson * z_mon_johnson[i, j]) * k.gain


@njit(cache=True, nogil=True, error_model="numpy")
def reference_voltages(led_cal_c, age_cal_h, board_cal_c, z_flicker, z_shot, z_johnson, led, k,
                       voltage_v, offset_lsb):  # pragma: no cover - compiled
    """Each subject's start-up reference voltage [V] and offset [LSB], (n_sub, n_led);
    arguments as :func:`reading_voltages` at the start-up temperatures and age."""
    n_sub, n_led = voltage_v.shape
    for s in range(n_sub):
        dark = _dark(k, board_cal_c[s])
        johnson = _johnson_sd(k, board_cal_c[s])
        offset = k.offset_per_c * (board_cal_c[s] - _T_REF_C)
        for j in range(n_led):
            p_cal = _led_power(led[0, j], k.thermal, led[2, j], led_cal_c[s, j], age_cal_h[s],
                               led[3, j] * z_flicker[s, j])
            i_ref = led[1, j] * p_cal * k.transmission
            voltage_v[s, j] = (i_ref + _shot(k, i_ref + dark, z_shot[s, j])
                               + johnson * z_johnson[s, j]) * k.gain
            offset_lsb[s, j] = offset
