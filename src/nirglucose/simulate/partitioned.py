"""Large datasets: partitioned Parquet written block by block in bounded memory."""

from __future__ import annotations

import json
from pathlib import Path

import pyarrow as pa
import pyarrow.parquet as pq

from ..config import ScenarioConfig
from ..dataset import _META_KEY, atomic_write
from .simulator import _tables, block_ranges, simulate_block

__all__ = ["write_partitioned"]


def _write_block(
    cfg, seed, block, start, n_sub, per_subject, tables, out: Path, meta: bytes
) -> int:
    import pandas as pd

    cols, _ = simulate_block(cfg, seed, block, start, n_sub, per_subject, tables)
    table = pa.Table.from_pandas(pd.DataFrame(cols), preserve_index=False)
    table = table.replace_schema_metadata({**(table.schema.metadata or {}), _META_KEY: meta})
    atomic_write(out / f"part-{block:06d}.parquet", lambda tmp: pq.write_table(table, tmp))
    return table.num_rows


def write_partitioned(
    cfg: ScenarioConfig,
    out: str | Path,
    n_subjects: int,
    per_subject: int,
    seed: int,
    n_jobs: int = 1,
) -> int:
    """Write ``part-NNNNNN.parquet`` files, one per block of subjects; returns the row count.

    Each part is written atomically; the parts are byte-identical whatever ``n_jobs``.
    """
    from .. import __version__

    out = Path(out)
    out.mkdir(exist_ok=True)
    meta = json.dumps(
        {"nirglucose_version": __version__, "seed": seed, "config": json.loads(cfg.to_json())},
        sort_keys=True,
    ).encode()
    tables = _tables(cfg)
    blocks = block_ranges(n_subjects)
    args = [(cfg, seed, b, s, k, per_subject, tables, out, meta) for b, s, k in blocks]
    if n_jobs == 1:
        counts = [_write_block(*a) for a in args]
    else:
        from joblib import Parallel, delayed

        counts = Parallel(n_jobs=n_jobs)(delayed(_write_block)(*a) for a in args)
    return int(sum(counts))
