"""The shared building blocks of the Enhanced Beer–Lambert features.

The parameters of the features (centres, nuisance coefficients, channel pairs and
curvature weights), the environment symbols dT, dH, dP, dB, dS (:data:`_ENV`), the
:class:`FeatureSpec` row type and the two kernels every table uses
(:func:`log10_absorbance`, :func:`perfusion_index`). The study's table
(:mod:`~nirglucose.features.study`) and the any-device table
(:mod:`~nirglucose.features.device`) are both built from these.

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

from ..constants import DEFAULT_LED_WAVELENGTHS_NM
from ..dataset import PMF_COLUMNS, measured_columns
from ..optics.absorption import (
    blood_mua_per_cm,
    melanosome_mua_per_cm,
    skin_baseline_mua_per_cm,
    water_mua_per_cm,
)

__all__ = [
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
    "log10_absorbance",
    "perfusion_index",
    "nuisance_alphas",
]

#: Channel labels in measured-column order. [nm]
_WL = tuple(f"{w:g}" for w in DEFAULT_LED_WAVELENGTHS_NM)
_WL_NM = np.asarray(DEFAULT_LED_WAVELENGTHS_NM, dtype=float)
_N_CH = len(_WL)
_N_PMF = len(PMF_COLUMNS)
_MEASURED = tuple(measured_columns())
#: Position of the first physiological column in the measured array (adc, adc_ref, pmf).
_PMF0 = 2 * _N_CH

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
#: The columns the PMF weight w needs.
_W_COLUMNS = (
    "skin_thickness_mm",
    "melanin_fraction",
    "skin_temp_c",
    "systolic_bp_mmhg",
    "pressure_mbar",
)
#: The second-order environment terms, in output order.
_ENV2 = (("dT", "dT"), ("dH", "dH"), ("dP", "dP"), ("dT", "dH"), ("dT", "dP"), ("dH", "dP"))

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

    wl = np.array([float(wavelength_nm)])
    skin = 0.1 * (0.65 * water_mua_per_cm(wl) + 0.33 * skin_baseline_mua_per_cm(wl))
    perf = 0.02 * blood_mua_per_cm(wl, 0.7) * 0.1
    mel = melanosome_mua_per_cm(wl) * 2 * 0.008
    return float(skin[0]), float(perf[0]), float(mel[0])
