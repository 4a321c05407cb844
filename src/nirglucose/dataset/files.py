"""Reading a device's own file as a prototype team writes it: delimiter, decimal comma,
header spelling, glucose unit, and one validation of the whole file.

:func:`read_frame` reads a CSV or Parquet file into the dataset schema's names and
units, and :func:`validate_frame` checks every schema column of the *whole* file once,
before any split, so a message names the file's own rows (spreadsheet numbering for a
CSV: the header is line 1, the first reading line 2).

Which parsing does what, and why
--------------------------------
Cells are parsed by pandas itself (``read_csv`` with the sniffed ``sep`` and
``decimal``, then ``pandas.to_numeric(errors="coerce")`` per column): it is
vectorised over columns, knows decimal commas and empty cells, and the cells it cannot
parse are exactly the text cells to report. Pydantic, which validates the package's
configuration, validates per record and would turn a 10^5-row file into 10^5 model
objects for no extra check, so it is used here only for the one option it serves,
the glucose unit (a ``Literal``). Every other check is a range, stated once below.

Examples
--------
>>> import io
>>> sniff_csv("subject_id;glucose_mmoll;adc_940\\n1;5,6;512,3\\n")
(';', ',')
>>> canonical_name("ADC_940 "), canonical_name("Glucose_mgdl")
('adc_940', 'glucose_mgdl')
"""

from __future__ import annotations

import re
from collections.abc import Iterable, Mapping
from csv import reader as csv_reader
from pathlib import Path
from typing import Any, Literal

import numpy as np
import pandas as pd
from pydantic import TypeAdapter, ValidationError

from ..constants import MGDL_PER_MMOLL_GLUCOSE, PHYSIOLOGICAL_RANGES
from ..exceptions import DataError
from .columns import (
    CODE_COLUMN_RE,
    COLUMN_UNITS,
    GLUCOSE_REPORTING_RANGE_MGDL,
    ID_COLUMNS,
    KNOWN_PHYSIOLOGY,
    WEAR_COLUMNS,
)

__all__ = [
    "GLUCOSE_UNITS",
    "GLUCOSE_COLUMNS",
    "MMOLL_SUSPECT_MEDIAN_MGDL",
    "canonical_name",
    "canonical_columns",
    "check_frame",
    "check_result_table",
    "check_glucose_unit",
    "sniff_csv",
    "read_frame",
    "validate_frame",
    "check_codes",
    "file_rows",
    "glucose_to_unit",
    "unread_column_notes",
]

#: Units a reference glucose column may be in.
GLUCOSE_UNITS = ("mg/dL", "mmol/L")
#: Reference glucose column names and the unit each carries.
GLUCOSE_COLUMNS = {"glucose_mgdl": "mg/dL", "glucose_mmoll": "mmol/L"}
#: A glucose column declared (or assumed) mg/dL whose median lies below this reads as
#: mmol/L: a cohort median under 35 mg/dL (1.9 mmol/L) is severe hypoglycaemia at most
#: readings, while every value a meter reports in mmol/L (1.1-33.3, i.e. 20-600 mg/dL
#: divided by :data:`~nirglucose.constants.MGDL_PER_MMOLL_GLUCOSE`) lies below it. [mg/dL]
MMOLL_SUSPECT_MEDIAN_MGDL = 35.0
#: Meter readings beyond its range, shown as text instead of a number.
_METER_FLAGS = ("HI", "LO")
#: Spellings of the glucose columns seen in real files, after :func:`canonical_name`.
_ALIASES = {
    "glucose_mg_dl": "glucose_mgdl",
    "glucose_mg/dl": "glucose_mgdl",
    "glucose_mmol_l": "glucose_mmoll",
    "glucose_mmol/l": "glucose_mmoll",
    "glucose_mmol": "glucose_mmoll",
}
_KNOWN = {*KNOWN_PHYSIOLOGY, *GLUCOSE_COLUMNS, *ID_COLUMNS}
_UNIT = TypeAdapter(Literal["mg/dL", "mmol/L"])


