"""table.md on a user's own data: no preset, no study columns."""

from __future__ import annotations

import numpy as np
import pandas as pd

from nirglucose.dataset import Dataset
from nirglucose.evaluation import Protocol, run_benchmark


def _device_frame() -> pd.DataFrame:
    rng = np.random.default_rng(0)
    n_subj, per = 15, 3
    n = n_subj * per
    f = pd.DataFrame({"subject_id": np.repeat(np.arange(n_subj), per)})
    f["glucose_mgdl"] = rng.uniform(70, 250, n)
    for nm in (850, 940, 1150):
        f[f"adc_{nm}"] = rng.integers(300, 900, n)
    f["age_yr"] = np.repeat(rng.uniform(20, 70, n_subj), per)
    return f


def test_user_data_table_has_no_study_columns(tmp_path):
    run_benchmark(
        Dataset(_device_frame(), metadata={"adc_bits": 10}),  # codes <= 1023: declared
        ["ebl", "mean"],
        protocol=Protocol(n_splits=3, repeats=1, resamples=50),
        out=tmp_path / "r",
        drop_one_models="none",
        timing={"n_single": 5, "min_single": 2, "batch_rows": 100, "batch_repeats": 1},
    )
    table = (tmp_path / "r" / "table.md").read_text()
    assert table.startswith("# Benchmark on your data")
    assert "your data" in table and "None" not in table
    assert "study" not in table.lower() and "n = 48" not in table
    header = next(line for line in table.splitlines() if line.startswith("| Model"))
    assert header.count("|") == 10  # model, 6 metrics, MACs, RMSE / oracle
