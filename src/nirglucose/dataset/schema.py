"""The one schema boundary: any device's measured columns -> named absorbances and physiology.

Every estimator reads its input through :class:`DeviceSchema` (the estimators' side,
which records the fitted input on an estimator, is :mod:`nirglucose.fitted`; the
scikit-learn transformer around it is
:class:`nirglucose.features.MeasurementTransformer`); nothing after it knows how many
LEDs a device has, whether it records a reference reading, its ADC resolution, or which
physiological columns it measures.

A device's file holds

* ``adc_<nm>``: ADC codes for any set of LED wavelengths (one or more);
* ``adc_ref_<nm>``: the device's reference codes for the same LEDs, where it has them
  (all or none); without them the ADC's full scale 2^bits - 1 plays I0;
* any of the known physiological columns (:data:`~nirglucose.dataset.KNOWN_PHYSIOLOGY`).

The ADC resolution comes from the declared option (the linear models' ``adc_bits=``
parameter, or a Dataset's ``metadata["adc_bits"]`` for any model), else the file's
scenario (``hardware.adc_bits``), else the package default (12 bits, the study's).
Absorbance is computed here and only here: A = log10(I0 / I) (the modified
Beer–Lambert law, Cope & Delpy 1988 [1]_).

A plain numeric array carries no column names, hence no device: the schema fitted on it
is *plain*, and its columns are taken as generic spectral inputs (absorbance-like, on
equally spaced channels, no physiology). This is what scikit-learn's estimator checks
exercise. An array given to a model fitted on a device's frame is read as that device's
:attr:`DeviceSchema.raw_columns`, in order.

References
----------
.. [1] M. Cope, D. T. Delpy, Med. Biol. Eng. Comput. 26, 289-294 (1988),
   doi:10.1007/BF02447083 (modified Beer–Lambert law).
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Any, NamedTuple

import numpy as np
import pandas as pd

from ..constants import DEFAULT_LED_WAVELENGTHS_NM, PHYSIOLOGICAL_RANGES
from ..exceptions import DataError, is_finite_number
from .adc import channel_converters, check_channel_bits, resolve_adc_bits
from .columns import (
    DEFAULT_ADC_BITS,
    GLUCOSE_REPORTING_RANGE_MGDL,
    KNOWN_PHYSIOLOGY,
    has_reference_columns,
    led_wavelengths_in,
)
from .container import Dataset
from .files import check_frame
from .small_data import MIN_FIT_ROWS, MIN_FIT_SUBJECTS

__all__ = [
    "DeviceSchema",
    "Measurements",
    "check_fit_size",
    "check_reference_glucose",
    "meter_flags",
    "schema_for_fit",
    "row_fingerprints",
    "rows_seen_in_training",
    "MAX_TRAIN_FINGERPRINTS",
]


def _first_rows(mask: np.ndarray, limit: int = 5) -> str:
    rows = np.flatnonzero(mask)
    shown = ", ".join(str(int(r)) for r in rows[:limit])
    more = f" and {len(rows) - limit} more" if len(rows) > limit else ""
    return f"rows {shown}{more}"


class Measurements(NamedTuple):
    """What the schema gives every estimator.

    Attributes
    ----------
    absorbance : numpy.ndarray
        (n, k) decadic absorbances A = log10(I0 / I), one column per LED. [-]
    physiology : numpy.ndarray
        (n, m) the physiological columns in :attr:`DeviceSchema.physiology` order.
        [column units]
    """

    absorbance: np.ndarray
    physiology: np.ndarray


@dataclass(frozen=True)
class DeviceSchema:
    """A device's measured columns.

    Parameters
    ----------
    wavelengths_nm : tuple of float
        LED wavelengths, ascending (empty for a plain schema). [nm]
    reference : bool
        Whether the device records reference codes ``adc_ref_<nm>``.
    adc_bits : int
        ADC resolution. [bit]
    physiology : tuple of str
        The known physiological columns the device records, in canonical order.
    n_plain : int
        Width of a plain schema (0 for a device).
    channel_bits : tuple of int
        Per LED, its converter's resolution where the device mixes converters (empty:
        ``adc_bits`` for every channel; :func:`~nirglucose.dataset.adc.channel_converters`).
        [bit]
    channel_full_scale : tuple of float
        Per LED, its full-scale code (empty: 2^bits - 1 of each channel). [ADC code]
    train_min, train_max : tuple of float
        Per raw column, the smallest and largest value the model was fitted on (empty
        before a fit, or for a model file written before they were recorded); values
        outside are extrapolation (:meth:`outside_training`). [column units]
    glucose_unit : str
        Unit of the reference glucose column the model was fitted on (``mg/dL`` or
        ``mmol/L``): what ``predict`` answers in unless asked otherwise.
    train_rows, train_rows_every, train_row_ids : tuple of str, int, tuple of str
        Fingerprints of the training rows (:func:`row_fingerprints`, their raw columns
        and identity columns ``train_row_ids``) of which one in ``train_rows_every`` is
        kept (at most :data:`MAX_TRAIN_FINGERPRINTS`): how ``predict`` tells that it was
        given the rows the model was fitted on.
    """

    wavelengths_nm: tuple[float, ...] = tuple(DEFAULT_LED_WAVELENGTHS_NM)
    reference: bool = True
    adc_bits: int = DEFAULT_ADC_BITS
    physiology: tuple[str, ...] = field(default_factory=lambda: tuple(KNOWN_PHYSIOLOGY[:12]))
    n_plain: int = 0
    # per-channel converters (issue 43): empty when every channel has adc_bits
    channel_bits: tuple[int, ...] = ()
    channel_full_scale: tuple[float, ...] = ()
    # the training range describes a fit, not the device: not part of equality
    train_min: tuple[float, ...] = field(default=(), compare=False)
    train_max: tuple[float, ...] = field(default=(), compare=False)
    glucose_unit: str = field(default="mg/dL", compare=False)
    train_rows: tuple[str, ...] = field(default=(), compare=False)
    train_rows_every: int = field(default=1, compare=False)
    train_row_ids: tuple[str, ...] = field(default=(), compare=False)

    # ------------------------------------------------------------------ construction

    @classmethod
    def plain(cls, width: int) -> DeviceSchema:
        """The schema of a plain numeric array of ``width`` columns."""
        return cls(wavelengths_nm=(), reference=False, adc_bits=0, physiology=(), n_plain=width)

    @classmethod
    def infer(cls, X: Any, adc_bits: Any = None, adc_full_scale: Any = None
              ) -> DeviceSchema:
        """The schema of a Dataset or DataFrame from its column names.

        Parameters
        ----------
        X : Dataset or pandas.DataFrame
            A device's measurements.
        adc_bits : int or mapping, optional
            Declared ADC resolution, one for every channel or per channel
            (``{"adc_940": 10, "adc_1050": 18}``); else the Dataset's
            ``metadata["adc_bits"]`` (what ``nirglucose fit --adc-bits`` sets), the
            scenario's ``hardware.adc_bits``, else the policy of
            :mod:`~nirglucose.dataset.adc`. [bit]
        adc_full_scale : mapping, optional
            Per channel, a full-scale code other than 2^bits - 1 (else the Dataset's
            ``metadata["adc_full_scale"]``). [ADC code]

        Raises
        ------
        DataError
            No ``adc_<nm>`` column, reference codes for some LEDs only, or a bad
            resolution.
        """
        frame = X.frame if isinstance(X, Dataset) else X
        meta_bits = None
        if isinstance(X, Dataset):
            meta_bits = X.metadata.get("adc_bits")
            if meta_bits is None and X.config is not None:
                meta_bits = int(X.config.hardware.adc_bits)
            if adc_full_scale is None:
                adc_full_scale = X.metadata.get("adc_full_scale")
        wl = led_wavelengths_in(frame.columns)
        if not wl:
            raise DataError(_no_adc_message(frame.columns))
        bits, _ = resolve_adc_bits(frame, adc_bits, meta_bits)
        reference = has_reference_columns(frame.columns, wl)
        physio = tuple(c for c in KNOWN_PHYSIOLOGY if c in frame.columns)
        if isinstance(bits, int) and not adc_full_scale:
            return cls(wl, reference, int(bits), physio, 0)
        labels = tuple(f"{w:g}" for w in wl)
        per_bits, per_fs = channel_converters(labels, bits, adc_full_scale)
        return cls(wl, reference, max(per_bits), physio, 0, per_bits, per_fs)

    @classmethod
    def from_json(cls, doc: Any) -> DeviceSchema:
        """Rebuild from :meth:`to_json` (validated; DataError when malformed)."""
        try:
            wl, ref, bits = doc["wavelengths_nm"], doc["reference"], doc["adc_bits"]
            physio, n_plain = doc["physiology"], doc.get("n_plain", 0)
            ok = (isinstance(wl, list) and all(is_finite_number(w) and w > 0 for w in wl)
                  and isinstance(ref, bool) and isinstance(physio, list)
                  and all(isinstance(c, str) for c in physio)
                  and is_finite_number(n_plain, integer=True) and n_plain >= 0)
        except (KeyError, TypeError):
            ok = False
        if not ok:
            raise DataError("model file has a malformed 'schema' entry; refit the model")
        plain_ok = bits == 0 and n_plain  # a plain array's schema has no ADC
        if not (is_finite_number(bits, integer=True) and (1 <= bits <= 32 or plain_ok)):
            raise DataError(f"model file's schema has adc_bits {bits!r}; expected an integer "
                            "from 1 to 32; the file is corrupt, refit the model")
        s = cls(tuple(float(w) for w in wl), ref, int(bits), tuple(physio), int(n_plain))
        s = _channels_from_json(s, doc)
        lo, hi = doc.get("train_min") or (), doc.get("train_max") or ()
        try:
            lo, hi = tuple(float(v) for v in lo), tuple(float(v) for v in hi)
        except (TypeError, ValueError):
            raise DataError(
                "model file has a malformed 'schema' training range; refit the model"
            ) from None
        if not np.isfinite([*lo, *hi]).all():
            raise DataError("model file's schema training range has NaN or infinite values; "
                            "the file is corrupt, refit the model")
        if len(lo) != len(hi) or (lo and len(lo) != len(s.raw_columns)):
            raise DataError(
                "model file's schema training range does not match its columns; refit the model"
            )
        s = replace(s, train_min=lo, train_max=hi)
        unknown = [c for c in s.physiology if c not in KNOWN_PHYSIOLOGY]
        if unknown or (s.n_plain == 0 and not s.wavelengths_nm):
            raise DataError(f"model file's schema names unknown columns {unknown}")
        return s

    def to_json(self) -> dict[str, Any]:
        """A JSON-ready dict."""
        return {
            "wavelengths_nm": list(self.wavelengths_nm),
            "reference": self.reference,
            "adc_bits": self.adc_bits,
            "physiology": list(self.physiology),
            "n_plain": self.n_plain,
            **({"train_min": list(self.train_min), "train_max": list(self.train_max)}
               if self.train_min else {}),
            **({"channel_bits": list(self.channel_bits),
                "channel_full_scale": list(self.channel_full_scale)}
               if self.channel_bits else {}),
            **({"glucose_unit": self.glucose_unit} if self.glucose_unit != "mg/dL" else {}),
            **({"train_rows": list(self.train_rows), "train_rows_every":
                self.train_rows_every, "train_row_ids": list(self.train_row_ids)}
               if self.train_rows else {}),
        }

    def with_training_range(self, Xa: np.ndarray) -> DeviceSchema:
        """This schema with the per-column range of validated raw columns ``Xa``."""
        if not len(Xa) or self.is_plain:
            return self
        return replace(self, train_min=tuple(float(v) for v in Xa.min(axis=0)),
                       train_max=tuple(float(v) for v in Xa.max(axis=0)))

    def outside_training(self, Xa: np.ndarray) -> list[str]:
        """Per row of validated raw columns, the columns outside the training range
        (``'adc_940>'`` above it, ``'adc_940<'`` below), ``';'``-joined; ``''`` inside.

        Examples
        --------
        >>> s = DeviceSchema((940.0,), reference=False, adc_bits=10, physiology=())
        >>> s.with_training_range(np.array([[500.0], [600.0]])).outside_training(
        ...     np.array([[550.0], [900.0]]))
        ['', 'adc_940>']
        """
        if not self.train_min:
            return [""] * len(Xa)
        lo, hi = np.asarray(self.train_min), np.asarray(self.train_max)
        cols = np.asarray(self.raw_columns, dtype=object)
        below, above = Xa < lo, Xa > hi
        return [";".join([f"{c}<" for c in cols[b]] + [f"{c}>" for c in cols[a]])
                for b, a in zip(below, above, strict=True)]

    # ------------------------------------------------------------------ description

    @property
    def is_plain(self) -> bool:
        """True for the schema of a plain array (no column names)."""
        return self.n_plain > 0

    @property
    def labels(self) -> tuple[str, ...]:
        """Channel labels: wavelengths as ``'940'``, or ``'x0'``.. for a plain schema."""
        if self.is_plain:
            return tuple(f"x{i}" for i in range(self.n_plain))
        return tuple(f"{w:g}" for w in self.wavelengths_nm)

    @property
    def n_channels(self) -> int:
        """Number of absorbance channels."""
        return self.n_plain if self.is_plain else len(self.wavelengths_nm)

    @property
    def full_scale(self) -> int:
        """Largest ADC code, 2^bits - 1 (of the widest converter where the channels have
        their own: :attr:`full_scales`). [ADC code]"""
        return 2**self.adc_bits - 1

    @property
    def per_channel(self) -> bool:
        """Whether the channels have converters of their own (:attr:`channel_bits`)."""
        return bool(self.channel_bits)

    @property
    def full_scales(self) -> tuple[float, ...]:
        """Per LED, its full-scale code (I0 without reference codes). [ADC code]"""
        if self.channel_full_scale:
            return self.channel_full_scale
        return (float(self.full_scale),) * self.n_channels

    def converter_metadata(self) -> dict[str, Any]:
        """The converters as a Dataset's metadata declares them (``adc_bits``: one int, or
        per channel; ``adc_full_scale`` where a channel's is not 2^bits - 1)."""
        if not self.per_channel:
            return {"adc_bits": self.adc_bits}
        cols = [f"adc_{w}" for w in self.labels]
        fs = {c: f for c, f, b in zip(cols, self.full_scales, self.channel_bits, strict=True)
              if f != 2 ** b - 1}
        return {"adc_bits": dict(zip(cols, self.channel_bits, strict=True)),
                **({"adc_full_scale": fs} if fs else {})}

    def code_full_scales(self) -> dict[str, float]:
        """Each code column (``adc_<nm>``, ``adc_ref_<nm>``) and its full scale (empty for
        a schema whose channels share one converter). [ADC code]"""
        if not self.per_channel:
            return {}
        out = {f"adc_{w}": fs for w, fs in zip(self.labels, self.full_scales, strict=True)}
        return {**out, **{f"adc_ref_{w}": fs for w, fs in zip(self.labels, self.full_scales,
                                                               strict=True)}}

    @property
    def raw_columns(self) -> tuple[str, ...]:
        """The columns read, in the order an array must give them."""
        if self.is_plain:
            return self.labels
        adc = tuple(f"adc_{w}" for w in self.labels)
        ref = tuple(f"adc_ref_{w}" for w in self.labels) if self.reference else ()
        return adc + ref + self.physiology

    @property
    def is_study(self) -> bool:
        """The study's device: four LEDs 850-1150 nm, references, the 12-entry vector."""
        return (
            not self.is_plain
            and self.wavelengths_nm == tuple(float(w) for w in DEFAULT_LED_WAVELENGTHS_NM)
            and self.reference
            and self.physiology == tuple(KNOWN_PHYSIOLOGY[:12])
        )

    def describe(self) -> str:
        """One line naming the device."""
        if self.is_plain:
            return f"a plain array of {self.n_plain} columns"
        ref = "with" if self.reference else "without"
        physio = (f"physiology [{', '.join(self.physiology)}]" if self.physiology
                  else "no physiological columns")
        if self.per_channel:
            conv = ", ".join(f"adc_{w} {b} bits" + (
                f" (full scale {fs:g})" if fs != 2 ** b - 1 else "")
                for w, b, fs in zip(self.labels, self.channel_bits, self.full_scales,
                                    strict=True))
            return (f"LEDs {', '.join(self.labels)} nm on their own converters ({conv}) "
                    f"{ref} reference codes, {physio}")
        return (
            f"LEDs {', '.join(self.labels)} nm at {self.adc_bits} bits {ref} reference codes, "
            f"{physio}"
        )

    # ------------------------------------------------------------------ reading

    def raw(self, X: Any) -> np.ndarray:
        """The raw columns of X as a float64 (n, width) array, validated.

        Parameters
        ----------
        X : Dataset, pandas.DataFrame or array_like
            A frame with (at least) :attr:`raw_columns`, or an array of exactly them.

        Raises
        ------
        DataError
            Missing columns, non-numeric, NaN/inf, ADC codes outside 1 .. 2^bits - 1,
            physiology outside physiological ranges.
        """
        if isinstance(X, Dataset):
            X = X.frame
        cols = self.raw_columns
        if isinstance(X, pd.DataFrame):
            check_frame(X)
            if self.is_plain:
                Xa = X.to_numpy(dtype=float) if X.shape[1] == self.n_plain else None
                if Xa is None:
                    raise DataError(f"expected {self.n_plain} columns, got {X.shape[1]}")
            else:
                missing = [c for c in cols if c not in X.columns]
                if missing:
                    raise DataError(
                        f"missing columns {missing}: the model was fitted on {self.describe()}"
                    )
                if len(X) == 0:
                    raise DataError("no rows: the data holds no measurements")
                parts = []
                for c in cols:
                    num = pd.to_numeric(X[c], errors="coerce")
                    bad = num.isna().to_numpy() & X[c].notna().to_numpy()
                    if bad.any():
                        raise DataError(f"column {c!r} has non-numeric cells at {_first_rows(bad)}")
                    parts.append(num.to_numpy(dtype=float))
                Xa = np.column_stack(parts) if parts else np.empty((len(X), 0))
        else:
            Xa = np.asarray(X, dtype=float)
            if Xa.ndim != 2 or Xa.shape[1] != len(cols):
                raise DataError(
                    f"expected a 2-D array with {len(cols)} columns ({', '.join(cols)}), "
                    f"got shape {Xa.shape}"
                )
        bad = ~np.isfinite(Xa)
        if bad.any():
            j = int(np.flatnonzero(bad.any(axis=0))[0])
            raise DataError(
                f"column {cols[j]!r} has NaN or infinite values at {_first_rows(bad[:, j])}"
            )
        self._check_ranges(Xa)
        return Xa

    def _check_ranges(self, Xa: np.ndarray) -> None:
        if self.is_plain:
            return
        k = self.n_channels * (2 if self.reference else 1)
        cols = self.raw_columns
        codes = Xa[:, :k]
        full = np.tile(np.asarray(self.full_scales), 2 if self.reference else 1)
        bits = np.tile(np.asarray(self.channel_bits or (self.adc_bits,) * self.n_channels),
                       2 if self.reference else 1)
        bad = (codes < 1) | (codes > full)
        if bad.any():
            j = int(np.flatnonzero(bad.any(axis=0))[0])
            top = float(codes[:, j].max())
            why = (
                f"codes up to {top:.0f} need a {int(np.ceil(np.log2(top + 1)))}-bit ADC; "
                "declare the device's resolution (--adc-bits N; Python adc_bits=N)"
                if top > full[j]
                else "a code of 0 or below is a dead or disconnected channel"
            )
            raise DataError(
                f"column {cols[j]!r} has ADC codes outside 1-{full[j]:.0f} "
                f"({bits[j]}-bit ADC) at {_first_rows(bad[:, j])}: {why}"
            )
        for j, c in enumerate(self.physiology, start=k):
            lo, hi, _ = PHYSIOLOGICAL_RANGES[c]
            bad = (Xa[:, j] < lo) | (Xa[:, j] > hi)
            if bad.any():
                raise DataError(
                    f"column {c!r} has values outside the physiological range {lo:g}-{hi:g} "
                    f"at {_first_rows(bad)} (ranges and sources: docs/user_guide/your_data.md)"
                )

    def split(self, Xa: np.ndarray) -> Measurements:
        """Absorbances and physiology from raw columns (already validated by :meth:`raw`).

        Plain schemas pass their columns through as the absorbances.
        """
        if self.is_plain:
            return Measurements(np.array(Xa, dtype=float), Xa[:, :0])
        k = self.n_channels
        adc = Xa[:, :k]
        if self.reference:
            ref = Xa[:, k : 2 * k]
            start = 2 * k
        else:
            ref = np.broadcast_to(np.asarray(self.full_scales, dtype=float), adc.shape)
            start = k
        if not (adc > 0).all() or not np.all(np.asarray(ref) > 0):
            raise DataError("ADC and reference codes must be > 0 to form absorbances log10(I0/I)")
        with np.errstate(divide="ignore"):
            a = np.log10(ref / adc)
        return Measurements(a, Xa[:, start:])

    def measurements(self, X: Any) -> Measurements:
        """:meth:`raw` then :meth:`split`."""
        return self.split(self.raw(X))

    def stacked(self, Xa: np.ndarray) -> np.ndarray:
        """(n, k + m) absorbances then physiology, from validated raw columns."""
        m = self.split(Xa)
        return np.hstack([m.absorbance, m.physiology])

    @property
    def stacked_names(self) -> tuple[str, ...]:
        """Names of :meth:`stacked`'s columns: ``A_<nm>`` per LED, then the physiology."""
        return tuple(f"A_{w}" for w in self.labels) + tuple(self.physiology)


