"""A day of meals, and the type 1 therapy that answers them.

Three meals a day at the clock times and carbohydrate sizes of the daily-life
simulation of Dalla Man et al. 2007 [1]_ (breakfast 08:00 45 g, lunch 12:00 70 g,
dinner 20:00 70 g). Each day's meals vary around them: the time by a normal draw of
:data:`MEAL_TIME_SD_MIN` truncated at :data:`MEAL_TIME_LIMIT_MIN`, the size by a
log-normal factor of log-SD :data:`MEAL_SIZE_LOG_SD` (assumptions of this package, the
spread of a regular but not clockwork diet).

Type 1 therapy (basal-bolus): the patient's basal insulin is the delivery that holds
its fasting steady state (``u2ss`` of the virtual patient [2]_); each meal gets a
bolus of carbohydrate / carbohydrate-ratio units at the meal's start (standard carb
counting, ADA Standards of Care 2024, section 9 [3]_), the ratio the virtual patient's
own (``carb_ratio_g_per_u``), the carbohydrate as the patient estimates it: adults with
type 1 diabetes misjudge a meal's carbohydrate by about 20 % on average (Brazeau et al.
2013 [5]_), taken here as a log-normal factor whose mean absolute relative error is that
20 % (log-SD :data:`CARB_COUNT_LOG_SD`, from :func:`.therapy.carb_count_log_sd`; the
other departures from ideal therapy are in :mod:`.therapy`).
1 U of insulin = 6.00 nmol (Vølund 1993 [4]_).

References
----------
.. [1] C. Dalla Man, R. A. Rizza, C. Cobelli, IEEE Trans. Biomed. Eng. 54(10),
   1740-1749 (2007), section "Simulation of daily life".
.. [2] B. P. Kovatchev et al., J. Diabetes Sci. Technol. 3(1), 44-55 (2009).
.. [3] American Diabetes Association, "Standards of Care in Diabetes-2024", Diabetes
   Care 47 (Suppl. 1), S158-S178, section 9 (insulin dosing by carbohydrate counting).
.. [4] A. Vølund, "Conversion of insulin units to SI units", Am. J. Clin. Nutr. 58,
   714-715 (1993).
.. [5] A. S. Brazeau, H. Mircescu, K. Desjardins, C. Leroux, I. Strychar, J. M. Ekoé,
   R. Rabasa-Lhoret, "Carbohydrate counting accuracy and blood glucose variability in
   adults with type 1 diabetes", Diabetes Res. Clin. Pract. 99(1), 19-23 (2013).
"""

from __future__ import annotations

import numpy as np

from .. import portable as pm
from ._random import truncated_normal
from .therapy import carb_count_log_sd

__all__ = [
    "DAILY_MEALS",
    "MEAL_TIME_SD_MIN",
    "MEAL_TIME_LIMIT_MIN",
    "MEAL_SIZE_LOG_SD",
    "INSULIN_PMOL_PER_UNIT",
    "CARB_COUNT_LOG_SD",
    "draw_meals",
    "estimated_carbs_g",
    "bolus_units",
    "meal_grid_mg",
]

#: (clock time [h], carbohydrate [g]) of the day's meals [1]_.
DAILY_MEALS = ((8.0, 45.0), (12.0, 70.0), (20.0, 70.0))
#: SD of a meal's time around its clock time (an assumption). [min]
MEAL_TIME_SD_MIN = 30.0
#: A meal is at most this far from its clock time (an assumption). [min]
MEAL_TIME_LIMIT_MIN = 90.0
#: SD of ln(meal size) (an assumption). [-]
MEAL_SIZE_LOG_SD = 0.2
#: Insulin per unit [4]_. [pmol/U]
INSULIN_PMOL_PER_UNIT = 6000.0
#: SD of ln(estimated / true carbohydrate) of a type 1 patient's carb count: the log-SD
#: whose mean absolute relative error is the 20 % of Brazeau et al. [5]_ (0.246). [-]
CARB_COUNT_LOG_SD = carb_count_log_sd()


def draw_meals(rng, n_days: int) -> tuple[np.ndarray, np.ndarray]:
    """Meal times since the wear's start and their carbohydrate, for ``n_days`` days.

    Returns
    -------
    tuple of numpy.ndarray
        Start minute of each meal (int64, sorted) [min] and its carbohydrate [g],
        (n_days * len(DAILY_MEALS),) each.
    """
    clock_min = np.array([60.0 * h for h, _ in DAILY_MEALS])
    size_g = np.array([g for _, g in DAILY_MEALS])
    n = n_days * len(DAILY_MEALS)
    lim = MEAL_TIME_LIMIT_MIN
    offset = truncated_normal(rng, 0.0, MEAL_TIME_SD_MIN, -lim, lim, size=n)
    day = np.repeat(np.arange(n_days), len(DAILY_MEALS))
    minute = np.rint(day * 1440.0 + np.tile(clock_min, n_days) + offset).astype(np.int64)
    carbs = np.tile(size_g, n_days) * pm.exp(MEAL_SIZE_LOG_SD * rng.normal(size=n))
    return minute, carbs


def estimated_carbs_g(rng, carbs_g) -> np.ndarray:
    """The patient's estimate of each meal's carbohydrate, true x exp(s z) [5]_. [g]"""
    carbs = np.asarray(carbs_g, dtype=float)
    return carbs * pm.exp(CARB_COUNT_LOG_SD * rng.normal(size=carbs.shape))


def bolus_units(carbs_g, carb_ratio_g_per_u) -> np.ndarray:
    """Meal bolus by carbohydrate counting, carbs / CR [3]_. [U]

    Examples
    --------
    >>> float(bolus_units(60.0, 10.0))
    6.0
    """
    return np.asarray(carbs_g, dtype=float) / np.asarray(carb_ratio_g_per_u, dtype=float)


def meal_grid_mg(minutes: np.ndarray, amounts, n_min: int) -> np.ndarray:
    """Per-minute grid of an amount eaten (or injected) at given minutes, (n_min,).

    Amounts at the same minute add up; minutes at or past ``n_min`` are dropped.

    Examples
    --------
    >>> meal_grid_mg(np.array([1, 3, 9]), np.array([2.0, 5.0, 1.0]), 5)
    array([0., 2., 0., 5., 0.])
    """
    grid = np.zeros(n_min)
    keep = (minutes >= 0) & (minutes < n_min)
    np.add.at(grid, minutes[keep], np.asarray(amounts, dtype=float)[keep])
    return grid
