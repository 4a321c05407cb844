"""The device a twin is fitted for, read from its file, and the base scenario it starts from.

A twin knows of a device only what its file declares (:class:`TwinDevice`): the LEDs
(``adc_<nm>`` columns), the ADC resolution, whether it records reference codes and
whether those change reading by reading (a monitor photodiode) or stay fixed per
subject (a start-up reference), which physiological columns it records, whether it
has reading times, and the study's size (subjects, readings per subject). What the file
does not declare is the base scenario's: the ``physical`` preset (glucose's optical
effects at the published magnitude, no device capabilities) with each LED given the
assumed width and responsivity below; the twin's parameters (:mod:`.parameters`)
then move the scenario to the file.
"""

from __future__ import annotations

import hashlib
import json
import warnings
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np
import pandas as pd

from .._version import __version__
from ..dataset import Dataset
from ..dataset.adc import check_dc_level
from ..dataset.columns import PPG_COLUMNS
from ..dataset.schema import DeviceSchema
from ..exceptions import DataError

__all__ = [
    "BASE_PRESET",
    "LED_FWHM_NM",
    "LED_RESPONSIVITY_A_PER_W",
    "NOMINAL_POWER_MW",
    "TIME_COLUMNS",
    "TwinDevice",
    "device_of",
    "base_overrides",
    "subject_codes",
]

#: The scenario a twin starts from: glucose at its published magnitude
#: (``glucose.signal_gain`` 1), no device capabilities (DESIGN.md, "Regimes").
BASE_PRESET = "physical"
#: Emission width assumed for an LED the file names only by its wavelength: the
#: TSAL6200 class (:class:`nirglucose.config.LED`'s ``fwhm_nm`` description). [nm]
LED_FWHM_NM = 40.0
#: Photodiode responsivity assumed at each LED (a silicon photodiode's 0.5-0.6 A/W in
#: 850-950 nm, Hamamatsu S1336); the fitted LED power absorbs any other value. [A/W]
LED_RESPONSIVITY_A_PER_W = 0.5
#: LED power of the nominal device from which the power prior is scaled. [mW]
NOMINAL_POWER_MW = 3.0
#: Columns that give a reading's time (the worn-device format's ``time_min``).
TIME_COLUMNS = ("time_min",)
#: Fewest subjects and readings per subject a twin is fitted from: a within-subject
#: spread needs two readings, a between-subject spread several people (the small-data
#: policy's 10 subjects for a grouped error; 5 here, warned below 10).
MIN_TWIN_SUBJECTS = 5
#: Largest within-person SD of reading times a twin simulates: a uniform over the year
#: that ``hardware.hours_since_reference_h`` allows (8760 h / sqrt(12)). [h]
MAX_TIME_SD_H = 8760.0 / 12 ** 0.5
MIN_TWIN_READINGS = 2


