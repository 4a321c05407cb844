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
from collections.abc import Iterable, Iterator
from dataclasses import dataclass
from types import UnionType
from typing import Annotated, Any, Union, get_args, get_origin

import annotated_types as at
from pydantic import BaseModel
from pydantic.fields import FieldInfo

from .scenario import ScenarioConfig

__all__ = [
    "Bounds",
    "KeyInfo",
    "bounds_of",
    "key_info",
    "key_range",
    "numeric_leaves",
    "out_of_range_message",
    "suggest_keys",
    "unit_of",
    "valid_keys",
]

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


# --- bounds: the allowed range of every numeric value (issue 20) -------------------------


@dataclass(frozen=True)
class Bounds:
    """Allowed range of one numeric config value, read from its pydantic constraints.

    ``None`` for a side with no constraint; ``lo_open`` / ``hi_open`` for ``gt`` / ``lt``.
    """

    lo: float | None = None
    hi: float | None = None
    lo_open: bool = False
    hi_open: bool = False

    def __str__(self) -> str:
        def num(x: float) -> str:  # 1e+09 -> 1e9
            return re.sub(r"e([+-])0*(\d)", lambda m: "e" + m.group(1).strip("+") + m.group(2),
                          f"{x:g}")

        if self.lo is not None and self.hi is not None and not (self.lo_open or self.hi_open):
            return f"between {num(self.lo)} and {num(self.hi)}"
        sides = []
        if self.lo is not None:
            sides.append(f"{'>' if self.lo_open else '>='} {num(self.lo)}")
        if self.hi is not None:
            sides.append(f"{'<' if self.hi_open else '<='} {num(self.hi)}")
        return " and ".join(sides) or "any value"

    @classmethod
    def from_metadata(cls, metadata: Iterable[Any]) -> Bounds:
        """Bounds from ``annotated_types`` constraints (``Field(ge=..., lt=...)``)."""
        lo = hi = None
        lo_open = hi_open = False
        for m in metadata:
            if isinstance(m, at.Ge):
                lo, lo_open = float(m.ge), False  # type: ignore[arg-type]
            elif isinstance(m, at.Gt):
                lo, lo_open = float(m.gt), True  # type: ignore[arg-type]
            elif isinstance(m, at.Le):
                hi, hi_open = float(m.le), False  # type: ignore[arg-type]
            elif isinstance(m, at.Lt):
                hi, hi_open = float(m.lt), True  # type: ignore[arg-type]
        return cls(lo, hi, lo_open, hi_open)


def _unwrap(ann: Any, metadata: list[Any]) -> tuple[Any, list[Any]]:
    """The bare type of ``Annotated[...]`` and the constraints collected on the way."""
    while True:
        if get_origin(ann) is Annotated:
            base, *extra = get_args(ann)
            for e in extra:
                metadata = [*metadata, *(e.metadata if isinstance(e, FieldInfo) else [e])]
            ann = base
        elif get_origin(ann) in (Union, UnionType) and type(None) in get_args(ann):
            # an optional value (``float | None``): the bounds of the value when given
            rest = [a for a in get_args(ann) if a is not type(None)]
            if len(rest) != 1:
                return ann, metadata
            ann = rest[0]
        else:
            return ann, metadata


def _children(ann: Any) -> Iterator[tuple[str, Any, list[Any]]]:
    """``(part, annotation, constraints)`` one level below a model, tuple or dict type."""
    if isinstance(ann, type) and issubclass(ann, BaseModel):
        for name, f in ann.model_fields.items():
            yield name, f.annotation, list(f.metadata)
    elif get_origin(ann) is tuple:
        args = get_args(ann)
        if len(args) == 2 and args[1] is Ellipsis:
            yield "<i>", args[0], []
        else:
            for i, a in enumerate(args):
                yield str(i), a, []
    elif get_origin(ann) is dict:
        yield "<name>", get_args(ann)[1], []


def _is_number(ann: Any) -> bool:
    return ann in (int, float)


