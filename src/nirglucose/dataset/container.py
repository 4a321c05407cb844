"""The Dataset container: its frame and scenario, Parquet/CSV IO, partitioned datasets.

One row per snapshot measurement (DESIGN.md, "Dataset schema"):

* identity: ``subject_id``, ``measurement_id``; a wear simulation's readings also carry
  their time (:data:`WEAR_COLUMNS`: ``time_min``, ``wear_day``, ``seating_id``)
* reference: ``glucose_mgdl``
* sensor: ``adc_<nm>`` and the start-up reference ``adc_ref_<nm>`` (integer codes)
* the measured physiological vector (:data:`PMF_COLUMNS`), ``ambient_lux``
* ground truth for analysis only, prefixed ``true_``
* file metadata: package version, resolved config (JSON), seed.

Writes are atomic: the file is written beside its destination under a temporary name
and renamed into place, so an interrupted write never leaves a file that looks complete.
Loading never executes code from the file (Parquet and CSV only; no pickle).
"""

from __future__ import annotations

import json
import os
import tempfile
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import Any

import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq

from .._version import __version__
from ..config import ScenarioConfig
from ..exceptions import DataError
from .adc import check_channel_bits
from .columns import (
    led_wavelengths_in,
)
from .files import (
    GLUCOSE_COLUMNS,
    check_frame,
    check_glucose_unit,
    read_frame,
    unread_column_notes,
    validate_frame,
)
from .meta import parse_meta

__all__ = [
    "Dataset",
    "PartitionedDataset",
    "load_dataset",
    "open_partitioned",
    "scan_dataset",
    "atomic_write",
    "MANIFEST",
    "META_KEY",
    "PART_PATTERN",
    "SUFFIXES",
]

#: File suffixes :meth:`Dataset.save` and :func:`load_dataset` understand.
SUFFIXES = (".parquet", ".csv")
#: Key of the package's JSON metadata in a Parquet file's schema metadata.
META_KEY = b"nirglucose"
#: Name of the file listing the parts of a finished partitioned write.
MANIFEST = "manifest.json"
#: Glob pattern of the part files of a partitioned dataset.
PART_PATTERN = "part-*.parquet"



def atomic_write(path: str | os.PathLike, write) -> Path:
    """Call ``write(tmp_path)`` then rename the temporary file onto ``path``.

    The parent directory must exist (a missing one is an error, not created silently).
    """
    path = Path(path)
    if not path.parent.exists():
        raise DataError(f"output directory {str(path.parent)!r} does not exist; create it first")
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    os.close(fd)
    try:
        write(tmp)
        # mkstemp creates 0600; give the result the permissions a plain open() would
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return path