@dataclass(frozen=True)
class TwinDevice:
    """What a device file declares, and the study's size.

    Parameters
    ----------
    wavelengths_nm : tuple of float
        LED centres, ascending. [nm]
    adc_bits : int
        ADC resolution. [bit]
    reference : bool
        The file has ``adc_ref_<nm>`` columns.
    monitor : bool
        Its reference codes change within a subject (a monitor photodiode read at each
        reading) rather than staying at a start-up value.
    physiology : tuple of str
        The known physiological columns the file records.
    times : bool
        The file has reading times (:data:`TIME_COLUMNS`).
    n_subjects : int
        People in the file. [-]
    per_subject : int
        Readings per person, the median over people (the simulated design). [-]
    time_sd_h : float
        With reading times: the pooled within-person SD of the readings' times (0
        without). The simulated readings follow each start-up reference by a uniform
        time with this SD (:func:`base_overrides`). [h]
    """

    wavelengths_nm: tuple[float, ...]
    adc_bits: int
    reference: bool
    monitor: bool
    physiology: tuple[str, ...]
    times: bool
    n_subjects: int
    per_subject: int
    time_sd_h: float = 0.0

    @property
    def full_scale(self) -> int:
        """The ADC's largest code, 2^bits - 1. [-]"""
        return 2 ** self.adc_bits - 1

    @property
    def labels(self) -> list[str]:
        """Each LED's column label (``940``, ``660.5``)."""
        return [f"{w:g}" for w in self.wavelengths_nm]

    def to_json(self) -> dict[str, Any]:
        """The device as plain JSON types."""
        doc = asdict(self)
        doc["wavelengths_nm"] = list(self.wavelengths_nm)
        doc["physiology"] = list(self.physiology)
        return doc

    @classmethod
    def from_json(cls, doc: Any) -> TwinDevice:
        """Rebuild from :meth:`to_json`; DataError (one line) when malformed."""
        try:
            out = cls(
                tuple(float(w) for w in doc["wavelengths_nm"]), int(doc["adc_bits"]),
                _bool(doc["reference"]), _bool(doc["monitor"]),
                tuple(str(c) for c in doc["physiology"]), _bool(doc["times"]),
                int(doc["n_subjects"]), int(doc["per_subject"]),
                float(doc.get("time_sd_h", 0.0)),
            )
        except (KeyError, TypeError, ValueError):
            raise DataError("twin.json has a malformed 'device' entry; fit the twin again "
                            "(nirglucose twin --data FILE --out DIR)") from None
        if (not out.wavelengths_nm or not 1 <= out.adc_bits <= 32 or out.n_subjects < 1
                or not 0 <= out.time_sd_h <= MAX_TIME_SD_H):
            raise DataError("twin.json's 'device' entry is out of range (no LED, adc_bits "
                            "outside 1-32, no subject or time_sd_h outside 0-"
                            f"{MAX_TIME_SD_H:g} h); fit the twin again")
        return out

    def cache_key(self, settings: dict[str, Any]) -> str:
        """A short hash of the device, the inference settings and the package version:
        the posterior estimator trained for one file serves every file with the same key."""
        doc = {"device": self.to_json(), "settings": settings, "version": __version__}
        return hashlib.sha256(json.dumps(doc, sort_keys=True).encode()).hexdigest()[:16]


def _bool(value: Any) -> bool:
    if not isinstance(value, bool):
        raise TypeError(value)
    return value


def device_of(ds: Dataset, adc_bits: int | None = None) -> TwinDevice:
    """The :class:`TwinDevice` a dataset (a device file read by
    :func:`nirglucose.load_dataset`) declares.

    Raises
    ------
    DataError
        No ``adc_<nm>`` column, no ``subject_id`` or ``glucose_mgdl`` column, fewer than
        :data:`MIN_TWIN_SUBJECTS` people or a median under :data:`MIN_TWIN_READINGS`
        readings per person, an undeclared ADC resolution where codes fit several.
    """
    frame = ds.frame
    schema = DeviceSchema.infer(ds, adc_bits=adc_bits)
    for col, why in (("subject_id", "a twin separates people from readings"),
                     ("glucose_mgdl", "a twin measures the code-glucose slope")):
        if col not in frame.columns:
            raise DataError(f"the file has no {col!r} column ({why}); add it "
                            "(docs/user_data.md, 'The device file')")
    _refuse_ac_coupled(frame, schema)
    counts = frame.groupby("subject_id", sort=False).size().to_numpy()
    per = int(np.median(counts))
    if len(counts) < MIN_TWIN_SUBJECTS or per < MIN_TWIN_READINGS:
        raise DataError(
            f"a twin needs at least {MIN_TWIN_SUBJECTS} people with {MIN_TWIN_READINGS} or "
            f"more readings each; the file has {len(counts)} people, a median of {per} "
            "readings each")
    monitor = False
    if schema.reference:
        refs = frame[[f"adc_ref_{w:g}" for w in schema.wavelengths_nm]]
        monitor = bool((refs.groupby(frame["subject_id"]).nunique() > 1).to_numpy().any())
    times = next((c for c in TIME_COLUMNS if c in frame.columns), None)
    return TwinDevice(
        wavelengths_nm=tuple(float(w) for w in schema.wavelengths_nm),
        adc_bits=int(schema.adc_bits), reference=bool(schema.reference), monitor=monitor,
        physiology=tuple(schema.physiology),
        times=times is not None,
        n_subjects=len(counts), per_subject=per,
        time_sd_h=0.0 if times is None else _time_sd_h(frame, times),
    )


