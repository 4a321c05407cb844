"""The 56 Enhanced Beer–Lambert features (function and scikit-learn transformer).

The features are computed from the measured columns only (ADC codes ``adc_<nm>``,
the device's reference intensities ``adc_ref_<nm>`` and the measured physiological
vector :data:`~nirglucose.dataset.PMF_COLUMNS`), never from ``true_*`` columns. They
follow the categories of the reference study's Enhanced Beer–Lambert model [1]_:

==========================  =====  ==========================================
block                       count  running total
==========================  =====  ==========================================
log absorbances A_k             4     4
glucose contrasts               3     7
other pairwise differences      3    10   (6 pairs of 4 channels, minus 3)
second-order curvature          2    12   (interior channels 940 and 1050)
products A_i A_j, i <= j       10    22   (4 squares + 6 cross products)
PMF-weighted absorbances        4    26   (one w_k A_k per channel)
temperature x A_k               4    30
hydration x A_k                 4    34
pressure x A_k                  4    38
direct PMF entries             12    50
temp/hydration/pressure 2nd     6    56   (3 squares + 3 cross products)
==========================  =====  ==========================================

so 4 + 3 + 3 + 2 + 10 + 4 + 3 x 4 + 12 + 6 = 56.

Notation: A_k = log10(I0_k / I_k) with I0 = ``adc_ref_k`` and I = ``adc_k``, channels
k = 850, 940, 1050, 1150 nm. dT = skin_temp_c − 33 [°C], dH = (hydration_pct − 100) /
100 [-], dP = (pressure_mbar − 1013.25) / 1013.25 [-]. The perfusion index
P = exp(0.03 dT + 0.002 (systolic_bp_mmhg − 120) + 0.001 (pressure_mbar − 1013.25)) and
the per-channel nuisance weight w_k = α_skin,k t + α_perf,k P + α_mel,k M with
t = skin_thickness_mm and M = melanin_fraction (coefficients in
:data:`ALPHA_SKIN_PER_MM`, :data:`ALPHA_PERF`, :data:`ALPHA_MEL`).

Every feature (the same table is in ``docs/features.md``; :func:`features_markdown`
generates it):

==  =================  =======================  ==========  ===============================
#   name               formula                  category    physical rationale
==  =================  =======================  ==========  ===============================
0   A_850              log10(I0_850/I_850)      absorbance  Hb/HbO2 and melanin band
1   A_940              log10(I0_940/I_940)      absorbance  water shoulder, perfusion
2   A_1050             log10(I0_1050/I_1050)    absorbance  glucose 2nd-overtone flank
3   A_1150             log10(I0_1150/I_1150)    absorbance  glucose C-H 2nd overtone peak
4   dA_1150_940        A_1150 - A_940           contrast    glucose vs water reference
5   dA_1050_850        A_1050 - A_850           contrast    glucose flank vs Hb reference
6   dA_1150_1050       A_1150 - A_1050          contrast    glucose overtone slope
7   dA_940_850         A_940 - A_850            difference  cancels coupling; blood/water
8   dA_1050_940        A_1050 - A_940           difference  cancels coupling; water slope
9   dA_1150_850        A_1150 - A_850           difference  cancels coupling; full span
10  d2A_940            d2A/dλ² (850,940,1050)   curvature   removes linear scatter baseline
11  d2A_1050           d2A/dλ² (940,1050,1150)  curvature   removes linear scatter baseline
12  A_850_x_A_850      A_850^2                  product     path-length nonlinearity
13  A_850_x_A_940      A_850 A_940              product     path-length nonlinearity
14  A_850_x_A_1050     A_850 A_1050             product     path-length nonlinearity
15  A_850_x_A_1150     A_850 A_1150             product     path-length nonlinearity
16  A_940_x_A_940      A_940^2                  product     path-length nonlinearity
17  A_940_x_A_1050     A_940 A_1050             product     path-length nonlinearity
18  A_940_x_A_1150     A_940 A_1150             product     path-length nonlinearity
19  A_1050_x_A_1050    A_1050^2                 product     path-length nonlinearity
20  A_1050_x_A_1150    A_1050 A_1150            product     path-length nonlinearity
21  A_1150_x_A_1150    A_1150^2                 product     path-length nonlinearity
22  w_x_A_850          w_850 A_850              pmf-weight  skin/blood/melanin path weight
23  w_x_A_940          w_940 A_940              pmf-weight  skin/blood/melanin path weight
24  w_x_A_1050         w_1050 A_1050            pmf-weight  skin/blood/melanin path weight
25  w_x_A_1150         w_1150 A_1150            pmf-weight  skin/blood/melanin path weight
26  dT_x_A_850         dT A_850                 temp        LED/water-band thermal drift
27  dT_x_A_940         dT A_940                 temp        LED/water-band thermal drift
28  dT_x_A_1050        dT A_1050                temp        LED/water-band thermal drift
29  dT_x_A_1150        dT A_1150                temp        LED/water-band thermal drift
30  dH_x_A_850         dH A_850                 hydration   water share of absorbance
31  dH_x_A_940         dH A_940                 hydration   water share of absorbance
32  dH_x_A_1050        dH A_1050                hydration   water share of absorbance
33  dH_x_A_1150        dH A_1150                hydration   water share of absorbance
34  dP_x_A_850         dP A_850                 pressure    perfusion/contact with pressure
35  dP_x_A_940         dP A_940                 pressure    perfusion/contact with pressure
36  dP_x_A_1050        dP A_1050                pressure    perfusion/contact with pressure
37  dP_x_A_1150        dP A_1150                pressure    perfusion/contact with pressure
38  age_yr             age_yr                   pmf         dermal thinning, collagen
39  bmi_kgm2           bmi_kgm2                 pmf         subcutaneous fat, lipid band
40  fitzpatrick_type   fitzpatrick_type         pmf         epidermal melanin class
41  melanin_fraction   melanin_fraction         pmf         epidermal absorption
42  skin_thickness_mm  skin_thickness_mm        pmf         dermal path length
43  hydration_pct      hydration_pct            pmf         dermal water content
44  systolic_bp_mmhg   systolic_bp_mmhg         pmf         perfusion (blood volume)
45  heart_rate_bpm     heart_rate_bpm           pmf         pulsatile blood volume
46  resp_rate_bpm      resp_rate_bpm            pmf         respiratory blood volume
47  skin_temp_c        skin_temp_c              pmf         water band, vasodilation
48  humidity_pct       humidity_pct             pmf         optical coupling loss
49  pressure_mbar      pressure_mbar            pmf         perfusion, probe contact
50  dT_sq              dT^2                     env-2nd     nonlinear thermal drift
51  dH_sq              dH^2                     env-2nd     nonlinear water effect
52  dP_sq              dP^2                     env-2nd     nonlinear pressure effect
53  dT_x_dH            dT dH                    env-2nd     temperature-water coupling
54  dT_x_dP            dT dP                    env-2nd     temperature-perfusion coupling
55  dH_x_dP            dH dP                    env-2nd     water-perfusion coupling
==  =================  =======================  ==========  ===============================

Physical rationale by block:

* **Absorbances.** Beer–Lambert: A_k = ε_k c l + nuisance, linear in each absorber's
  concentration; the device's start-up reference plays I0.
* **Glucose contrasts and differences.** Contact, coupling and LED-power changes add
  nearly the same offset to every A_k; differences cancel it. 1150 nm sits on glucose's
  C–H second overtone; 940 and 850 nm are water- and haemoglobin-dominated references.
* **Curvature.** A three-point second derivative in wavelength (non-uniform spacing,
  per (100 nm)²) removes offsets and linear slopes such as the scattering baseline
  μs'(λ) = a (λ/500 nm)^−b.
* **Products.** The modified Beer–Lambert path length depends on absorption itself
  (the differential path-length factor falls as μa grows), so A is not exactly linear in
  concentration; second-order terms absorb this curvature.
* **PMF-weighted absorbances.** w_k estimates the per-channel optical density of the
  skin that is not glucose (dermal water/baseline over the thickness, blood scaled by
  perfusion, round-trip epidermal melanin); w_k A_k lets the model rescale each channel
  by the subject's measured skin.
* **Temperature, hydration and pressure terms.** Water bands shift and LEDs drift with
  temperature, the water share of μa follows hydration, and perfusion and contact follow
  pressure; they modulate the absorbances multiplicatively (x A_k) and act directly
  (PMF entries and their second-order terms).

References
----------
.. [1] R. Gani, "Physics-Informed Neural Networks vs. Physics Models for Non-Invasive
   Glucose Monitoring: A Comparative Study Under Noise-Stressed Synthetic Conditions",
   University College London.
.. [2] M. Cope, D. T. Delpy, "System for long-term measurement of cerebral blood and
   tissue oxygenation on newborn infants by near infra-red transillumination",
   Med. Biol. Eng. Comput. 26, 289-294 (1988), doi:10.1007/BF02447083 (modified
   Beer–Lambert law).
.. [3] S. L. Jacques, "Optical properties of biological tissues: a review",
   Phys. Med. Biol. 58, R37-R61 (2013), doi:10.1088/0031-9155/58/11/R37
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pandas as pd
from sklearn.base import BaseEstimator, TransformerMixin

from .constants import DEFAULT_LED_WAVELENGTHS_NM
from .dataset import PMF_COLUMNS, Dataset, measured_columns
from .exceptions import DataError
from .fitted import require_fitted
from .schema import DeviceSchema, as_raw_input, fit_schema

__all__ = [
    "N_FEATURES",
    "FEATURE_NAMES",
    "FEATURE_TABLE",
    "FeatureSpec",
    "ALPHA_SKIN_PER_MM",
    "ALPHA_PERF",
    "NOMINAL_BLOOD_PCT",
    "NOMINAL_SO2_PCT",
    "ALPHA_MEL",
    "SKIN_TEMP_CENTER_C",
    "HYDRATION_CENTER_PCT",
    "PRESSURE_CENTER_MBAR",
    "CONTRAST_PAIRS",
    "DIFFERENCE_PAIRS",
    "PRODUCT_PAIRS",
    "CURVATURE_WEIGHTS",
    "PERFUSION_COEFFS",
    "ebl_feature_matrix",
    "enhanced_beer_lambert",
    "log10_absorbance",
    "perfusion_index",
    "features_markdown",
    "EnhancedBeerLambertFeatures",
    "feature_table",
    "compute_features",
    "nuisance_alphas",
]

#: Channel labels in measured-column order. [nm]
_WL = tuple(f"{w:g}" for w in DEFAULT_LED_WAVELENGTHS_NM)
_WL_NM = np.asarray(DEFAULT_LED_WAVELENGTHS_NM, dtype=float)
_N_CH = len(_WL)
_N_PMF = len(PMF_COLUMNS)
_MEASURED = tuple(measured_columns())
#: Column positions in the measured array (adc, adc_ref, pmf).
_PMF0 = 2 * _N_CH
_P = {c: _PMF0 + i for i, c in enumerate(PMF_COLUMNS)}

# --- parameters of the features (data, not code: pvlib habit) -------------------------
#: Centre of the temperature terms, a typical wrist skin temperature. [°C]
SKIN_TEMP_CENTER_C = 33.0
#: Centre of the hydration terms, nominal dermal water. [% of nominal]
HYDRATION_CENTER_PCT = 100.0
#: Centre of the pressure terms, standard atmosphere. [mbar]
PRESSURE_CENTER_MBAR = 1013.25
#: Perfusion index P = exp(a dT + b (SBP - 120 mmHg) + c (p - 1013.25 mbar)):
#: vasodilation about 3 %/°C (Charkoudian, Mayo Clin. Proc. 78, 603 (2003)), and a small
#: rise with arterial and ambient pressure. Keys: 'temp' [1/°C], 'sbp' [1/mmHg],
#: 'sbp_center' [mmHg], 'pressure' [1/mbar].
PERFUSION_COEFFS = {"temp": 0.03, "sbp": 0.002, "sbp_center": 120.0, "pressure": 0.001}
#: Bloodless dermis (65 % water + 33 % baseline tissue) absorption per mm of skin at each
#: LED, 0.1 (0.65 mua_water + 0.33 mua_baseline) from the packaged Kou (1993) water and
#: Jacques (2013) baseline tables. [1/mm]
ALPHA_SKIN_PER_MM = (0.0109, 0.0199, 0.0189, 0.0717)
#: Blood at nominal perfusion (2 % blood, SO2 0.7; Bosschaart 2014) along 1 mm of
#: dermal path, per unit perfusion index. [-]
ALPHA_PERF = (0.0094, 0.0117, 0.0082, 0.0053)
#: The blood volume at which the perfusion index is 1 (the 2 % of :data:`ALPHA_PERF`):
#: a device that measures ``blood_volume_pct`` (PPG) gives P = blood_volume_pct / 2
#: instead of the temperature/pressure proxy :func:`perfusion_index`. [%]
NOMINAL_BLOOD_PCT = 2.0
#: The oxygen saturation at which :data:`ALPHA_PERF` is tabulated (SO2 0.7). [%]
NOMINAL_SO2_PCT = 70.0
#: Melanosome absorption (Jacques 1998) over a round trip through an 80 um epidermis,
#: per unit melanosome volume fraction. [-]
ALPHA_MEL = (1.8565, 1.3278, 0.9186, 0.6785)

#: The study's glucose contrasts, as (i, j) channel indices of A_i - A_j.
CONTRAST_PAIRS = ((3, 1), (2, 0), (3, 2))
#: The remaining pairwise differences A_i - A_j.
DIFFERENCE_PAIRS = ((1, 0), (2, 1), (3, 0))
#: Products A_i A_j with i <= j.
PRODUCT_PAIRS = tuple((i, j) for i in range(_N_CH) for j in range(i, _N_CH))


def _curvature_weights(wavelengths_nm: np.ndarray) -> np.ndarray:
    """Weights of the 3-point second derivative at each interior channel, (n_int, n_ch).

    d2A/dx2 = 2 [(A2 - A1)/h2 - (A1 - A0)/h1] / (h1 + h2), x in units of 100 nm.
    """
    x = wavelengths_nm / 100.0
    w = np.zeros((len(x) - 2, len(x)))
    for m in range(1, len(x) - 1):
        h1, h2 = x[m] - x[m - 1], x[m + 1] - x[m]
        s = 2.0 / (h1 + h2)
        w[m - 1, m - 1] = s / h1
        w[m - 1, m] = -s * (1.0 / h1 + 1.0 / h2)
        w[m - 1, m + 1] = s / h2
    return w


#: Weights of the curvature features over (A_850, A_940, A_1050, A_1150). [1/(100 nm)^2]
CURVATURE_WEIGHTS = _curvature_weights(_WL_NM)
CURVATURE_WEIGHTS.setflags(write=False)


@dataclass(frozen=True)
class FeatureSpec:
    """One feature: its name, formula, category and physical rationale."""

    name: str
    formula: str
    category: str
    rationale: str
    #: How to compute it from (A, physiology): ``("A", k)``, ``("lin", ((k, w), ...))``,
    #: ``("AA", i, j)``, ``("w", k, a_skin, a_perf, a_mel)``, ``("envA", sym, k)``,
    #: ``("pmf", m)``, ``("env2", sym1, sym2)``; sym in dT, dH, dP.
    op: tuple = field(default=(), compare=False, repr=False)


def _build_table() -> tuple[FeatureSpec, ...]:
    rows: list[FeatureSpec] = []
    a = [f"A_{w}" for w in _WL]
    why_a = (
        "Hb/HbO2 and melanin band",
        "water shoulder, perfusion",
        "glucose 2nd-overtone flank",
        "glucose C-H 2nd overtone peak",
    )
    for k in range(_N_CH):
        rows.append(FeatureSpec(a[k], f"log10(I0_{_WL[k]}/I_{_WL[k]})", "absorbance", why_a[k]))
    why_c = (
        "glucose vs water reference",
        "glucose flank vs Hb reference",
        "glucose overtone slope",
    )
    for (i, j), why in zip(CONTRAST_PAIRS, why_c, strict=True):
        rows.append(FeatureSpec(f"dA_{_WL[i]}_{_WL[j]}", f"{a[i]} - {a[j]}", "contrast", why))
    why_d = (
        "cancels coupling; blood/water",
        "cancels coupling; water slope",
        "cancels coupling; full span",
    )
    for (i, j), why in zip(DIFFERENCE_PAIRS, why_d, strict=True):
        rows.append(FeatureSpec(f"dA_{_WL[i]}_{_WL[j]}", f"{a[i]} - {a[j]}", "difference", why))
    for m in range(1, _N_CH - 1):
        rows.append(
            FeatureSpec(
                f"d2A_{_WL[m]}",
                f"d2A/dλ² ({_WL[m - 1]},{_WL[m]},{_WL[m + 1]})",
                "curvature",
                "removes linear scatter baseline",
            )
        )
    for i, j in PRODUCT_PAIRS:
        formula = f"{a[i]}^2" if i == j else f"{a[i]} {a[j]}"
        rows.append(FeatureSpec(f"{a[i]}_x_{a[j]}", formula, "product", "path-length nonlinearity"))
    for k in range(_N_CH):
        rows.append(
            FeatureSpec(
                f"w_x_{a[k]}", f"w_{_WL[k]} {a[k]}", "pmf-weight", "skin/blood/melanin path weight"
            )
        )
    for sym, cat, why in (
        ("dT", "temp", "LED/water-band thermal drift"),
        ("dH", "hydration", "water share of absorbance"),
        ("dP", "pressure", "perfusion/contact with pressure"),
    ):
        for k in range(_N_CH):
            rows.append(FeatureSpec(f"{sym}_x_{a[k]}", f"{sym} {a[k]}", cat, why))
    why_pmf = {
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
    for c in PMF_COLUMNS:
        rows.append(FeatureSpec(c, c, "pmf", why_pmf[c]))
    for name, formula, why in (
        ("dT_sq", "dT^2", "nonlinear thermal drift"),
        ("dH_sq", "dH^2", "nonlinear water effect"),
        ("dP_sq", "dP^2", "nonlinear pressure effect"),
        ("dT_x_dH", "dT dH", "temperature-water coupling"),
        ("dT_x_dP", "dT dP", "temperature-perfusion coupling"),
        ("dH_x_dP", "dH dP", "water-perfusion coupling"),
    ):
        rows.append(FeatureSpec(name, formula, "env-2nd", why))
    return tuple(rows)


#: Every feature, in output order.
FEATURE_TABLE: tuple[FeatureSpec, ...] = _build_table()
#: Feature names, in output order.
FEATURE_NAMES: tuple[str, ...] = tuple(f.name for f in FEATURE_TABLE)
#: Number of features (56, the study's count).
N_FEATURES = len(FEATURE_TABLE)
assert N_FEATURES == 56, N_FEATURES  # the arithmetic in the module docstring

# Slices of the output by block (used by the estimators' fast paths and the C export).
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

_DIFF_W = np.zeros((_N_CH, 6))
for _c, (_i, _j) in enumerate(CONTRAST_PAIRS + DIFFERENCE_PAIRS):
    _DIFF_W[_i, _c], _DIFF_W[_j, _c] = 1.0, -1.0
_PI = np.array([i for i, _ in PRODUCT_PAIRS])
_PJ = np.array([j for _, j in PRODUCT_PAIRS])


def _check_array(X) -> np.ndarray:
    X = np.asarray(X, dtype=float)
    if X.ndim != 2 or X.shape[1] != len(_MEASURED):
        raise DataError(
            f"expected a 2-D array with {len(_MEASURED)} measured columns "
            f"({', '.join(_MEASURED)}), got shape {X.shape}"
        )
    return X


_LOG10_2 = float(np.log10(2.0))
_LOG2_E = float(np.log2(np.e))


def log10_absorbance(adc, adc_ref, out: np.ndarray | None = None) -> np.ndarray:
    """Absorbance A = log10(I0 / I) from ADC codes I and reference codes I0.

    Evaluated as log2(I0 / I) log10(2), the same number to rounding but several times
    faster than :func:`numpy.log10` on common CPUs.

    Parameters
    ----------
    adc : array_like
        Detected intensity I (ADC codes), positive. [ADC code]
    adc_ref : array_like
        Reference intensity I0 (ADC codes), positive, broadcastable with ``adc``.
        [ADC code]
    out : numpy.ndarray, optional
        Output array.

    Returns
    -------
    numpy.ndarray
        Absorbance. [-]

    Examples
    --------
    >>> float(log10_absorbance(100.0, 1000.0))
    1.0
    """
    out = np.asarray(np.divide(adc_ref, adc, out=out), dtype=float)
    np.log2(out, out=out)
    out *= _LOG10_2
    return out


def perfusion_index(skin_temp_c, systolic_bp_mmhg, pressure_mbar, out=None) -> np.ndarray:
    """Relative perfusion P = exp(0.03 dT + 0.002 (SBP - 120) + 0.001 (p - 1013.25)).

    Parameters
    ----------
    skin_temp_c : array_like
        Measured skin temperature. [°C]
    systolic_bp_mmhg : array_like
        Measured systolic blood pressure. [mmHg]
    pressure_mbar : array_like
        Measured barometric pressure. [mbar]
    out : numpy.ndarray, optional
        Output array.

    Returns
    -------
    numpy.ndarray
        P, 1 at 33 °C, 120 mmHg and 1013.25 mbar. [-]

    Examples
    --------
    >>> float(perfusion_index(33.0, 120.0, 1013.25))
    1.0
    """
    pc = PERFUSION_COEFFS
    x = np.asarray(np.subtract(skin_temp_c, SKIN_TEMP_CENTER_C, out=out), dtype=float)
    x *= pc["temp"] * _LOG2_E
    x += (pc["sbp"] * _LOG2_E) * (np.asarray(systolic_bp_mmhg) - pc["sbp_center"])
    x += (pc["pressure"] * _LOG2_E) * (np.asarray(pressure_mbar) - PRESSURE_CENTER_MBAR)
    return np.exp2(x, out=x)  # exp(y) = 2^(y log2 e): same value, faster


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


# ----------------------------------------------------------------- any device


#: Environment symbols, the column each needs, and its centring (x - c) / s.
_ENV = {
    "dT": ("skin_temp_c", SKIN_TEMP_CENTER_C, 1.0),
    "dH": ("hydration_pct", HYDRATION_CENTER_PCT, HYDRATION_CENTER_PCT),
    "dP": ("pressure_mbar", PRESSURE_CENTER_MBAR, PRESSURE_CENTER_MBAR),
    # A device that measures perfusion and saturation (PPG): blood's share of each
    # absorbance scales with its volume, and its spectrum with its saturation, relative to
    # the nominal blood of ALPHA_PERF (2 %, SO2 0.7).
    "dB": ("blood_volume_pct", NOMINAL_BLOOD_PCT, NOMINAL_BLOOD_PCT),
    "dS": ("spo2_pct", NOMINAL_SO2_PCT, NOMINAL_SO2_PCT),
}
_W_COLUMNS = (
    "skin_thickness_mm",
    "melanin_fraction",
    "skin_temp_c",
    "systolic_bp_mmhg",
    "pressure_mbar",
)
_ENV2 = (("dT", "dT"), ("dH", "dH"), ("dP", "dP"), ("dT", "dH"), ("dT", "dP"), ("dH", "dP"))


def nuisance_alphas(wavelength_nm: float) -> tuple[float, float, float]:
    """(α_skin, α_perf, α_mel) of the PMF weight w at one LED wavelength.

    The study's four LEDs use the tabulated :data:`ALPHA_SKIN_PER_MM`, :data:`ALPHA_PERF`
    and :data:`ALPHA_MEL`; any other wavelength computes them the same way from the
    packaged tables: 0.1 (0.65 μa_water + 0.33 μa_baseline) per mm of skin (Kou 1993
    water, Jacques 1998 baseline), 0.02 μa_blood(SO2 0.7) over 1 mm (Bosschaart 2014),
    μa_melanosome over a round trip through 80 μm of epidermis (Jacques 1998).

    Parameters
    ----------
    wavelength_nm : float
        LED wavelength. [nm]

    Returns
    -------
    tuple of float
        α_skin [1/mm], α_perf [-], α_mel [-].
    """
    study = [float(w) for w in DEFAULT_LED_WAVELENGTHS_NM]
    if float(wavelength_nm) in study:
        k = study.index(float(wavelength_nm))
        return ALPHA_SKIN_PER_MM[k], ALPHA_PERF[k], ALPHA_MEL[k]
    from .optics.absorption import (
        blood_mua_per_cm,
        melanosome_mua_per_cm,
        skin_baseline_mua_per_cm,
        water_mua_per_cm,
    )

    wl = np.array([float(wavelength_nm)])
    skin = 0.1 * (0.65 * water_mua_per_cm(wl) + 0.33 * skin_baseline_mua_per_cm(wl))
    perf = 0.02 * blood_mua_per_cm(wl, 0.7) * 0.1
    mel = melanosome_mua_per_cm(wl) * 2 * 0.008
    return float(skin[0]), float(perf[0]), float(mel[0])


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
    k = len(lab)
    a = [f"A_{w}" for w in lab]
    rows: list[FeatureSpec] = []
    for i in range(k):
        rows.append(
            FeatureSpec(
                a[i],
                f"log10(I0_{lab[i]}/I_{lab[i]})",
                "absorbance",
                "absorbance at this LED",
                ("A", i),
            )
        )
    for i in range(k):
        for j in range(i):
            rows.append(
                FeatureSpec(
                    f"dA_{lab[i]}_{lab[j]}",
                    f"{a[i]} - {a[j]}",
                    "difference",
                    "cancels coupling and LED-power offsets",
                    ("lin", ((i, 1.0), (j, -1.0))),
                )
            )
    if k >= 3:
        x = (
            np.asarray(schema.wavelengths_nm, dtype=float)
            if not schema.is_plain
            else 100.0 * np.arange(k)
        )
        cw = _curvature_weights(x)
        for m in range(1, k - 1):
            rows.append(
                FeatureSpec(
                    f"d2A_{lab[m]}",
                    f"d2A/dλ² ({lab[m - 1]},{lab[m]},{lab[m + 1]})",
                    "curvature",
                    "removes linear scatter baseline",
                    ("lin", tuple((c, float(cw[m - 1, c])) for c in (m - 1, m, m + 1))),
                )
            )
    for i in range(k):
        for j in range(i, k):
            formula = f"{a[i]}^2" if i == j else f"{a[i]} {a[j]}"
            rows.append(
                FeatureSpec(
                    f"{a[i]}_x_{a[j]}", formula, "product", "path-length nonlinearity", ("AA", i, j)
                )
            )
    phys = schema.physiology
    if all(c in phys for c in _W_COLUMNS):
        for i, w in enumerate(schema.wavelengths_nm):
            rows.append(
                FeatureSpec(
                    f"w_x_{a[i]}",
                    f"w_{lab[i]} {a[i]}",
                    "pmf-weight",
                    "skin/blood/melanin path weight",
                    ("w", i, *nuisance_alphas(w)),
                )
            )
    syms = [s for s in _ENV if _ENV[s][0] in phys]
    cat = {
        "dT": ("temp", "LED/water-band thermal drift"),
        "dH": ("hydration", "water share of absorbance"),
        "dP": ("pressure", "perfusion/contact with pressure"),
        "dB": ("blood-volume", "blood's share of the absorbance (PPG perfusion)"),
        "dS": ("saturation", "Hb/HbO2 balance of the blood's spectrum (PPG SpO2)"),
    }
    for s in syms:
        for i in range(k):
            rows.append(FeatureSpec(f"{s}_x_{a[i]}", f"{s} {a[i]}", *cat[s], ("envA", s, i)))
    for m, c in enumerate(phys):
        rows.append(FeatureSpec(c, c, "pmf", "measured physiology", ("pmf", m)))
    for s1, s2 in _ENV2:
        if s1 in syms and s2 in syms:
            name = f"{s1}_sq" if s1 == s2 else f"{s1}_x_{s2}"
            formula = f"{s1}^2" if s1 == s2 else f"{s1} {s2}"
            rows.append(
                FeatureSpec(name, formula, "env-2nd", "second-order environment", ("env2", s1, s2))
            )
    return tuple(rows)


def _study_ops() -> None:
    """Attach the ops to the study's fixed table (same numbers as ebl_feature_matrix)."""
    ops: list[tuple] = [("A", k) for k in range(_N_CH)]
    ops += [("lin", ((i, 1.0), (j, -1.0))) for i, j in CONTRAST_PAIRS + DIFFERENCE_PAIRS]
    for m in range(len(CURVATURE_WEIGHTS)):
        ops.append(("lin", tuple((c, float(CURVATURE_WEIGHTS[m, c])) for c in (m, m + 1, m + 2))))
    ops += [("AA", i, j) for i, j in PRODUCT_PAIRS]
    ops += [("w", k, ALPHA_SKIN_PER_MM[k], ALPHA_PERF[k], ALPHA_MEL[k]) for k in range(_N_CH)]
    ops += [("envA", s, k) for s in ("dT", "dH", "dP") for k in range(_N_CH)]
    ops += [("pmf", m) for m in range(_N_PMF)]
    ops += [("env2", s1, s2) for s1, s2 in _ENV2]
    for spec, op in zip(FEATURE_TABLE, ops, strict=True):
        object.__setattr__(spec, "op", op)


