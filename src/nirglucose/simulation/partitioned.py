"""Large datasets: partitioned Parquet written block by block in bounded memory.

:func:`write_partitioned` writes one ``part-NNNNNN.parquet`` per block of
:data:`~nirglucose.simulation._random.BLOCK_SUBJECTS` subjects, each block simulated
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
the parts. The reading side lives in :mod:`nirglucose.dataset` (reading data must
not load the simulator) and is re-exported here.

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
from pathlib import Path

import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq

from .._version import __version__
from ..config import ScenarioConfig
from ..dataset import (
    MANIFEST,
    META_KEY,
    PART_PATTERN,
    PartitionedDataset,
    atomic_write,
    open_partitioned,
    scan_dataset,
)
from ..exceptions import DataError
from .simulator import block_ranges, scenario_tables, simulate_block

__all__ = [
    "MANIFEST",
    "PART_PATTERN",
    "write_partitioned",
    "open_partitioned",
    "scan_dataset",
    "PartitionedDataset",
]

_MANIFEST_FORMAT = 1


def _part_name(block: int) -> str:
    return f"part-{block:06d}.parquet"


def _write_block(cfg, seed, block, start, n_sub, per_subject, tables, out: Path,
                 meta: bytes) -> tuple[int, int]:
    cols, _ = simulate_block(cfg, seed, block, start, n_sub, per_subject, tables)
    table = pa.Table.from_pandas(pd.DataFrame(cols), preserve_index=False)
    del cols
    table = table.replace_schema_metadata({**(table.schema.metadata or {}), META_KEY: meta})
    atomic_write(out / _part_name(block), lambda tmp: pq.write_table(table, tmp))
    return block, table.num_rows


def prepare_partitioned_dir(out: str | Path) -> Path:
    """The output directory of a partitioned dataset, created, with no part or manifest
    left from an earlier run (so nothing incomplete looks complete).

    Raises
    ------
    DataError
        The parent does not exist, or ``out`` exists and is not a directory.
    """
    out = Path(out)
    if not out.parent.exists():
        raise DataError(f"output directory {str(out.parent)!r} does not exist; create it first")
    if out.exists() and not out.is_dir():
        raise DataError(f"{str(out)!r} exists and is not a directory")
    out.mkdir(exist_ok=True)
    for stale in [out / MANIFEST, *out.glob(PART_PATTERN)]:
        stale.unlink(missing_ok=True)
    return out


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
    out = prepare_partitioned_dir(out)
    meta_doc = {"nirglucose_version": __version__, "seed": seed,
                "config": json.loads(cfg.to_json())}
    meta = json.dumps(meta_doc, sort_keys=True).encode()
    tables = scenario_tables(cfg)
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
