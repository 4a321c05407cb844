"""The LED set: one record per LED, the study's four by default, and the former layout."""

from __future__ import annotations

from typing import Any

from pydantic import Field, field_validator, model_validator

from ..constants import DEFAULT_LED_WAVELENGTHS_NM
from ..exceptions import ConfigError
from ._base import _Model
from .parts import led_part


class LED(_Model):
    """One LED of the set: where it emits, how wide, how strong, how well it is detected."""

    wavelength_nm: float = Field(
        ...,
        ge=700,
        le=1700,
        description="Centre wavelength, within the optics tables' 700-1700 nm range "
        "(data/optics/SOURCES.md). [nm]",
    )
    fwhm_nm: float = Field(
        ...,
        gt=0,
        le=150,
        description="Emission full width at half maximum, typical of IR LEDs "
        "(e.g. Vishay VSLY5850 30 nm, TSAL6200 40 nm at 940 nm; longer wavelengths wider); "
        "at most 150 nm, a quarter of the optics tables' first 700-1300 nm span. [nm]",
    )
    power_mw: float = Field(
        ...,
        gt=0,
        le=1000,
        description="Optical power at 25 degC as driven (IR LEDs give 5-40 mW at 20-100 mA; "
        "chosen per channel so tissue codes sit mid-scale); at most 1 W, the class of "
        "high-power IR emitters. [mW]",
    )
    responsivity_a_per_w: float | None = Field(
        None,
        gt=0,
        le=1.38,
        description="Photodiode responsivity at this LED (the study's set: Hamamatsu S1336 "
        "typical spectral response read at 850/940/1050/1150 nm); at most 1.38, quantum "
        "efficiency 1 at 1700 nm (lambda / 1239.8 nm A/W = 1.371). None: the scenario's "
        "detector's curve averaged over this LED's band (config.detector). [A/W]",
    )
    part: str | None = Field(
        None,
        description="Catalogue part this record came from (data/parts/leds.csv), None for "
        "a record given by value. [-]",
    )
    glucose_gain: float | None = Field(
        None,
        gt=0,
        le=100,
        description="Multiplies glucose's three optical effects in this LED's band in place "
        "of glucose.signal_gain (1: the published magnitudes); a device's twin fits one per "
        "channel (nirglucose.twin). None: glucose.signal_gain. At most 100, as signal_gain. [-]",
    )
    read_noise_lsb: float = Field(
        0.0,
        ge=0,
        le=1e6,
        description="Temporal (white) noise of this channel's conversion beyond the modelled "
        "shot, Johnson, INL and quantisation noise, Gaussian per reading, scaled by "
        "noise_scale: the temporal dark noise sigma_d in digital numbers of the EMVA 1288 "
        "sensor characterisation (EMVA Standard 1288, release 4.0, 2021). 0: none. At most "
        "1e6 LSB, a 24-bit ADC's 6 % of full scale (an assumption). [LSB]",
    )
    flicker_rel: float | None = Field(
        None,
        ge=0,
        le=0.1,
        description="This LED's relative reading-to-reading power SD in place of "
        "hardware.led_flicker_rel (e.g. a channel with its own driver or optical path). "
        "None: hardware.led_flicker_rel. At most 10 %, as led_flicker_rel. [-]",
    )
    ageing_per_1000h: float | None = Field(
        None,
        ge=0,
        le=1,
        description="This LED's relative power loss per 1000 h of operation in place of "
        "hardware.led_ageing_per_1000h (DESIGN.md; P = P0 [1 - b t / 1000 h], "
        "nirglucose.simulation.hardware.led_power_w): a device's twin fits one per channel "
        "from a file with reading times. None: hardware.led_ageing_per_1000h. At most 1, "
        "as led_ageing_per_1000h. [1/(1000 h)]",
    )


#: The study's four LEDs: FWHM typical of IR LEDs, power per channel for mid-scale
#: tissue codes, S1336 responsivity at each wavelength (:class:`LED` field sources).
DEFAULT_LEDS: tuple[LED, ...] = tuple(
    LED(wavelength_nm=wl, fwhm_nm=fwhm, power_mw=p, responsivity_a_per_w=r)
    for wl, fwhm, p, r in zip(
        DEFAULT_LED_WAVELENGTHS_NM,
        (40.0, 45.0, 50.0, 60.0),
        (2.0, 2.0, 2.7, 10.0),
        (0.58, 0.62, 0.40, 0.15),
        strict=True,
    )
)

#: Per-LED keys of the former layout (before issue 22) -> the :class:`LED` field they set.
LEGACY_LED_KEYS = {
    "leds.wavelengths_nm": "wavelength_nm",
    "leds.fwhm_nm": "fwhm_nm",
    "hardware.led_power_mw": "power_mw",
    "hardware.responsivity_a_per_w": "responsivity_a_per_w",
}


