"""The one builder of Enhanced Beer–Lambert feature tables, for any device.

:func:`build_feature_table` lays out the features of a device's
:class:`~nirglucose.dataset.schema.DeviceSchema` block by block from the shared blocks of
:mod:`~nirglucose.features.blocks` (the blocks and their arithmetic are in the
:mod:`nirglucose.features` docstring). The study's table
(:data:`~nirglucose.features.study.FEATURE_TABLE`) is this builder at the study's
device with the study's per-feature rationale (``notes``) and its glucose contrasts
first; :func:`~nirglucose.features.device.feature_table` is it at any other device.

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

from collections.abc import Mapping, Sequence

import numpy as np

from .blocks import _ENV, _ENV2, _W_COLUMNS, FeatureSpec, _curvature_weights, nuisance_alphas

__all__ = ["build_feature_table"]

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


def _difference_rows(lab, a, first: Sequence[tuple[int, int]]) -> list[FeatureSpec]:
    """All k(k-1)/2 pairwise differences A_i - A_j: ``first`` pairs, then the rest
    (j < i, by i then j)."""
    pairs = [(i, j) for i in range(len(lab)) for j in range(i)]
    pairs = list(first) + [p for p in pairs if p not in first]
    return [
        FeatureSpec(f"dA_{lab[i]}_{lab[j]}", f"{a[i]} - {a[j]}", "difference",
                    "cancels coupling and LED-power offsets", ("lin", ((i, 1.0), (j, -1.0))))
        for i, j in pairs
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


def build_feature_table(
    schema,
    notes: Mapping[str, tuple[str, str]] | None = None,
    first_differences: Sequence[tuple[int, int]] = (),
) -> tuple[FeatureSpec, ...]:
    """The Enhanced Beer–Lambert features of a device, in output order [1]_ [2]_.

    Blocks, each where the device's columns allow it: k absorbances; all k(k-1)/2
    pairwise differences; k - 2 curvatures; k(k+1)/2 products; PMF-weighted absorbances
    (needs skin thickness, melanin, skin temperature, systolic BP and pressure);
    temperature, hydration, pressure (and, measured by PPG, blood volume and
    saturation) x A_k, each where its column is recorded; every physiological column;
    the second-order temperature/hydration/pressure terms among those present. A plain
    schema's channels sit one (100 nm) unit apart for the curvature.

    Parameters
    ----------
    schema : DeviceSchema
        The device (its LEDs, whether plain, its physiological columns).
    notes : mapping, optional
        Feature name -> ``(category, rationale)`` replacing the block's generic text
        (the study's per-feature notes).
    first_differences : sequence of (int, int), optional
        Channel pairs (i, j) whose differences A_i - A_j come first in their block
        (the study's glucose contrasts).

    Returns
    -------
    tuple of FeatureSpec
        Name, formula, category, rationale and how to compute each feature.

    Examples
    --------
    >>> from nirglucose.dataset.schema import DeviceSchema
    >>> t = build_feature_table(DeviceSchema(wavelengths_nm=(940.0, 1050.0), physiology=()))
    >>> [f.name for f in t]
    ['A_940', 'A_1050', 'dA_1050_940', 'A_940_x_A_940', 'A_940_x_A_1050', 'A_1050_x_A_1050']
    """
    lab = schema.labels
    a = [f"A_{w}" for w in lab]
    table = (
        _absorbance_rows(lab, a)
        + _difference_rows(lab, a, tuple(first_differences))
        + _curvature_rows(schema, lab)
        + _product_rows(a)
        + _weight_rows(schema, lab, a)
        + _environment_rows(schema, a)
    )
    if notes:
        table = [
            FeatureSpec(f.name, f.formula, *notes[f.name], f.op) if f.name in notes else f
            for f in table
        ]
    return tuple(table)
