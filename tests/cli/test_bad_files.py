"""Ordinary file mistakes: exit 2, one line, nothing left behind (issue 20)."""

from __future__ import annotations

import json

import pyarrow as pa
import pyarrow.parquet as pq
import pytest
from cli_helpers import SRC, assert_one_line_error, listing

import nirglucose as ng
from nirglucose.dataset import load_dataset
from nirglucose.exceptions import DataError


@pytest.fixture(scope="module")
def small():
    return ng.simulate("paper", 4, 2, seed=0)


def test_out_names_an_existing_directory(cli, workdir):
    (workdir / "a.csv").mkdir()
    code, _, err = cli("simulate", "--out", "a.csv", "--subjects", 2)
    assert_one_line_error(code, err, contains=["is a directory"])
    assert listing(workdir) == {"a.csv"}


@pytest.mark.parametrize("out", ["missing/a.parquet", "missing/deeper/a.csv"])
def test_out_parent_missing(cli, workdir, out):
    code, _, err = cli("simulate", "--out", out, "--subjects", 2)
    assert_one_line_error(code, err, contains=["does not exist"])
    assert not list(workdir.iterdir())


def test_out_parent_is_a_file(cli, workdir):
    (workdir / "f").write_text("x")
    code, _, err = cli("simulate", "--out", "f/a.csv", "--subjects", 2)
    assert_one_line_error(code, err, contains=["not a directory"])


def test_out_under_proc(cli):
    code, _, err = cli("simulate", "--out", "/proc/x.parquet", "--subjects", 2)
    line = assert_one_line_error(code, err, contains=["/proc"])
    assert ".tmp" not in line


@pytest.mark.parametrize("cmd", ["fit", "predict"])
def test_fit_predict_out_is_a_directory(cli, workdir, small, cmd):
    small.save(workdir / "d.parquet")
    name = "m.json" if cmd == "fit" else "p.csv"
    (workdir / name).mkdir()
    model = ["--model", "ebl"] if cmd == "fit" else ["--model", "nothere.json"]
    code, _, err = cli(cmd, *model, "--data", "d.parquet", "--out", name)
    assert_one_line_error(code, err, contains=["is a directory"])


def test_huge_subject_count_refused_up_front(cli, workdir):
    code, _, err = cli("simulate", "--out", "a.parquet", "--subjects", 1_000_000_000_000)
    assert_one_line_error(code, err, contains=["GiB"])
    assert not list(workdir.iterdir())


def _with_meta(small, path, meta):
    table = pa.Table.from_pandas(small.frame, preserve_index=False)
    raw = meta if isinstance(meta, bytes) else json.dumps(meta).encode()
    pq.write_table(table.replace_schema_metadata({b"nirglucose": raw}), path)


BAD_META = {
    "list": [1, 2],
    "number": 3,
    "not-json": b"{nope",
    "unknown-config-key": {"config": {"no_such_section": 1}},
    "out-of-range": {"config": {"hardware": {"adc_bits": 99}}},
    "config-a-list": {"config": [1]},
    "negative-seed": {"seed": -1},
    "text-seed": {"seed": "zero"},
    "version-a-number": {"nirglucose_version": 1},
}


@pytest.mark.parametrize("meta", BAD_META.values(), ids=list(BAD_META))
def test_malformed_parquet_metadata(cli, workdir, small, meta):
    _with_meta(small, workdir / "d.parquet", meta)
    with pytest.raises(DataError, match="d.parquet"):
        load_dataset(workdir / "d.parquet")
    code, _, err = cli("fit", "--model", "ebl", "--data", "d.parquet", "--out", "m.json")
    assert_one_line_error(code, err, contains=["d.parquet"])
    assert listing(workdir) == {"d.parquet"}


def test_valid_metadata_still_loads(workdir, small):
    small.save(workdir / "d.parquet")
    back = load_dataset(workdir / "d.parquet")
    assert back.seed == small.seed and back.config == small.config


@pytest.mark.parametrize("name", ["meta.json", "histories.json"])
@pytest.mark.parametrize("doc", [[1, 2], "text", 3])
def test_results_json_of_the_wrong_shape(cli, tmp_path, monkeypatch, name, doc):
    from pathlib import Path

    monkeypatch.syspath_prepend(str(Path(__file__).parents[1] / "report"))
    from report_fixtures import write_synthetic_results

    d = tmp_path / "res"
    write_synthetic_results(d)
    (d / name).write_text(json.dumps(doc))
    code, _, err = cli("report", d, "--out", tmp_path / "r.html")
    assert_one_line_error(code, err, contains=[name])
    assert not (tmp_path / "r.html").exists()


def test_missing_data_file(cli, workdir):
    code, _, err = cli("fit", "--model", "ebl", "--data", "nothere.csv", "--out", "m.json")
    assert_one_line_error(code, err, contains=["nothere.csv"])


def test_api_refuses_huge_simulation_up_front():
    """In a subprocess capped at 4 GiB, so a regression fails instead of exhausting memory."""
    import resource
    import subprocess
    import sys

    def cap():
        resource.setrlimit(resource.RLIMIT_AS, (4 * 2**30, 4 * 2**30))

    code = ("import nirglucose as ng\n"
            "try:\n    ng.simulate('paper', 10**12, 3)\n"
            "except ng.ConfigError as e:\n    print('refused:', e)\n")
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         preexec_fn=cap, timeout=120, env={"PYTHONPATH": SRC, "PATH": ""})
    assert res.stdout.startswith("refused:") and "GiB" in res.stdout, res.stderr[-500:]
