"""Where the device is worn: ambient conditions and the probe's contact with the skin."""

from __future__ import annotations

from pydantic import Field, field_validator, model_validator

from ._base import _check_range, _Model, _num, _pair


class EnvironmentConfig(_Model):
    """Ambient temperature, humidity, pressure and light."""

    temperature_c: _pair(-20, 50) = Field(
        (18.0, 30.0),
        description="Range of a session's ambient temperature. Within -20 to 50 degC, where "
        "wearables are specified to work (an assumption). [degC]",
    )
    temperature_within_sd_c: float = Field(
        1.0,
        ge=0,
        le=20,
        description="SD of ambient temperature within a subject's session. At most 20 degC (an "
        "assumption). [degC]",
    )
    humidity_within_sd_pct: float = Field(
        5.0,
        ge=0,
        le=50,
        description="SD of relative humidity within a session. At most 50 %, half the RH scale. "
        "[%]",
    )
    pressure_within_sd_mbar: float = Field(
        1.0,
        ge=0,
        le=50,
        description="SD of pressure within a session (weather over hours). At most 50 mbar (an "
        "assumption). [mbar]",
    )
    humidity_pct: _pair(0, 100) = Field((30.0, 90.0), description="RH range. Within 0-100 %. [%]")
    humidity_coupling_loss: float = Field(
        0.03,
        ge=0,
        le=0.5,
        description="Coupling-efficiency loss at the top of the RH range (issue: up to 3 %). [-]",
    )
    # 300-1100 mbar: Everest summit (~337 mbar, West 1983) to the Dead Sea shore (~1065 mbar)
    pressure_mbar_mean: float = Field(
        1013.25, ge=300, le=1100, description="Mean barometric pressure. [mbar]"
    )
    pressure_mbar_sd: float = Field(
        12.0,
        ge=0,
        le=100,
        description="SD of pressure. At most 100 mbar (an assumption). [mbar]",
    )
    pressure_mbar: _pair(300, 1100) = Field(
        (950.0, 1050.0),
        description="Range. Within 300-1100 mbar, as pressure_mbar_mean. [mbar]",
    )
    perfusion_per_mbar: float = Field(
        1.0e-3,
        ge=-0.01,
        le=0.01,
        description="Relative blood-volume change per mbar above perfusion_reference_mbar (an "
        "assumption). At most +-0.01 (an assumption). [1/mbar]",
    )
    perfusion_reference_mbar: float = Field(
        1013.25,
        ge=300,
        le=1100,
        description="Pressure of nominal perfusion: the standard atmosphere (ISO 2533). [mbar]",
    )
    ambient_lux: _pair(0.1, 100_000) = Field(
        (10.0, 1000.0),
        description="Illuminance range, drawn log-uniformly. Within 0.1 lx (night) to 100,000 "
        "lx (direct sun). [lx]",
    )
    light_source_probs: dict[str, _num(0, 1)] = Field(
        {"sun": 0.1, "fluorescent": 0.45, "led": 0.45},
        description="Ambient spectrum mix. [-]",
    )
    baffle_optical_density: float = Field(
        2.0,
        ge=0,
        le=10,
        description="Baffle OD (issue). At most OD 10 (1e-10 leaks). [-]",
    )

    _ranges = field_validator("temperature_c", "humidity_pct", "pressure_mbar", "ambient_lux")(
        lambda v, info: _check_range(v, info.field_name)
    )

    @model_validator(mode="after")
    def _limits(self) -> EnvironmentConfig:
        valid = {"sun", "fluorescent", "led"}
        if not set(self.light_source_probs) <= valid:
            raise ValueError(f"light_source_probs keys must be among {sorted(valid)}")
        if abs(sum(self.light_source_probs.values()) - 1) > 1e-6:
            raise ValueError("light_source_probs must sum to 1")
        return self


class ContactConfig(_Model):
    """Probe contact pressure: changes coupling, blood content and optical path."""

    coupling_sd: float = Field(
        0.03,
        ge=0,
        le=1,
        description="Relative SD of optical coupling between placements (at most 1: a "
        "relative SD beyond 100 % has no physical meaning for a coupling factor). [-]",
    )
    blanching: float = Field(
        0.3, ge=0, le=1, description="Blood-volume loss at full contact pressure (assumption). [-]"
    )
    compression: float = Field(
        0.1,
        ge=0,
        le=0.5,
        description="Skin-thickness loss at full contact pressure (assumption). [-]",
    )
    pressure_beta: _pair(0, 100, gt=True) = Field(
        (2.0, 2.0),
        description="Beta(a, b) shape of a hand-placed probe's contact pressure, a share of "
        "full scale (an assumption: unimodal, mean 0.5). Each above 0, at most 100. [-]",
    )
    constant_force_pressure: float = Field(
        0.5,
        ge=0,
        le=1,
        description="Contact pressure held by a constant-force probe (device.constant_force_probe"
        "), a share of full scale: the mean of Beta(2, 2), so the cohort's mean blanching and "
        "compression are unchanged. [-]",
    )
