"""The :class:`Twin`: a device's posterior, ``twin.json``, and its scenario
(:func:`nirglucose.twin.fit.fit_twin` fits one).

``twin.json`` (``format: nirglucose-twin``, ``format_version`` 1) holds one entry per
parameter (its scenario ``key``, ``median``, ``lower`` and ``upper`` of the central 90 %
interval, ``identified``, the prior, the base scenario's value, the published
magnitude, and for a parameter held at its prior the ``reason``), beside the device,
the settings, the file's summaries, the warnings, the posterior predictive checks and
posterior draws. Reading it validates every entry: a hand-edited or malformed file is one
:class:`~nirglucose.exceptions.DataError` line.
"""

from __future__ import annotations

import copy
import json
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .._version import __version__
from ..config import ScenarioConfig, resolve_config
from ..dataset import atomic_write
from ..exceptions import ConfigError, DataError
from .device import BASE_PRESET, TwinDevice, base_overrides
from .parameters import IDENTIFIED_WIDTH_RATIO, Parameter

__all__ = ["FORMAT", "TWIN_MODES", "LED_CARRIED", "Twin", "TwinStart", "load_twin",
           "twin_scenario", "INTERVAL", "parameter_entry"]

#: ``twin.json``'s format tag and version.
FORMAT = ("nirglucose-twin", 1)
#: How a twin becomes a scenario: ``map`` its most probable draw, ``posterior`` one
#: posterior draw per simulation (by its seed).
TWIN_MODES = ("map", "posterior")
#: The reported interval: central 90 %. [-]
INTERVAL = (0.05, 0.95)


#: Per-LED fields a study with LEDs of its own carries from the twin's channels to each
#: new LED, and how the channels are averaged (:meth:`Twin.study_start`).
LED_CARRIED = {"glucose_gain": "geometric", "flicker_rel": "geometric",
               "ageing_per_1000h": "geometric", "read_noise_lsb": "mean"}


@dataclass(frozen=True)
class TwinStart:
    """Where a study starts from a twin (:meth:`Twin.study_start`).

    Attributes
    ----------
    preset : str
        :data:`~.device.BASE_PRESET`.
    overrides : dict
        Scenario overrides of ``preset``.
    led_fields : dict
        Fields every LED the study chooses takes (empty when the study keeps the twin's
        LEDs).
    """

    preset: str
    overrides: dict[str, Any]
    led_fields: dict[str, float]


