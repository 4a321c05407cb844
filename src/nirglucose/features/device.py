"""The Enhanced Beer–Lambert features of any device, and their evaluation.

:func:`feature_table` builds the feature table of a device's
:class:`~nirglucose.schema.DeviceSchema` (any LEDs, optional reference codes, any known
physiological columns) block by block from the shared blocks of
:mod:`~nirglucose.features.blocks`; at the study's device it is the study's
:data:`~nirglucose.features.study.FEATURE_TABLE`. :func:`compute_features` evaluates
any such table from absorbances and physiology.

References
----------
.. [1] R. Gani, "Physics-Informed Neural Networks vs. Physics Models for Non-Invasive
   Glucose Monitoring: A Comparative Study Under Noise-Stressed Synthetic Conditions",
   University College London.
.. [2] M. Cope, D. T. Delpy, "System for long-term measurement of cerebral blood and
   tissue oxygenation on newborn infants by near infra-red transillumination",
   Med. Biol. Eng. Comput. 26, 289-294 (1988), doi:10.1007/BF02447083 (modified
   Beer–Lambert law).
"""

from __future__ import annotations

import numpy as np

from .blocks import (
    _ENV,
    _ENV2,
    _W_COLUMNS,
    NOMINAL_BLOOD_PCT,
    FeatureSpec,
    _curvature_weights,
    nuisance_alphas,
    perfusion_index,
)
from .study import FEATURE_TABLE

__all__ = ["feature_table", "compute_features"]

#: Category and rationale of each environment symbol's x A_k block.
_ENV_CATEGORY = {
    "dT": ("temp", "LED/water-band thermal drift"),
    "dH": ("hydration", "water share of absorbance"),
    "dP": ("pressure", "perfusion/contact with pressure"),
    "dB": ("blood-volume", "blood's share of the absorbance (PPG perfusion)"),
    "dS": ("saturation", "Hb/HbO2 balance of the blood's spectrum (PPG SpO2)"),
}
#: Channel spacing of a plain schema, for its curvature. [nm]
_PLAIN_SPACING_NM = 100.0


def _absorbance_rows(lab, a) -> list[FeatureSpec]:
    return [
        FeatureSpec(a[i], f"log10(I0_{lab[i]}/I_{lab[i]})", "absorbance",
                    "absorbance at this LED", ("A", i))
        for i in range(len(lab))
    ]


def _difference_rows(lab, a) -> list[FeatureSpec]:
    """All k(k-1)/2 pairwise differences A_i - A_j, j < i."""
    return [
        FeatureSpec(f"dA_{lab[i]}_{lab[j]}", f"{a[i]} - {a[j]}", "difference",
                    "cancels coupling and LED-power offsets", ("lin", ((i, 1.0), (j, -1.0))))
        for i in range(len(lab))
        for j in range(i)
    ]


def _curvature_rows(schema, lab) -> list[FeatureSpec]:
    """k - 2 second derivatives (none under three channels)."""
    k = len(lab)
    if k < 3:
        return []
    x = (
        np.asarray(schema.wavelengths_nm, dtype=float)
        if not schema.is_plain
        else _PLAIN_SPACING_NM * np.arange(k)
    )
    cw = _curvature_weights(x)
    return [
        FeatureSpec(
            f"d2A_{lab[m]}",
            f"d2A/dλ² ({lab[m - 1]},{lab[m]},{lab[m + 1]})",
            "curvature",
            "removes linear scatter baseline",
            ("lin", tuple((c, float(cw[m - 1, c])) for c in (m - 1, m, m + 1))),
        )
        for m in range(1, k - 1)
    ]


def _product_rows(a) -> list[FeatureSpec]:
    k = len(a)
    return [
        FeatureSpec(f"{a[i]}_x_{a[j]}", f"{a[i]}^2" if i == j else f"{a[i]} {a[j]}",
                    "product", "path-length nonlinearity", ("AA", i, j))
        for i in range(k)
        for j in range(i, k)
    ]


def _weight_rows(schema, lab, a) -> list[FeatureSpec]:
    """w_k A_k, where the device measures every column w needs."""
    if not all(c in schema.physiology for c in _W_COLUMNS):
        return []
    return [
        FeatureSpec(f"w_x_{a[i]}", f"w_{lab[i]} {a[i]}", "pmf-weight",
                    "skin/blood/melanin path weight", ("w", i, *nuisance_alphas(w)))
        for i, w in enumerate(schema.wavelengths_nm)
    ]