def _channels_from_json(s: DeviceSchema, doc: Any) -> DeviceSchema:
    """``s`` with the optional per-channel converters, training unit and row
    fingerprints of a model file's schema (absent from files written before issue 43)."""
    bits, fs = doc.get("channel_bits") or (), doc.get("channel_full_scale") or ()
    unit = doc.get("glucose_unit", "mg/dL")
    rows, every = doc.get("train_rows") or (), doc.get("train_rows_every", 1)
    ids = doc.get("train_row_ids") or ()
    try:
        bits = tuple(check_channel_bits(int(b)) for b in bits)
        fs = tuple(float(v) for v in fs)
        ok = (len(bits) == len(fs) and (not bits or len(bits) == s.n_channels)
              and all(1 <= f <= 2 ** b - 1 for b, f in zip(bits, fs, strict=True))
              and unit in ("mg/dL", "mmol/L") and all(isinstance(r, str) for r in rows)
              and all(c in _ROW_ID_COLUMNS for c in ids)
              and is_finite_number(every, integer=True) and every >= 1)
    except (TypeError, ValueError, DataError):
        ok = False
    if not ok:
        raise DataError("model file has a malformed 'schema' converter, unit or training "
                        "rows entry; refit the model")
    return replace(s, channel_bits=bits, channel_full_scale=fs, glucose_unit=unit,
                   train_rows=tuple(rows), train_rows_every=int(every),
                   train_row_ids=tuple(ids))


