"""The twin's parameters as data: scenario key, prior, transform, preset and published values.

Each :class:`Parameter` is one scenario key that a device file may identify, with a
uniform prior on its fitting scale (``log10`` of a scale or size, or the value itself
for an error that may be 0). :func:`fitted_parameters` lists those the twin fits for a
device; :func:`held_parameters` those a file of this kind cannot inform at all (a
measurement error of a column the file lacks, drift without reading times): they are
reported with their prior and ``identified: false``, never fitted.

Prior ranges are assumptions of this package, stated per parameter; each lies inside
its key's own bounds (``nirglucose keys``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..config import resolve_config
from ..config.instrument import MeasurementConfig
from ..config.presets import PAPER_SIGNAL_GAIN, WEARABLE_SIGNAL_GAIN
from ..dataset.columns import KNOWN_PHYSIOLOGY
from .device import BASE_PRESET, NOMINAL_POWER_MW, TwinDevice
from .simulate import nominal_levels

__all__ = [
    "KINDS",
    "Parameter",
    "fitted_parameters",
    "held_parameters",
    "IDENTIFIED_WIDTH_RATIO",
    "MEASUREMENT_KEYS",
    "PRESET_GAINS",
]

#: What each parameter describes, in the order a report lists them.
KINDS = (
    "glucose signal",
    "white noise",
    "between-reading noise",
    "between-subject spread",
    "measurement error",
    "drift",
    "level",
    "reference level",
)

#: A parameter is identified when its posterior's central 90 % interval is narrower than
#: this share of its prior's (on the fitting scale): a posterior that fills 80 % or more
#: of what the prior allows has learnt little from the file.
IDENTIFIED_WIDTH_RATIO = 0.8

#: Known physiological column -> the scenario key of its measurement error.
MEASUREMENT_KEYS = {
    **{c: f"measurement.{c}" for c in KNOWN_PHYSIOLOGY[:12] if c != "fitzpatrick_type"},
    "fitzpatrick_type": "measurement.fitzpatrick_misclass",
    "blood_volume_pct": "device.blood_volume_error_rel",
    "spo2_pct": "device.spo2_error_pct",
}
#: Prior of a measurement error: 0 (an exact instrument) to this many times the
#: instrument's value in the base scenario, within the key's bound.
_MEASUREMENT_PRIOR_FACTOR = 4.0
#: Glucose gain prior: a tenth of the published magnitude to the key's bound, 100
#: (the presets use 11 and 12.5). [-]
_GAIN_PRIOR = (0.1, 100.0)
#: White (read) noise prior as shares of the ADC's full scale: 1e-5 (below a 16-bit
#: LSB) to 2 % (20 LSB at 10 bits). [-]
_READ_NOISE_PRIOR_FS = (1e-5, 0.02)
#: Per-channel reading-to-reading power noise prior, relative SD: ten times below the
#: datasheet-class 0.1 % (DESIGN.md) to 5 %. [-]
_FLICKER_PRIOR = (1e-4, 0.05)
#: Spread priors, multipliers of the base scenario's literature spreads. [-]
_VARIATION_PRIOR = (0.2, 5.0)
_PLACEMENT_PRIOR = (0.05, 5.0)
#: The noise-free tissue code of the nominal device is scaled into this share of full
#: scale by the LED power prior; the reference code likewise by the transmission prior.
_LEVEL_PRIOR_FS = (0.02, 0.98)
#: LED ageing drift prior, relative power loss per 1000 h, per channel: a tenth of the
#: package's 0.1 % per 1000 h (constants.LED_AGEING_PER_1000H, DESIGN.md) to a hundred
#: times it. [1/(1000 h)]
_DRIFT_PRIOR = (1e-4, 0.1)


@dataclass(frozen=True)
class Parameter:
    """One scenario key a twin fits or reports.

    Parameters
    ----------
    key : str
        The scenario key (``leds.emitters.0.glucose_gain``).
    label : str
        What it is, in words.
    kind : str
        One of :data:`KINDS`.
    low, high : float
        Prior bounds. [unit]
    log : bool
        Prior uniform in log10 of the value (else in the value).
    preset : float
        The base scenario's value. [unit]
    unit : str
        Its unit.
    channel : float or None
        The LED it belongs to (None: the whole device). [nm]
    published : float or None
        The published magnitude where one exists (glucose gain 1). [unit]
    reason : str
        Why it is held at its prior (held parameters only).
    """

    key: str
    label: str
    kind: str
    low: float
    high: float
    log: bool
    preset: float
    unit: str
    channel: float | None = None
    published: float | None = None
    reason: str = ""

    def to_fit(self, value):
        """Values on the fitting scale (log10 or as they are)."""
        value = np.asarray(value, dtype=float)
        return np.log10(value) if self.log else value

    def from_fit(self, z):
        """Fitting-scale values back to the key's unit."""
        z = np.asarray(z, dtype=float)
        return 10.0 ** z if self.log else z

    @property
    def fit_bounds(self) -> tuple[float, float]:
        """The prior's bounds on the fitting scale."""
        lo, hi = self.to_fit([self.low, self.high])
        return float(lo), float(hi)

    def prior_quantile(self, q):
        """Quantiles of the prior in the key's unit."""
        lo, hi = self.fit_bounds
        return self.from_fit(lo + np.asarray(q, dtype=float) * (hi - lo))

    def to_json(self) -> dict:
        """Prior and provenance as plain JSON types."""
        return {"key": self.key, "label": self.label, "kind": self.kind,
                "channel_nm": self.channel, "unit": self.unit,
                "prior": {"low": self.low, "high": self.high,
                          "scale": "log10" if self.log else "linear"},
                "preset": self.preset, "published": self.published}