def check_glucose_unit(unit: Any) -> str | None:
    """``unit`` when it is one of :data:`GLUCOSE_UNITS` (or None), else DataError."""
    if unit is None:
        return None
    try:
        return _UNIT.validate_python(unit)
    except ValidationError:
        raise DataError(
            f"unknown glucose unit {unit!r}; valid: {', '.join(GLUCOSE_UNITS)}"
        ) from None


def canonical_name(name: Any) -> str:
    """A header as the schema spells it: stripped, case-folded, spaces and '-' as '_',
    an LED's wavelength as :func:`~nirglucose.dataset.columns.adc_columns` writes it
    (``adc_0850``, ``adc_850.0`` -> ``adc_850``).

    Examples
    --------
    >>> canonical_name(" ADC_Ref_0940.0 ")
    'adc_ref_940'
    """
    text = re.sub(r"[\s\-]+", "_", str(name).strip().casefold())
    m = CODE_COLUMN_RE.match(text)
    if m:
        text = f"adc_{m.group(1) or ''}{float(m.group(2)):g}"
    return _ALIASES.get(text, text)


def canonical_columns(columns: Iterable[Any]) -> tuple[dict[Any, str], list[str]]:
    """Renames of the schema's columns spelled otherwise, and one note per rename.

    Only names that become a schema column (``adc_<nm>``, ``adc_ref_<nm>``, a known
    physiological or glucose column, ``subject_id``, ``measurement_id``) are renamed.

    Raises
    ------
    DataError
        Two headers that read as the same column.
    """
    columns = list(columns)
    _refuse_repeated(columns, " in the header")
    renames: dict[Any, str] = {}
    for c in columns:
        new = canonical_name(c)
        if new != c and (new in _KNOWN or CODE_COLUMN_RE.match(new)):
            renames[c] = new
    final = [renames.get(c, c) for c in columns]
    dup = sorted({n for n in final if final.count(n) > 1}, key=str)
    if dup:
        same = [repr(c) for c in columns if renames.get(c, c) == dup[0]]
        raise DataError(f"columns {' and '.join(same)} both read as {dup[0]!r}; keep one")
    notes = [f"read column {c!r} as {n!r}" for c, n in renames.items()]
    return renames, notes


def _refuse_repeated(columns: Iterable[Any], where: str = "") -> None:
    """DataError naming the first column name given more than once."""
    names = pd.Index(list(columns))
    if names.has_duplicates:
        c = names[names.duplicated()][0]
        raise DataError(f"column {c!r} appears {int((names == c).sum())} times{where}; keep one")


def check_frame(frame: Any) -> None:
    """Refuse what is not a table of measurements: not a pandas DataFrame, or one with a
    column name given twice (which column would the model read?).

    Raises
    ------
    DataError
        One line saying what was given and what to give.

    Examples
    --------
    >>> check_frame(pd.DataFrame([[1, 2]], columns=["adc_850", "adc_850"]))
    Traceback (most recent call last):
    ...
    nirglucose.exceptions.DataError: column 'adc_850' appears 2 times; keep one
    """
    if not isinstance(frame, pd.DataFrame):
        raise DataError(f"expected a pandas DataFrame of measurements, got "
                        f"{type(frame).__name__}; read a file with nirglucose.load_dataset")
    _refuse_repeated(frame.columns)


#: Column name endings that say a results table's column holds numbers (its unit).
_NUMBER_SUFFIXES = ("_mgdl", "_pct", "_low", "_high", "_s", "_ms", "_mse", "_nm")


