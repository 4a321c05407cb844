"""A fleet of units: the preset's device with part-to-part deviations drawn from tolerances.

A team builds many units of one design. Each unit's parts differ from the datasheet's
typical values within the parts' tolerances: the LED's peak wavelength lies somewhere in
its bin, its power between the datasheet's minimum and typical values, the photodiode's
responsivity and the ADC's offset vary from unit to unit. :func:`draw_units` draws such
units, deterministically per ``(seed, unit index)``; each :class:`Unit` carries the
dotted overrides that make its device in :func:`nirglucose.simulate` and the ADC offset
the simulator has no key for (its offset is trimmed at 25 degC and only drifts), which
:func:`simulate_unit` adds to every code. The unit's data is relabelled with the
design's nominal wavelengths: firmware names a channel by the part it ordered, not by
the peak the part happens to have.

Every unit's deviations are fixed draws ``u`` in [-1, 1] scaled by
``tolerance_scale`` (0: every unit is the nominal device; 1: :class:`FleetTolerances`
as stated; 2: twice as wide), so the same unit index is the same unit at every scale
and a study across scales is paired.

Tolerances at scale 1 (:class:`FleetTolerances`, sources in each field):

* LED peak wavelength: uniform +-10 nm per LED, the SMC870's bin (860-880 nm,
  data/parts/leds.csv);
* LED power: uniform between (min / typ) and 1 times the nominal per LED, the L8957's
  3.4 mW min / 5.8 mW typ [1]_;
* photodiode responsivity: uniform +-5 %, one factor per unit (ASSUMPTION);
* ADC offset left after the factory trim: a uniform integer within +-4 LSB
  (ASSUMPTION).

References
----------
.. [1] Hamamatsu Photonics, L8957 infrared LED datasheet: radiant flux 3.4 min, 5.8 typ
   mW at 50 mA, peak wavelength 840-900 nm (data/parts/SOURCES.md).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pandas as pd

from ..api import simulate
from ..config import resolve_config
from ..config.detector import band_responsivity_a_per_w, responsivity_curve
from ..config.parts import led_part
from ..dataset import Dataset
from ..exceptions import ConfigError, check_seed

__all__ = [
    "DEFAULT_BIN_PART",
    "FleetTolerances",
    "MAX_TOLERANCE_SCALE",
    "Unit",
    "apply_adc_offset",
    "draw_units",
    "simulate_unit",
]

#: Largest tolerance scale: beyond it the LED power's lower end reaches zero. [-]
MAX_TOLERANCE_SCALE = 2.4


#: Catalogue LED whose peak-wavelength bin sets the default tolerance (860-880 nm).
DEFAULT_BIN_PART = "SMC870"


def _bin_half_width_nm(part: str) -> float:
    """Half the min-max peak-wavelength bin of a catalogue LED (data/parts/leds.csv). [nm]"""
    p = led_part(part)
    if p.wavelength_min_nm is None or p.wavelength_max_nm is None:
        raise ConfigError(f"LED part {part!r} states no wavelength bin; pick one that does")
    return (p.wavelength_max_nm - p.wavelength_min_nm) / 2


@dataclass(frozen=True)
class FleetTolerances:
    """Half-widths of the part-to-part deviations at tolerance scale 1.

    Attributes
    ----------
    wavelength_half_width_nm : float
        LED peak wavelength within +- this of its nominal value: by default half the
        bin of :data:`DEFAULT_BIN_PART`, read from data/parts/leds.csv (the SMC870's
        860-880 nm: 10 nm), the narrowest stated bin of the catalogue; the L8957's is
        +-30 nm (:meth:`from_catalogue`). [nm]
    power_min_ratio : float
        LED power uniform between this fraction of the nominal and the nominal: the
        L8957 datasheet's 3.4 mW min / 5.8 mW typ (data/parts/SOURCES.md); the typical
        value is the upper end, since a unit driven for mid-scale codes must not clip.
        At scale s the lower end is ``1 - s (1 - ratio)``. [-]
    responsivity_rel : float
        Photodiode responsivity within +- this fraction, one factor per unit for all
        its LEDs (one photodiode per unit). ASSUMPTION: the catalogue gives typical
        responsivities only. [-]
    adc_offset_lsb : int
        ADC offset left after the factory's offset trim, a uniform integer within
        +- this, the same for the reading and the reference (one converter).
        ASSUMPTION. [LSB]
    """

    wavelength_half_width_nm: float = field(
        default_factory=lambda: _bin_half_width_nm(DEFAULT_BIN_PART)
    )
    power_min_ratio: float = 3.4 / 5.8
    responsivity_rel: float = 0.05
    adc_offset_lsb: int = 4

    @classmethod
    def from_catalogue(cls, part: str) -> FleetTolerances:
        """Tolerances with the wavelength bin of a catalogue LED (``data/parts/leds.csv``).

        The half-width is half the part's min-max peak-wavelength bin.

        Raises
        ------
        ConfigError
            Unknown part, or a part whose datasheet states no bin.

        Examples
        --------
        >>> FleetTolerances.from_catalogue("L8957").wavelength_half_width_nm
        30.0
        """
        return cls(wavelength_half_width_nm=_bin_half_width_nm(part))


@dataclass(frozen=True)
class Unit:
    """One unit of the fleet.

    Attributes
    ----------
    index : int
        The unit's index in the fleet (its draws depend on it and the seed only). [-]
    overrides : dict
        Dotted overrides that make this unit's device (``leds``: every LED record with
        its drawn wavelength, power and responsivity), over the design's overrides.
    adc_offset_lsb : int
        The unit's ADC offset, added to every code by :func:`simulate_unit`. [LSB]
    nominal_wavelengths_nm : tuple of float
        The design's LED wavelengths, the unit's channel names. [nm]
    wavelength_shift_nm, power_ratio : tuple of float
        Per LED: peak wavelength minus nominal [nm]; power over nominal [-].
    responsivity_ratio : float
        The unit's responsivity over nominal. [-]
    """

    index: int
    overrides: dict[str, Any] = field(repr=False)
    adc_offset_lsb: int
    nominal_wavelengths_nm: tuple[float, ...]
    wavelength_shift_nm: tuple[float, ...]
    power_ratio: tuple[float, ...]
    responsivity_ratio: float


def _check_scale(tolerance_scale: Any) -> float:
    ok = isinstance(tolerance_scale, int | float) and not isinstance(tolerance_scale, bool)
    if not ok or not (0 <= float(tolerance_scale) <= MAX_TOLERANCE_SCALE):
        raise ConfigError(
            f"tolerance_scale must be a number in 0-{MAX_TOLERANCE_SCALE:g} (0: identical "
            f"units, 1: the stated tolerances), got {tolerance_scale!r}"
        )
    return float(tolerance_scale)


def _unit_draws(seed: int, index: int, n_led: int) -> dict[str, Any]:
    """The fixed standardised draws of one unit (independent of the scale)."""
    rng = np.random.default_rng(np.random.SeedSequence([int(seed), 0xF1EE7, int(index)]))
    return {
        "wavelength": rng.uniform(-1.0, 1.0, n_led),
        "power": rng.uniform(0.0, 1.0, n_led),
        "responsivity": float(rng.uniform(-1.0, 1.0)),
        "offset": float(rng.uniform(-1.0, 1.0)),
    }


def draw_units(
    preset: str = "paper",
    n_units: int = 8,
    tolerance_scale: float = 1.0,
    seed: int = 0,
    *,
    overrides: dict[str, Any] | None = None,
    tolerances: FleetTolerances | None = None,
) -> list[Unit]:
    """Draw ``n_units`` units of the preset's device with part-to-part deviations.

    Parameters
    ----------
    preset : str
        The design's preset.
    n_units : int
        Units to draw. [-]
    tolerance_scale : float
        Multiplier of every tolerance of ``tolerances`` (0: nominal units). [-]
    seed : int
        Seed; unit ``i``'s deviations depend on ``(seed, i)`` only.
    overrides : dict, optional
        The design's own dotted overrides (its LED set, detector, ...).
    tolerances : FleetTolerances, optional
        Half-widths at scale 1 (default :class:`FleetTolerances`).

    Returns
    -------
    list of Unit

    Raises
    ------
    ConfigError
        A bad count, seed or scale, or a unit the config refuses.

    Examples
    --------
    >>> u = draw_units("paper", 2, 1.0, seed=0)
    >>> len(u), len(u[0].wavelength_shift_nm), all(abs(s) <= 10 for s in u[0].wavelength_shift_nm)
    (2, 4, True)
    >>> draw_units("paper", 1, 0.0)[0].wavelength_shift_nm
    (0.0, 0.0, 0.0, 0.0)
    """
    if isinstance(n_units, bool) or not isinstance(n_units, int | np.integer) or n_units < 1:
        raise ConfigError(f"n_units must be a positive integer, got {n_units!r}")
    check_seed(seed)
    scale = _check_scale(tolerance_scale)
    tol = tolerances or FleetTolerances()
    base = dict(overrides or {})
    cfg = resolve_config(preset, base)
    emitters = [e.model_dump(mode="json") for e in cfg.leds.emitters]
    curve = responsivity_curve(cfg.detector) if cfg.detector is not None else None
    nominal = tuple(float(w) for w in cfg.leds.wavelengths_nm)
    out = []
    for i in range(int(n_units)):
        d = _unit_draws(int(seed), i, len(emitters))
        shift = np.round(scale * tol.wavelength_half_width_nm * d["wavelength"], 2)
        power = 1.0 - scale * (1.0 - tol.power_min_ratio) * d["power"]
        resp = 1.0 + scale * tol.responsivity_rel * d["responsivity"]
        offset = int(np.rint(scale * tol.adc_offset_lsb * d["offset"]))
        records = []
        for e, ds_nm, p in zip(emitters, shift, power, strict=True):
            wl = round(float(e["wavelength_nm"]) + float(ds_nm), 2)
            r = e["responsivity_a_per_w"]
            if curve is not None:  # the detector's curve at the unit's own peak
                r = band_responsivity_a_per_w(wl, e["fwhm_nm"], curve)
            records.append({**e, "wavelength_nm": wl, "power_mw": float(e["power_mw"]) * float(p),
                            "responsivity_a_per_w": float(r) * resp})
        unit_over = {"leds": records}
        resolve_config(preset, {**base, **unit_over})  # refuse a unit the config refuses
        out.append(
            Unit(
                index=i,
                overrides=unit_over,
                adc_offset_lsb=offset,
                nominal_wavelengths_nm=nominal,
                wavelength_shift_nm=tuple(float(s) + 0.0 for s in shift),
                power_ratio=tuple(float(p) for p in power),
                responsivity_ratio=float(resp),
            )
        )
    return out


def _relabel(frame: pd.DataFrame, actual_nm, nominal_nm) -> pd.DataFrame:
    """Per-LED columns named by the unit's actual peaks renamed to the nominal ones."""
    mapping = {}
    for a, n in zip(actual_nm, nominal_nm, strict=True):
        la, ln = f"_{a:g}", f"_{n:g}"
        if la == ln:
            continue
        for c in frame.columns:
            if isinstance(c, str) and c.endswith(la) and (c.startswith("adc_") or
                                                           c.startswith("true_")):
                mapping[c] = c[: -len(la)] + ln
    return frame.rename(columns=mapping)


