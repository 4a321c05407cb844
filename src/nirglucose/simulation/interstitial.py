"""Blood-to-interstitial glucose: a first-order lag.

Glucose reaches the interstitial fluid from the capillaries by diffusion; with uptake by
the surrounding cells the interstitial concentration follows the blood's through a
first-order system, dG_i/dt = (G_b - G_i) / tau (Rebrin et al. 1999 [1]_). Tracer
studies put the delay at 5-10 min: 5.3-6.2 min (mean) in the abdominal subcutaneous
fluid of healthy adults (Basu et al. 2013 [2]_). The NIR probe sees dermal interstitial
and intracellular water more than blood (the dermis holds about 70 % water and 1-5 %
blood), so the optics of the wear simulation see G_i, while the reference column stays
the blood (plasma) glucose; that the dermal lag equals the subcutaneous one is an
assumption of this package.

References
----------
.. [1] K. Rebrin, G. M. Steil, W. P. van Antwerp, J. J. Mastrototaro, "Subcutaneous
   glucose predicts plasma glucose independent of insulin: implications for continuous
   monitoring", Am. J. Physiol. 277, E561-E571 (1999).
.. [2] A. Basu, S. Dube, M. Slama, I. Errazuriz, J. C. Amezcua, Y. C. Kudva, T. Peyser,
   R. E. Carter, C. Cobelli, R. Basu, "Time lag of glucose from intravascular to
   interstitial compartment in humans", Diabetes 62(12), 4083-4087 (2013),
   doi:10.2337/db13-1132.
"""

from __future__ import annotations

import numpy as np
from scipy.signal import lfilter, lfilter_zi

from .. import portable as pm
from ..exceptions import ConfigError

__all__ = ["ISF_LAG_MIN", "interstitial_glucose_mgdl"]

#: Time constant of the blood-to-interstitial lag: the middle of Basu et al.'s
#: 5.3-6.2 min [2]_, rounded. [min]
ISF_LAG_MIN = 6.0


def interstitial_glucose_mgdl(blood_mgdl, step_min: float, tau_min: float = ISF_LAG_MIN):
    """Interstitial glucose of a blood glucose series sampled every ``step_min`` [1]_.

    The exact discretisation of dG_i/dt = (G_b - G_i)/tau with the blood glucose held
    over each step: G_i[k+1] = a G_i[k] + (1 - a) G_b[k], a = exp(-step/tau), starting
    at equilibrium with the first sample; the last axis is time. ``tau_min = 0`` returns
    the blood series. [mg/dL]

    Examples
    --------
    >>> g = interstitial_glucose_mgdl(np.r_[100.0, np.full(6, 200.0)], 6.0, 6.0)
    >>> round(float(g[2]), 2)  # one time constant after the step: 1 - 1/e of it
    163.21
    """
    blood = np.asarray(blood_mgdl, dtype=float)
    if not (np.isfinite(tau_min) and tau_min >= 0) or not step_min > 0:
        raise ConfigError(f"the interstitial lag needs tau >= 0 and a step > 0 min, got tau "
                          f"{tau_min!r} min and step {step_min!r} min")
    if tau_min == 0:
        return blood.copy()
    a = float(pm.exp(-step_min / tau_min))
    b_coef, a_coef = [0.0, 1.0 - a], [1.0, -a]
    zi = lfilter_zi(b_coef, a_coef) * blood[..., :1]
    out, _ = lfilter(b_coef, a_coef, blood, axis=-1, zi=zi)
    return out
