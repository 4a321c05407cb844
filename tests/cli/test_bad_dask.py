"""Dask backends: no local worker outlives a killed run; a remote cluster's are left alone
but our futures are cancelled (issue 20).

The kill test runs the real CLI (``sweep --scheduler local``) in a subprocess.
"""

from __future__ import annotations

import signal
import subprocess
import sys
import time

import pytest

pytest.importorskip("distributed")
psutil = pytest.importorskip("psutil")

from cli_helpers import PROGRESS, all_gone, subprocess_env  # noqa: E402

from nirglucose.evaluation.engine.executors import resolve_backend, run_unordered  # noqa: E402

pytestmark = pytest.mark.skipif(not sys.platform.startswith("linux"), reason="POSIX signals")

SWEEP = ["sweep", "--vary", "noise_scale=0.5,1,2,4", "--seeds", "3", "--models", "ebl,pls",
         "--subjects", "40", "--resamples", "20", "--no-figures"]


def _cli(*args, **kwargs):
    return subprocess.Popen(
        [sys.executable, "-c", "import sys; from nirglucose.cli import main; sys.exit(main())",
         *args], env=subprocess_env(), text=True, **kwargs)


def _dask_workers(proc: psutil.Process) -> list[psutil.Process]:
    return [c for c in proc.children(recursive=True)
            if "spawn_main" in " ".join(c.cmdline())]


def _alive(p: psutil.Process) -> bool:
    try:
        return p.is_running() and p.status() != psutil.STATUS_ZOMBIE
    except psutil.NoSuchProcess:
        return False


def test_local_scheduler_is_a_dask_backend_of_jobs_workers():
    assert resolve_backend(3, "local") == ("dask", 3)
    assert resolve_backend(None, "tcp://h:8786") == ("dask", 0)


def test_no_dask_worker_outlives_a_sigkilled_sweep(tmp_path):
    proc = _cli(*SWEEP, "--jobs", "2", "--scheduler", "local", "--out", str(tmp_path / "res"),
                stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    parent = psutil.Process(proc.pid)
    t0 = time.monotonic()
    workers: list[psutil.Process] = []
    while time.monotonic() - t0 < 30 and len(workers) < 2:
        time.sleep(0.2)
        workers = _dask_workers(parent)
    if len(workers) < 2:
        proc.kill()
        pytest.fail("no Dask workers started")
    time.sleep(1.0)  # tasks running
    descendants = parent.children(recursive=True)  # workers, resource tracker
    assert proc.poll() is None, "the sweep ended before the kill: make it longer"
    proc.kill()  # SIGKILL: no handler, no cleanup in the parent
    proc.wait(timeout=10)
    survivors = [p for p in descendants if _alive(p)] if not all_gone(descendants, _alive) else []
    for p in survivors:
        p.kill()
    assert survivors == [], "a Dask worker outlived its SIGKILLed parent"


def nap(s: float) -> float:
    time.sleep(s)
    return s


@pytest.fixture
def remote():
    """A Dask cluster that is not ours (threads in this process) and a client of it."""
    from distributed import Client, LocalCluster

    cluster = LocalCluster(n_workers=1, threads_per_worker=3, processes=False,
                           protocol="tcp://", host="127.0.0.1", dashboard_address=None)
    client = Client(cluster, set_as_default=False)
    yield cluster, client
    client.close()
    cluster.close()


def _n_tasks(client) -> int:
    return client.run_on_scheduler(lambda dask_scheduler: len(dask_scheduler.tasks))


def test_closing_the_stream_cancels_our_futures_on_a_remote_cluster(remote, monkeypatch):
    cluster, client = remote
    cancelled = []
    cancel = client.cancel
    monkeypatch.setattr(client, "cancel", lambda fs, **kw: (cancelled.extend(fs),
                                                            cancel(fs, **kw)))
    stream = run_unordered(nap, [0.05, 2.0, 2.0], scheduler=client)
    assert next(stream) == (0, 0.05)
    assert _n_tasks(client) >= 2
    stream.close()  # what Ctrl-C / SIGTERM (turned into an exception) does to the run
    assert sorted(f.key[-1] for f in cancelled) == ["1", "2"]  # the unfinished ones, explicitly
    t0 = time.monotonic()
    while _n_tasks(client) and time.monotonic() - t0 < 5:
        time.sleep(0.05)
    assert _n_tasks(client) == 0  # cancelled while our client stays connected
    assert client.status == "running" and len(cluster.workers) == 1  # workers not ours: kept


def test_sigterm_on_a_remote_cluster_cancels_and_keeps_its_workers(tmp_path, remote):
    cluster, client = remote
    proc = _cli(*SWEEP, "--scheduler", cluster.scheduler_address, "--out", str(tmp_path / "r"),
                stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    t0 = time.monotonic()
    while _n_tasks(client) == 0 and time.monotonic() - t0 < 30:
        time.sleep(0.1)
    assert _n_tasks(client) > 0, "no task reached the scheduler"
    proc.send_signal(signal.SIGTERM)
    try:
        _, err = proc.communicate(timeout=30)
    except subprocess.TimeoutExpired:
        proc.kill()
        pytest.fail("the run did not stop")
    assert proc.returncode == 143, err
    lines = [ln for ln in err.splitlines() if ln.strip() and not PROGRESS.match(ln)]
    assert len(lines) == 1 and lines[0].startswith("error: terminated"), err
    t0 = time.monotonic()
    while _n_tasks(client) and time.monotonic() - t0 < 5:
        time.sleep(0.05)
    assert _n_tasks(client) == 0
    assert len(cluster.workers) == 1 and client.status == "running"


@pytest.fixture
def deaf_scheduler():
    """A TCP address that accepts connections and never answers (distributed.Client
    waits forever on it)."""
    import socket

    server = socket.socket()
    server.bind(("127.0.0.1", 0))
    server.listen(4)
    yield f"tcp://127.0.0.1:{server.getsockname()[1]}"
    server.close()


def test_a_scheduler_that_does_not_answer_is_one_line_before_any_task(
        cli, tmp_path, deaf_scheduler, monkeypatch):
    from cli_helpers import assert_one_line_error

    from nirglucose.evaluation.engine import executors

    monkeypatch.setattr(executors, "SCHEDULER_TIMEOUT_S", 1.0)
    t0 = time.monotonic()
    code, _, err = cli("sweep", "--study", "noise-scale", "--seeds", "1", "--subjects", "10",
                       "--models", "ebl", "--scheduler", deaf_scheduler, "--out",
                       tmp_path / "r")
    assert time.monotonic() - t0 < 20
    line = assert_one_line_error(code, err, contains=("cannot connect to the Dask scheduler",
                                                     "no answer within 1 s"))
    assert deaf_scheduler in line and "sweep:" not in err  # refused before the progress


def test_a_live_scheduler_passes_the_check(remote):
    from nirglucose.evaluation.engine.executors import check_scheduler

    cluster, _ = remote
    check_scheduler(cluster.scheduler_address, timeout_s=5)
    check_scheduler("local")  # started by the run itself: nothing to check

# Long-running (whole studies, end-to-end runs, Monte Carlo or every model): `make test-slow`,
# which CI runs beside the fast `make test` (tests/test_slow_marks.py)
pytestmark = [pytestmark, pytest.mark.slow]