def _no_adc_message(columns) -> str:
    """No ``adc_<nm>`` column: the columns read and the nearest names."""
    import difflib

    read = [str(c) for c in columns]
    near = [c for c in read if difflib.get_close_matches(c.strip().casefold(), ["adc_940",
            "adc_850", "adc_660", "adc_1050"], n=1, cutoff=0.6)
            or c.strip().casefold().startswith(("adc", "led", "ch", "ir", "nir"))]
    shown = ", ".join(repr(c) for c in read[:12]) + (" ..." if len(read) > 12 else "")
    hint = f"; nearest: {', '.join(repr(c) for c in near[:4])}" if near else ""
    return (f"no ADC columns: a device file needs at least one 'adc_<nm>' column (e.g. "
            f"adc_940 for a 940 nm LED); columns read: {shown or 'none'}{hint}")


def check_fit_size(n_rows: int, groups: Any = None) -> None:
    """The one fitting-size policy of every model.

    At least :data:`~nirglucose.dataset.MIN_FIT_ROWS` rows, and, where subject ids are
    known, at least :data:`~nirglucose.dataset.MIN_FIT_SUBJECTS` subjects.

    Raises
    ------
    DataError
        Too few rows or subjects (a ValueError, as scikit-learn expects).
    """
    if n_rows < MIN_FIT_ROWS:
        raise DataError(
            f"too few rows to fit: {n_rows} sample(s); every model needs at least {MIN_FIT_ROWS}"
        )
    if groups is not None:
        missing = pd.isna(np.asarray(groups, dtype=object))
        if missing.any():
            raise DataError(f"subject ids (groups) are empty at {_first_rows(missing)}: "
                            "every reading needs its subject's id (validation is by subject)")
        n_sub = len(np.unique(np.asarray(groups)))
        if n_sub < MIN_FIT_SUBJECTS:
            raise DataError(
                f"too few subjects to fit: {n_sub}; every model needs at least "
                f"{MIN_FIT_SUBJECTS} (its validation is grouped by subject)"
            )