@dataclass
class Twin:
    """A device's twin: posterior over scenario parameters, and how it was obtained.

    Parameters
    ----------
    device : TwinDevice
        What the file declares.
    parameters : list of dict
        One entry per parameter (module docstring), fitted first, then held.
    draws : numpy.ndarray
        Posterior draws of the fitted parameters in their units, (n, n_fitted).
    map_values : numpy.ndarray
        The most probable draw, (n_fitted,).
    info : dict
        ``settings``, ``summaries``, ``warnings``, ``ppc``, ``timing``, ``source``.
    """

    device: TwinDevice
    parameters: list[dict[str, Any]]
    draws: np.ndarray
    map_values: np.ndarray
    info: dict[str, Any] = field(default_factory=dict)

    @property
    def fitted_keys(self) -> list[str]:
        """Scenario keys of the fitted parameters (columns of :attr:`draws`)."""
        return [p["key"] for p in self.parameters if p["fitted"]]

    @property
    def warnings(self) -> list[str]:
        """The one-line warnings of the fit."""
        return list(self.info.get("warnings", []))

    def entry(self, key: str) -> dict[str, Any]:
        """The ``twin.json`` entry of a scenario key (KeyError when absent)."""
        for p in self.parameters:
            if p["key"] == key:
                return p
        raise KeyError(key)

    def overrides(self, mode: str = "map", seed: int = 0) -> dict[str, Any]:
        """Scenario overrides of :data:`~.device.BASE_PRESET` that make the twin's device:
        the file's LEDs and ADC and the fitted values, the ``map`` draw or one posterior
        draw chosen by ``seed``; parameters held at their prior keep the base value."""
        if mode not in TWIN_MODES:
            raise ConfigError(f"unknown twin mode {mode!r}; valid: {', '.join(TWIN_MODES)}")
        if mode == "map":
            row = self.map_values
        else:
            rng = np.random.default_rng(np.random.SeedSequence([int(seed), 5]))
            row = self.draws[int(rng.integers(0, len(self.draws)))]
        values = {k: float(v) for k, v in zip(self.fitted_keys, row, strict=True)}
        return {**base_overrides(self.device), **values}

    def study_start(self, mode: str = "map", seed: int = 0, *,
                    own_leds: bool = True) -> TwinStart:
        """Where a study starts from this twin: :data:`~.device.BASE_PRESET`, its overrides
        and, for a study that chooses its own LEDs (``own_leds=False``: the wavelengths
        study), the fields each new LED takes from the twin.

        With ``own_leds`` the overrides are :meth:`overrides` (the twin's LEDs, ADC and
        fitted values). Without, they keep what does not belong to one LED (ADC,
        reference, placement noise, between-subject spread, measurement errors) and drop
        the LED set and the per-LED values; each new LED gets :data:`LED_CARRIED` from the
        twin's channels: the geometric mean of their glucose gains, flicker and drift, and
        the mean of their white noise (an assumption: the twin knows these only at its
        own wavelengths). The LED powers are the study's own (a design choice).
        """
        values = self.overrides(mode, seed)
        if own_leds:
            return TwinStart(BASE_PRESET, values, {})
        per_led: dict[str, list[float]] = {}
        device_wide = {}
        for key, v in values.items():
            parts = key.split(".")
            if key == "leds":
                continue
            if len(parts) == 4 and parts[:2] == ["leds", "emitters"]:
                per_led.setdefault(parts[3], []).append(float(v))
            else:
                device_wide[key] = v
        fields = {}
        for name, how in LED_CARRIED.items():
            got = per_led.get(name)
            if got:
                arr = np.asarray(got, dtype=float)
                fields[name] = float(np.exp(np.mean(np.log(arr))) if how == "geometric"
                                     else np.mean(arr))
        return TwinStart(BASE_PRESET, device_wide, fields)

    def scenario(self, mode: str = "map", seed: int = 0) -> ScenarioConfig:
        """The twin's scenario (:meth:`overrides` on :data:`~.device.BASE_PRESET`)."""
        return resolve_config(BASE_PRESET, self.overrides(mode, seed))

    def to_json(self) -> dict[str, Any]:
        """``twin.json``'s document."""
        return {
            "format": FORMAT[0], "format_version": FORMAT[1], "version": __version__,
            "base_preset": BASE_PRESET, "device": self.device.to_json(),
            "parameters": copy.deepcopy(self.parameters),
            "map": dict(zip(self.fitted_keys, self.map_values.tolist(), strict=True)),
            "draws": self.draws.tolist(), **copy.deepcopy(self.info),
        }

    def save(self, folder: str | Path) -> Path:
        """Write ``folder/twin.json`` atomically (the folder is created); its path."""
        folder = Path(folder)
        if folder.exists() and not folder.is_dir():
            raise DataError(f"--out {str(folder)!r} is a file; give a directory for the twin")
        folder.mkdir(parents=True, exist_ok=True)
        text = json.dumps(self.to_json(), indent=1, allow_nan=False)
        return atomic_write(folder / "twin.json", lambda p: Path(p).write_text(text))


def load_twin(path: str | Path) -> Twin:
    """Read and validate ``twin.json`` (or a folder holding one).

    Raises
    ------
    DataError
        Missing, unreadable or malformed file (one line naming what is wrong).
    """
    path = Path(path)
    if path.is_dir():
        path = path / "twin.json"
    try:
        doc = json.loads(path.read_text())
    except FileNotFoundError:
        raise DataError(f"no twin file {str(path)!r}; fit one with nirglucose twin --data "
                        "FILE --out DIR") from None
    except (OSError, ValueError) as exc:
        raise DataError(f"cannot read twin file {str(path)!r}: {exc}") from None
    return _twin_from_json(doc, path)


