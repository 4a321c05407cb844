"""EBL folded into one polynomial: the vectorised kernel and the scalar fast path.

A fitted :class:`~nirglucose.models.linear.EnhancedBeerLambert` on the study's device
is a polynomial in the four absorbances and the physiological entries; its 56
coefficients and the scaler fold into 57 numbers (:func:`fold_ebl`).
:class:`FoldedKernel` evaluates it over many rows, :func:`folded_predict_one` for one
reading in plain Python (no numpy), the same arithmetic the exported C function does
(``nirglucose export-c``).
"""

from __future__ import annotations

import math

import numpy as np

from ..dataset import PMF_COLUMNS
from ..exceptions import DataError
from ..features import (
    ALPHA_MEL,
    ALPHA_PERF,
    ALPHA_SKIN_PER_MM,
    CONTRAST_PAIRS,
    CURVATURE_WEIGHTS,
    DIFFERENCE_PAIRS,
    HYDRATION_CENTER_PCT,
    PERFUSION_COEFFS,
    PRESSURE_CENTER_MBAR,
    PRODUCT_PAIRS,
    SKIN_TEMP_CENTER_C,
    log10_absorbance,
    perfusion_index,
)

__all__ = ["FoldedKernel", "fold_ebl", "folded_predict_one", "predict_one_row"]

_N_CH = 4
_log10 = math.log10
_exp = math.exp
_T0 = SKIN_TEMP_CENTER_C
_H0 = HYDRATION_CENTER_PCT
_INV_H0 = 1.0 / HYDRATION_CENTER_PCT
_P0 = PRESSURE_CENTER_MBAR
_INV_P0 = 1.0 / PRESSURE_CENTER_MBAR
_PC_T = PERFUSION_COEFFS["temp"]
_PC_S = PERFUSION_COEFFS["sbp"]
_PC_S0 = PERFUSION_COEFFS["sbp_center"]
_PC_P = PERFUSION_COEFFS["pressure"]


def predict_one_row(model, adc, adc_ref, pmf) -> float:
    """predict_one for any device: one raw row through :meth:`predict`."""
    s = model.schema_
    parts = [np.ravel(np.asarray(adc, dtype=float))]
    if s.reference:
        parts.append(np.ravel(np.asarray(adc_ref, dtype=float)))
    parts.append(np.ravel(np.asarray(pmf if pmf is not None else [], dtype=float)))
    row = np.concatenate(parts)
    if row.size != len(s.raw_columns):
        raise DataError(
            f"predict_one takes {len(s.raw_columns)} values for this device "
            f"({', '.join(s.raw_columns)}), got {row.size}"
        )
    return float(model.predict(row[None, :])[0])


def fold_ebl(coef: np.ndarray, intercept: float) -> tuple[float, ...]:
    """Fold the 56 raw-feature coefficients into the 57-number polynomial of the model.

    The model is b + sum_k A_k g_k + sum_m e_m pmf_m + (dT, dH, dP) quadratic, with
    g_k = l_k + t_k t + P_k P + M_k M + T_k dT + H_k dH + D_k dP + sum_{j>=k} q_kj A_j.
    Returns ``(b, [l_k, t_k, P_k, M_k, T_k, H_k, D_k] for k = 0..3, q_00, q_01, q_02,
    q_03, q_11, q_12, q_13, q_22, q_23, q_33, e_0..e_11, v_TT, v_HH, v_PP, v_TH, v_TP,
    v_HP)``: 1 + 28 + 10 + 12 + 6 = 57 floats.
    """
    c = np.asarray(coef, dtype=float)
    lin = c[0:4].copy()
    for m, (i, j) in enumerate(CONTRAST_PAIRS + DIFFERENCE_PAIRS):
        lin[i] += c[4 + m]
        lin[j] -= c[4 + m]
    lin += CURVATURE_WEIGHTS.T @ c[10:12]
    cw, ct, chy, cp = c[22:26], c[26:30], c[30:34], c[34:38]
    per_channel: list[float] = []
    for k in range(_N_CH):
        per_channel += [
            lin[k],
            cw[k] * ALPHA_SKIN_PER_MM[k],
            cw[k] * ALPHA_PERF[k],
            cw[k] * ALPHA_MEL[k],
            ct[k],
            chy[k],
            cp[k],
        ]
    assert PRODUCT_PAIRS == tuple((i, j) for i in range(4) for j in range(i, 4))
    return tuple(float(v) for v in [intercept, *per_channel, *c[12:22], *c[38:50], *c[50:56]])


