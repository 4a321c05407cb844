"""How a type 1 patient's basal-bolus therapy departs from the ideal, day by day.

A type 1 virtual patient dosed exactly (every meal bolused, every carbohydrate count
right, the same insulin sensitivity every day) stays in range far more than people with
type 1 diabetes do. Three imperfections are drawn here, each from a published value
(``data/uva_padova/type1_therapy.csv``, SOURCES.md there):

* **Carbohydrate counting.** The patient doses for an estimate, true x exp(s Z), Z
  standard normal. Adults with type 1 diabetes miss a meal's carbohydrate by about
  20 % on average (Brazeau et al. 2013 [1]_); ``s`` is the log-SD whose mean absolute
  relative error is that value, E|exp(s Z) - 1| = exp(s^2 / 2) (2 Phi(s) - 1)
  (:func:`carb_count_log_sd`; s = 0.246 for 20 %). Unbiased in the median (an
  assumption: the study's direction of error is not used).
* **Missed boluses.** Each meal's bolus is skipped with the probability a real-world
  smart-pen study measured for that meal on a day (Ampudia-Blasco et al. 2024 [2]_:
  7.5 % breakfast, 12.2 % lunch, 11.1 % dinner; adults with type 1 or type 2 diabetes
  on bolus insulin), independently of other meals (an assumption). A dose later than
  60 min after the meal counted as missed there, so no separate late bolus is drawn.
* **Day-to-day insulin sensitivity.** Both insulin actions of the model (``Vmx``,
  peripheral utilisation; ``kp3``, suppression of liver glucose production) are scaled
  for a whole day by one factor, log-normal of median 1, whose coefficient of variation
  is that of adults' total daily insulin requirement under closed loop, 17 % (Ruan et
  al. 2016 [3]_): log-SD sqrt(ln(1 + CV^2)) (:func:`daily_sensitivity_log_sd`). The
  day's need varies as 1 / SI, and 1 / factor has the same CV; the published CV also
  holds the day-to-day change of what was eaten, so this is an upper estimate of the
  sensitivity's part (stated, not corrected). Time-varying ``Vmx`` and ``kp3`` follow
  the UVA/Padova S2017 simulator's time-varying insulin sensitivity (Visentin et al.
  2018 [4]_); its within-day pattern is not modelled (Hinshaw et al. [5]_ found it
  specific to the individual, with no population pattern).

Each draw uses one named stream of the subject (:class:`._random.SubjectStreams`):
``wear.missed_bolus`` and ``wear.insulin_sensitivity`` (the carbohydrate estimate keeps
``wear.carb_count``), so the draws do not depend on chunking or workers, and adding one
does not move another.

References
----------
.. [1] A. S. Brazeau, H. Mircescu, K. Desjardins, C. Leroux, I. Strychar, J. M. Ekoé,
   R. Rabasa-Lhoret, "Carbohydrate counting accuracy and blood glucose variability in
   adults with type 1 diabetes", Diabetes Res. Clin. Pract. 99(1), 19-23 (2013).
.. [2] F. J. Ampudia-Blasco et al., "Multinational analysis of factors associated with
   missed bolus insulin doses", Diabetes 73 (Suppl. 1), 843-P (2024).
.. [3] Y. Ruan, H. Thabit, L. Leelarathna et al., "Variability of insulin requirements
   over 12 weeks of closed-loop insulin delivery in adults with type 1 diabetes",
   Diabetes Care 39(5), 830-832 (2016), doi:10.2337/dc15-2623.
.. [4] R. Visentin, E. Campos-Náñez, M. Schiavon, D. Lv, M. Vettoretti, M. Breton,
   B. P. Kovatchev, C. Dalla Man, C. Cobelli, "The UVA/Padova type 1 diabetes simulator
   goes from single meal to single day", J. Diabetes Sci. Technol. 12(2), 273-281
   (2018), doi:10.1177/1932296818757747.
.. [5] L. Hinshaw, C. Dalla Man, D. K. Nandy et al., "Diurnal pattern of insulin action
   in type 1 diabetes: implications for a closed-loop system", Diabetes 62(7),
   2223-2229 (2013).
"""

from __future__ import annotations

import csv
from functools import cache
from importlib import resources

import numpy as np
from scipy.optimize import brentq
from scipy.special import ndtr

from .. import portable as pm
from ..constants import MINUTES_PER_DAY
from ..exceptions import ConfigError

__all__ = [
    "MEALS_PER_DAY",
    "THERAPY_ERRORS",
    "check_therapy_errors",
    "therapy_table",
    "carb_count_log_sd",
    "daily_sensitivity_log_sd",
    "missed_bolus_probabilities",
    "draw_missed_boluses",
    "draw_daily_sensitivity",
    "sensitivity_per_minute",
]