def check_reference_glucose(y: np.ndarray) -> None:
    """Refuse reference glucose no meter reports (outside 20-600 mg/dL).

    Raises
    ------
    DataError
        Any value outside :data:`~nirglucose.dataset.GLUCOSE_REPORTING_RANGE_MGDL`.
    """
    lo, hi = GLUCOSE_REPORTING_RANGE_MGDL
    y = np.asarray(y, dtype=float)
    bad = ~((y >= lo) & (y <= hi))
    if bad.any():
        raise DataError(
            f"reference glucose_mgdl outside what a meter reports, {lo:g}-{hi:g} [mg/dL], at "
            f"{_first_rows(bad)}"
        )


def meter_flags(glucose_mgdl: Any) -> np.ndarray:
    """``'LO'`` below 20 mg/dL, ``'HI'`` above 600 mg/dL, ``''`` otherwise, as a meter shows.

    Parameters
    ----------
    glucose_mgdl : array_like
        Predicted glucose. [mg/dL]

    Returns
    -------
    numpy.ndarray
        One string per value.

    Examples
    --------
    >>> meter_flags([5.0, 100.0, 900.0]).tolist()
    ['LO', '', 'HI']
    """
    g = np.asarray(glucose_mgdl, dtype=float)
    lo, hi = GLUCOSE_REPORTING_RANGE_MGDL
    out = np.full(g.shape, "", dtype=object)
    out[g < lo] = "LO"
    out[g > hi] = "HI"
    return out


