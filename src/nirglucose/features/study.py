"""The study's 56-feature table and its vectorised evaluation.

:data:`FEATURE_TABLE` is the reference study's Enhanced Beer–Lambert features [1]_ at
its four LEDs and 12-entry physiological vector: the one builder
(:func:`~nirglucose.features.table.build_feature_table`) at the study's device, with
the study's rationale for each feature and its glucose contrasts first (the table
with every formula is in the :mod:`nirglucose.features` docstring and
``docs/features.md``); :func:`ebl_feature_matrix` computes them from a raw
measurement array without a row loop, and :func:`features_markdown` writes the docs page.

References
----------
.. [1] R. Gani, "Physics-Informed Neural Networks vs. Physics Models for Non-Invasive
   Glucose Monitoring: A Comparative Study Under Noise-Stressed Synthetic Conditions",
   University College London.
"""

from __future__ import annotations

import numpy as np

from ..constants import DEFAULT_LED_WAVELENGTHS_NM
from ..dataset import PMF_COLUMNS
from ..dataset.schema import DeviceSchema
from ..exceptions import DataError
from .blocks import (
    _ENV2,
    _MEASURED,
    _N_CH,
    _PMF0,
    _WL,
    ALPHA_MEL,
    ALPHA_PERF,
    ALPHA_SKIN_PER_MM,
    CONTRAST_PAIRS,
    CURVATURE_WEIGHTS,
    DIFFERENCE_PAIRS,
    HYDRATION_CENTER_PCT,
    PRESSURE_CENTER_MBAR,
    PRODUCT_PAIRS,
    SKIN_TEMP_CENTER_C,
    FeatureSpec,
    log10_absorbance,
    perfusion_index,
)
from .table import build_feature_table

__all__ = [
    "N_FEATURES",
    "FEATURE_NAMES",
    "FEATURE_TABLE",
    "ebl_feature_matrix",
    "features_markdown",
]

# --- the physical rationale of each study feature (data: one entry per row) -----------
_WHY_A = (
    "Hb/HbO2 and melanin band",
    "water shoulder, perfusion",
    "glucose 2nd-overtone flank",
    "glucose C-H 2nd overtone peak",
)
_WHY_CONTRAST = (
    "glucose vs water reference",
    "glucose flank vs Hb reference",
    "glucose overtone slope",
)
_WHY_DIFFERENCE = (
    "cancels coupling; blood/water",
    "cancels coupling; water slope",
    "cancels coupling; full span",
)
_WHY_PMF = {
    "age_yr": "dermal thinning, collagen",
    "bmi_kgm2": "subcutaneous fat, lipid band",
    "fitzpatrick_type": "epidermal melanin class",
    "melanin_fraction": "epidermal absorption",
    "skin_thickness_mm": "dermal path length",
    "hydration_pct": "dermal water content",
    "systolic_bp_mmhg": "perfusion (blood volume)",
    "heart_rate_bpm": "pulsatile blood volume",
    "resp_rate_bpm": "respiratory blood volume",
    "skin_temp_c": "water band, vasodilation",
    "humidity_pct": "optical coupling loss",
    "pressure_mbar": "perfusion, probe contact",
}
#: Second-order environment terms, in :data:`~nirglucose.features.blocks._ENV2` order.
_WHY_ENV2 = (
    "nonlinear thermal drift",
    "nonlinear water effect",
    "nonlinear pressure effect",
    "temperature-water coupling",
    "temperature-perfusion coupling",
    "water-perfusion coupling",
)



def _study_notes() -> dict[str, tuple[str, str]]:
    """Feature name -> (category, rationale) where the study's table says more than a
    generic device's: each LED's band, the contrasts, each physiological column."""
    notes = {f"A_{w}": ("absorbance", why) for w, why in zip(_WL, _WHY_A, strict=True)}
    for cat, pairs, whys in (("contrast", CONTRAST_PAIRS, _WHY_CONTRAST),
                             ("difference", DIFFERENCE_PAIRS, _WHY_DIFFERENCE)):
        for (i, j), why in zip(pairs, whys, strict=True):
            notes[f"dA_{_WL[i]}_{_WL[j]}"] = (cat, why)
    notes.update({c: ("pmf", why) for c, why in _WHY_PMF.items()})
    for (s1, s2), why in zip(_ENV2, _WHY_ENV2, strict=True):
        notes[f"{s1}_sq" if s1 == s2 else f"{s1}_x_{s2}"] = ("env-2nd", why)
    return notes


#: The study's device: its four LEDs, reference codes and 12-entry physiological vector.
_STUDY_DEVICE = DeviceSchema(
    wavelengths_nm=tuple(float(w) for w in DEFAULT_LED_WAVELENGTHS_NM),
    physiology=tuple(PMF_COLUMNS),
)

#: Every feature, in output order.
FEATURE_TABLE: tuple[FeatureSpec, ...] = build_feature_table(
    _STUDY_DEVICE, _study_notes(), first_differences=CONTRAST_PAIRS
)
#: Feature names, in output order.
FEATURE_NAMES: tuple[str, ...] = tuple(f.name for f in FEATURE_TABLE)
#: Number of features (56, the study's count).
N_FEATURES = len(FEATURE_TABLE)
assert N_FEATURES == 56, N_FEATURES  # the arithmetic in the package docstring