class Dataset:
    """Simulated or measured snapshots with the scenario that produced them.

    Parameters
    ----------
    frame : pandas.DataFrame
        One row per measurement (schema in the module docstring).
    config : ScenarioConfig, optional
        The resolved scenario (``None`` for a user's own measurements).
    seed : int, optional
        The seed that generated it.
    metadata : dict, optional
        Extra metadata (package version, source file).

    Attributes
    ----------
    frame, config, seed, metadata
    """

    def __init__(
        self,
        frame: pd.DataFrame,
        config: ScenarioConfig | None = None,
        seed: int | None = None,
        metadata: dict[str, Any] | None = None,
    ) -> None:
        if frame is not None or type(self) is Dataset:  # a lazy dataset reads it later
            check_frame(frame)
        self.frame = frame
        self.config = config
        self.seed = seed
        self.metadata = {"nirglucose_version": __version__, **(metadata or {})}

    def __len__(self) -> int:
        return len(self.frame)

    def rows(self, idx: Any) -> Dataset:
        """The rows at ``idx``, renumbered from 0, keeping config, seed and metadata.

        Parameters
        ----------
        idx : array-like of int or bool
            Row positions or a boolean mask over the rows.

        Returns
        -------
        Dataset
            A new dataset (the declared ``metadata["adc_bits"]`` travels with the rows).
        """
        try:
            frame = self.frame.iloc[idx].reset_index(drop=True)
        except IndexError as exc:
            raise DataError(f"rows {str(idx)[:60]} do not fit a dataset of {len(self)} rows: "
                            f"{' '.join(str(exc).split())}") from None
        return Dataset(frame, config=self.config, seed=self.seed, metadata=dict(self.metadata))

    def __repr__(self) -> str:
        preset = self.config.preset if self.config is not None else "user data"
        who = (f"{self.frame['subject_id'].nunique()} subjects" if "subject_id" in self.frame
               else "no subject_id")
        return f"Dataset({len(self)} snapshots, {who}, preset={preset!r}, seed={self.seed})"

    @property
    def wavelengths_nm(self) -> tuple[float, ...]:
        """LED wavelengths of the dataset. [nm]"""
        if self.config is not None:
            return tuple(self.config.leds.wavelengths_nm)
        return led_wavelengths_in(self.frame.columns)

    def _meta(self) -> dict[str, Any]:
        return {
            **self.metadata,
            "seed": self.seed,
            "config": None if self.config is None else json.loads(self.config.to_json()),
        }

    def save(self, path: str | os.PathLike) -> Path:
        """Write to ``.parquet`` (with metadata) or ``.csv``, atomically.

        Returns
        -------
        pathlib.Path
            The written path.
        """
        path = Path(path)
        if path.suffix not in SUFFIXES:
            raise DataError(
                f"unknown file type {path.suffix!r} for {str(path)!r}; use one of {SUFFIXES}"
            )
        if path.suffix == ".parquet":
            table = pa.Table.from_pandas(self.frame, preserve_index=False)
            meta = dict(table.schema.metadata or {})
            meta[META_KEY] = json.dumps(self._meta(), sort_keys=True).encode()
            table = table.replace_schema_metadata(meta)
            return atomic_write(path, lambda tmp: pq.write_table(table, tmp))
        return atomic_write(path, lambda tmp: self.frame.to_csv(tmp, index=False))

    def content_hash(self) -> str:
        """SHA-256 of the frame's contents (stable across file formats), 16 hex digits."""
        import hashlib

        h = hashlib.sha256()
        h.update(",".join(self.frame.columns).encode())
        h.update(pd.util.hash_pandas_object(self.frame, index=False).to_numpy().tobytes())
        return h.hexdigest()[:16]


# --------------------------------------------------------------------------- parts
def _part_paths(path: Path) -> tuple[list[Path], dict[str, Any] | None]:
    """The parts of a directory (the manifest's when there is one) and the manifest."""
    manifest = None
    mpath = path / MANIFEST
    if mpath.exists():
        try:
            manifest = json.loads(mpath.read_text(encoding="utf-8"))
            parts = [path / p["file"] for p in manifest["parts"]]
        except (OSError, ValueError, KeyError, TypeError):
            raise DataError(f"{str(mpath)!r} is malformed; rewrite the dataset") from None
        missing = [p.name for p in parts if not p.exists()]
        if missing:
            raise DataError(f"{str(path)!r} lacks parts listed in its manifest: "
                            f"{missing[:3]}{' ...' if len(missing) > 3 else ''}")
        return parts, manifest
    parts = sorted(path.glob("*.parquet"))
    if not parts:
        raise DataError(f"directory {str(path)!r} holds no .parquet files")
    return parts, None