def fitted_parameters(device: TwinDevice) -> list[Parameter]:
    """The parameters the twin fits for ``device``, in a fixed order."""
    tissue, ref = nominal_levels(device)
    fs = device.full_scale
    out: list[Parameter] = []
    for i, (w, label) in enumerate(zip(device.wavelengths_nm, device.labels, strict=True)):
        lo, hi = (NOMINAL_POWER_MW * f / tissue[i] for f in _LEVEL_PRIOR_FS)
        out += [
            Parameter(f"leds.emitters.{i}.glucose_gain", f"glucose signal at {label} nm",
                      "glucose signal", *_GAIN_PRIOR, True, 1.0, "x published", w, 1.0),
            Parameter(f"leds.emitters.{i}.read_noise_lsb", f"white noise at {label} nm",
                      "white noise", fs * _READ_NOISE_PRIOR_FS[0],
                      fs * _READ_NOISE_PRIOR_FS[1], True, 0.0, "LSB", w),
            Parameter(f"leds.emitters.{i}.flicker_rel",
                      f"reading-to-reading power noise at {label} nm",
                      "between-reading noise", *_FLICKER_PRIOR, True,
                      _base_value("hardware.led_flicker_rel"), "relative SD", w),
            Parameter(f"leds.emitters.{i}.power_mw", f"LED power at {label} nm (code level)",
                      "level", max(lo, 1e-3), min(hi, 1000.0), True, NOMINAL_POWER_MW, "mW",
                      w),
        ]
    out += [
        Parameter("noise.contact_pressure.scale", "placement (coupling, pressure) noise",
                  "between-reading noise", *_PLACEMENT_PRIOR, True, 1.0, "x base"),
        Parameter("physiology.variation_scale", "between-subject spread of physiology",
                  "between-subject spread", *_VARIATION_PRIOR, True, 1.0, "x base"),
    ]
    if device.reference:
        # reference code share at power P and transmission T: ref (P / P_nom) (T / T0);
        # at the power prior's middle the transmission prior spans _LEVEL_PRIOR_FS
        t0 = _base_value("hardware.reference_transmission")
        mid = float(np.sqrt(_LEVEL_PRIOR_FS[0] * _LEVEL_PRIOR_FS[1]))
        per_t = float(np.median(ref / tissue)) * mid / t0
        lo, hi = (f / per_t for f in _LEVEL_PRIOR_FS)
        out.append(Parameter("hardware.reference_transmission",
                             "reference path transmission (reference code level)",
                             "reference level", max(lo, 1e-6), min(hi, 1.0), True, t0, "-"))
    out += [_measurement(c) for c in device.physiology if c in MEASUREMENT_KEYS]
    if device.times:
        out += _drift(device)
    return out


def _drift(device: TwinDevice, reason: str = "") -> list[Parameter]:
    """Each LED's power drift over time (``leds.emitters.<i>.ageing_per_1000h``)."""
    base = _base_value("hardware.led_ageing_per_1000h")
    return [Parameter(f"leds.emitters.{i}.ageing_per_1000h",
                      f"LED power drift over time at {label} nm", "drift", *_DRIFT_PRIOR,
                      True, base, "1/(1000 h)", w, reason=reason)
            for i, (w, label) in enumerate(zip(device.wavelengths_nm, device.labels,
                                               strict=True))]


def held_parameters(device: TwinDevice) -> list[Parameter]:
    """Parameters a file of this kind cannot inform, reported with their prior."""
    out = [
        _measurement(c, reason=f"the file has no {c} column")
        for c in MEASUREMENT_KEYS if c not in device.physiology
    ]
    if not device.times:
        out += _drift(device, reason="the file has no reading times (time_min)")
    return out


def _base_value(key: str) -> float:
    cfg = resolve_config(BASE_PRESET)
    obj = cfg
    for part in key.split("."):
        obj = getattr(obj, part)
    return float(obj)


def _measurement(col: str, reason: str = "") -> Parameter:
    key = MEASUREMENT_KEYS[col]
    base = _base_value(key)
    cap = {"measurement.fitzpatrick_misclass": 1.0, "device.blood_volume_error_rel": 1.0,
           "device.spo2_error_pct": 50.0}.get(key)
    if cap is None:
        cap = _field_bound(key)
    return Parameter(key, f"measurement error of {col}", "measurement error", 0.0,
                     min(_MEASUREMENT_PRIOR_FACTOR * base, cap), False, base,
                     "probability" if col == "fitzpatrick_type" else "SD", reason=reason)


def _field_bound(key: str) -> float:
    field = MeasurementConfig.model_fields[key.split(".", 1)[1]]
    for meta in field.metadata:
        if hasattr(meta, "le"):
            return float(meta.le)
    return float("inf")


#: The presets' glucose gains, for reports that set a fitted gain beside them.
PRESET_GAINS = {"physical": 1.0, "paper": PAPER_SIGNAL_GAIN, "wearable": WEARABLE_SIGNAL_GAIN}
