"""Compiled per-reading state of the physiology layer: one pass instead of about forty.

:func:`nirglucose.simulation.physiology.sample_state` turns each reading's draws into its
hydration, blood pressure, heart and respiration rate, skin temperature, saturation and
dermal blood volume as about forty NumPy passes over (readings,) arrays. :func:`state`
does the same operations, in the same order per value, in one compiled pass: + - x / are
IEEE 754 basic operations (correctly rounded, the same bits on every CPU), ``tanh``
and ``sin`` are the C library's through :mod:`math` (what :mod:`nirglucose.portable`
calls) and ``exp`` its algorithm inline (:func:`nirglucose.libm.exp1`), and numba
neither fuses a multiply-add nor reorders without ``fastmath``; so the values equal the
NumPy reference's bit for bit (a test holds them so). The physics, units and citations live in
:mod:`nirglucose.simulation.physiology`, which stays the reference; the caller makes the
draws, in the reference's streams and counts.
"""

from __future__ import annotations

import math

from numba import njit

from ...libm import exp1

__all__ = ["state"]


@njit(cache=True, inline="always")
def _clip(x, lo, hi):
    """``np.clip`` of one value as NumPy takes it: a limit only where the value is
    beyond it (a tie, a zero at a zero limit included, keeps the value), NaN kept."""
    if x < lo:
        x = lo
    if x > hi:
        x = hi
    return x


@njit(cache=True, nogil=True, error_model="numpy")
def state(base, stress, ambient_c, pressure_mbar, z, phase, k, out):  # pragma: no cover
    """Each reading's state into ``out`` (8, n): hydration [%], water fraction, systolic
    BP, heart rate, respiration rate, skin temperature, saturation, blood fraction.

    ``base`` (5, n): the subject's hydration offset, systolic BP, heart rate, respiration
    rate and log blood fraction at each reading; ``stress`` (n,) 0/1; ``z`` (7, n): the
    ``physiology.state`` normals in the reference's order; ``phase`` (2, n): the cardiac
    and respiratory phases; ``k``: the scalars of
    :func:`nirglucose.simulation.physiology._state_constants`.
    """
    (c_hyd, lim, water_nominal, c_sbp, stress_sbp, sbp_lo, sbp_hi, c_hr, stress_hr, hr_lo,
     hr_hi, c_rr, rr_lo, rr_hi, neutral, per_ambient, ambient_ref, c_skin, sat_mean, c_sat,
     sat_lo, sat_hi, c_blood, per_c, per_mmhg, ref_sbp, per_mbar, ref_mbar, pulse,
     pulse_depth, resp_depth, blood_lo, blood_hi) = k
    for i in range(out.shape[1]):
        s = float(stress[i])
        hydration = lim * math.tanh((base[0, i] + c_hyd * z[0, i]) / lim)
        sbp = _clip(base[1, i] + c_sbp * z[1, i] + stress_sbp * s, sbp_lo, sbp_hi)
        hr = _clip(base[2, i] + c_hr * z[2, i] + stress_hr * s, hr_lo, hr_hi)
        rr = _clip(base[3, i] + c_rr * z[3, i], rr_lo, rr_hi)
        skin = neutral + per_ambient * (ambient_c[i] - ambient_ref) + c_skin * z[4, i]
        log_blood = (base[4, i] + c_blood * z[6, i] + per_c * (skin - neutral)
                     + per_mmhg * (sbp - ref_sbp) + per_mbar * (pressure_mbar[i] - ref_mbar))
        modulation = 1.0 + pulse * (pulse_depth * math.sin(phase[0, i])
                                    + resp_depth * math.sin(phase[1, i]))
        out[0, i] = 100.0 + hydration
        out[1, i] = water_nominal * (1.0 + hydration / 100.0)
        out[2, i] = sbp
        out[3, i] = hr
        out[4, i] = rr
        out[5, i] = skin
        out[6, i] = _clip(sat_mean + c_sat * z[5, i], sat_lo, sat_hi)
        out[7, i] = _clip(exp1(log_blood) * modulation, blood_lo, blood_hi)
