"""What each config key means: unit, description and close matches of a misspelt key.

The unit of a key is the bracketed tail of its pydantic field description
(``"Mean barometric pressure. [mbar]"`` -> ``"mbar"``), as STYLE.md asks every
field to end.

Examples
--------
>>> unit_of("environment.pressure_mbar_mean")
'mbar'
>>> suggest_keys("hardware.adc_bit")[0]
'hardware.adc_bits'
"""

from __future__ import annotations

import difflib
import re
from collections.abc import Iterable
from typing import get_args

from pydantic import BaseModel

__all__ = ["KeyInfo", "key_info", "suggest_keys", "unit_of"]

_UNIT = re.compile(r"\s*\[([^\[\]]*)\]\s*$")

#: difflib similarity a key must reach to be suggested (its default, 0.6, also
#: proposes unrelated keys of the same section).
_CUTOFF = 0.75


class KeyInfo(tuple):
    """``(key, unit, description)`` of one dotted config key."""

    __slots__ = ()

    def __new__(cls, key: str, unit: str, description: str) -> KeyInfo:
        return super().__new__(cls, (key, unit, description))

    key = property(lambda self: self[0])
    unit = property(lambda self: self[1])
    description = property(lambda self: self[2])


def _model_of(ann) -> type[BaseModel] | None:
    """The model a field holds: itself, or the item of a tuple of records (``leds.emitters``)."""
    if isinstance(ann, type) and issubclass(ann, BaseModel):
        return ann
    args = [a for a in get_args(ann) if a is not Ellipsis]
    if len(args) == 1 and isinstance(args[0], type) and issubclass(args[0], BaseModel):
        return args[0]
    return None


def _field(dotted: str):
    from .config import ScenarioConfig

    model: type[BaseModel] | None = ScenarioConfig
    field = None
    for part in dotted.split("."):
        if part.isdigit() and field is not None and _model_of(field.annotation) is not None:
            continue  # one record of a tuple of records: leds.emitters.<i>.<field>
        if model is None or part not in model.model_fields:
            return None
        field = model.model_fields[part]
        model = _model_of(field.annotation)
    return field


def key_info(dotted: str) -> KeyInfo:
    """Unit and description of a dotted key (empty strings where the field has none).

    Parameters
    ----------
    dotted : str
        A key of :func:`nirglucose.config.valid_keys`, e.g. ``"hardware.adc_bits"``.
        A noise source's ``enabled`` / ``scale`` are described from the source; one
        LED's value (``leds.emitters.2.power_mw``) from the LED record's field, and
        ``leds`` as ``leds.emitters``.

    Returns
    -------
    KeyInfo
        The key, its unit (``"-"`` for a dimensionless one) and its description.
    """
    field = _field("leds.emitters" if dotted == "leds" else dotted)
    text = (field.description or "") if field is not None else ""
    if not text and dotted.startswith("noise.") and dotted.count(".") == 2:
        source, attr = dotted.split(".")[1:]
        what = "switches it on or off" if attr == "enabled" else "multiplies it"
        text = f"Noise source {source}: {what}. [-]"
    m = _UNIT.search(text)
    unit = m.group(1).strip() if m else ""
    desc = _UNIT.sub("", text).strip() if m else text.strip()
    return KeyInfo(dotted, unit, desc)


def unit_of(dotted: str) -> str:
    """Unit of a dotted key or error location, ``""`` if unknown (see :func:`key_info`).

    Item indices of an error location (``environment.temperature_c.0``) are dropped.
    """
    parts = dotted.split(".")
    while parts and parts[-1].isdigit():
        parts.pop()
    return key_info(".".join(parts)).unit


def suggest_keys(dotted: str, keys: Iterable[str] | None = None) -> list[str]:
    """Valid keys closest to a misspelt one (at most three, best first).

    Compares the whole dotted key and, separately, its last part, so both
    ``hardware.adc_bit`` and ``adc_bits`` find ``hardware.adc_bits``.
    """
    if keys is None:
        from .config import valid_keys

        keys = valid_keys()
    keys = sorted(keys)
    found = difflib.get_close_matches(dotted, keys, n=3, cutoff=_CUTOFF)
    leaf = dotted.split(".")[-1]
    by_leaf: dict[str, list[str]] = {}
    for k in keys:
        by_leaf.setdefault(k.split(".")[-1], []).append(k)
    for name in difflib.get_close_matches(leaf, list(by_leaf), n=3, cutoff=_CUTOFF):
        found.extend(k for k in by_leaf[name] if k not in found)
    return found[:3]