class PartitionedDataset(Dataset):
    """A dataset stored as Parquet parts; ``frame`` is read on first access.

    Parameters
    ----------
    path : Path
        The directory.
    parts : sequence of Path
        Part files in row order.
    config, seed, metadata
        As :class:`~nirglucose.dataset.Dataset`.
    n_rows : int
        Total rows (from the manifest or the parts' footers).

    Attributes
    ----------
    path, parts
    """

    def __init__(
        self,
        path: Path,
        parts: Sequence[Path],
        config: ScenarioConfig | None,
        seed: int | None,
        metadata: dict[str, Any],
        n_rows: int,
    ) -> None:
        self._frame: pd.DataFrame | None = None
        self.path = Path(path)
        self.parts = list(parts)
        self._n_rows = int(n_rows)
        super().__init__(None, config=config, seed=seed, metadata=metadata)

    @property
    def frame(self) -> pd.DataFrame:
        """Every row as one DataFrame (read from the parts on first access)."""
        if self._frame is None:
            frames = [pq.read_table(p).to_pandas() for p in self.parts]
            self._frame = frames[0] if len(frames) == 1 else pd.concat(frames, ignore_index=True)
        return self._frame

    @frame.setter
    def frame(self, value: pd.DataFrame | None) -> None:
        self._frame = value

    @property
    def loaded(self) -> bool:
        """Whether ``frame`` has been read into memory."""
        return self._frame is not None

    def __len__(self) -> int:
        return self._n_rows if self._frame is None else len(self._frame)

    def __repr__(self) -> str:
        preset = self.config.preset if self.config is not None else "user data"
        return (f"PartitionedDataset({len(self)} snapshots in {len(self.parts)} parts, "
                f"preset={preset!r}, seed={self.seed}, path={str(self.path)!r})")

    def iter_frames(self, columns: Sequence[str] | None = None) -> Iterator[pd.DataFrame]:
        """Yield the parts one at a time as DataFrames (bounded memory)."""
        for p in self.parts:
            yield pq.read_table(p, columns=list(columns) if columns else None).to_pandas()

    def scan(self):
        """The parts as a :class:`pyarrow.dataset.Dataset` (lazy, filter/project pushdown)."""
        import pyarrow.dataset as pads

        return pads.dataset([str(p) for p in self.parts], format="parquet")

    def to_dask(self, columns: Sequence[str] | None = None):
        """The parts as a lazy :class:`dask.dataframe.DataFrame` (one partition per part)."""
        import dask.dataframe as dd

        return dd.read_parquet([str(p) for p in self.parts],
                               columns=list(columns) if columns else None)


def open_partitioned(path: str | os.PathLike) -> PartitionedDataset:
    """Open a partitioned Parquet directory without reading its rows.

    Parameters
    ----------
    path : str or path-like
        A directory written by
        :func:`~nirglucose.simulation.partitioned.write_partitioned` (or any directory
        of Parquet files of the dataset schema, read in name order).

    Returns
    -------
    PartitionedDataset

    Raises
    ------
    DataError
        No parts, a malformed manifest or metadata, a missing part.
    """
    path = Path(path)
    parts, manifest = _part_paths(path)
    try:
        raw = pq.read_schema(parts[0]).metadata or {}
        n_rows = (int(manifest["n_rows"]) if manifest is not None else
                  sum(pq.ParquetFile(p).metadata.num_rows for p in parts))
    except (OSError, ValueError, KeyError, TypeError, pa.ArrowException) as exc:
        raise DataError(f"cannot read {str(path)!r}: {exc}") from None
    meta, config, seed = parse_meta(raw.get(META_KEY), path)  # one-line errors (issue 20)
    extra = {k: v for k, v in meta.items() if k not in ("config", "seed")}
    if manifest is not None:
        extra.update(n_subjects=manifest.get("n_subjects"), per_subject=manifest.get("per_subject"))
    return PartitionedDataset(path, parts, config, seed,
                              {**extra, "source": str(path)}, n_rows)