class FoldedKernel:
    """Vectorised evaluation of the folded polynomial, chunked over rows.

    Per chunk: A (4 rows), the basis u = (1, t, P, M, dT, dH, dP); one small matrix
    product gives g_k for all k at once (u and A stacked), then
    sum_k A_k g_k + e . pmf + the (dT, dH, dP) quadratic.
    """

    _CHUNK = 8192

    def __init__(self, folded: tuple[float, ...]):
        f = np.asarray(folded, dtype=float)
        self.b = float(f[0])
        per = f[1:29].reshape(4, 7)
        q = np.zeros((4, 4))
        q[np.triu_indices(4)] = f[29:39]
        self.C = np.hstack([q, per])  # (4, 11) acting on [A; u]
        self.E = np.ascontiguousarray(f[39:51])
        v = f[51:57]
        self.V = np.array([[v[0], v[3], v[4]], [0.0, v[1], v[5]], [0.0, 0.0, v[2]]])

    def __call__(self, X: np.ndarray) -> np.ndarray:
        n = len(X)
        out = np.empty(n)
        if n == 0:
            return out
        col_major = X.strides[0] == X.itemsize
        size = min(n, self._CHUNK)
        Z = np.empty((11, size))  # rows: A_0..A_3, 1, t, P, M, dT, dH, dP
        Z[4] = 1.0
        G = np.empty((4, size))
        for start in range(0, n, self._CHUNK):
            stop = min(start + self._CHUNK, n)
            m = stop - start
            T = X[start:stop].T
            if not col_major:
                T = np.ascontiguousarray(T)
            # codes are >= 1 here: predict_input checked them at the schema boundary
            z = Z[:, :m]
            A, u = z[:4], z[4:]
            log10_absorbance(T[:_N_CH], T[_N_CH : 2 * _N_CH], out=A)
            pmf = T[2 * _N_CH :]
            u[1] = pmf[4]
            u[3] = pmf[3]
            np.subtract(pmf[9], _T0, out=u[4])
            np.subtract(pmf[5], _H0, out=u[5])
            u[5] *= _INV_H0
            np.subtract(pmf[11], _P0, out=u[6])
            u[6] *= _INV_P0
            perfusion_index(pmf[9], pmf[6], pmf[11], out=u[2])
            g = np.matmul(self.C, z, out=G[:, :m])
            o = out[start:stop]
            np.einsum("km,km->m", A, g, out=o)
            o += self.E @ pmf
            d = u[4:7]
            o += np.einsum("km,km->m", d, self.V @ d)
        out += self.b
        return out


def folded_predict_one(folded: tuple[float, ...], adc, adc_ref, pmf) -> float:
    """Glucose from one reading of the study's device, with the folded coefficients.

    Longer than 60 lines on purpose: the 57 coefficients are unpacked into locals and
    the polynomial is written out term by term, so one call is a few dozen float
    operations with no loop, no numpy and no indexing (tens of microseconds less per
    reading than :meth:`predict` on one row); the exported C function mirrors it.

    Parameters
    ----------
    folded : tuple of 57 float
        :func:`fold_ebl`'s coefficients.
    adc, adc_ref : sequence of 4 float
        ADC and reference codes at 850, 940, 1050, 1150 nm. [ADC code]
    pmf : sequence of 12 float
        Physiological entries in :data:`~nirglucose.dataset.PMF_COLUMNS` order.
        [column units]

    Returns
    -------
    float
        Glucose. [mg/dL]
    """
    # fmt: off
    (b,
     l0, t0, P0, m0, T0, H0, D0, l1, t1, P1, m1, T1, H1, D1,
     l2, t2, P2, m2, T2, H2, D2, l3, t3, P3, m3, T3, H3, D3,
     q00, q01, q02, q03, q11, q12, q13, q22, q23, q33,
     e0, e1, e2, e3, e4, e5, e6, e7, e8, e9, e10, e11,
     vtt, vhh, vpp, vth, vtp, vhp) = folded
    # fmt: on
    if type(adc) is np.ndarray:  # numpy scalars are slow in scalar math
        adc = adc.tolist()
    if type(adc_ref) is np.ndarray:
        adc_ref = adc_ref.tolist()
    if type(pmf) is np.ndarray:
        pmf = pmf.tolist()
    try:
        i0, i1, i2, i3 = adc
        r0, r1, r2, r3 = adc_ref
        (x0, x1, x2, mel, t, hyd, sbp, x7, x8, temp, x10, pres) = pmf
        a0 = _log10(r0 / i0)
        a1 = _log10(r1 / i1)
        a2 = _log10(r2 / i2)
        a3 = _log10(r3 / i3)
    except (ValueError, TypeError, ZeroDivisionError):
        raise DataError(
            "predict_one needs 4 positive ADC codes, 4 positive reference codes and "
            f"{len(PMF_COLUMNS)} physiological values"
        ) from None
    dt = temp - _T0
    dh = (hyd - _H0) * _INV_H0
    dp = (pres - _P0) * _INV_P0
    p = _exp(_PC_T * dt + _PC_S * (sbp - _PC_S0) + _PC_P * (pres - _P0))
    return (
        b
        + a0
        * (
            l0
            + t0 * t
            + P0 * p
            + m0 * mel
            + T0 * dt
            + H0 * dh
            + D0 * dp
            + q00 * a0
            + q01 * a1
            + q02 * a2
            + q03 * a3
        )
        + a1
        * (
            l1
            + t1 * t
            + P1 * p
            + m1 * mel
            + T1 * dt
            + H1 * dh
            + D1 * dp
            + q11 * a1
            + q12 * a2
            + q13 * a3
        )
        + a2 * (l2 + t2 * t + P2 * p + m2 * mel + T2 * dt + H2 * dh + D2 * dp + q22 * a2 + q23 * a3)
        + a3 * (l3 + t3 * t + P3 * p + m3 * mel + T3 * dt + H3 * dh + D3 * dp + q33 * a3)
        + e0 * x0
        + e1 * x1
        + e2 * x2
        + e3 * mel
        + e4 * t
        + e5 * hyd
        + e6 * sbp
        + e7 * x7
        + e8 * x8
        + e9 * temp
        + e10 * x10
        + e11 * pres
        + dt * (vtt * dt + vth * dh + vtp * dp)
        + dh * (vhh * dh + vhp * dp)
        + vpp * dp * dp
    )
