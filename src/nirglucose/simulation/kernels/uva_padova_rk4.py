"""Compiled fixed-step RK4 of the UVA/Padova model: the same bits as the NumPy loop.

:func:`nirglucose.simulation.uva_padova.integrate` steps both model variants by
classical RK4 with a 1-minute step; written with NumPy element-wise operations over the
subjects, 14 days are 20,160 steps of four right-hand sides, each some forty NumPy calls
on arrays of a dozen elements, so Python's overhead is nearly all of its time. This
module does the same arithmetic in one compiled loop per subject (numba, no fast-math:
no reassociation, no fused multiply-add), operation for operation in the NumPy
functions' order, with ``tanh`` the C library's (``math.tanh``, as
:func:`nirglucose.portable.tanh`), so every result is the same IEEE 754 double. It is an
implementation detail: the equations, units and citations live in
:func:`~nirglucose.simulation.uva_padova.rhs_2007`,
:func:`~nirglucose.simulation.uva_padova.rhs_type1` and
:func:`~nirglucose.simulation.uva_padova.gastric_emptying_per_min`, which stay the
reference, and ``tests/simulation/test_uva_padova_kernel.py`` holds the two bit-equal.

The NumPy loop couples its subjects only through two whole-array tests, whether anyone
eats (or ate the minute before: then every subject's stomach gets its meal, 0 for most,
and its dose terms are recomputed) and whether any subject's insulin sensitivity changed
(then every subject's factor is re-read). Both depend on the inputs alone, so
:func:`meal_steps` and :func:`sensitivity_columns` find them first and each subject is
then integrated on its own.

The functions are compiled separately (numba's ``inline="always"`` quadrupled the compile
time, about 5 s without it on a fresh machine, for no gain: LLVM inlines them anyway) and
cached beside this file (``cache=True``).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

__all__ = ["COMMON", "EXTRA_2007", "EXTRA_TYPE1", "meal_steps", "sensitivity_columns",
           "integrate_rk4"]

#: Parameter rows shared by both variants (``Fcns``: the type 1 sets call it ``Fsnc``;
#: ``kgri``: the type 1 sets take ``kmax``).
COMMON = ("kmax", "kmin", "b", "d", "kgri", "f", "kabs", "BW", "Vm0", "Vmx", "Km0", "ke1",
          "ke2", "k1", "k2", "Fcns", "kp1", "kp2", "kp3")
#: Rows after :data:`COMMON` of the secreting model.
EXTRA_2007 = ("VG", "kp4", "VI", "gamma", "m6", "m5", "m1", "beta", "h", "Sb", "alpha",
              "K", "m2", "m4", "ki", "p2U", "Ib")
#: Rows after :data:`COMMON` of the type 1 model (``u2ss`` the basal delivery).
EXTRA_TYPE1 = ("Vg", "Vi", "m1", "m2", "m4", "m30", "ki", "p2u", "Ib", "ka1", "ka2", "kd",
               "u2ss")
_VMX, _KP3, _E = COMMON.index("Vmx"), COMMON.index("kp3"), len(COMMON)
_GP, _ISC1 = 3, 10  # rows of gp (both variants) and isc1 (type 1)


@njit(cache=True)
def meal_steps(meals):  # pragma: no cover - compiled
    """(n_min,) bool: the minutes at which the NumPy loop runs its meal block (some
    subject eats then, or ate the minute before)."""
    n, n_min = meals.shape
    run = np.zeros(n_min, dtype=np.bool_)
    for k in range(n_min):
        for i in range(n):
            if meals[i, k] != 0.0 or (k > 0 and meals[i, k - 1] > 0.0):
                run[k] = True
                break
    return run


@njit(cache=True)
def sensitivity_columns(sens):  # pragma: no cover - compiled
    """(n_min,) int: the minute whose column holds the sensitivity factors in force at
    each minute (the NumPy loop re-reads them when any subject's factor changes)."""
    n, n_min = sens.shape
    col = np.zeros(n_min, dtype=np.int64)
    last = 0
    for k in range(1, n_min):
        for i in range(n):
            if sens[i, k] != sens[i, last]:
                last = k
                break
        col[k] = last
    return col


@njit(cache=True)
def _max0(v):  # pragma: no cover - compiled
    """``np.maximum(v, 0.0)``: v if positive or NaN, else +0.0 (also for -0.0)."""
    return v if (v > 0.0 or v != v) else 0.0


@njit(cache=True)
def _terms(dose, b, d):  # pragma: no cover - compiled
    """``uva_padova._emptying_terms`` of one subject: (D > 0, b D, d D, a, c)."""
    has = dose > 0
    safe = dose if has else 1.0
    return has, b * safe, d * safe, 5.0 / (2.0 * safe * (1.0 - b)), 5.0 / (2.0 * safe * d)


@njit(cache=True)
def _gut_and_flows(x, q, vmx, xx, production, terms, out):  # pragma: no cover - compiled
    """Rows 0-4 of either right-hand side (``uva_padova._gut``, ``_kempt``,
    ``_glucose_flows``) into ``out``; ``xx`` the remote insulin action X, ``production``
    EGP before its floor at 0.
    Returns dGp/dt."""
    has, b_dose, d_dose, a, c = terms
    kmax, kmin, gp, gt = q[0], q[1], x[3], x[4]
    qsto = x[0] + x[1]
    k = kmin + 0.5 * (kmax - kmin) * (
        math.tanh(a * (qsto - b_dose)) - math.tanh(c * (qsto - d_dose)) + 2.0)
    kempt = k if has else kmax + 0.0 * k
    kgri, kabs = q[4], q[6]
    ra = q[5] * kabs * x[2] / q[7]
    out[0] = -kgri * x[0]
    out[1] = kgri * x[0] - kempt * x[1]
    out[2] = kempt * x[1] - kabs * x[2]
    egp = _max0(production)
    uid = (q[8] + vmx * xx) * gt / (q[10] + gt)
    renal = q[11] * _max0(gp - q[12])
    dgp = egp + ra - q[15] - renal - q[13] * gp + q[14] * gt
    out[3] = dgp
    out[4] = -uid + q[13] * gp - q[14] * gt
    return dgp


@njit(cache=True)
def _rhs_2007(x, q, vmx, kp3, terms, out):  # pragma: no cover - compiled
    """:func:`~nirglucose.simulation.uva_padova.rhs_2007` of one subject into ``out``."""
    gp, il, ip, i1, id_, xx, y, ipo = x[3], x[5], x[6], x[7], x[8], x[9], x[10], x[11]
    vg, kp4, vi, gamma, m6, m5, m1 = q[_E], q[_E + 1], q[_E + 2], q[_E + 3], q[_E + 4], \
        q[_E + 5], q[_E + 6]
    beta, h, sb, alpha, kk = q[_E + 7], q[_E + 8], q[_E + 9], q[_E + 10], q[_E + 11]
    m2, m4, ki, p2u, ib = q[_E + 12], q[_E + 13], q[_E + 14], q[_E + 15], q[_E + 16]
    dgp = _gut_and_flows(x, q, vmx, xx, q[16] - q[17] * gp - kp3 * id_ - kp4 * ipo, terms, out)
    g, i = gp / vg, ip / vi
    s = gamma * ipo
    he = m6 - m5 * s
    m3 = he * m1 / (1.0 - he)
    excess = beta * (g - h)
    dy = -alpha * (y - excess) if excess >= -sb else -alpha * (y + sb)
    spo = y + sb + kk * _max0(dgp / vg)
    out[5] = -(m1 + m3) * il + m2 * ip + s
    out[6] = -(m2 + m4) * ip + m1 * il
    out[7] = -ki * (i1 - i)
    out[8] = -ki * (id_ - i1)
    out[9] = -p2u * xx + p2u * (i - ib)
    out[10] = dy
    out[11] = -gamma * ipo + spo


@njit(cache=True)
def _rhs_type1(x, q, vmx, kp3, terms, out):  # pragma: no cover - compiled
    """:func:`~nirglucose.simulation.uva_padova.rhs_type1` of one subject into ``out``
    (``u`` the basal delivery ``u2ss``)."""
    gp, ip, xx, i1, id_, il, isc1, isc2 = x[3], x[5], x[6], x[7], x[8], x[9], x[10], x[11]
    vi, m1, m2, m4, m30, ki = q[_E + 1], q[_E + 2], q[_E + 3], q[_E + 4], q[_E + 5], q[_E + 6]
    p2u, ib, ka1, ka2, kd, u = q[_E + 7], q[_E + 8], q[_E + 9], q[_E + 10], q[_E + 11], \
        q[_E + 12]
    _gut_and_flows(x, q, vmx, xx, q[16] - q[17] * gp - kp3 * id_, terms, out)
    i = ip / vi
    out[5] = -(m2 + m4) * ip + m1 * il + ka1 * isc1 + ka2 * isc2
    out[6] = -p2u * xx + p2u * (i - ib)
    out[7] = -ki * (i1 - i)
    out[8] = -ki * (id_ - i1)
    out[9] = -(m1 + m30) * il + m2 * ip
    out[10] = -(kd + ka1) * isc1 + u
    out[11] = kd * isc1 - ka2 * isc2


@njit(cache=True)
def _rhs(type1, x, q, vmx, kp3, terms, out):  # pragma: no cover - compiled
    if type1:
        _rhs_type1(x, q, vmx, kp3, terms, out)
    else:
        _rhs_2007(x, q, vmx, kp3, terms, out)


@njit(cache=True)
def _rk4_step(type1, x, q, vmx, kp3, terms, h, ks, xs):  # pragma: no cover - compiled
    """One RK4 step of ``x`` in place, as the NumPy loop: stages x + (h/2) k1, x + (h/2)
    k2, x + h k3, then x + (h/6) (k1 + 2 k2 + 2 k3 + k4) summed left to right."""
    half = 0.5 * h
    _rhs(type1, x, q, vmx, kp3, terms, ks[0])
    for j in range(12):
        xs[j] = x[j] + half * ks[0, j]
    _rhs(type1, xs, q, vmx, kp3, terms, ks[1])
    for j in range(12):
        xs[j] = x[j] + half * ks[1, j]
    _rhs(type1, xs, q, vmx, kp3, terms, ks[2])
    for j in range(12):
        xs[j] = x[j] + h * ks[2, j]
    _rhs(type1, xs, q, vmx, kp3, terms, ks[3])
    sixth = h / 6.0
    for j in range(12):
        x[j] = x[j] + sixth * (ks[0, j] + 2.0 * ks[1, j] + 2.0 * ks[2, j] + ks[3, j])


@njit(cache=True)
def _subject(type1, q, x, meals, run, bolus, has_bolus, sens, col, has_sens, h,
             out):  # pragma: no cover - compiled
    """One subject's minutes (the NumPy loop's body, restricted to it) into ``out``."""
    ks, xs = np.empty((4, 12)), np.empty(12)
    dose, eating = 0.0, False
    terms = _terms(dose, q[2], q[3])
    vmx, kp3 = q[_VMX], q[_KP3]
    for k in range(meals.shape[0]):
        out[k] = x[_GP] / q[_E]
        if has_sens:
            factor = sens[col[k]]
            vmx, kp3 = q[_VMX] * factor, q[_KP3] * factor
        if run[k]:
            meal = meals[k]
            x[0] += meal
            if meal > 0:
                dose = dose + meal if eating else meal
            eating = meal > 0
            terms = _terms(dose, q[2], q[3])
        if has_bolus:
            x[_ISC1] += bolus[k]
        _rk4_step(type1, x, q, vmx, kp3, terms, h, ks, xs)


@njit(cache=True)
def integrate_rk4(type1, q, x0, meals, bolus, has_bolus, sens, has_sens,
                  h):  # pragma: no cover - compiled
    """Plasma glucose (n, n_min) [mg/dL], as
    :func:`~nirglucose.simulation.uva_padova.integrate`: ``q`` (len(COMMON) + extras, n)
    parameter rows (:data:`COMMON` then :data:`EXTRA_2007` or :data:`EXTRA_TYPE1`),
    ``x0`` (12, n), ``meals``, ``bolus`` and ``sens`` (n, n_min) (the flags say whether
    the last two apply), ``h`` the step [min]."""
    n, n_min = meals.shape
    run = meal_steps(meals)
    col = sensitivity_columns(sens) if has_sens else np.zeros(n_min, dtype=np.int64)
    out = np.empty((n, n_min))
    for i in range(n):
        _subject(type1, q[:, i].copy(), x0[:, i].copy(), meals[i], run, bolus[i], has_bolus,
                 sens[i], col, has_sens, h, out[i])
    return out