def apply_adc_offset(frame: pd.DataFrame, offset_lsb: int, adc_bits: int) -> pd.DataFrame:
    """Add a static ADC offset to every code (``adc_*`` and ``adc_ref_*``), clipped.

    The offset is added to the converter's output like the simulator's offset drift
    (:func:`~nirglucose.simulation.hardware.adc_convert`: round(V/Vref FS + INL +
    offset), clipped to 0 .. 2^bits - 1); an integer offset commutes with the rounding.

    Parameters
    ----------
    frame : pandas.DataFrame
        A dataset's frame.
    offset_lsb : int
        Offset. [LSB]
    adc_bits : int
        Resolution. [bit]

    Returns
    -------
    pandas.DataFrame
        A copy with the codes shifted.

    Examples
    --------
    >>> apply_adc_offset(pd.DataFrame({"adc_850": [10, 4094]}), 3, 12)["adc_850"].tolist()
    [13, 4095]
    """
    if isinstance(offset_lsb, bool) or not isinstance(offset_lsb, int | np.integer):
        raise ConfigError(f"offset_lsb must be an integer number of LSB, got {offset_lsb!r}")
    out = frame.copy()
    if offset_lsb == 0:
        return out
    full = 2 ** int(adc_bits) - 1
    for c in out.columns:
        if isinstance(c, str) and c.startswith("adc_"):
            out[c] = np.clip(out[c].to_numpy() + int(offset_lsb), 0, full)
    return out