def _is_device_frame(frame: pd.DataFrame) -> bool:
    """True when a frame names any schema column (a device's file, perhaps malformed)."""
    known = set(KNOWN_PHYSIOLOGY) | {"glucose_mgdl", "subject_id", "measurement_id"}
    return any(
        isinstance(c, str) and (c.startswith(("adc_", "true_")) or c in known)
        for c in frame.columns
    )


def schema_for_fit(X: Any, adc_bits: int | None = None) -> DeviceSchema | None:
    """The device schema of fitting input ``X``, with its training range; None for
    generic input.

    Datasets and frames that name any schema column are a device's measurements: their
    schema comes from the column names (:meth:`DeviceSchema.infer`) and records the
    training range of the raw columns. Arrays, and frames naming none (generic tables),
    are generic input: None, and the estimator takes a plain schema after scikit-learn's
    own input checks (:func:`nirglucose.fitted.fit_schema`). Nothing is written onto any
    estimator here.

    Parameters
    ----------
    X : Dataset, pandas.DataFrame or array_like
        The fitting input.
    adc_bits : int, optional
        Declared ADC resolution. [bit]

    Returns
    -------
    DeviceSchema or None
    """
    frame = X.frame if isinstance(X, Dataset) else X
    if isinstance(frame, pd.DataFrame) and (isinstance(X, Dataset) or _is_device_frame(frame)):
        schema = DeviceSchema.infer(X, adc_bits)
        Xa = schema.raw(X)
        unit = X.metadata.get("glucose_unit") if isinstance(X, Dataset) else None
        names = tuple(c for c in _ROW_ID_COLUMNS if c in frame.columns)
        rows, every = _kept_fingerprints(_row_hashes(Xa, _id_frame(frame, names)))
        return replace(schema.with_training_range(Xa), glucose_unit=unit or "mg/dL",
                       train_rows=rows, train_rows_every=every, train_row_ids=names)
    return None


