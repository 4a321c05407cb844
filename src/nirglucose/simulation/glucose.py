"""Glucose layer: snapshots conditioned on diabetes status, meals, stress and time of day.

A subject has a diabetes status (normal, prediabetes, type 1, type 2) and a fasting
baseline; each snapshot adds a postprandial excursion (a gamma-shaped curve peaking
``meal_peak_h`` after a meal), a stress rise and the dawn phenomenon. Values outside
the reported range are reflected back into it, which keeps a continuous density
(no pile-up at the limits, unlike clipping).

References
----------
.. [1] American Diabetes Association, "Standards of Care in Diabetes-2024", Diabetes
   Care 47 (Suppl. 1), S20-S42, section 2 (diagnostic thresholds).
.. [2] D. C. Rizza et al., "Dawn phenomenon in diabetes", N. Engl. J. Med. 310, 746
   (1984) (the early-morning rise).
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from .. import portable as pm
from ..config import ScenarioConfig
from ._random import RandomStreams, categorical, categories

__all__ = [
    "DIABETES_STATUSES",
    "meal_excursion",
    "dawn_profile",
    "reflect_into_range",
    "sample_glucose",
]

DIABETES_STATUSES = ("normal", "prediabetes", "type1", "type2")


def meal_excursion(hours_since_meal: np.ndarray, peak_h: float) -> np.ndarray:
    """Normalised postprandial curve (t / tp) exp(1 - t / tp): 0 at the meal, 1 at tp.

    Examples
    --------
    >>> float(meal_excursion(1.0, 1.0))
    1.0
    """
    x = np.asarray(hours_since_meal, dtype=float) / peak_h
    return x * pm.exp(1.0 - x)


def dawn_profile(hour_of_day: np.ndarray, peak_hour: float, width_h: float) -> np.ndarray:
    """Normalised dawn-phenomenon rise exp(-((h - h_peak) / w)^2): 1 at the peak [2]_.

    The early-morning peak is from Rizza et al. [2]_; the Gaussian shape and width are
    assumptions (``glucose.dawn_peak_hour``, ``glucose.dawn_width_h``).

    Examples
    --------
    >>> float(dawn_profile(6.0, 6.0, 2.0))
    1.0
    """
    return pm.exp(-(((np.asarray(hour_of_day, dtype=float) - peak_hour) / width_h) ** 2))


def reflect_into_range(x: np.ndarray, low: float, high: float) -> np.ndarray:
    """Reflect values at the range limits (a mirror at each end), keeping them inside.

    Examples
    --------
    >>> reflect_into_range(np.array([50.0, 100.0, 410.0]), 60.0, 400.0)
    array([ 70., 100., 390.])
    """
    width = high - low
    y = np.mod(np.asarray(x, dtype=float) - low, 2.0 * width)
    return low + np.where(y > width, 2.0 * width - y, y)


def sample_glucose(
    cfg: ScenarioConfig, n_subjects: int, per_subject: int, streams: RandomStreams,
    *, compiled: bool = True,
) -> dict:
    """Draw statuses (per subject) and glucose snapshots (per measurement).

    ``compiled``: the same draws, then one compiled pass with the same operations in the
    same order (:mod:`nirglucose.simulation.kernels.glucose_kernel`: the same bits);
    False: the NumPy form, the reference.
    """
    g = cfg.glucose
    rng = streams("glucose")
    names = list(g.status_probs)
    probs = np.array([g.status_probs[k] for k in names])
    status_idx = categorical(rng, probs, n_subjects)
    status_codes = status_idx
    fasting_mean = np.array([g.fasting_mgdl[k][0] for k in names])[status_idx]
    fasting_sd = np.array([g.fasting_mgdl[k][1] for k in names])[status_idx]
    baseline = fasting_mean + fasting_sd * rng.normal(size=n_subjects)

    n = n_subjects * per_subject
    rep = np.repeat(np.arange(n_subjects), per_subject)
    hours_since_meal = rng.uniform(*g.hours_since_meal_h, size=n)
    meal_size = rng.lognormal(0.0, g.meal_size_log_sd, size=n)
    peak_by_status = np.array([g.meal_peak_mgdl[k] for k in names], dtype=float)
    stressed = rng.random(size=n) < g.stress_prob
    stress_u = rng.uniform(*g.stress_mgdl, size=n)
    hour = rng.uniform(0.0, 24.0, size=n)  # hour of day
    dawn_by_status = np.array([g.dawn_mgdl[k] for k in names], dtype=float)
    if compiled:
        from .kernels.glucose_kernel import snapshots

        glucose = np.empty(n)
        snapshots(baseline, status_idx, rep, peak_by_status, dawn_by_status,
                  hours_since_meal, meal_size, stressed, stress_u, hour,
                  tuple(float(x) for x in (g.meal_peak_h, g.dawn_peak_hour, g.dawn_width_h,
                                           *g.range_mgdl)), glucose)
    else:
        peak = peak_by_status[status_idx][rep]
        dawn_rise = dawn_by_status[status_idx][rep] * dawn_profile(
            hour, g.dawn_peak_hour, g.dawn_width_h)
        raw = (
            baseline[rep]
            + peak * meal_size * meal_excursion(hours_since_meal, g.meal_peak_h)
            + np.where(stressed, stress_u, 0.0)
            + dawn_rise
        )
        glucose = reflect_into_range(raw, *g.range_mgdl)
    return {
        "glucose_mgdl": glucose,
        "diabetes_status": pd.Categorical.from_codes(status_codes[rep],
                                                   dtype=categories(tuple(names))),
        "true_hours_since_meal": hours_since_meal,
        "true_stress": stressed.astype(np.int64),
        "true_hour_of_day": hour,
    }