# Slices of the output by block (used by ebl_feature_matrix).
_S_A = slice(0, 4)
_S_DIFF = slice(4, 10)
_S_CURV = slice(10, 12)
_S_PROD = slice(12, 22)
_S_W = slice(22, 26)
_S_T = slice(26, 30)
_S_H = slice(30, 34)
_S_PRES = slice(34, 38)
_S_PMF = slice(38, 50)
_S_ENV2 = slice(50, 56)


def _check_array(X) -> np.ndarray:
    X = np.asarray(X, dtype=float)
    if X.ndim != 2 or X.shape[1] != len(_MEASURED):
        raise DataError(
            f"expected a 2-D array with {len(_MEASURED)} measured columns "
            f"({', '.join(_MEASURED)}), got shape {X.shape}"
        )
    return X


def ebl_feature_matrix(X, out: np.ndarray | None = None) -> np.ndarray:
    """The 56 features of raw measurements given as an array (vectorised, no row loop).

    Parameters
    ----------
    X : array_like, (n, 20)
        Measured columns in :func:`~nirglucose.dataset.measured_columns` order: four ADC
        codes, four reference codes, the twelve physiological entries. Column-major
        (Fortran-ordered) input, as a DataFrame gives, is fastest. [ADC code,
        column units]
    out : numpy.ndarray, optional
        A (56, n) C-contiguous float64 array to write into (its transpose is returned).

    Returns
    -------
    numpy.ndarray
        (n, 56) features in :data:`FEATURE_NAMES` order (a column-major array: each
        feature is contiguous).

    Raises
    ------
    DataError
        Wrong shape, or ADC/reference codes that are not positive and finite (an
        absorbance needs I > 0 and I0 > 0).

    Examples
    --------
    >>> x = np.r_[[2000.0, 2000, 2000, 2000], [3000.0, 3000, 3000, 3000],
    ...           [50, 28, 3, 0.05, 1.8, 100, 120, 72, 16, 33, 60, 1013.25]]
    >>> f = ebl_feature_matrix(x[None])
    >>> f.shape, round(float(f[0, 0]), 6), float(f[0, 4])
    ((1, 56), 0.176091, 0.0)
    """
    X = _check_array(X)
    n = X.shape[0]
    if not X.flags.f_contiguous:
        X = np.asfortranarray(X)
    cols = X.T  # (20, n): each measured column contiguous
    codes = cols[:_PMF0]
    if n and not (codes.min() > 0 and np.isfinite(codes).all()):
        bad = ~((codes > 0) & np.isfinite(codes)).all(axis=0)
        rows = np.flatnonzero(bad)
        raise DataError(
            f"ADC and reference codes must be positive and finite; {len(rows)} rows are "
            f"not, first row {int(rows[0])}"
        )
    if out is None:
        out = np.empty((N_FEATURES, n))
    elif out.shape != (N_FEATURES, n) or not out.flags.c_contiguous:
        raise ValueError(f"out must be a C-contiguous ({N_FEATURES}, {n}) array")
    f = out  # one contiguous row per feature
    A = f[_S_A]
    log10_absorbance(cols[:_N_CH], cols[_N_CH:_PMF0], out=A)
    for m, (i, j) in enumerate(CONTRAST_PAIRS + DIFFERENCE_PAIRS):
        np.subtract(A[i], A[j], out=f[4 + m])
    for m in range(len(CURVATURE_WEIGHTS)):
        row = f[_S_CURV.start + m]
        w0, w1, w2 = CURVATURE_WEIGHTS[m, m : m + 3]
        np.multiply(A[m], w0, out=row)
        row += w1 * A[m + 1]
        row += w2 * A[m + 2]
    for m, (i, j) in enumerate(PRODUCT_PAIRS):
        np.multiply(A[i], A[j], out=f[_S_PROD.start + m])
    pmf = cols[_PMF0:]
    d_t = pmf[9] - SKIN_TEMP_CENTER_C
    d_h = (pmf[5] - HYDRATION_CENTER_PCT) / HYDRATION_CENTER_PCT
    d_p = (pmf[11] - PRESSURE_CENTER_MBAR) / PRESSURE_CENTER_MBAR
    perf = perfusion_index(pmf[9], pmf[6], pmf[11])
    for k in range(_N_CH):
        w = f[_S_W.start + k]
        np.multiply(pmf[4], ALPHA_SKIN_PER_MM[k], out=w)
        w += ALPHA_PERF[k] * perf
        w += ALPHA_MEL[k] * pmf[3]
        w *= A[k]
    np.multiply(d_t, A, out=f[_S_T])
    np.multiply(d_h, A, out=f[_S_H])
    np.multiply(d_p, A, out=f[_S_PRES])
    f[_S_PMF] = pmf
    env = f[_S_ENV2]
    np.multiply(d_t, d_t, out=env[0])
    np.multiply(d_h, d_h, out=env[1])
    np.multiply(d_p, d_p, out=env[2])
    np.multiply(d_t, d_h, out=env[3])
    np.multiply(d_t, d_p, out=env[4])
    np.multiply(d_h, d_p, out=env[5])
    return out.T


