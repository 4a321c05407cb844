"""Dotted ``--set`` overrides: valid keys, parsing, applying, and resolving a scenario."""

from __future__ import annotations

import json
import re
from collections.abc import Mapping
from typing import Any

from pydantic import BaseModel, ValidationError

from ..exceptions import ConfigError, unknown_name
from .keys import out_of_range_message, suggest_keys, unit_of, valid_keys
from .leds import LED, LEGACY_LED_KEYS, _merge_legacy_leds
from .presets import PRESETS
from .scenario import DETECTOR_KEYS, ScenarioConfig, detector_key_default

#: A bracketed list of bare names, ``[L8957, G17190-005K]`` (part names typed unquoted).
_BARE_NAMES = re.compile(r"\[\s*[A-Za-z][\w.\-]*(\s*,\s*[A-Za-z][\w.\-]*)*\s*\]")


def parse_override(text: str) -> tuple[str, Any]:
    """Parse ``"key=value"`` from the command line; the value is read as JSON if it can be.

    Examples
    --------
    >>> parse_override("hardware.adc_bits=14")
    ('hardware.adc_bits', 14)
    >>> parse_override("environment.temperature_c=[5, 35]")
    ('environment.temperature_c', [5, 35])
    >>> parse_override("leds=[L8957, L1909]")
    ('leds', ['L8957', 'L1909'])
    """
    if "=" not in text:
        raise ConfigError(f"override {text!r} must look like key=value, e.g. hardware.adc_bits=14")
    key, raw = text.split("=", 1)
    key, raw = key.strip(), raw.strip()
    if not key:
        raise ConfigError(f"override {text!r} has an empty key")
    try:
        value = json.loads(raw)
    except json.JSONDecodeError as exc:
        if _BARE_NAMES.fullmatch(raw):  # [L8957, L1909]: part names without quotes
            return key, [n.strip() for n in raw[1:-1].split(",")]
        if "{" in raw:  # records: only JSON reads them
            raise ConfigError(
                f"override {key}: {raw!r} is not valid JSON ({exc.msg} at character "
                f"{exc.pos + 1}); quote names, write numbers plainly (no nan)") from None
        lowered = raw.lower()
        value = {"true": True, "false": False}.get(lowered, raw)
    return key, value


#: ``leds.emitters.<i>.<field>``: one value of one LED.
_PER_LED_KEY = re.compile(r"leds\.emitters\.(\d+)\.(\w+)")


def is_valid_key(dotted: str) -> bool:
    """Whether :func:`apply_overrides` accepts a dotted key.

    Besides :func:`valid_keys`: ``leds`` (the whole LED set, a list of records), one
    LED's value ``leds.emitters.<i>.<field>`` and the former per-LED list keys
    (:data:`LEGACY_LED_KEYS`).

    Examples
    --------
    >>> is_valid_key("leds.emitters.3.power_mw"), is_valid_key("leds.emitters.0.colour")
    (True, False)
    """
    if dotted in valid_keys() or dotted == "leds" or dotted in LEGACY_LED_KEYS:
        return True
    m = _PER_LED_KEY.fullmatch(dotted)
    return m is not None and m.group(2) in LED.model_fields


def _plain(value: Any) -> Any:
    """A value with models dumped and tuples as lists (LED records given as :class:`LED`)."""
    if isinstance(value, BaseModel):
        return value.model_dump(mode="json")
    if isinstance(value, list | tuple):
        return [_plain(v) for v in value]
    return value


def check_overrides(overrides: Any) -> dict[str, Any]:
    """``overrides`` as a dict, refused (one line) unless it maps dotted keys to values.

    Examples
    --------
    >>> check_overrides(["hardware.adc_bits"])  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    nirglucose.exceptions.ConfigError: overrides must be a dict of dotted keys to values, ...
    """
    if overrides is None:
        return {}
    if not isinstance(overrides, Mapping) or not all(isinstance(k, str) for k in overrides):
        raise ConfigError(
            f"overrides must be a dict of dotted keys to values, e.g. "
            f"{{'hardware.adc_bits': 14}}, got a {type(overrides).__name__}: "
            f"{str(overrides)[:80]}"
        )
    return dict(overrides)


def _set_per_led(out: dict[str, Any], dotted: str, value: Any) -> None:
    m = _PER_LED_KEY.fullmatch(dotted)
    assert m is not None  # apply_overrides queues only leds.emitters.<i>.<field> here
    emitters = out["leds"]["emitters"]
    i = int(m.group(1))
    if i >= len(emitters):
        raise ConfigError(
            f"{dotted}: the scenario has {len(emitters)} LEDs (indices 0-{len(emitters) - 1})"
        )
    emitters[i][m.group(2)] = value