def _environment_rows(schema, a) -> list[FeatureSpec]:
    """Environment x A_k, every physiological column, the 2nd-order terms present."""
    phys = schema.physiology
    syms = [s for s in _ENV if _ENV[s][0] in phys]
    rows = [
        FeatureSpec(f"{s}_x_{a[i]}", f"{s} {a[i]}", *_ENV_CATEGORY[s], ("envA", s, i))
        for s in syms
        for i in range(len(a))
    ]
    rows += [
        FeatureSpec(c, c, "pmf", "measured physiology", ("pmf", m)) for m, c in enumerate(phys)
    ]
    for s1, s2 in _ENV2:
        if s1 in syms and s2 in syms:
            name, formula = (f"{s1}_sq", f"{s1}^2") if s1 == s2 else (f"{s1}_x_{s2}", f"{s1} {s2}")
            rows.append(
                FeatureSpec(name, formula, "env-2nd", "second-order environment", ("env2", s1, s2))
            )
    return rows


def feature_table(schema) -> tuple[FeatureSpec, ...]:
    """The Enhanced Beer–Lambert features of any device (its :class:`DeviceSchema`).

    Blocks, each where the device's columns allow it: k absorbances; all k(k-1)/2
    pairwise differences (the study's contrasts first at its four LEDs); k - 2
    curvatures; k(k+1)/2 products; PMF-weighted absorbances (needs skin thickness,
    melanin, skin temperature, systolic BP and pressure); temperature, hydration and
    pressure x A_k (each needs its column); every physiological column; the
    second-order temperature/hydration/pressure terms among those present. At the
    study's four LEDs with its 12-entry vector this is exactly :data:`FEATURE_TABLE`.
    A plain schema's channels sit one (100 nm) unit apart for the curvature.
    """
    if schema.is_study:
        return FEATURE_TABLE
    lab = schema.labels
    a = [f"A_{w}" for w in lab]
    return tuple(
        _absorbance_rows(lab, a)
        + _difference_rows(lab, a)
        + _curvature_rows(schema, lab)
        + _product_rows(a)
        + _weight_rows(schema, lab, a)
        + _environment_rows(schema, a)
    )


def compute_features(table, schema, absorbance, physiology) -> np.ndarray:
    """Evaluate a :func:`feature_table` on absorbances and physiology, (n, p).

    Parameters
    ----------
    table : sequence of FeatureSpec
        The features.
    schema : DeviceSchema
        The device (names the physiological columns).
    absorbance : numpy.ndarray
        (n, k) decadic absorbances. [-]
    physiology : numpy.ndarray
        (n, m) physiological columns in ``schema.physiology`` order. [column units]
    """
    A = np.asarray(absorbance, dtype=float).T
    P = np.asarray(physiology, dtype=float).T
    col = {c: P[m] for m, c in enumerate(schema.physiology)}
    env = {s: (col[c] - c0) / sc for s, (c, c0, sc) in _ENV.items() if c in col}
    perf = None
    out = np.empty((len(table), A.shape[1]))
    for r, spec in enumerate(table):
        op = spec.op
        kind = op[0]
        if kind == "A":
            out[r] = A[op[1]]
        elif kind == "lin":
            out[r] = sum(w * A[c] for c, w in op[1])
        elif kind == "AA":
            out[r] = A[op[1]] * A[op[2]]
        elif kind == "w":
            if perf is None:
                perf = (
                    col["blood_volume_pct"] / NOMINAL_BLOOD_PCT  # measured (PPG)
                    if "blood_volume_pct" in col
                    else perfusion_index(
                        col["skin_temp_c"], col["systolic_bp_mmhg"], col["pressure_mbar"]
                    )
                )
            _, k, a_s, a_p, a_m = op
            out[r] = (
                a_s * col["skin_thickness_mm"] + a_p * perf + a_m * col["melanin_fraction"]
            ) * A[k]
        elif kind == "envA":
            out[r] = env[op[1]] * A[op[2]]
        elif kind == "pmf":
            out[r] = P[op[1]]
        elif kind == "env2":
            out[r] = env[op[1]] * env[op[2]]
        else:  # pragma: no cover - tables are built here
            raise ValueError(f"unknown feature op {op!r}")
    return out.T