#: Most training-row fingerprints a model file keeps (16 hex digits each, about 100 kB
#: of JSON); of a larger training set one row in ``ceil(n / this)`` by fingerprint. [-]
MAX_TRAIN_FINGERPRINTS = 5000
#: Columns that identify a reading beside its values, hashed with them where present
#: (one LED's integer codes alone repeat across people).
_ROW_ID_COLUMNS = ("subject_id", "measurement_id", "time_min")


def _row_hashes(Xa: np.ndarray, ids: pd.DataFrame | None = None) -> np.ndarray:
    """Each row's 64-bit hash (:func:`pandas.util.hash_pandas_object`) of its values and
    of the identity columns ``ids`` as text."""
    parts = pd.DataFrame(np.asarray(Xa, dtype=np.float64) + 0.0)  # -0.0 as 0.0
    if ids is not None and len(ids.columns):
        parts = pd.concat([parts, ids.astype(str).reset_index(drop=True)], axis=1)
    return pd.util.hash_pandas_object(parts, index=False).to_numpy(np.uint64)


def _hex(h: np.ndarray) -> np.ndarray:
    return np.array([f"{v:016x}" for v in h.tolist()], dtype="<U16")


def row_fingerprints(Xa: np.ndarray, ids: pd.DataFrame | None = None) -> np.ndarray:
    """Each row's 64-bit hash of its values and identity columns ``ids`` (as text), as 16
    hex digits: equal rows, equal fingerprints.

    Examples
    --------
    >>> a = np.array([[500.0, 30.0], [600.0, 40.0], [500.0, 30.0]])
    >>> f = row_fingerprints(a)
    >>> bool(f[0] == f[2]), bool(f[0] == f[1]), len(f[0])
    (True, False, 16)
    """
    return _hex(_row_hashes(Xa, ids))