def check_result_table(frame: pd.DataFrame, name: str, required: Iterable[str] = (),
                       text: Iterable[str] = ("model", "label", *ID_COLUMNS)) -> None:
    """Refuse a results table (``metrics.csv``, ``sweep.csv``) that lacks ``required``
    columns or has text in a column of numbers (a hand edit, a corrupted file).

    A column is one of numbers when its name carries a unit or a count (``_mgdl``,
    ``_pct``, ``_ci_low``, ``n_``...: the units-in-names convention) or any of its cells
    is a number; the ``text`` columns are not checked.

    Raises
    ------
    DataError
        One line naming the file, the column and the first bad cell.

    Examples
    --------
    >>> check_result_table(pd.DataFrame({"model": ["a"], "note": ["x"]}), "m.csv")
    >>> check_result_table(pd.DataFrame({"model": ["a"], "rmse_mgdl": ["x"]}), "m.csv")
    ... # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    nirglucose.exceptions.DataError: m.csv: column 'rmse_mgdl' has text 'x' in row 1 ...
    """
    missing = [c for c in required if c not in frame.columns]
    if missing:
        raise DataError(f"{name} lacks column(s) {missing}; it has {list(frame.columns)[:12]}")
    skip = set(text)
    for col in frame.columns:
        raw = frame[col]
        if col in skip or pd.api.types.is_numeric_dtype(raw):
            continue
        num = pd.to_numeric(raw, errors="coerce")
        bad = (num.isna() & raw.notna()).to_numpy()
        named = str(col).endswith(_NUMBER_SUFFIXES) or str(col).startswith("n_")
        if (named or num.notna().any()) and bad.any():
            i = int(np.flatnonzero(bad)[0])
            raise DataError(f"{name}: column {col!r} has text {raw.iloc[i]!r} in row {i + 1} "
                            "where numbers are; rerun what wrote it")


def sniff_csv(text: str) -> tuple[str, str]:
    """``(delimiter, decimal)`` of a CSV file's first lines.

    The delimiter is the candidate (``,``, ``;``, tab) that splits the header into the
    most fields and every sampled line into the same number; decimal commas are
    recognised in a file not delimited by commas.
    """
    lines = [ln for ln in text.splitlines() if ln.strip()][:50]
    if not lines:
        return ",", "."
    best, best_n = ",", 1
    for sep in (",", ";", "\t"):
        n = lines[0].count(sep) + 1
        if n > best_n and all(ln.count(sep) + 1 == n for ln in lines[1:]):
            best, best_n = sep, n
    decimal = "."
    if best != ",":
        cells = [c.strip().strip('"') for ln in lines[1:] for c in ln.split(best)]
        if any(re.fullmatch(r"[+-]?\d*,\d+", c) for c in cells):
            decimal = ","
    return best, decimal


def read_frame(path: Path) -> tuple[pd.DataFrame, dict[bytes, bytes], list[str]]:
    """``(frame, Parquet schema metadata, notes)`` of a CSV or Parquet file, with the
    schema's column names (:func:`canonical_columns`)."""
    import pyarrow.parquet as pq

    notes: list[str] = []
    if path.suffix == ".parquet":
        table = pq.read_table(path)
        raw, frame = dict(table.schema.metadata or {}), table.to_pandas()
    else:
        with open(path, encoding="utf-8-sig", errors="replace") as fh:
            head = fh.read(65536)
        sep, decimal = sniff_csv(head)
        first = next((ln for ln in head.splitlines() if ln.strip()), "")
        # pandas renames a repeated header (adc_940, adc_940.1): read it as written
        header = next(csv_reader([first], delimiter=sep), [])
        _refuse_repeated(header, " in the header")
        # ids as written ("007" stays "007"; plain integers become ints in validate_frame)
        ids = {c: str for c in header if canonical_name(c) in ID_COLUMNS}
        frame = pd.read_csv(path, sep=sep, decimal=decimal, encoding="utf-8-sig", dtype=ids)
        frame.attrs["decimal"] = decimal
        raw = {}
        if (sep, decimal) != (",", "."):
            what = {";": "';'", "\t": "tab"}.get(sep, repr(sep))
            notes.append(f"read {path.name!r} as {what}-delimited"
                         + (" with decimal commas" if decimal == "," else ""))
    renames, rename_notes = canonical_columns(frame.columns)
    return frame.rename(columns=renames), raw, notes + rename_notes