def load_dataset(
    path: str | os.PathLike, *, glucose_unit: str | None = None, adc_bits: Any = None,
    adc_full_scale: Any = None,
) -> Dataset:
    """Read a dataset written by :meth:`Dataset.save` (or a user's CSV/Parquet file).

    A user's file is read as a prototype team writes it
    (:mod:`~nirglucose.dataset.files`): the CSV delimiter (``,``, ``;`` or tab) and a decimal
    comma are detected; headers are matched after stripping and case-folding
    (``ADC_940`` is ``adc_940``); the reference glucose may be ``glucose_mgdl`` or
    ``glucose_mmoll`` and is converted to ``glucose_mgdl``; the whole file is validated
    once, with the file's own row numbers. ``metadata["read_notes"]`` lists what was
    read differently from the schema's spelling (renames, delimiter, unit), and
    ``metadata["glucose_unit"]`` the unit its reference column was read in (what the
    commands print glucose in unless asked otherwise).

    A directory is opened as a partitioned Parquet dataset (the parts its
    ``manifest.json`` lists, else all ``*.parquet`` files in name order) without reading
    its rows: a :class:`PartitionedDataset`, whose
    ``frame`` is read on first access.

    Parameters
    ----------
    path : str or path-like
        The file or directory.
    glucose_unit : {"mg/dL", "mmol/L"}, optional
        Unit of the file's reference glucose (default: the column's, ``glucose_mgdl``
        mg/dL and ``glucose_mmoll`` mmol/L); the dataset holds mg/dL.
    adc_bits : int or mapping, optional
        The device's ADC resolution, recorded as ``metadata["adc_bits"]``: one for every
        channel, or per channel (``{"adc_940": 10, "adc_1050": 18}``, ``"default"`` for
        the rest) for a device that mixes converters. [bit]
    adc_full_scale : mapping, optional
        Per channel, a full-scale code other than 2^bits - 1, recorded as
        ``metadata["adc_full_scale"]``. [ADC code]

    Raises
    ------
    DataError
        Missing file, unknown suffix, unreadable content, malformed metadata, or a bad
        cell (one line naming the column and the file's rows).
    """
    path = Path(path)
    check_glucose_unit(glucose_unit)
    if not path.exists():
        raise DataError(f"no such file {str(path)!r}")
    try:
        if path.is_dir():
            return open_partitioned(path)
        if path.suffix not in SUFFIXES:
            raise DataError(f"unknown file type {path.suffix!r}; use one of {SUFFIXES}")
        frame, raw, notes = read_frame(path)
    except DataError:
        raise
    except (OSError, ValueError, pa.ArrowException) as exc:
        raise DataError(f"cannot read {str(path)!r}: {exc}") from None
    if not len(frame):
        raise DataError(f"{str(path)!r} holds no measurements (a header, no rows)")
    meta, config, seed = parse_meta(raw.get(META_KEY), path)  # one-line errors (issue 20)
    read_unit = glucose_unit or next(
        (u for c, u in GLUCOSE_COLUMNS.items() if c in frame.columns), None)
    notes += validate_frame(frame, csv=path.suffix == ".csv", glucose_unit=glucose_unit)
    notes += unread_column_notes(frame.columns)
    extra = {k: v for k, v in meta.items() if k not in ("config", "seed")}
    extra.update(source=str(path), read_notes=notes)
    if read_unit is not None:  # the unit the reference was read in (issue 43); a file
        extra.setdefault("glucose_unit", read_unit)  # saved by nirglucose keeps its own
    if adc_bits is not None:
        extra["adc_bits"] = check_channel_bits(adc_bits)
    if adc_full_scale:
        extra["adc_full_scale"] = dict(adc_full_scale)
    return Dataset(frame, config=config, seed=seed, metadata=extra)


def scan_dataset(path: str | os.PathLike):
    """A partitioned dataset directory as a lazy :class:`pyarrow.dataset.Dataset`.

    For out-of-core work on data too large for memory: filters and column selections
    are pushed down to the Parquet parts (``.to_table(columns=..., filter=...)``,
    ``.to_batches()``, ``.count_rows()``).

    Raises
    ------
    DataError
        Not a directory of Parquet parts.
    """
    path = Path(path)
    if not path.is_dir():
        raise DataError(f"{str(path)!r} is not a partitioned dataset directory")
    return open_partitioned(path).scan()