def simulate_unit(
    unit: Unit,
    preset: str = "paper",
    n_subjects: int = 20,
    per_subject: int = 3,
    seed: int = 0,
    *,
    overrides: dict[str, Any] | None = None,
) -> Dataset:
    """Readings of ``n_subjects`` subjects measured by one unit, named as the design's.

    The unit's device is simulated by :func:`nirglucose.simulate` with the design's and
    the unit's overrides; its ADC offset is added to every code
    (:func:`apply_adc_offset`); per-LED columns are renamed to the nominal wavelengths;
    and the dataset carries the *design's* config, so an estimator sees what a unit
    reports -- its part numbers, not its parts (the oracle then inverts the nominal
    design's optics with every reading's true nuisances).

    Parameters
    ----------
    unit : Unit
        From :func:`draw_units` with the same preset and overrides.
    preset : str
        The design's preset.
    n_subjects, per_subject : int
        Subjects and readings per subject. [-]
    seed : int
        Seed of the subjects and the noise (the same seed gives the same subjects on
        every unit: the transfer standards).
    overrides : dict, optional
        The design's dotted overrides (as given to :func:`draw_units`).

    Returns
    -------
    Dataset
    """

    base = dict(overrides or {})
    own = {**base, **unit.overrides}
    ds = simulate(preset, n_subjects, per_subject, seed, overrides=own)
    actual = resolve_config(preset, own).leds.wavelengths_nm
    design = resolve_config(preset, base)
    frame = apply_adc_offset(ds.frame, unit.adc_offset_lsb, design.hardware.adc_bits)
    frame = _relabel(frame, actual, unit.nominal_wavelengths_nm)
    return Dataset(frame, config=design, seed=int(seed))