# ------------------------------------------------------------------------ validation
def _ids(frame: pd.DataFrame, csv: bool) -> None:
    """Refuse empty ids; in place, text ids that are all plain integers ("12", not
    "012") become integers, as pandas would have read them, so one file gives the same
    ids (and folds) as CSV and as Parquet."""
    for col in [c for c in ID_COLUMNS if c in frame.columns]:
        raw = frame[col]
        text = None if pd.api.types.is_numeric_dtype(raw) else raw.astype(str).str.strip()
        empty = raw.isna().to_numpy() | (text.eq("").to_numpy() if text is not None
                                          else False)
        if empty.any():
            raise DataError(f"column {col!r} is empty at {file_rows(empty, csv)}: every "
                            "reading needs its id (models validate by subject)")
        # an int64 holds every integer of up to 18 digits
        if text is not None and text.str.fullmatch(r"-?(0|[1-9]\d{0,17})").all():
            frame[col] = text.astype(np.int64)


def file_rows(mask: np.ndarray, csv: bool, limit: int = 5) -> str:
    """The flagged rows as the file numbers them (CSV: its lines, header = line 1)."""
    idx = np.flatnonzero(mask)
    first = 2 if csv else 1
    shown = ", ".join(str(int(i) + first) for i in idx[:limit])
    more = f" and {len(idx) - limit} more" if len(idx) > limit else ""
    where = ("line" if csv else "row") + ("s" if len(idx) > 1 else "")
    how = " (line 1 is the header)" if csv else " (first row = 1)"
    return f"{where} {shown}{more}{how}"


def _numeric(frame: pd.DataFrame, col: str, csv: bool, allow_empty: bool = False
             ) -> np.ndarray:
    """Column ``col`` as floats; text, empty and infinite cells refused with their rows."""
    raw = frame[col]
    if pd.api.types.is_numeric_dtype(raw):
        num = raw
    else:  # a text cell keeps pandas from applying the decimal comma to its column
        txt = raw.astype(str).str.strip()
        if frame.attrs.get("decimal") == ",":
            txt = txt.str.replace(",", ".", regex=False)
        num = pd.to_numeric(txt.where(raw.notna()), errors="coerce")
    vals = np.asarray(num, dtype=float)
    text = np.isnan(vals) & raw.notna().to_numpy()
    if text.any():
        cells = raw[text].astype(str).str.strip()
        flags = cells.str.upper().isin(_METER_FLAGS).to_numpy()
        if col in GLUCOSE_COLUMNS and flags.any():
            shown = "/".join(dict.fromkeys(cells[flags].str.upper()))
            raise DataError(
                f"column {col!r} holds the meter's out-of-range flag {shown} at "
                f"{file_rows(text & _flag_mask(raw), csv)}: the meter read beyond its range, "
                "so the reading has no value; drop those rows or give a laboratory value"
            )
        shown = ", ".join(repr(v) for v in dict.fromkeys(cells.tolist()[:3]))
        raise DataError(f"column {col!r} has text cells ({shown}) at {file_rows(text, csv)}; "
                        "give numbers")
    missing = raw.isna().to_numpy()
    if missing.any() and not allow_empty:
        raise DataError(f"column {col!r} has empty or NaN cells at {file_rows(missing, csv)}")
    inf = np.isinf(vals)
    if inf.any():
        raise DataError(f"column {col!r} has infinite values at {file_rows(inf, csv)}")
    return vals


def _numbers(frame: pd.DataFrame, col: str, csv: bool) -> np.ndarray:
    """:func:`_numeric` of a column that must be complete, stored back as floats when it
    was read as text (a numeric column keeps its dtype, and the dataset its hash)."""
    vals = _numeric(frame, col, csv)
    if not pd.api.types.is_numeric_dtype(frame[col]):
        frame[col] = vals
    return vals


def _flag_mask(raw: pd.Series) -> np.ndarray:
    return raw.astype(str).str.strip().str.upper().isin(_METER_FLAGS).to_numpy()