def _clear_detector_values(out: dict[str, Any]) -> None:
    """Before a new detector: the values a detector decides back to their defaults and
    the LED set's responsivities cleared, so the new detector sets them (values given in
    the same overrides still win: they are applied after)."""
    for section, key, _ in DETECTOR_KEYS:
        out.setdefault(section, {})[key] = detector_key_default(section, key)
    for e in out.get("leds", {}).get("emitters", []):
        if isinstance(e, dict):
            e["responsivity_a_per_w"] = None


def apply_overrides(data: dict[str, Any], overrides: dict[str, Any]) -> dict[str, Any]:
    """Return a copy of a config dict with dotted overrides set; unknown keys raise.

    Whole values are set first (``leds`` is ``leds.emitters``), then the former per-LED
    lists (:data:`LEGACY_LED_KEYS`) are merged into the LED records, then single LED
    values (``leds.emitters.<i>.<field>``).
    """
    out = json.loads(json.dumps(data))
    if overrides.get("detector") is not None:
        _clear_detector_values(out)
    keys = set(valid_keys())
    legacy: dict[str, Any] = {}
    per_led: dict[str, Any] = {}
    for dotted, value in overrides.items():
        if dotted == "leds":  # the whole LED set
            if not isinstance(value, list | tuple):
                raise ConfigError(
                    f"leds must be a list of LED records or part names, e.g. "
                    f"[{{'wavelength_nm': 850, 'power_mw': 3}}, 'L8957'], got "
                    f"{type(value).__name__}: {str(value)[:80]}")
            dotted = "leds.emitters"
        if dotted in LEGACY_LED_KEYS:
            legacy[dotted] = value
            continue
        if dotted not in keys:
            if is_valid_key(dotted):
                per_led[dotted] = value
                continue
            close = suggest_keys(dotted, keys)
            hint = f"; did you mean {', '.join(close)}?" if close else ""
            raise ConfigError(
                f"unknown config key {dotted!r}{hint} (run `nirglucose keys` for the valid keys)"
            )
        node = out
        parts = dotted.split(".")
        for part in parts[:-1]:
            node = node.setdefault(part, {})
        node[parts[-1]] = _plain(value)
    if legacy:
        out["leds"]["emitters"] = _merge_legacy_leds(out["leds"]["emitters"], legacy)
    for dotted, value in per_led.items():
        _set_per_led(out, dotted, value)
    return out


#: pydantic error types of a number outside its ``ge/gt/le/lt`` bounds.
_RANGE_ERRORS = ("greater_than", "greater_than_equal", "less_than", "less_than_equal")


def resolve_config(
    preset: str | ScenarioConfig = "paper", overrides: dict[str, Any] | None = None
) -> ScenarioConfig:
    """Build the scenario of a preset with dotted overrides, validated.

    Parameters
    ----------
    preset : str or ScenarioConfig
        A name of :data:`PRESETS`, or a config to start from.
    overrides : dict, optional
        Dotted keys (``"hardware.adc_bits"``) to values.

    Raises
    ------
    ConfigError
        Unknown preset or key, or a value outside its valid range.

    Examples
    --------
    >>> resolve_config("paper", {"hardware.adc_bits": 14}).hardware.adc_bits
    14
    """
    given = check_overrides(overrides)
    if isinstance(preset, ScenarioConfig):
        base = preset.model_dump(mode="json")
        all_overrides = given
    else:
        if preset not in PRESETS:
            raise ConfigError(unknown_name("preset", preset, PRESETS))
        base = ScenarioConfig(preset=preset).model_dump(mode="json")
        all_overrides = {**PRESETS[preset], **given}
    data = apply_overrides(base, all_overrides)
    try:
        return ScenarioConfig.model_validate(data)
    except ValidationError as exc:
        err = exc.errors()[0]
        cause = (err.get("ctx") or {}).get("error")
        if isinstance(cause, ConfigError):  # a validator's own one-line message
            raise ConfigError(str(cause)) from None
        loc = ".".join(str(p) for p in err["loc"]) or "config"
        if err["type"] in _RANGE_ERRORS:
            msg = out_of_range_message(loc, err.get("input"))
            if msg is not None:
                raise ConfigError(msg) from None
        unit = unit_of(loc)
        msg = err["msg"].removeprefix("Value error, ")  # pydantic's prefix for a validator's
        raise ConfigError(
            f"invalid value for {loc}: {msg}{f' [{unit}]' if unit else ''} "
            f"(got {err.get('input')!r})"
        ) from None
