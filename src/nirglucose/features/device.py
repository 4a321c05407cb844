"""The Enhanced Beer–Lambert features of any device, and their evaluation.

:func:`feature_table` is the feature table of a device's
:class:`~nirglucose.dataset.schema.DeviceSchema` (any LEDs, optional reference codes, any known
physiological columns), from the one builder
:func:`~nirglucose.features.table.build_feature_table`; at the study's device it is the
study's :data:`~nirglucose.features.study.FEATURE_TABLE`. :func:`compute_features` evaluates
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

from .blocks import _ENV, NOMINAL_BLOOD_PCT, FeatureSpec, perfusion_index
from .study import FEATURE_TABLE
from .table import build_feature_table

__all__ = ["feature_table", "compute_features"]


def feature_table(schema) -> tuple[FeatureSpec, ...]:
    """The Enhanced Beer–Lambert features of any device (its :class:`DeviceSchema`).

    :func:`~nirglucose.features.table.build_feature_table` at that device; at the
    study's four LEDs with its 12-entry vector exactly :data:`FEATURE_TABLE` (the same
    builder with the study's notes and its glucose contrasts first).
    """
    if schema.is_study:
        return FEATURE_TABLE
    return build_feature_table(schema)


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