def glucose_to_unit(values_mgdl: Any, unit: str) -> np.ndarray:
    """Glucose in ``unit`` from mg/dL (``mmol/L``: divided by
    :data:`~nirglucose.constants.MGDL_PER_MMOLL_GLUCOSE`, 18.016 mg/dL per mmol/L)."""
    v = np.asarray(values_mgdl, dtype=float)
    return v / MGDL_PER_MMOLL_GLUCOSE if check_glucose_unit(unit) == "mmol/L" else v


def _glucose(frame: pd.DataFrame, unit: str | None, csv: bool) -> list[str]:
    """Convert the reference glucose column to ``glucose_mgdl`` and check it; notes."""
    present = [c for c in GLUCOSE_COLUMNS if c in frame.columns]
    if not present:
        return []
    if len(present) > 1:
        raise DataError("the file has both 'glucose_mgdl' and 'glucose_mmoll'; keep one")
    col = present[0]
    named = GLUCOSE_COLUMNS[col]
    if unit is not None and col == "glucose_mmoll" and unit != named:
        raise DataError(f"column 'glucose_mmoll' is declared {unit}; rename it "
                        "'glucose_mgdl' if its values are mg/dL")
    unit = unit or named
    vals = _numeric(frame, col, csv, allow_empty=True)  # needed at fit only: checked there
    known = vals[np.isfinite(vals)]
    if not len(known):
        return []
    lo, hi = GLUCOSE_REPORTING_RANGE_MGDL
    if (known <= 0).any():
        raise DataError(f"reference glucose {col!r} has values of 0 or below at "
                        f"{file_rows(vals <= 0, csv)}; a meter reports {lo:g}-{hi:g} [mg/dL]")
    notes = []
    if unit == "mmol/L":
        if np.median(known) > MMOLL_SUSPECT_MEDIAN_MGDL:
            raise DataError(
                f"reference glucose {col!r} is declared mmol/L but looks like mg/dL (median "
                f"{np.median(known):g}; a mmol/L median is below {MMOLL_SUSPECT_MEDIAN_MGDL:g}); "
                "declare mg/dL (--glucose-unit mg/dL; Python glucose_unit='mg/dL')"
            )
        vals = vals * MGDL_PER_MMOLL_GLUCOSE
        notes.append(f"reference glucose {col!r} read in mmol/L and converted to mg/dL "
                     f"(x {MGDL_PER_MMOLL_GLUCOSE} mg/dL per mmol/L)")
    elif np.median(known) < MMOLL_SUSPECT_MEDIAN_MGDL:
        raise DataError(
            f"reference glucose {col!r} looks like mmol/L (values {known.min():g}-"
            f"{known.max():g}, median {np.median(known):g}; a mg/dL median is above "
            f"{MMOLL_SUSPECT_MEDIAN_MGDL:g}); declare the unit mmol/L "
            "(--glucose-unit mmol/L; Python glucose_unit='mmol/L') or name it 'glucose_mmoll'"
        )
    bad = (vals < lo) | (vals > hi)
    if bad.any():
        raise DataError(
            f"reference glucose {col!r} outside what a meter reports, {lo:g}-{hi:g} [mg/dL] "
            f"({lo / MGDL_PER_MMOLL_GLUCOSE:.1f}-{hi / MGDL_PER_MMOLL_GLUCOSE:.1f} mmol/L), "
            f"at {file_rows(bad, csv)}"
        )
    if col != "glucose_mgdl" or unit != "mg/dL" or not pd.api.types.is_numeric_dtype(frame[col]):
        frame[col] = vals  # in place, so the columns keep their order
        frame.columns = ["glucose_mgdl" if c == col else c for c in frame.columns]
    return notes


