"""Ctrl-C and SIGTERM stop a run with one line and 130 / 143; no worker survives (issue 20).

The signal tests run the real console script in a subprocess, with short bounded runs.
"""

from __future__ import annotations

import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest
from cli_helpers import PROGRESS, all_gone, subprocess_env

import nirglucose.evaluation.benchmark.run as bench_mod

pytestmark = pytest.mark.skipif(not sys.platform.startswith("linux"), reason="uses /proc")


def _children(pid: int) -> list[int]:
    """Direct children of ``pid`` (from /proc)."""
    out = []
    for d in Path("/proc").iterdir():
        if d.name.isdigit():
            try:
                stat = (d / "stat").read_text()
            except OSError:
                continue
            if int(stat.rsplit(")", 1)[1].split()[1]) == pid:
                out.append(int(d.name))
    return out


def _alive(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except OSError:
        return False
    return state != "Z"


def _wait_for_workers(proc, n: int, timeout_s: float = 60.0) -> list[int]:
    """The loky worker pids once ``n`` are running and a task has started."""
    t0 = time.monotonic()
    while time.monotonic() - t0 < timeout_s:
        workers = [c for c in _children(proc.pid)
                   if "popen_loky_posix" in Path(f"/proc/{c}/cmdline").read_bytes().decode(
                       errors="replace")]
        if len(workers) >= n:
            return workers
        time.sleep(0.2)
    proc.kill()
    pytest.fail("no workers started")


BENCH = ["benchmark", "--subjects", "30", "--models", "ebl,pls,sdnn", "--jobs", "2",
         "--resamples", "20"]


@pytest.mark.parametrize(("sig", "status", "word"), [(signal.SIGTERM, 143, "terminated"),
                                                     (signal.SIGINT, 130, "interrupted")])
def test_signal_stops_benchmark_and_its_workers(tmp_path, sig, status, word):
    proc = subprocess.Popen(
        [sys.executable, "-c", "import sys; from nirglucose.cli import main; "
         "sys.exit(main())", *BENCH, "--out", str(tmp_path / "res")],
        env=subprocess_env(), stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )
    workers = _wait_for_workers(proc, 2)
    time.sleep(1.0)
    proc.send_signal(sig)
    try:
        _, err = proc.communicate(timeout=30)
    except subprocess.TimeoutExpired:
        proc.kill()
        pytest.fail("the run did not stop")
    assert proc.returncode == status, err
    lines = [ln for ln in err.splitlines() if ln.strip() and not PROGRESS.match(ln)]
    assert len(lines) == 1 and lines[0].startswith(f"error: {word}"), err
    assert "Traceback" not in err
    assert all_gone(workers, _alive), "a worker outlived the run"


def test_workers_die_with_a_killed_parent(tmp_path):
    script = tmp_path / "run.py"
    script.write_text(textwrap.dedent("""
        import time
        from nirglucose.evaluation.engine.executors import run_unordered

        def nap(s):
            time.sleep(s)
            return s

        if __name__ == "__main__":
            list(run_unordered(nap, [60, 60], jobs=2))
    """))
    proc = subprocess.Popen([sys.executable, str(script)], env=subprocess_env(), cwd=tmp_path,
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    workers = _wait_for_workers(proc, 2)
    proc.kill()  # SIGKILL: no handler, no cleanup in the parent
    proc.wait(timeout=10)
    assert all_gone(workers, _alive), "a worker outlived its SIGKILLed parent"


def test_ctrl_c_in_process_exits_130(cli, workdir, monkeypatch):
    def interrupt(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(bench_mod, "run_benchmark", interrupt)
    code, _, err = cli("benchmark", "--out", "res", "--subjects", 4, "--folds", 2, "--models",
                       "ebl")
    assert code == 130
    assert err.strip().startswith("error: interrupted") and len(err.strip().splitlines()) == 1


@pytest.mark.parametrize(("sig", "status", "word"), [(signal.SIGTERM, 143, "terminated"),
                                                     (signal.SIGINT, 130, "interrupted")])
def test_a_signal_while_the_script_starts_is_one_line(tmp_path, sig, status, word):
    """The console script handles the signal before the package's imports (about 1.5 s)
    start; later, the command's own handler does: one line and 130 / 143 either way."""
    script = Path(sys.executable).parent / "nirglucose"
    if not script.is_file():
        pytest.skip("the console script is not installed beside this Python")
    proc = subprocess.Popen([str(script), "simulate", "--subjects", "400", "--out",
                             str(tmp_path / "d.csv")], env=subprocess_env(), cwd=tmp_path,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    # numpy being mapped means the package's imports are under way (the window aimed at)
    t0 = time.monotonic()
    while time.monotonic() - t0 < 10 and proc.poll() is None:
        try:
            if "numpy" in Path(f"/proc/{proc.pid}/maps").read_text(errors="replace"):
                break
        except OSError:
            pass
        time.sleep(0.01)
    proc.send_signal(sig)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == status, err
    lines = [ln for ln in err.splitlines() if ln.strip() and not PROGRESS.match(ln)]
    assert len(lines) == 1 and lines[0].startswith(f"error: {word}"), err
    assert not (tmp_path / "d.csv").exists()

# Long-running (whole studies, end-to-end runs, Monte Carlo or every model): `make test-slow`,
# which CI runs beside the fast `make test` (tests/test_slow_marks.py)
pytestmark = [pytestmark, pytest.mark.slow]
