"""What a person expects of a CLI: version, model list, described keys, progress lines."""

from __future__ import annotations

import re

import pytest
from cli_helpers import PROGRESS, assert_one_line_error

import nirglucose
import nirglucose.evaluation.engine.executors as executors
from nirglucose.config import PRESETS, valid_keys
from nirglucose.evaluation.engine.progress import MAX_LINES, TaskProgress
from nirglucose.models.registry import available_models


def test_version(cli):
    code, out, _ = cli("--version")
    assert code == 0 and out.strip() == f"nirglucose {nirglucose.__version__}"


def test_models_lists_one_line_each(cli):
    code, out, _ = cli("models")
    assert code == 0
    lines = out.strip().splitlines()
    assert [ln.split()[0] for ln in lines] == available_models()
    assert all(len(ln.split()) > 2 for ln in lines)  # a description follows each name
    # plain text (issue 42): no reST roles or literals, no private class names
    assert not re.search(r":[a-z]+:`|``|_ResidualHybrid", out)
    # one column for the names, the longest included
    assert len({len(ln) - len(ln[len(ln.split()[0]):].lstrip()) for ln in lines}) == 1
    # the -fm variants name their base and the defaults they change
    fm = next(ln for ln in lines if ln.startswith("original-pinn-fm "))
    assert "original-pinn with physics_form='forward', lambda_phys=0.1" in fm


def test_keys_have_units_and_descriptions(cli):
    code, out, _ = cli("keys")
    assert code == 0
    lines = out.strip().splitlines()
    assert len(lines) == len(valid_keys())
    by_key = {ln.split(" = ")[0]: ln for ln in lines}
    assert re.search(r"\[mbar\] \(between 300 and 1100\)  # Mean barometric pressure", by_key[
        "environment.pressure_mbar_mean"])
    assert "[bit]" in by_key["hardware.adc_bits"]
    assert sum("[" in ln and "#" in ln for ln in lines) >= 0.9 * len(lines)


@pytest.mark.parametrize("cmd", ["benchmark", "sweep", "simulate"])
def test_presets_listed_in_help(cli, cmd):
    code, out, _ = cli(cmd, "--help")
    assert code == 0
    text = " ".join(out.split())
    assert all(name in text for name in PRESETS), text


def test_jobs_above_cores_warns(cli, workdir, monkeypatch):
    monkeypatch.setattr(executors, "available_cores", lambda: 1)
    code, _, err = cli("simulate", "--out", "a.csv", "--subjects", 2, "--jobs", 2)
    assert code == 0, err
    assert "warning: --jobs 2 exceeds the 1 available cores" in err


@pytest.mark.slow  # make test-slow (CI runs it)
def test_progress_lines_when_not_a_terminal(cli, workdir):
    code, _, err = cli("benchmark", "--out", "res", "--subjects", 10, "--per-subject", 2,
                       "--models", "ebl", "--folds", 2, "--repeats", 1, "--resamples", 10)
    assert code == 0, err
    progress = [ln for ln in err.splitlines() if PROGRESS.match(ln)]
    assert progress[0].startswith("benchmark: 0/")
    assert "done after" in progress[-1]
    assert len(progress) >= 3


def test_progress_is_throttled(capsys):
    import io

    buf = io.StringIO()
    bar = TaskProgress("sweep", 1000, 0, "reused", stream=buf)
    for i in range(1000):
        bar.advance(f"task {i}")
    bar.close()
    lines = buf.getvalue().splitlines()
    assert len(lines) <= MAX_LINES + 2
    assert lines[-2].startswith("sweep: 1000/1000 tasks") and "done after" in lines[-1]


@pytest.mark.parametrize(
    ("args", "hint"),
    [
        (["simulate", "--preset", "papr", "--out", "a.csv"], "did you mean 'paper'?"),
        (["benchmark", "--models", "ebll", "--out", "res"], "did you mean 'ebl'?"),
        (["sweep", "--study", "devise", "--out", "sw"], "did you mean 'device'?"),
    ],
)
def test_did_you_mean_for_presets_models_and_studies(cli, workdir, args, hint):
    code, _, err = cli(*args)
    assert_one_line_error(code, err, contains=[hint])


def test_jobs_and_resamples_mean_the_same_in_every_command():
    """One --jobs (default: the available cores) and one --resamples default everywhere."""
    import inspect

    from nirglucose import cli as cli_module

    for command in (cli_module.simulate, cli_module.benchmark, cli_module.sweep):
        params = inspect.signature(command).parameters
        assert params["jobs"].default is None, command.__name__
        if "resamples" in params:
            assert params["resamples"].default == cli_module.DEFAULT_RESAMPLES
