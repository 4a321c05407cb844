"""`nirglucose sweep --study requirements` and `nirglucose report` of its directory.

The study's search is shrunk (32 pilot states, four generic LEDs, a looser target) by
wrapping the library function the command calls, so the command's own work -- options,
files, figures, answer lines, the report page -- runs end to end in seconds.
"""

from __future__ import annotations

import functools
import json

import pytest

import nirglucose.evaluation.sweep.requirements as req
from nirglucose.cli import main
from nirglucose.evaluation.sweep.requirements import REQUIREMENTS_FILES, RequirementsResult

SMALL = dict(n_states=32, wavelengths_nm=(800.0, 1000.0), target_rmse_mgdl=20.0,
             target_mard_pct=15.0)
TINY = ["--vary", "detector=BPW34", "--models", "mean,oracle", "--subjects", "10",
        "--per-subject", "2", "--folds", "2", "--resamples", "50", "--jobs", "1"]


@pytest.fixture
def small_study(monkeypatch):
    monkeypatch.setattr(req, "requirements_study",
                        functools.partial(req.requirements_study, **SMALL))


@pytest.fixture(scope="module")
def ran(tmp_path_factory):
    out = tmp_path_factory.mktemp("req") / "out"
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(req, "requirements_study", functools.partial(req.requirements_study, **SMALL))
        from contextlib import redirect_stdout
        from io import StringIO

        # the CLI's console writes to whatever sys.stdout is (setting its `file` would
        # pin this buffer, or pytest's capture, for every later test of the process)
        buf = StringIO()
        with redirect_stdout(buf):
            rc = main(["sweep", "--study", "requirements", "--out", str(out), *TINY])
    assert rc == 0
    return out, buf.getvalue()


def test_writes_its_files_figures_and_one_answer_line_per_detector(ran):
    out, printed = ran
    for name in REQUIREMENTS_FILES:
        assert (out / name).is_file(), name
    for stem in ("requirements_averaging", "requirements_designs"):
        assert (out / "figures" / f"{stem}.png").stat().st_size > 1000
    doc = json.loads((out / "requirements.json").read_text())
    (line,) = doc["answer"]  # one detector asked, one line
    assert line.startswith("[physical, glucose signal gain 1] Si (BPW34): ")
    assert " ".join(line.split()) in " ".join(printed.split())
    meta = doc["meta"]
    assert (meta["confirm_subjects"], meta["confirm_per_subject"], meta["confirm_folds"],
            meta["confirm_resamples"]) == (10, 2, 2, 50)
    assert meta["confirm_models"] == ["mean", "oracle"]
    back = RequirementsResult.from_dir(out)
    assert back.answer_lines() == doc["answer"]  # the tables read back give the same line
    assert set(back.confirmation["model"]) == {"mean", "oracle"}


def test_report_renders_the_answer_first_then_figures_and_limits(ran):
    out, _ = ran
    assert main(["report", str(out)]) == 0
    page = (out / "report.html").read_text()
    answer = json.loads((out / "requirements.json").read_text())["answer"][0]
    first = page.index("Si (BPW34)")
    assert first < page.index("<img") < page.index("Confirmation by simulation")
    assert page.index("Confirmation by simulation") < page.index("<h2>Limits</h2>")
    assert page.count('src="data:image/png;base64,') == 2
    assert "privileged reference" in page  # the oracle is a reference, not a competitor
    import html

    assert html.escape(answer) in page


@pytest.mark.parametrize("args, match", [
    (["--seeds", "2"], "--seeds"),
    (["--set", "noise.no_such=2"], "--set"),
    (["--repeats", "2"], "--repeats"),
    (["--calibration", "1"], "--calibration"),
    (["--vary", "noise_scale=1,2"], "varies only the detector"),
    (["--vary", "detector=NOPE"], "NOPE"),
    (["--preset", "physcal"], "unknown preset"),
    (["--models", "nope"], "unknown model"),
    (["--subjects", "0"], "--subjects"),
])
def test_bad_input_exit_2_one_line(tmp_path, capsys, small_study, args, match):
    rc = main(["sweep", "--study", "requirements", "--out", str(tmp_path / "r"), *args])
    err = capsys.readouterr().err
    assert rc == 2
    assert match in err and len(err.strip().splitlines()) == 1, err
    assert not (tmp_path / "r").exists()


def test_report_of_a_broken_directory_is_one_line(tmp_path, capsys):
    d = tmp_path / "r"
    d.mkdir()
    (d / "requirements.json").write_text("{}")
    (d / "minimal_designs.csv").write_text("detector\nBPW34\n")
    assert main(["report", str(d)]) == 2
    err = capsys.readouterr().err
    assert "missing" in err and len(err.strip().splitlines()) == 1, err
