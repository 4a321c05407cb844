"""Partitioned Parquet: chunk invariance, manifest, lazy loading, out-of-core access."""

from __future__ import annotations

import json

import pandas as pd
import pytest

import nirglucose as ng
from nirglucose.dataset import scan_dataset
from nirglucose.exceptions import DataError
from nirglucose.simulation import _random
from nirglucose.simulation.partitioned import (
    MANIFEST,
    PartitionedDataset,
    write_partitioned,
)
from nirglucose.simulation.simulator import simulate_frame


@pytest.fixture
def small_blocks(monkeypatch):
    monkeypatch.setattr(_random, "BLOCK_SUBJECTS", 10)


@pytest.fixture
def cfg():
    return ng.resolve_config("paper")


def test_one_vs_two_workers_byte_identical(small_blocks, cfg, tmp_path):
    n1 = write_partitioned(cfg, tmp_path / "one", 45, 3, 11, n_jobs=1)
    n2 = write_partitioned(cfg, tmp_path / "two", 45, 3, 11, n_jobs=2)
    assert n1 == n2 == 135
    one = sorted((tmp_path / "one").glob("part-*.parquet"))
    two = sorted((tmp_path / "two").glob("part-*.parquet"))
    assert [p.name for p in one] == [p.name for p in two] and len(one) == 5
    for a, b in zip(one, two, strict=True):
        assert a.read_bytes() == b.read_bytes(), a.name
    assert (tmp_path / "one" / MANIFEST).read_bytes() == (tmp_path / "two" / MANIFEST).read_bytes()


def test_lazy_load_round_trip(small_blocks, cfg, tmp_path):
    write_partitioned(cfg, tmp_path / "d", 25, 2, 4)
    ds = ng.load_dataset(tmp_path / "d")
    assert isinstance(ds, PartitionedDataset) and isinstance(ds, ng.Dataset)
    assert len(ds) == 50 and not ds.loaded  # row count from the manifest
    assert ds.seed == 4 and ds.config == cfg and len(ds.parts) == 3
    assert "50 snapshots in 3 parts" in repr(ds) and not ds.loaded
    expected = simulate_frame(cfg, 25, 2, 4)
    pd.testing.assert_frame_equal(ds.frame, expected)
    assert ds.loaded
    chunks = list(ds.iter_frames(columns=["subject_id", "glucose_mgdl"]))
    assert [len(c) for c in chunks] == [20, 20, 10]
    assert scan_dataset(tmp_path / "d").count_rows() == 50
    table = ds.scan().to_table(columns=["glucose_mgdl"])
    assert table.column("glucose_mgdl").to_pylist() == expected["glucose_mgdl"].tolist()
    dd = ds.to_dask(columns=["glucose_mgdl"])
    assert dd.npartitions == 3


def test_rewrite_removes_stale_parts(small_blocks, cfg, tmp_path):
    write_partitioned(cfg, tmp_path / "d", 35, 1, 0)
    (tmp_path / "d" / "notes.txt").write_text("mine")
    write_partitioned(cfg, tmp_path / "d", 12, 1, 0)
    assert sorted(p.name for p in (tmp_path / "d").glob("*.parquet")) == [
        "part-000000.parquet", "part-000001.parquet"]
    assert len(ng.load_dataset(tmp_path / "d").frame) == 12
    assert (tmp_path / "d" / "notes.txt").exists()


def test_missing_part_and_bad_manifest(small_blocks, cfg, tmp_path):
    d = tmp_path / "d"
    write_partitioned(cfg, d, 25, 1, 0)
    (d / "part-000001.parquet").unlink()
    with pytest.raises(DataError, match="lacks parts"):
        ng.load_dataset(d)
    (d / MANIFEST).write_text("{not json")
    with pytest.raises(DataError, match="malformed"):
        ng.load_dataset(d)


def test_directory_without_manifest_still_loads(small_blocks, cfg, tmp_path):
    d = tmp_path / "d"
    write_partitioned(cfg, d, 25, 2, 1)
    manifest = json.loads((d / MANIFEST).read_text())
    (d / MANIFEST).unlink()
    ds = ng.load_dataset(d)
    assert len(ds) == manifest["n_rows"] == 50 and not ds.loaded
    pd.testing.assert_frame_equal(ds.frame, simulate_frame(cfg, 25, 2, 1))
    with pytest.raises(DataError, match="no .parquet"):
        ng.load_dataset(tmp_path)
