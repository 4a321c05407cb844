"""The simulator's noise-free forward model, as an estimator or a design bound sees it.

:class:`ForwardModel` evaluates the noise-free log ratio ln(fraction / T_ref) of each
reading for any glucose and any tissue and probe state: the simulator's optics through
its band integral (:func:`nirglucose.simulation.simulator.simulate_block`'s optics layer,
:mod:`nirglucose.optics.forward`), with the forward model chosen by name. The physics
inversion estimator (:mod:`nirglucose.models.inversion`) fits it to readings; the
design bound (:mod:`nirglucose.design.bound`) differentiates it. Neither needs the
models package to evaluate it, so it lives beside the simulator whose tables it reads.

The optics and their citations are the simulator's: tissue mixing
(:mod:`nirglucose.optics.tissue`), the forward models (:mod:`nirglucose.optics.forward`).
Where the scenario's ``noise.water_temperature`` switch is on, water absorbs at the skin
temperature (:func:`~nirglucose.simulation.simulator.water_temperature_delta_c`), which
is then one more unknown: :attr:`ForwardModel.nuisances` ends with ``skin_temp_c``.

Examples
--------
>>> import numpy as np
>>> from nirglucose.config import resolve_config
>>> fm = ForwardModel(resolve_config("paper"), "beer-lambert")
>>> theta = np.array([[np.log(0.02), 0.7, 0.6, 0.5, 0.05, 1.5, 0.0, 0.0]])
>>> fm.log_ratio(np.array([100.0]), theta).shape
(1, 4)
"""

from __future__ import annotations

import numpy as np

from ..config import ScenarioConfig
from ..constants import MGDL_PER_MMOLL_GLUCOSE
from ..optics import tissue
from ..optics.forward import FORWARD_MODELS
from .simulator import _band_detected_fraction, scenario_tables, water_temperature_delta_c

__all__ = ["NUISANCES", "PHYSICAL_BOUNDS", "TEMPERATURE_NUISANCE", "ForwardModel"]

#: The unknowns besides glucose, in column order: ln of the detected dermal blood
#: fraction, saturation, dermal water fraction, subcutis fat fraction, epidermal
#: melanosome fraction, skin thickness under the probe [mm], the LEDs' common thermal
#: peak shift [nm], ln of the optical coupling.
NUISANCES = (
    "log_blood_fraction",
    "saturation",
    "water_fraction",
    "subcutis_fat_fraction",
    "melanin_fraction",
    "skin_thickness_mm",
    "led_shift_nm",
    "log_coupling",
)
#: Where the forward model is evaluated, per unknown: volume fractions inside (0, 1),
#: a thickness inside the configured skin range's order of magnitude (0.1-10 mm), LED
#: shifts within +/- 30 nm (a 100 degC swing at the datasheets' 0.3 nm/degC). The
#: estimate itself is never clipped; only the model's argument is.
PHYSICAL_BOUNDS = {
    "log_blood_fraction": (np.log(1e-4), np.log(0.5)),
    "saturation": (0.01, 0.999),
    "water_fraction": (0.05, 0.95),
    "subcutis_fat_fraction": (0.05, 0.95),
    "melanin_fraction": (0.0, 0.6),
    "skin_thickness_mm": (0.1, 10.0),
    "led_shift_nm": (-30.0, 30.0),
    "log_coupling": (-2.0, 2.0),
}
#: The unknown the ``water_temperature`` switch adds after :data:`NUISANCES`: the skin
#: (tissue water) temperature [degC], evaluated within the skin-thermometer display range
#: of ``constants.PHYSIOLOGICAL_RANGES`` (15-45 degC).
TEMPERATURE_NUISANCE = "skin_temp_c"
_TEMPERATURE_BOUNDS = (15.0, 45.0)

class ForwardModel:
    """ln(fraction / T_ref) per LED for given glucose and nuisance state.

    Parameters
    ----------
    cfg : ScenarioConfig
        The device and optics (LED bands, geometry, tables, glucose's optical signal).
    model : str
        The forward model assumed, one of :data:`nirglucose.optics.forward.FORWARD_MODELS`
        (may differ from the one that made the data).
    """

    def __init__(self, cfg: ScenarioConfig, model: str):
        if model not in FORWARD_MODELS:
            raise ValueError(f"unknown forward model {model!r}")
        optics = cfg.optics.model_copy(update={"model": model})
        self.cfg = cfg.model_copy(update={"optics": optics})
        self.tables = scenario_tables(self.cfg)
        #: The unknowns besides glucose that :meth:`log_ratio` reads: :data:`NUISANCES`,
        #: then :data:`TEMPERATURE_NUISANCE` where ``noise.water_temperature`` is on.
        self.nuisances = NUISANCES + (
            (TEMPERATURE_NUISANCE,) if cfg.noise_factor("water_temperature") != 0.0 else ())

    def log_ratio(self, glucose_mgdl: np.ndarray, theta: np.ndarray) -> np.ndarray:
        """(n, n_led) noise-free ln(adc / adc_ref) at glucose [mg/dL] and ``theta``.

        ``theta`` is (n, len(NUISANCES)), columns as :data:`NUISANCES`, or (n,
        len(:attr:`nuisances`)) with the skin temperature [degC] last; without that
        column the water is at the thermoneutral skin temperature
        (``physiology.skin_temp_c_neutral``).
        """
        cfg = self.cfg
        theta = np.asarray(theta, dtype=float)
        k = len(NUISANCES)
        if theta.shape[-1] not in (k, len(self.nuisances)):
            raise ValueError(f"theta has {theta.shape[-1]} columns; expected {k} "
                             f"(NUISANCES) or {len(self.nuisances)} ({', '.join(self.nuisances)})")
        th = _clip_physical(theta[:, :k])
        temp_c = (np.clip(theta[:, k], *_TEMPERATURE_BOUNDS) if theta.shape[-1] > k
                  else np.full(len(th), cfg.physiology.skin_temp_c_neutral))
        glucose_mmoll = np.asarray(glucose_mgdl, float) / MGDL_PER_MMOLL_GLUCOSE
        water_dt = water_temperature_delta_c(cfg, temp_c)
        n_led = len(cfg.leds.wavelengths_nm)
        shift = np.repeat(th[:, 6:7], n_led, axis=1)
        # one pass at glucose.signal_gain where no LED sets its own glucose_gain, else one
        # per distinct gain, each LED's column from its own (as the simulator does)
        gains = np.asarray(cfg.leds.glucose_gains(cfg.glucose.signal_gain))

        def fraction(gain: float) -> np.ndarray:
            state = tissue.TissueState(np.exp(th[:, 0]), th[:, 1], th[:, 2], th[:, 3],
                                       gain * glucose_mmoll, water_dt)
            return _band_detected_fraction(cfg, self.tables, state, th[:, 4], th[:, 5], shift)

        distinct = sorted(set(gains.tolist()))
        frac = fraction(distinct[0])
        for gain in distinct[1:]:
            frac = np.where(gains[None, :] == gain, fraction(gain), frac)
        return np.log(frac / cfg.hardware.reference_transmission) + th[:, 7:8]


#: :data:`PHYSICAL_BOUNDS` of the :data:`NUISANCES`, in their order (low, high).
_PHYSICAL_LOW = np.array([PHYSICAL_BOUNDS[k][0] for k in NUISANCES])
_PHYSICAL_HIGH = np.array([PHYSICAL_BOUNDS[k][1] for k in NUISANCES])


def _clip_physical(theta: np.ndarray) -> np.ndarray:
    return np.clip(theta, _PHYSICAL_LOW, _PHYSICAL_HIGH)