def _refuse_ac_coupled(frame: pd.DataFrame, schema) -> None:
    """Refuse, in one line, channels whose every reading sits at mid-scale: an AC-coupled
    front end records no light level, which is what a twin fits
    (:func:`~nirglucose.dataset.adc.check_dc_level`)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the refusal below says it
        flagged = check_dc_level(frame, tuple(f"adc_{w}" for w in schema.labels),
                                 schema.full_scales)
    if flagged:
        raise DataError(
            f"{', '.join(flagged)}: every reading sits at mid-scale (an AC-coupled front end, "
            "which removes the light level?): a twin fits the light each LED reads through "
            "the skin, and these codes carry none; give the DC-coupled readings")


def _time_sd_h(frame: pd.DataFrame, column: str) -> float:
    """Pooled within-person SD of the reading times (minutes in the file). [h]

    Raises
    ------
    DataError
        A time that is not a finite number, or a spread beyond :data:`MAX_TIME_SD_H`.
    """
    t = pd.to_numeric(frame[column], errors="coerce").to_numpy(float)
    if not np.isfinite(t).all():
        raise DataError(f"the file's {column} column holds values that are not finite numbers "
                        "(minutes); fix or drop them")
    sid, k = subject_codes(frame)
    n_per = np.bincount(sid, minlength=k)
    dev = t - (np.bincount(sid, t, k) / n_per)[sid]
    sd_h = float(np.sqrt(dev @ dev / max(len(t) - k, 1))) / 60.0
    if sd_h > MAX_TIME_SD_H:
        raise DataError(f"the file's {column} spread within a person ({sd_h:.0f} h SD) exceeds "
                        f"{MAX_TIME_SD_H:g} h: a twin simulates readings within a year of a "
                        "start-up reference (hardware.hours_since_reference_h)")
    return round(sd_h, 4)


def base_overrides(device: TwinDevice) -> dict[str, Any]:
    """Overrides of :data:`BASE_PRESET` that give the device's LEDs (at the assumed width,
    responsivity and :data:`NOMINAL_POWER_MW`), its ADC, its kind of reference and its
    PPG columns; the physiological vector is measured (with the instruments' errors); with
    reading times, a ``time_min`` column and readings a uniform time after each start-up
    reference whose SD is the file's (:attr:`TwinDevice.time_sd_h`)."""
    led = {"fwhm_nm": LED_FWHM_NM, "power_mw": NOMINAL_POWER_MW,
           "responsivity_a_per_w": LED_RESPONSIVITY_A_PER_W}
    out = {
        "leds": [{"wavelength_nm": w, **led} for w in device.wavelengths_nm],
        "hardware.adc_bits": device.adc_bits,
        "device.monitor_photodiode": device.monitor,
        "device.ppg_perfusion_spo2": any(c in device.physiology for c in PPG_COLUMNS),
        "device.physiology": "measured",
    }
    if device.times:  # readings a uniform time after the reference, the file's spread
        out["device.reading_times"] = True
        out["hardware.hours_since_reference_h"] = [0.0, round(12 ** 0.5 * device.time_sd_h, 4)]
    return out


def subject_codes(frame: pd.DataFrame) -> tuple[np.ndarray, int]:
    """Each row's subject as 0..k-1 (in order of first appearance) and k."""
    codes, uniques = pd.factorize(frame["subject_id"], sort=False)
    return codes.astype(np.int64), len(uniques)
