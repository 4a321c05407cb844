"""Large datasets: partitioned Parquet written block by block in bounded memory.

:func:`write_partitioned` writes one ``part-NNNNNN.parquet`` per block of
:data:`~nirglucose.simulate._random.BLOCK_SUBJECTS` subjects, each block simulated
from its own :class:`numpy.random.SeedSequence` streams, so the parts are
byte-identical whatever the number of worker processes or the order they finish in.
A worker holds one block at a time (about ``BLOCK_SUBJECTS × per_subject`` rows), so
memory does not grow with the dataset. ``manifest.json``, written last, lists the
parts, their row counts and the run's seed and config: a directory without it is an
unfinished write.

:func:`open_partitioned` (what :func:`nirglucose.load_dataset` does with a directory)
returns a :class:`PartitionedDataset`: its row count, config and seed come from the
file metadata, and ``.frame`` is read only when first used. :func:`scan_dataset` gives
a :mod:`pyarrow.dataset` for out-of-core queries, and
:meth:`PartitionedDataset.iter_frames` / :meth:`PartitionedDataset.to_dask` stream
the parts.

Examples
--------
>>> import nirglucose as ng, tempfile, pathlib
>>> d = pathlib.Path(tempfile.mkdtemp()) / "big"
>>> write_partitioned(ng.resolve_config("paper"), d, 10, 2, seed=0)
20
>>> ds = ng.load_dataset(d)
>>> len(ds), ds.loaded
(20, False)
"""

from __future__ import annotations

import json
import os
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import Any

import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq

from ..config import ScenarioConfig
from ..dataset import _META_KEY, Dataset, atomic_write
from ..exceptions import DataError
from .simulator import _tables, block_ranges, simulate_block

__all__ = [
    "MANIFEST",
    "PART_PATTERN",
    "write_partitioned",
    "open_partitioned",
    "scan_dataset",
    "PartitionedDataset",
]

#: Name of the file listing the parts of a finished write.
MANIFEST = "manifest.json"
#: Glob pattern of the part files.
PART_PATTERN = "part-*.parquet"
_MANIFEST_FORMAT = 1


def _part_name(block: int) -> str:
    return f"part-{block:06d}.parquet"


def _write_block(cfg, seed, block, start, n_sub, per_subject, tables, out: Path,
                 meta: bytes) -> tuple[int, int]:
    cols, _ = simulate_block(cfg, seed, block, start, n_sub, per_subject, tables)
    table = pa.Table.from_pandas(pd.DataFrame(cols), preserve_index=False)
    del cols
    table = table.replace_schema_metadata({**(table.schema.metadata or {}), _META_KEY: meta})
    atomic_write(out / _part_name(block), lambda tmp: pq.write_table(table, tmp))
    return block, table.num_rows


def write_partitioned(
    cfg: ScenarioConfig, out: str | Path, n_subjects: int, per_subject: int, seed: int,
    n_jobs: int = 1,
) -> int:
    """Write ``part-NNNNNN.parquet`` files, one per block of subjects; returns the row count.

    Parameters
    ----------
    cfg : ScenarioConfig
        The resolved scenario.
    out : str or Path
        Directory (created if its parent exists). Part files and a manifest of an
        earlier write there are replaced; other files are left alone.
    n_subjects, per_subject : int
        Subjects and measurements per subject. [-]
    seed : int
        Seed of every random stream. [-]
    n_jobs : int
        Worker processes (blocks are simulated in parallel); the bytes written do not
        depend on it.

    Returns
    -------
    int
        Snapshots written.

    Notes
    -----
    Each part is written atomically as its block finishes; ``manifest.json`` last.
    Peak memory is about ``n_jobs`` blocks of ``BLOCK_SUBJECTS × per_subject`` rows
    plus each worker's interpreter, whatever ``n_subjects`` is.
    """
    from .. import __version__

    out = Path(out)
    if not out.parent.exists():
        raise DataError(f"output directory {str(out.parent)!r} does not exist; create it first")
    if out.exists() and not out.is_dir():
        raise DataError(f"{str(out)!r} exists and is not a directory")
    out.mkdir(exist_ok=True)
    for stale in [out / MANIFEST, *out.glob(PART_PATTERN)]:
        stale.unlink(missing_ok=True)
    meta_doc = {"nirglucose_version": __version__, "seed": seed,
                "config": json.loads(cfg.to_json())}
    meta = json.dumps(meta_doc, sort_keys=True).encode()
    tables = _tables(cfg)
    blocks = block_ranges(n_subjects)
    args = [(cfg, seed, b, s, k, per_subject, tables, out, meta) for b, s, k in blocks]
    if n_jobs == 1 or len(blocks) == 1:
        counts = dict(_write_block(*a) for a in args)
    else:
        from joblib import Parallel, delayed

        counts = dict(Parallel(n_jobs=min(n_jobs, len(blocks)), return_as="generator_unordered")(
            delayed(_write_block)(*a) for a in args))
    parts = [{"file": _part_name(b), "rows": int(counts[b]), "first_subject": int(s),
              "subjects": int(k)} for b, s, k in blocks]
    manifest = {"format": _MANIFEST_FORMAT, **meta_doc, "n_subjects": int(n_subjects),
                "per_subject": int(per_subject), "n_rows": int(sum(counts.values())),
                "parts": parts}
    text = json.dumps(manifest, indent=1, sort_keys=True) + "\n"
    atomic_write(out / MANIFEST, lambda tmp: Path(tmp).write_text(text, encoding="utf-8"))
    return manifest["n_rows"]


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
        super().__init__(None, config=config, seed=seed, metadata=metadata)  # type: ignore[arg-type]

    @property
    def frame(self) -> pd.DataFrame:  # type: ignore[override]
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
        A directory written by :func:`write_partitioned` (or any directory of Parquet
        files of the dataset schema, read in name order).

    Returns
    -------
    PartitionedDataset

    Raises
    ------
    DataError
        No parts, a malformed manifest or metadata, a missing part.
    """
    from ..dataset_meta import parse_meta

    path = Path(path)
    parts, manifest = _part_paths(path)
    try:
        raw = pq.read_schema(parts[0]).metadata or {}
        n_rows = (int(manifest["n_rows"]) if manifest is not None else
                  sum(pq.ParquetFile(p).metadata.num_rows for p in parts))
    except (OSError, ValueError, KeyError, TypeError, pa.ArrowException) as exc:
        raise DataError(f"cannot read {str(path)!r}: {exc}") from None
    meta, config, seed = parse_meta(raw.get(_META_KEY), path)  # one-line errors (issue 20)
    extra = {k: v for k, v in meta.items() if k not in ("config", "seed")}
    if manifest is not None:
        extra.update(n_subjects=manifest.get("n_subjects"), per_subject=manifest.get("per_subject"))
    return PartitionedDataset(path, parts, config, seed,
                              {**extra, "source": str(path)}, n_rows)


def scan_dataset(path: str | os.PathLike):
    """A partitioned directory as a lazy :class:`pyarrow.dataset.Dataset`.

    Examples
    --------
    >>> scan_dataset(d).count_rows()  # doctest: +SKIP
    20
    """
    return open_partitioned(path).scan()