#: The closing paragraph of :func:`features_markdown`: what a richer device adds.
_DEVICE_EXTRAS = (
    "A device that records more of the physiology adds its columns as direct entries after",
    "the study's twelve, and a PPG front end's perfusion and saturation modulate the",
    "absorbances as temperature, hydration and pressure do. The `paper` preset's device gives",
    "`blood_volume_pct` (perfusion: blood dominates 850 and 940 nm) and `spo2_pct` (the",
    "Hb/HbO2 balance of the blood's spectrum), so EBL there has **66** features: the 56, the",
    "two direct entries, blood volume × A_k (`dB_x_A_850`, `dB_x_A_940`, `dB_x_A_1050`,",
    "`dB_x_A_1150`, dB = (blood_volume_pct − 2) / 2) and saturation × A_k (`dS_x_A_850`,",
    "`dS_x_A_940`, `dS_x_A_1050`, `dS_x_A_1150`, dS = (spo2_pct − 70) / 70, relative to the",
    "nominal blood of α_perf: 2 %, SO2 0.7). The measured blood volume also replaces the",
    "temperature/pressure proxy as the perfusion P of w_k. On another LED set the same blocks",
    "are built from that set's channels (`features.feature_table`).",
    "",
)


def features_markdown() -> str:
    """The feature table as Markdown (the content of ``docs/features.md``)."""
    lines = [
        "# The 56 Enhanced Beer–Lambert features",
        "",
        "Generated from `nirglucose.features.FEATURE_TABLE` (`features_markdown()`); a test",
        "keeps this file in sync. Inputs are the measured columns only: ADC codes `adc_<nm>`,",
        "reference intensities `adc_ref_<nm>` and the measured physiological vector.",
        "",
        "Notation: A_k = log10(I0_k / I_k) with I0 = `adc_ref_k`, I = `adc_k`;",
        f"dT = skin_temp_c − {SKIN_TEMP_CENTER_C:g} °C; "
        f"dH = (hydration_pct − {HYDRATION_CENTER_PCT:g}) / {HYDRATION_CENTER_PCT:g}; "
        f"dP = (pressure_mbar − {PRESSURE_CENTER_MBAR:g}) / {PRESSURE_CENTER_MBAR:g};",
        "perfusion index P = exp(0.03 dT + 0.002 (systolic_bp_mmhg − 120) + 0.001 "
        "(pressure_mbar − 1013.25));",
        "w_k = α_skin,k · skin_thickness_mm + α_perf,k · P + α_mel,k · melanin_fraction, with",
        "",
        "| channel | α_skin [1/mm] | α_perf [-] | α_mel [-] |",
        "|---|---|---|---|",
    ]
    for k in range(_N_CH):
        lines.append(
            f"| {_WL[k]} nm | {ALPHA_SKIN_PER_MM[k]:g} | {ALPHA_PERF[k]:g} | {ALPHA_MEL[k]:g} |"
        )
    lines += [
        "",
        "(bloodless dermis absorption per mm; blood at 2 % volume and SO2 0.7 along 1 mm;",
        "melanosome absorption over a round trip through an 80 µm epidermis).",
        "",
        "Count: 4 absorbances + 3 glucose contrasts + 3 other pairwise differences (6 pairs",
        "of 4 channels minus the 3 contrasts) + 2 curvatures (interior channels) + 10",
        "products A_i·A_j, i ≤ j + 4 PMF-weighted absorbances + 3 × 4 temperature, hydration",
        "and pressure × A_k + 12 direct PMF entries + 6 second-order temperature/hydration/",
        "pressure terms = **56**.",
        "",
        "| # | name | formula | category | physical rationale |",
        "|---|---|---|---|---|",
    ]
    for i, f in enumerate(FEATURE_TABLE):
        lines.append(f"| {i} | `{f.name}` | {f.formula} | {f.category} | {f.rationale} |")
    lines += [
        "",
        "Rationale by block: differences cancel the offset that contact, coupling and LED",
        "power add to every channel; 1150 nm sits on glucose's C–H second overtone, 940 and",
        "850 nm are water- and haemoglobin-dominated references; the curvature (a 3-point",
        "second derivative per (100 nm)², non-uniform spacing) removes linear scattering",
        "baselines; products absorb the path-length nonlinearity of the modified",
        "Beer–Lambert law; w_k A_k rescales each channel by the subject's measured skin;",
        "temperature, hydration and pressure modulate absorbances multiplicatively (× A_k)",
        "and act directly (PMF entries and their second-order terms).",
        "",
        *_DEVICE_EXTRAS,
        "Reference: R. Gani, *Physics-Informed Neural Networks vs. Physics Models for",
        "Non-Invasive Glucose Monitoring*, UCL (the Enhanced Beer–Lambert model).",
        "",
    ]
    return "\n".join(lines)