def _id_frame(frame: pd.DataFrame, names: tuple[str, ...]) -> pd.DataFrame | None:
    """The identity columns ``names`` of ``frame`` (None when any is missing)."""
    if not all(c in frame.columns for c in names):
        return None
    return frame[list(names)]


def _kept(h: np.ndarray, every: int) -> np.ndarray:
    """Which row hashes a model file keeps: those whose low 32 bits are 0 mod ``every``."""
    return (h & np.uint64(0xFFFFFFFF)) % np.uint64(every) == 0


def _kept_fingerprints(h: np.ndarray) -> tuple[tuple[str, ...], int]:
    """The sorted unique fingerprints a model file keeps, one in ``every``."""
    uniq = np.unique(h)
    every = max(1, int(np.ceil(len(uniq) / MAX_TRAIN_FINGERPRINTS)))
    return tuple(str(f) for f in _hex(uniq[_kept(uniq, every)])), every


def rows_seen_in_training(schema: DeviceSchema, Xa: np.ndarray,
                          frame: pd.DataFrame) -> tuple[int, int]:
    """``(matched, checked)``: of the rows (raw columns ``Xa`` of ``frame``) whose
    fingerprint the model file would keep, how many are training rows (``(0, 0)`` for a
    model file without them, or a frame without the identity columns it hashed)."""
    ids = _id_frame(frame, schema.train_row_ids)
    if not schema.train_rows or ids is None:
        return 0, 0
    h = _row_hashes(Xa, ids)
    checked = _hex(h[_kept(h, schema.train_rows_every)])
    return int(np.isin(checked, np.asarray(schema.train_rows)).sum()), int(len(checked))
