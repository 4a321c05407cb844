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

The package, by concept: :mod:`~nirglucose.features.blocks` (the parameters above, the
environment symbols and the kernels :func:`log10_absorbance` and :func:`perfusion_index`),
:mod:`~nirglucose.features.table` (the one table builder,
:func:`~nirglucose.features.table.build_feature_table`, for any device),
:mod:`~nirglucose.features.study` (:data:`FEATURE_TABLE`: that builder at the study's
device with the study's notes, and the vectorised :func:`ebl_feature_matrix`),
:mod:`~nirglucose.features.device` (:func:`feature_table` of any device and
:func:`compute_features`) and :mod:`~nirglucose.features.transform`
(:func:`enhanced_beer_lambert` and :class:`EnhancedBeerLambertFeatures`); every public
name is importable from ``nirglucose.features``.

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

from .blocks import _ENV as _ENV  # the environment symbols, read by export/c_codegen.py
from .blocks import (
    ALPHA_MEL,
    ALPHA_PERF,
    ALPHA_SKIN_PER_MM,
    CONTRAST_PAIRS,
    CURVATURE_WEIGHTS,
    DIFFERENCE_PAIRS,
    HYDRATION_CENTER_PCT,
    NOMINAL_BLOOD_PCT,
    NOMINAL_SO2_PCT,
    PERFUSION_COEFFS,
    PRESSURE_CENTER_MBAR,
    PRODUCT_PAIRS,
    SKIN_TEMP_CENTER_C,
    FeatureSpec,
    log10_absorbance,
    nuisance_alphas,
    perfusion_index,
)
from .device import compute_features, feature_table
from .study import FEATURE_NAMES, FEATURE_TABLE, N_FEATURES, ebl_feature_matrix, features_markdown
from .transform import (
    EnhancedBeerLambertFeatures,
    MeasurementTransformer,
    enhanced_beer_lambert,
)

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
    "MeasurementTransformer",
    "feature_table",
    "compute_features",
    "nuisance_alphas",
]
