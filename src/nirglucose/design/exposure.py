"""How much light an LED may put on skin and into an eye: published exposure limits.

A worn NIR glucose sensor presses its LEDs on the skin for hours; off the wrist, the
same LEDs may be looked into. :func:`max_led_power_mw` gives the largest optical power
of one LED that keeps both exposures within the published limits; the requirements
study (:mod:`~nirglucose.design.requirements`) caps every LED's drive there.

Skin (the binding limit). For exposures longer than 10 s the limits for incoherent
sources protect the skin only up to 10 s (ICNIRP 2013 [1]_: skin thermal hazard
H = 20,000 t^0.25 J/m^2 for t < 10 s, 380-3,000 nm; IEC 62471 [3]_ takes the same
value), so a continuously worn emitter is held here to the smaller of

* that dose spread over 10 s, 20,000 x 10^0.25 / 10 = 3,557 W/m^2, and
* the laser limit for skin for 10 s to 30,000 s (ICNIRP 2013 [2]_, IEC 60825-1): 2 C_A
  kW/m^2 for 700-1,400 nm, with C_A = 10^(0.002 (lambda - 700)) up to 1,050 nm and 5
  above, and 1 kW/m^2 for 1,400 nm to 1 mm,

averaged over the laser guideline's 3.5 mm limiting aperture for skin [2]_. An LED on
the skin puts (nearly) all its power through that aperture, so P <= E_limit x
pi (1.75 mm)^2: 34.2 mW at 700-1,400 nm, 9.6 mW at 1,400-1,700 nm. Time-multiplexing
(each LED lit one frame in n_led + 1) would allow more on average; the cap does not
count on it.

Eye. The infrared limit for the cornea and lens, E_IR = 100 W/m^2 for t > 1,000 s
(780-3,000 nm; [1]_, the exempt group of [3]_), at IEC 62471's 200 mm measurement
distance for a Lambertian LED (on-axis intensity P / pi sr): P <= 100 W/m^2 x
pi x (0.2 m)^2 = 12.6 W, far above any LED here. The retinal thermal limit for weak
visual stimuli (780-1,400 nm, [3]_: L_IR <= 6,000 / alpha W m^-2 sr^-1) is likewise
far above a milliwatt emitter of millimetre size and is not evaluated.

Not modelled: the probe's own heating of the skin (ISO 80601-2-61 holds a pulse-oximeter
probe's tissue interface at <= 41 degC), which limits the LEDs' electrical, not optical,
power.

References
----------
.. [1] ICNIRP, "Guidelines on limits of exposure to incoherent visible and infrared
   radiation", Health Phys. 105(1), 74-96 (2013). doi:10.1097/HP.0b013e318289a611
.. [2] ICNIRP, "Guidelines on limits of exposure to laser radiation of wavelengths
   between 180 nm and 1,000 um", Health Phys. 105(3), 271-295 (2013).
   doi:10.1097/HP.0b013e3182983fd4
.. [3] IEC 62471:2006 / CIE S 009:2002, "Photobiological safety of lamps and lamp
   systems" (exempt group; 200 mm measurement distance).
"""

from __future__ import annotations

import numpy as np

from ..exceptions import ConfigError

__all__ = [
    "EYE_IR_IRRADIANCE_W_PER_M2",
    "EYE_DISTANCE_M",
    "SKIN_APERTURE_MM",
    "SKIN_THERMAL_DOSE_10S_J_PER_M2",
    "eye_limit_power_mw",
    "max_led_power_mw",
    "skin_irradiance_limit_w_per_m2",
]