#: Meals of a day the missed-bolus probabilities are given for: breakfast, lunch,
#: dinner (the order of :data:`.meal_scenario.DAILY_MEALS`).
MEALS_PER_DAY = ("breakfast", "lunch", "dinner")
#: The departures from ideal therapy, by name (each can be left out, to ablate it).
THERAPY_ERRORS = ("carb_count", "missed_bolus", "sensitivity")


def check_therapy_errors(errors) -> frozenset[str]:
    """The set of therapy errors named, checked against :data:`THERAPY_ERRORS`.

    Examples
    --------
    >>> sorted(check_therapy_errors(["sensitivity"]))
    ['sensitivity']
    >>> check_therapy_errors(["snacks"])
    Traceback (most recent call last):
    ...
    nirglucose.exceptions.ConfigError: unknown therapy error(s) ['snacks']; valid: carb_count, ...
    """
    chosen = [str(e) for e in errors]
    unknown = [e for e in chosen if e not in THERAPY_ERRORS]
    if unknown:
        raise ConfigError(f"unknown therapy error(s) {unknown}; valid: "
                          f"{', '.join(THERAPY_ERRORS)}")
    return frozenset(chosen)


@cache
def therapy_table() -> dict[str, float]:
    """The published values of ``data/uva_padova/type1_therapy.csv`` [1]_ [2]_ [3]_.

    Examples
    --------
    >>> therapy_table()["daily_insulin_need_cv"]
    0.17
    """
    path = resources.files("nirglucose.data").joinpath("uva_padova", "type1_therapy.csv")
    with path.open(encoding="utf-8") as fh:
        return {r["parameter"]: float(r["value"]) for r in csv.DictReader(fh)}


def _mean_abs_relative_error(log_sd: float) -> float:
    """E|exp(s Z) - 1| for Z standard normal: exp(s^2/2) (2 Phi(s) - 1)."""
    return float(pm.exp(np.array(0.5 * log_sd * log_sd)) * (2.0 * ndtr(log_sd) - 1.0))


@cache
def carb_count_log_sd() -> float:
    """Log-SD of the carbohydrate estimate whose mean absolute relative error is the
    published one (Brazeau et al. [1]_; module docstring). [-]

    Examples
    --------
    >>> round(carb_count_log_sd(), 3)
    0.246
    """
    target = therapy_table()["carb_count_mean_abs_error"]
    return float(brentq(lambda s: _mean_abs_relative_error(s) - target, 1e-9, 5.0,
                        xtol=1e-15, rtol=1e-15))


def daily_sensitivity_log_sd() -> float:
    """Log-SD of the day's insulin-sensitivity factor, sqrt(ln(1 + CV^2)), CV the
    day-to-day variation of the total daily insulin requirement (Ruan et al. [3]_). [-]

    Examples
    --------
    >>> round(daily_sensitivity_log_sd(), 4)
    0.1688
    """
    cv = therapy_table()["daily_insulin_need_cv"]
    return float(np.sqrt(pm.log(np.array(1.0 + cv * cv))))


def missed_bolus_probabilities() -> np.ndarray:
    """Probability that a meal's bolus is missed, per meal of the day (breakfast,
    lunch, dinner; Ampudia-Blasco et al. [2]_). [-]

    Examples
    --------
    >>> missed_bolus_probabilities()
    array([0.075, 0.122, 0.111])
    """
    t = therapy_table()
    return np.array([t[f"missed_bolus_prob_{m}"] for m in MEALS_PER_DAY])


def draw_missed_boluses(rng, n_days: int) -> np.ndarray:
    """Whether each meal's bolus is missed, (n_days * 3,) bool in meal order [2]_.

    One uniform per meal, compared with its meal's probability.
    """
    p = np.tile(missed_bolus_probabilities(), int(n_days))
    return rng.random(size=p.size) < p


def draw_daily_sensitivity(rng, n_days: int) -> np.ndarray:
    """Insulin-sensitivity factor of each day of the wear, log-normal of median 1 [3]_,
    (n_days,). [-]"""
    return pm.exp(daily_sensitivity_log_sd() * rng.normal(size=int(n_days)))


def sensitivity_per_minute(day_factor: np.ndarray, n_min: int) -> np.ndarray:
    """A day's factor at every minute of that day (days from 00:00), (n_min,). [-]

    Examples
    --------
    >>> sensitivity_per_minute(np.array([1.0, 2.0]), 2881)[[0, 1439, 1440, 2880]]
    array([1., 1., 2., 2.])
    """
    day = np.arange(n_min) // MINUTES_PER_DAY
    return np.asarray(day_factor, dtype=float)[np.minimum(day, len(day_factor) - 1)]