def numeric_leaves(
    model: type[BaseModel] | None = None, prefix: str = ""
) -> list[tuple[str, Bounds]]:
    """Every numeric value a config holds, as ``(path, bounds)``.

    A path is a dotted key with ``<i>`` for any item of a variable-length tuple and
    ``<name>`` for any value of a dict (``glucose.fasting_mgdl.<name>.1``).
    """
    if model is None:
            model = ScenarioConfig
    return _leaves(model, [], prefix)


def _leaves(ann: Any, meta: list[Any], path: str) -> list[tuple[str, Bounds]]:
    """``(path, bounds)`` of every number under an annotation, depth first."""
    ann, meta = _unwrap(ann, meta)
    if _is_number(ann):
        return [(path, Bounds.from_metadata(meta))]
    return [leaf for part, sub, sub_meta in _children(ann)
            for leaf in _leaves(sub, sub_meta, f"{path}.{part}" if path else part)]


def _resolve(dotted: str) -> tuple[Any, list[Any], int] | None:
    """Annotation and constraints at a dotted key or error location (``a.b.0``).

    The third value counts the trailing parts that index a tuple or dict (not a field).
    """
    ann: Any = ScenarioConfig
    meta: list[Any] = []
    trailing = 0
    for part in dotted.split("."):
        ann, _ = _unwrap(ann, [])
        for name, sub, sub_meta in _children(ann):
            if name == part or name == "<name>" or (name == "<i>" and part.isdigit()):
                is_field = isinstance(ann, type) and issubclass(ann, BaseModel)
                trailing = 0 if is_field else trailing + 1
                ann, meta = sub, sub_meta
                break
        else:
            return None
    ann, meta = _unwrap(ann, meta)
    return ann, meta, trailing


def bounds_of(dotted: str) -> Bounds | None:
    """Allowed range of a numeric value (``hardware.adc_bits``, ``environment.temperature_c.0``).

    ``None`` where the location is not a single number.
    """
    found = _resolve(dotted)
    if found is None or not _is_number(found[0]):
        return None
    return Bounds.from_metadata(found[1])


def key_range(dotted: str) -> str:
    """Allowed range of every number under a key, for ``nirglucose keys`` (``""``: none).

    One range when all agree (``"between -20 and 50"``); otherwise one per item
    (``"1: >= 0 and <= 200; 0: between 20 and 600"``).
    """
    found = _resolve("leds.emitters" if dotted == "leds" else dotted)
    if found is None:
        return ""
    ann, meta, _ = found
    if _is_number(ann):
        return str(Bounds.from_metadata(meta))
    if isinstance(ann, type) and issubclass(ann, BaseModel):
        return ""
    leaves = _leaves(ann, meta, "")
    ranges = {str(b) for _, b in leaves}
    if len(ranges) <= 1:
        return next(iter(ranges), "")
    def label(path: str) -> str:
        return ".".join(p for p in path.split(".") if p not in ("<i>", "<name>")) or "each"

    return "; ".join(f"{label(p)}: {b}" for p, b in leaves)


def out_of_range_message(loc: str, value: Any) -> str | None:
    """One-line ``key=value is out of range: must be ... [unit]``, or ``None``.

    ``None`` where ``loc`` is not a bounded number or ``value`` lies within its bounds
    (another error then applies). Tuple items and dict values show as ``key[0]``.
    """
    found = _resolve(loc)
    if found is None or not _is_number(found[0]):
        return None
    bounds = Bounds.from_metadata(found[1])
    parts = loc.split(".")
    n_field = len(parts) - found[2]
    key = ".".join(parts[:n_field]) + "".join(f"[{p}]" for p in parts[n_field:])
    unit = unit_of(".".join(parts[:n_field]))
    return f"{key}={value!r} is out of range: must be {bounds}{f' [{unit}]' if unit else ''}"


def valid_keys(model: type[BaseModel] = ScenarioConfig, prefix: str = "") -> list[str]:
    """Every dotted key accepted by :func:`~nirglucose.config.apply_overrides`."""
    keys = []
    for name, field in model.model_fields.items():
        ann = field.annotation
        if not prefix and name == "preset":  # a label set by the preset, not a setting
            continue
        if isinstance(ann, type) and issubclass(ann, BaseModel):
            keys.extend(valid_keys(ann, f"{prefix}{name}."))
        else:
            keys.append(f"{prefix}{name}")
    return keys
