"""Same seed, same bytes, whatever the chunking or the number of workers."""

from __future__ import annotations

import pandas as pd
import pytest

import nirglucose as ng
from nirglucose.simulation import _random
from nirglucose.simulation.partitioned import write_partitioned
from nirglucose.simulation.simulator import block_ranges, simulate_frame


def test_same_seed_byte_identical_parquet(tmp_path):
    a = ng.simulate("paper", 40, 3, 7)
    b = ng.simulate("paper", 40, 3, 7)
    pa_, pb = a.save(tmp_path / "a.parquet"), b.save(tmp_path / "b.parquet")
    assert pa_.read_bytes() == pb.read_bytes()


def test_different_seed_differs():
    a = ng.simulate("paper", 20, 3, 1).frame
    b = ng.simulate("paper", 20, 3, 2).frame
    assert not a["glucose_mgdl"].equals(b["glucose_mgdl"])


@pytest.fixture
def small_blocks(monkeypatch):
    monkeypatch.setattr(_random, "BLOCK_SUBJECTS", 10)


def test_one_chunk_vs_seven_chunks(small_blocks, tmp_path):
    cfg = ng.resolve_config("paper")
    assert len(block_ranges(70)) == 7
    one = simulate_frame(cfg, 70, 3, 5, n_jobs=1)
    two_workers = simulate_frame(cfg, 70, 3, 5, n_jobs=2)
    pd.testing.assert_frame_equal(one, two_workers)
    write_partitioned(cfg, tmp_path / "parts", 70, 3, 5, n_jobs=2)
    parts = sorted((tmp_path / "parts").glob("*.parquet"))
    assert len(parts) == 7
    back = ng.load_dataset(tmp_path / "parts").frame
    pd.testing.assert_frame_equal(one, back)


def test_blocks_do_not_depend_on_later_subjects(small_blocks):
    cfg = ng.resolve_config("paper")
    small = simulate_frame(cfg, 30, 2, 9)
    large = simulate_frame(cfg, 70, 2, 9)
    pd.testing.assert_frame_equal(small, large.iloc[: len(small)].reset_index(drop=True))


def test_parquet_metadata_round_trip(tmp_path):
    ds = ng.simulate("lab", 5, 2, 3, overrides={"hardware.adc_bits": 14})
    back = ng.load_dataset(ds.save(tmp_path / "d.parquet"))
    assert back.seed == 3
    assert back.config == ds.config
    assert back.metadata["nirglucose_version"] == ng.__version__
    pd.testing.assert_frame_equal(back.frame, ds.frame)


def test_csv_round_trip(tmp_path):
    ds = ng.simulate("paper", 5, 2, 3)
    back = ng.load_dataset(ds.save(tmp_path / "d.csv"))
    pd.testing.assert_frame_equal(back.frame, ds.frame, check_dtype=False, check_categorical=False)
