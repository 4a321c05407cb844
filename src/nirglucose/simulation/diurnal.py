"""The day's cycles a worn device lives through: air temperature and humidity, heart
rate, and when the device is taken off and put back on.

* Temperature: a cosine over the day, warmest at :data:`TEMPERATURE_PEAK_HOUR`, of
  amplitude :data:`TEMPERATURE_AMPLITUDE_C` (an assumption of this package for the air
  around a wrist that is mostly indoors: a few degC, far less than outdoors' 10-15 degC
  diurnal range).
* Humidity: the day's water-vapour pressure is constant, so the relative humidity falls
  as the air warms, RH = 100 e / e_s(T) with the Magnus saturation pressure
  (:func:`saturation_vapour_pressure_hpa`, WMO [1]_).
* Heart rate: a cosinor, lowest at night and highest in the afternoon; Degaute et al.
  [2]_ measured heart rate about 15-20 /min lower asleep than awake in healthy young men;
  :data:`HEART_RATE_AMPLITUDE_BPM` (half of 16 /min) and the acrophase
  :data:`HEART_RATE_PEAK_HOUR` are taken from that day-night contrast.
* Re-seating: the device comes off once a day (a shower at :data:`SHOWER_HOUR`, an
  assumption) and goes back on with a new contact state; :func:`seating_index` counts
  the placements.

References
----------
.. [1] World Meteorological Organization, "Guide to Meteorological Instruments and
   Methods of Observation", WMO-No. 8 (2008), Annex 4.B (Magnus formula over water:
   e_s = 6.112 exp(17.62 T / (243.12 + T)) hPa, T in degC).
.. [2] J. P. Degaute, P. van de Borne, P. Linkowski, E. Van Cauter, "Quantitative
   analysis of the 24-hour blood pressure and heart rate patterns in young men",
   Hypertension 18(2), 199-210 (1991).
"""

from __future__ import annotations

import numpy as np

from .. import portable as pm

__all__ = [
    "TEMPERATURE_AMPLITUDE_C",
    "TEMPERATURE_PEAK_HOUR",
    "HEART_RATE_AMPLITUDE_BPM",
    "HEART_RATE_PEAK_HOUR",
    "SHOWER_HOUR",
    "diurnal_cosine",
    "saturation_vapour_pressure_hpa",
    "relative_humidity_pct",
    "seating_index",
]

#: Amplitude of the air temperature's daily cycle at the wrist (an assumption). [degC]
TEMPERATURE_AMPLITUDE_C = 2.0
#: Hour of the warmest air (mid-afternoon, an assumption). [h]
TEMPERATURE_PEAK_HOUR = 15.0
#: Amplitude of the heart rate's daily cycle [2]_. [1/min]
HEART_RATE_AMPLITUDE_BPM = 8.0
#: Hour of the highest heart rate (afternoon) [2]_. [h]
HEART_RATE_PEAK_HOUR = 15.0
#: Hour of the daily shower, when the device is taken off and put back on (an
#: assumption). [h]
SHOWER_HOUR = 7.5


def diurnal_cosine(hour_of_day, amplitude: float, peak_hour: float) -> np.ndarray:
    """A 24-hour cosine of ``amplitude``, highest at ``peak_hour``, zero mean.

    Examples
    --------
    >>> float(diurnal_cosine(15.0, 2.0, 15.0)), float(diurnal_cosine(3.0, 2.0, 15.0))
    (2.0, -2.0)
    """
    phase = 2.0 * np.pi * (np.asarray(hour_of_day, dtype=float) - peak_hour) / 24.0
    return amplitude * pm.cos(phase)


def saturation_vapour_pressure_hpa(temperature_c) -> np.ndarray:
    """Saturation vapour pressure over water, the Magnus formula [1]_. [hPa]

    Examples
    --------
    >>> round(float(saturation_vapour_pressure_hpa(20.0)), 2)
    23.33
    """
    t = np.asarray(temperature_c, dtype=float)
    return 6.112 * pm.exp(17.62 * t / (243.12 + t))


def relative_humidity_pct(vapour_pressure_hpa, temperature_c) -> np.ndarray:
    """Relative humidity of air of a vapour pressure at a temperature, 100 e / e_s(T). [%]

    Examples
    --------
    >>> e = 0.5 * saturation_vapour_pressure_hpa(20.0)
    >>> round(float(relative_humidity_pct(e, 20.0)), 6), bool(relative_humidity_pct(e, 25.0) < 50)
    (50.0, True)
    """
    return 100.0 * np.asarray(vapour_pressure_hpa) / saturation_vapour_pressure_hpa(temperature_c)


def seating_index(time_min, shower_hour: float = SHOWER_HOUR) -> np.ndarray:
    """Placement of the device at each time: 0 until the first shower, then +1 a day.

    ``time_min`` counts from 00:00 of the wear's first day.

    Examples
    --------
    >>> seating_index(np.array([0, 449, 450, 1889, 1890]))
    array([0, 0, 1, 1, 2])
    """
    hours = np.asarray(time_min, dtype=float) / 60.0
    return (np.floor((hours - shower_hour) / 24.0) + 1.0).astype(np.int64).clip(min=0)
