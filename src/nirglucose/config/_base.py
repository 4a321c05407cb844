"""The shared base of every config section: finite, bounded, frozen pydantic models."""

from __future__ import annotations

from typing import Annotated, Any, get_args

from pydantic import BaseModel, ConfigDict, Field, ValidationInfo, field_validator

#: Magnitude no setting may exceed, whatever its own bounds: the largest default is
#: 1e5 (ambient lux, TIA gain in ohm); beyond 1e9 a value can only overflow the
#: simulation (exp, squares) into garbage codes (issue 20). [-]
MAX_ABS_VALUE = 1e9


class _Model(BaseModel):
    # every value finite: NaN or infinity would reach the ADC as garbage codes (issue 20)
    model_config = ConfigDict(
        extra="forbid", frozen=True, validate_default=True, allow_inf_nan=False
    )

    @field_validator("*", mode="before")
    @classmethod
    def _no_bool_for_a_number(cls, v: Any, info: ValidationInfo) -> Any:
        # pydantic reads True as 1 in a number field: `--set leds.band_points=true`
        # would silently become 1 point
        if isinstance(v, bool) and info.field_name is not None:
            ann = cls.model_fields[info.field_name].annotation
            if {int, float} & {ann, *get_args(ann)} and bool not in {ann, *get_args(ann)}:
                raise ValueError(f"takes a number, not {str(v).lower()}")
        return v

    @field_validator("*")
    @classmethod
    def _bounded(cls, v: Any) -> Any:
        items = v.values() if isinstance(v, dict) else v if isinstance(v, tuple) else (v,)
        for x in items:
            if isinstance(x, int | float) and not isinstance(x, bool) and abs(x) > MAX_ABS_VALUE:
                raise ValueError(f"must lie within +-{MAX_ABS_VALUE:.0e}")
        return v


def _num(lo: float, hi: float, *, gt: bool = False) -> Any:
    """A float type within ``[lo, hi]`` (``(lo, hi]`` with ``gt``), as pydantic constraints."""
    return Annotated[float, Field(gt=lo, le=hi) if gt else Field(ge=lo, le=hi)]


def _pair(lo: float, hi: float, *, gt: bool = False) -> Any:
    """A ``(low, high)`` range type whose two values lie within ``[lo, hi]`` (see :func:`_num`)."""
    item = _num(lo, hi, gt=gt)
    return tuple[item, item]


def _check_range(value: tuple[float, float], name: str) -> tuple[float, float]:
    low, high = value
    if not low < high:
        raise ValueError(f"{name} range must have low < high, got ({low}, {high})")
    return value