#: Skin thermal hazard dose at its longest duration, t = 10 s: 20,000 t^0.25 J/m^2 [1]_.
SKIN_THERMAL_DOSE_10S_J_PER_M2 = 20_000.0 * 10.0**0.25
#: Limiting aperture (diameter) over which skin exposure is averaged [2]_. [mm]
SKIN_APERTURE_MM = 3.5
#: Infrared limit for the cornea and lens for t > 1,000 s, 780-3,000 nm [1]_, [3]_. [W/m^2]
EYE_IR_IRRADIANCE_W_PER_M2 = 100.0
#: IEC 62471's measurement distance for lamps other than general lighting [3]_. [m]
EYE_DISTANCE_M = 0.2
#: Laser skin limit for 10 s - 30 ks: 2 C_A kW/m^2 at 700-1,400 nm, 1 kW/m^2 beyond [2]_.
_LASER_SKIN_W_PER_M2_700_1400 = 2_000.0
_LASER_SKIN_W_PER_M2_ABOVE_1400 = 1_000.0
#: Range the limits here are stated for (the package's LEDs: 700-1,700 nm). [nm]
_RANGE_NM = (700.0, 1700.0)


def _check_wavelengths(wavelength_nm) -> np.ndarray:
    wl = np.asarray(wavelength_nm, dtype=float)
    if not np.all(np.isfinite(wl)) or np.any(wl < _RANGE_NM[0]) or np.any(wl > _RANGE_NM[1]):
        raise ConfigError(
            f"exposure limits are stated here for {_RANGE_NM[0]:g}-{_RANGE_NM[1]:g} nm, got "
            f"{np.atleast_1d(wl).tolist()} nm"
        )
    return wl


def skin_irradiance_limit_w_per_m2(wavelength_nm) -> np.ndarray:
    """Largest skin irradiance for exposures longer than 10 s (module docstring).

    min(20,000 x 10^0.25 J/m^2 / 10 s [1]_, laser limit 2 C_A kW/m^2 (700-1,400 nm) or
    1 kW/m^2 (above 1,400 nm) [2]_), C_A = 10^(0.002 (lambda - 700)), at most 5.

    Parameters
    ----------
    wavelength_nm : float or array_like
        Emission wavelength, 700-1,700 nm. [nm]

    Returns
    -------
    numpy.ndarray
        Irradiance limit. [W/m^2]

    Examples
    --------
    >>> [round(float(e)) for e in skin_irradiance_limit_w_per_m2([700, 850, 1550])]
    [2000, 3557, 1000]
    """
    wl = _check_wavelengths(wavelength_nm)
    c_a = np.minimum(10.0 ** (0.002 * (wl - 700.0)), 5.0)  # [2], C_A
    laser = np.where(wl <= 1400.0, _LASER_SKIN_W_PER_M2_700_1400 * c_a,
                     _LASER_SKIN_W_PER_M2_ABOVE_1400)
    return np.minimum(SKIN_THERMAL_DOSE_10S_J_PER_M2 / 10.0, laser)


def eye_limit_power_mw() -> float:
    """Largest LED power whose on-axis irradiance at 200 mm stays within E_IR (module
    docstring): 100 W/m^2 x pi sr x (0.2 m)^2, a Lambertian emitter's P = pi I. [mW]

    Examples
    --------
    >>> round(eye_limit_power_mw())
    12566
    """
    return EYE_IR_IRRADIANCE_W_PER_M2 * np.pi * EYE_DISTANCE_M**2 * 1e3


def max_led_power_mw(wavelength_nm) -> np.ndarray:
    """Largest optical power of one LED within the skin and eye limits.

    P_max = min(E_skin(lambda) x pi (3.5 mm / 2)^2, eye limit) (module docstring).

    Parameters
    ----------
    wavelength_nm : float or array_like
        Emission wavelength, 700-1,700 nm. [nm]

    Returns
    -------
    numpy.ndarray
        Power cap. [mW]

    Examples
    --------
    >>> [round(float(p), 1) for p in max_led_power_mw([850, 1300, 1550])]
    [34.2, 34.2, 9.6]
    """
    area_m2 = np.pi * (SKIN_APERTURE_MM * 1e-3 / 2.0) ** 2
    skin_mw = skin_irradiance_limit_w_per_m2(wavelength_nm) * area_m2 * 1e3
    return np.minimum(skin_mw, eye_limit_power_mw())