_study_ops()


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


def enhanced_beer_lambert(
    frame: pd.DataFrame | Dataset, adc_bits: int | None = None
) -> pd.DataFrame:
    """The Enhanced Beer–Lambert features of a device's measurements.

    Parameters
    ----------
    frame : pandas.DataFrame or Dataset
        Measurements with ``adc_<nm>`` columns (any LEDs), optional ``adc_ref_<nm>``
        and any known physiological columns; other columns (``true_*``) are ignored.
    adc_bits : int, optional
        Declared ADC resolution (else the file's, or 12). [bit]

    Returns
    -------
    pandas.DataFrame
        (n, p) features of :func:`feature_table` (56 at the study's device), the
        input's index.

    Raises
    ------
    DataError
        Missing columns, non-numeric cells, NaN, ADC codes out of range, implausible
        physiology (the message names the column and rows).

    Examples
    --------
    >>> import nirglucose as ng
    >>> ds = ng.simulate("wearable", n_subjects=2, per_subject=2, seed=0)
    >>> enhanced_beer_lambert(ds).shape
    (4, 56)
    """
    schema = DeviceSchema.infer(frame, adc_bits)
    if isinstance(frame, Dataset):
        frame = frame.frame
    Xa = schema.raw(frame)
    table = feature_table(schema)
    if schema.is_study:
        values = ebl_feature_matrix(Xa)
    else:
        m = schema.split(Xa)
        values = compute_features(table, schema, m.absorbance, m.physiology)
    return pd.DataFrame(
        values,
        columns=[f.name for f in table],
        index=frame.index,
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
        "Reference: R. Gani, *Physics-Informed Neural Networks vs. Physics Models for",
        "Non-Invasive Glucose Monitoring*, UCL (the Enhanced Beer–Lambert model).",
        "",
    ]
    return "\n".join(lines)