def _bad(path: Path, what: str) -> DataError:
    return DataError(f"twin file {str(path)!r} is malformed: {what}; fit the twin again "
                     "(nirglucose twin --data FILE --out DIR)")


def _twin_from_json(doc: Any, path: Path) -> Twin:
    if not isinstance(doc, dict) or doc.get("format") != FORMAT[0]:
        raise _bad(path, f"it is not a twin file (no 'format': {FORMAT[0]!r})")
    if doc.get("format_version") != FORMAT[1]:
        raise _bad(path, f"format_version {doc.get('format_version')!r}, expected {FORMAT[1]}")
    device = TwinDevice.from_json(doc.get("device"))
    params = doc.get("parameters")
    if not isinstance(params, list) or not params:
        raise _bad(path, "no 'parameters' list")
    for p in params:
        _check_entry(p, path)
    fitted = [p["key"] for p in params if p["fitted"]]
    draws, map_doc = doc.get("draws"), doc.get("map")
    try:
        draws = np.asarray(draws, dtype=float)
        map_values = np.asarray([map_doc[k] for k in fitted], dtype=float)
    except (TypeError, ValueError, KeyError):
        raise _bad(path, "'draws' or 'map' do not match the fitted parameters") from None
    if draws.ndim != 2 or draws.shape[1] != len(fitted) or not len(draws):
        raise _bad(path, f"'draws' must be a table of {len(fitted)} columns")
    if not (np.isfinite(draws).all() and np.isfinite(map_values).all()):
        raise _bad(path, "'draws' or 'map' hold non-finite values")
    info = {k: v for k, v in doc.items() if k not in (
        "format", "format_version", "version", "base_preset", "device", "parameters", "map",
        "draws")}
    return Twin(device, params, draws, map_values, info)


def _check_entry(p: Any, path: Path) -> None:
    """One parameter entry's fields and their order (lower <= median <= upper)."""
    if not isinstance(p, dict) or not isinstance(p.get("key"), str):
        raise _bad(path, "a parameter entry has no 'key'")
    key = p["key"]
    nums = [p.get(k) for k in ("median", "lower", "upper")]
    if not all(isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v)
               for v in nums):
        raise _bad(path, f"{key}: median, lower and upper must be finite numbers")
    if not nums[1] <= nums[0] <= nums[2]:
        raise _bad(path, f"{key}: lower {nums[1]} <= median {nums[0]} <= upper {nums[2]} "
                         "does not hold")
    for flag in ("identified", "fitted"):
        if not isinstance(p.get(flag), bool):
            raise _bad(path, f"{key}: {flag!r} must be true or false")


def parameter_entry(p: Parameter, fit_draws: np.ndarray | None) -> dict[str, Any]:
    """A parameter's ``twin.json`` entry from its fitting-scale draws (None: held)."""
    lo_b, hi_b = p.fit_bounds
    if fit_draws is None:
        q = p.prior_quantile([INTERVAL[0], 0.5, INTERVAL[1]])
        ratio = 1.0
    else:
        zq = np.quantile(fit_draws, [INTERVAL[0], 0.5, INTERVAL[1]])
        q = p.from_fit(zq)
        ratio = float((zq[2] - zq[0]) / ((INTERVAL[1] - INTERVAL[0]) * (hi_b - lo_b)))
    return {
        **p.to_json(), "median": float(q[1]), "lower": float(q[0]), "upper": float(q[2]),
        "identified": bool(fit_draws is not None and ratio < IDENTIFIED_WIDTH_RATIO),
        "width_ratio": round(ratio, 3), "fitted": fit_draws is not None,
        "reason": p.reason,
    }


def twin_scenario(twin: Twin | str | Path, mode: str = "map", seed: int = 0) -> ScenarioConfig:
    """The scenario of a device's twin (a :class:`Twin`, or the path of its ``twin.json``
    or folder) in ``mode`` ``"map"`` or ``"posterior"`` (a draw chosen by ``seed``): what
    the simulator and every study take in place of a preset
    (``ng.simulate(twin_scenario("twin/"), ...)``, ``--twin`` on the command line).
    """
    return (twin if isinstance(twin, Twin) else load_twin(twin)).scenario(mode, int(seed))