def check_codes(frame: pd.DataFrame, bits: int, *, csv: bool,
                full_scales: Mapping[str, float] | None = None) -> None:
    """Refuse ADC and reference codes above the full scale, 2^bits - 1 or a channel's own
    (``full_scales``: column -> full-scale code, per-channel converters), with the file's
    rows (codes of 0 or below are refused by :func:`validate_frame`)."""
    for col in [c for c in frame.columns if isinstance(c, str) and CODE_COLUMN_RE.match(c)]:
        full = float((full_scales or {}).get(col, 2**bits - 1))
        vals = np.asarray(frame[col], dtype=float)
        bad = vals > full
        if bad.any():
            need = int(np.ceil(np.log2(vals.max() + 1)))
            per = (f"its {need}-bit converter (--adc-bits {col.replace('ref_', '')}={need},..."
                   "; Python adc_bits={...})" if full_scales else
                   "the device's resolution (--adc-bits N; Python adc_bits=N)")
            raise DataError(
                f"column {col!r} has ADC codes above {full:.0f} (the "
                f"{'channel' if full_scales else f'{bits}-bit'} full scale) at "
                f"{file_rows(bad, csv)}: codes up to {vals.max():g} need a {need}-bit ADC; "
                f"declare {per}"
            )


def validate_frame(frame: pd.DataFrame, *, csv: bool, glucose_unit: str | None = None
                   ) -> list[str]:
    """Check every schema column of the whole file once, in place; notes to show.

    ADC codes become floats and must be finite and > 0 (their upper bound depends on
    the resolution, :mod:`~nirglucose.dataset.adc`); physiological columns lie in
    :data:`~nirglucose.dataset.PHYSIOLOGICAL_RANGES`; the reference glucose becomes
    ``glucose_mgdl`` in mg/dL within the meter's range.

    Raises
    ------
    DataError
        One line naming the column, the file's rows and the fix.
    """
    unit = check_glucose_unit(glucose_unit)
    _ids(frame, csv)
    for col in [c for c in frame.columns if isinstance(c, str) and CODE_COLUMN_RE.match(c)]:
        vals = _numbers(frame, col, csv)
        if (vals <= 0).any():
            raise DataError(f"column {col!r} has ADC codes of 0 or below at "
                            f"{file_rows(vals <= 0, csv)}: a dead or disconnected channel")
    for col in [c for c in WEAR_COLUMNS if c in frame.columns]:  # a worn device's times
        _numbers(frame, col, csv)
    for col in [c for c in KNOWN_PHYSIOLOGY if c in frame.columns]:
        vals = _numbers(frame, col, csv)
        lo, hi, _ = PHYSIOLOGICAL_RANGES[col]
        bad = (vals < lo) | (vals > hi)
        if bad.any():
            raise DataError(f"column {col!r} has values outside the physiological range "
                            f"{lo:g}-{hi:g} at {file_rows(bad, csv)} "
                            "(docs/user_guide/your_data.md)")
    return _glucose(frame, unit, csv)


def unread_column_notes(columns: Iterable[Any]) -> list[str]:
    """A note for each column no model reads whose name is near a physiological column's
    (``bmi`` -> ``bmi_kgm2``, ``Heart rate`` -> ``heart_rate_bpm``): the schema reads a
    column by its exact name and unit, so a near miss is ignored without it.

    Examples
    --------
    >>> unread_column_notes(["adc_940", "bmi", "diabetic"])[0][:52]
    "column 'bmi' is not read: a model reads 'bmi_kgm2' ["
    """
    import difflib

    out = []
    for c in columns:
        if not isinstance(c, str) or c in _KNOWN or CODE_COLUMN_RE.match(c) or c in WEAR_COLUMNS:
            continue
        name = canonical_name(c)
        near = [k for k in KNOWN_PHYSIOLOGY if k.startswith(f"{name}_")] or \
            difflib.get_close_matches(name, KNOWN_PHYSIOLOGY, n=1, cutoff=0.75)
        if near:
            out.append(f"column {c!r} is not read: a model reads {near[0]!r} "
                       f"[{COLUMN_UNITS.get(near[0], '-')}]; rename it if it holds that "
                       f"(in that unit)")
    return out