class EnhancedBeerLambertFeatures(TransformerMixin, BaseEstimator):
    """scikit-learn transformer: a device's measured columns -> its EBL features.

    ``fit`` records the device (:class:`~nirglucose.schema.DeviceSchema`: from the
    column names of a frame, or plain for an array) and the feature table
    (:func:`feature_table`; 56 features at the study's device), so it can sit in a
    :class:`~sklearn.pipeline.Pipeline` before a scaler and a regressor.

    Parameters
    ----------
    adc_bits : int, optional
        Declared ADC resolution (else the data's, or 12). [bit]

    Examples
    --------
    >>> import nirglucose as ng
    >>> ds = ng.simulate("wearable", n_subjects=2, per_subject=2, seed=0)
    >>> t = EnhancedBeerLambertFeatures().fit(ds.frame)
    >>> t.transform(ds.frame).shape, t.get_feature_names_out()[4]
    ((4, 56), 'dA_1150_940')
    """

    def __init__(self, adc_bits: int | None = None):
        self.adc_bits = adc_bits

    def fit(self, X, y=None):
        """Record the device's schema and feature table; returns self."""
        self.schema_ = fit_schema(self, X, self.adc_bits)
        self.table_ = feature_table(self.schema_)
        if isinstance(X, pd.DataFrame | Dataset):
            self.schema_.raw(X)
        return self

    def transform(self, X) -> np.ndarray:
        """The (n, p) feature matrix."""
        require_fitted(self, "schema_")
        Xa = self.schema_.raw(as_raw_input(self, X, self.schema_))
        if self.schema_.is_study:
            return ebl_feature_matrix(Xa)
        m = self.schema_.split(Xa)
        return compute_features(self.table_, self.schema_, m.absorbance, m.physiology)

    def get_feature_names_out(self, input_features=None) -> np.ndarray:
        """The feature names."""
        require_fitted(self, "schema_")
        return np.asarray([f.name for f in self.table_], dtype=object)

    def __sklearn_tags__(self):
        tags = super().__sklearn_tags__()
        tags.requires_fit = True
        if tags.transformer_tags is not None:
            tags.transformer_tags.preserves_dtype = ["float64"]  # always float64 out
        return tags