class LEDConfig(_Model):
    """The LED set, one record per LED (``leds.emitters``), and its band integration.

    One override replaces the set: ``leds=[{"wavelength_nm": 850, "fwhm_nm": 40,
    "power_mw": 2.0, "responsivity_a_per_w": 0.58}, ...]`` (or ``leds.emitters=[...]``);
    one LED's value is ``leds.emitters.<i>.<field>``. The per-LED tuples the layers use
    are read-only properties (:attr:`wavelengths_nm`, :attr:`fwhm_nm`, :attr:`power_mw`,
    :attr:`responsivity_a_per_w`).
    """

    emitters: tuple[LED, ...] = Field(
        DEFAULT_LEDS,
        min_length=1,
        description="The LED set, one record per LED with wavelength_nm [nm], fwhm_nm [nm], "
        "power_mw [mW] and responsivity_a_per_w [A/W] (the study's four by default). "
        "[nm, nm, mW, A/W]",
    )
    band_points: int = Field(
        3,
        ge=1,
        le=31,
        description="Gauss-Hermite points integrating each LED band. 3 points are within "
        "0.1-6 % of a 21-point integral, a near-constant factor per LED (spread across "
        "subjects <= 0.2 %) that the reference reading absorbs; raise it for accuracy. [-]",
    )

    @model_validator(mode="before")
    @classmethod
    def _from_list(cls, data: Any) -> Any:
        # ``leds=[...]``: the LED records alone; the former {wavelengths_nm, fwhm_nm} layout
        if isinstance(data, list | tuple):
            return {"emitters": data}
        return data

    @field_validator("emitters", mode="before")
    @classmethod
    def _parts(cls, data: Any) -> Any:
        # catalogue LEDs by name: "L8957" or {"part": "L8957", "power_mw": 3.0}
        if isinstance(data, list | tuple):
            return tuple(expand_led_part(e) for e in data)
        return data

    @model_validator(mode="after")
    def _unique(self) -> LEDConfig:
        if len(set(self.wavelengths_nm)) != len(self.wavelengths_nm):
            raise ValueError("the LED set must not repeat a wavelength")
        return self

    wavelengths_nm = property(lambda self: tuple(e.wavelength_nm for e in self.emitters))
    fwhm_nm = property(lambda self: tuple(e.fwhm_nm for e in self.emitters))
    power_mw = property(lambda self: tuple(e.power_mw for e in self.emitters))
    responsivity_a_per_w = property(
        lambda self: tuple(e.responsivity_a_per_w for e in self.emitters)
    )

    def glucose_gains(self, signal_gain: float) -> tuple[float, ...]:
        """Each LED's glucose gain: its own ``glucose_gain`` or ``signal_gain``. [-]"""
        return tuple(signal_gain if e.glucose_gain is None else e.glucose_gain
                     for e in self.emitters)

    def ageings(self, led_ageing_per_1000h: float) -> tuple[float, ...]:
        """Each LED's ageing: its own ``ageing_per_1000h`` or the scenario's. [1/(1000 h)]"""
        return tuple(led_ageing_per_1000h if e.ageing_per_1000h is None
                     else e.ageing_per_1000h for e in self.emitters)

    def flicker_rels(self, led_flicker_rel: float) -> tuple[float, ...]:
        """Each LED's relative flicker SD: its own ``flicker_rel`` or the scenario's. [-]"""
        return tuple(led_flicker_rel if e.flicker_rel is None else e.flicker_rel
                     for e in self.emitters)


def expand_led_part(record: Any) -> Any:
    """An LED record with a catalogue part filled in (``"L8957"`` or ``{"part": ...}``).

    Fields given beside ``part`` override the catalogue's; anything else passes through.

    Raises
    ------
    ConfigError
        Unknown part name (the message lists the catalogue).
    """
    if isinstance(record, str):
        return led_part(record).led_record()
    if isinstance(record, dict) and record.get("part") is not None:
        given = {k: v for k, v in record.items() if v is not None}
        return {**led_part(str(record["part"])).led_record(), **given}
    return record


def _merge_legacy_leds(emitters: list[dict], old: dict[str, Any]) -> list[dict]:
    """LED records with the former per-LED lists (:data:`LEGACY_LED_KEYS`) merged in."""
    for key, value in old.items():
        if not isinstance(value, list | tuple):
            raise ConfigError(f"{key} needs one value per LED (a list), got {value!r}")
    counts = {key: len(value) for key, value in old.items()}
    if len(set(counts.values())) > 1:
        lengths = ", ".join(f"{k}: {n}" for k, n in counts.items())
        raise ConfigError(f"the per-LED lists differ in length ({lengths}); give one per LED")
    n = next(iter(counts.values()))
    if n != len(emitters) and len(old) < len(LEGACY_LED_KEYS):
        key = next(iter(old))
        raise ConfigError(
            f"{key} gives {n} LEDs but the scenario has {len(emitters)}; set a new LED set with "
            'one key: leds=[{"wavelength_nm": ..., "fwhm_nm": ..., "power_mw": ..., '
            '"responsivity_a_per_w": ...}, ...]'
        )
    out = [dict(e) for e in emitters] if n == len(emitters) else [{} for _ in range(n)]
    for key, value in old.items():
        for record, v in zip(out, value, strict=True):
            record[LEGACY_LED_KEYS[key]] = v
    return out
