"""Where independent tasks run: this process, a local process pool, or a Dask cluster.

:func:`run_unordered` applies one picklable function to a list of items and yields
``(index, result)`` pairs as the tasks finish, in whatever order they finish. The
caller owns the results (it writes them, counts them, shows progress), so the same
loop serves every backend:

``jobs=1``
    In this process, in order (no start-up cost, easiest to debug).
``jobs=N``
    A local pool of ``N`` worker processes (joblib's loky backend; workers are reused,
    BLAS threads are limited so that ``N`` workers do not oversubscribe the cores).
``scheduler="local"``
    A Dask ``LocalCluster`` of ``jobs`` single-threaded worker processes that this
    process starts and closes. Each Dask worker process exits when the pipe its parent
    holds open closes (``distributed.process.AsyncProcess``), so none outlives this
    process, even SIGKILLed (tests/cli/test_bad_dask.py checks it).
``scheduler="tcp://host:8786"`` (or a :class:`distributed.Client`)
    An existing Dask cluster. The workers need the same ``nirglucose`` version
    installed; nothing else changes. They are not ours: an interrupted run (Ctrl-C,
    SIGTERM turned into an exception, the caller closing the stream) cancels its
    unfinished futures and leaves the workers running.

A task must be seeded from its own specification, never from the order or the place
it ran, so results are the same for every backend (the sweep's tasks are).

Examples
--------
>>> sorted(run_unordered(abs, [-1, -2, 3]))
[(0, 1), (1, 2), (2, 3)]
"""

from __future__ import annotations

import contextlib
import os
import threading
import time
from collections.abc import Callable, Iterator, Sequence
from typing import Any

from ...exceptions import ConfigError

__all__ = [
    "BACKENDS",
    "LOCAL_SCHEDULER",
    "SCHEDULER_TIMEOUT_S",
    "available_cores",
    "check_scheduler",
    "resolve_backend",
    "run_unordered",
    "watch_parent",
    "worker_guard",
]

#: Backend names :func:`resolve_backend` returns.
BACKENDS = ("serial", "processes", "dask")

#: ``scheduler`` value that starts a Dask LocalCluster of ``jobs`` worker processes.
LOCAL_SCHEDULER = "local"

#: How long a Dask scheduler address may take to accept a connection and answer one
#: ``identity`` request before the run is refused; ``distributed.Client`` waits forever
#: on a peer that accepts but never answers. [s]
SCHEDULER_TIMEOUT_S = 10.0


def check_scheduler(scheduler: Any, timeout_s: float | None = None) -> None:
    """Refuse a Dask scheduler address that does not answer, before any task starts.

    Connects to ``scheduler`` (a ``tcp://host:port`` string; ``'local'``, None and
    :class:`distributed.Client` objects pass unchecked) and sends one ``identity``
    request, the message ``distributed.Client`` opens with, all within ``timeout_s``
    (default :data:`SCHEDULER_TIMEOUT_S`). [s]

    Raises
    ------
    ConfigError
        Nothing listens there, it does not answer within ``timeout_s``, or it answers
        something other than a Dask scheduler.
    """
    if not isinstance(scheduler, str) or scheduler == LOCAL_SCHEDULER:
        return
    import asyncio

    timeout_s = SCHEDULER_TIMEOUT_S if timeout_s is None else float(timeout_s)
    try:
        from distributed.comm import connect
    except ImportError:  # pragma: no cover - distributed is a dependency
        raise ConfigError(
            "a Dask scheduler needs the 'distributed' package; pip install 'dask[distributed]'"
        ) from None

    async def identity() -> Any:
        comm = await connect(scheduler, timeout=timeout_s)
        try:
            await comm.write({"op": "identity", "reply": True})
            return await comm.read()
        finally:
            comm.abort()

    try:
        reply = asyncio.run(asyncio.wait_for(identity(), timeout_s))
    except (OSError, TimeoutError, ValueError) as exc:
        why = str(exc) or f"no answer within {timeout_s:g} s"
        raise ConfigError(f"cannot connect to the Dask scheduler at {scheduler!r}: {why}; "
                          "check the address and that the scheduler is running") from None
    if not (isinstance(reply, dict) and reply.get("type") == "Scheduler"):
        raise ConfigError(f"{scheduler!r} answered, but not as a Dask scheduler; check the "
                          "address (tcp://host:8786)")


def available_cores() -> int:
    """CPU cores this process may run on (its affinity mask, else ``os.cpu_count()``)."""
    try:
        return max(len(os.sched_getaffinity(0)), 1)
    except AttributeError:  # not Linux
        return max(os.cpu_count() or 1, 1)


def resolve_backend(jobs: int | None, scheduler: Any = None) -> tuple[str, int]:
    """Backend name and worker count for ``jobs`` / ``scheduler``.

    Parameters
    ----------
    jobs : int or None
        Local worker processes; None uses :func:`available_cores`. Ignored with a
        scheduler. [-]
    scheduler : str or distributed.Client, optional
        Dask scheduler address (``tcp://host:8786``), a connected client, or
        :data:`LOCAL_SCHEDULER` (a LocalCluster of ``jobs`` worker processes).

    Returns
    -------
    tuple of (str, int)
        One of :data:`BACKENDS` and the local worker count (0 for a remote Dask
        cluster, ``jobs`` for a LocalCluster).

    Raises
    ------
    ConfigError
        ``jobs`` not a positive integer, or a scheduler that is neither an address
        nor a client.
    """
    if scheduler == LOCAL_SCHEDULER:
        _, n = resolve_backend(jobs)
        return "dask", n
    if scheduler is not None:
        if isinstance(scheduler, str):
            if "://" not in scheduler:
                raise ConfigError(
                    f"scheduler {scheduler!r} is not an address; use e.g. tcp://host:8786 "
                    f"or {LOCAL_SCHEDULER!r} (a local Dask cluster)"
                )
        elif not hasattr(scheduler, "submit"):
            raise ConfigError(
                f"scheduler must be an address or a distributed.Client, got "
                f"{type(scheduler).__name__}"
            )
        return "dask", 0
    if jobs is None:
        jobs = available_cores()
    if isinstance(jobs, bool) or not isinstance(jobs, int) or jobs < 1:
        raise ConfigError(f"jobs must be a positive integer, got {jobs!r}")
    return ("serial", 1) if jobs == 1 else ("processes", int(jobs))


#: How often a worker checks that its parent still runs. [s]
PARENT_POLL_S = 0.2

_watching: list[int] = []


def _watch_loop(parent_pid: int, poll_s: float) -> None:  # pragma: no cover - in a worker
    while True:
        time.sleep(poll_s)
        if os.getppid() != parent_pid:  # re-parented: the parent died (even by SIGKILL)
            os._exit(1)


def watch_parent(parent_pid: int, poll_s: float = PARENT_POLL_S) -> None:
    """Make this (worker) process exit as soon as ``parent_pid`` is no longer its parent.

    A pool initializer: a daemon thread polls :func:`os.getppid`, which changes when
    the parent dies, however it died (SIGKILL included), so no worker outlives the
    run that started it. Calling it again in the same process does nothing.

    Parameters
    ----------
    parent_pid : int
        Process id of the parent, taken in the parent (``os.getpid()``).
    poll_s : float
        Polling interval. [s]
    """
    if _watching or os.getpid() == parent_pid:
        return
    _watching.append(parent_pid)
    if os.getppid() != parent_pid:
        os._exit(1)
    threading.Thread(
        target=_watch_loop, args=(parent_pid, poll_s), name="nirglucose-parent-watch",
        daemon=True,
    ).start()


@contextlib.contextmanager
def worker_guard() -> Iterator[None]:
    """Within it, every joblib/loky worker started exits when this process dies.

    Sets joblib's default backend to loky with :func:`watch_parent` as the worker
    initializer for the duration of the ``with`` block only (joblib's own
    ``parallel_config`` context); the command line runs the commands that start workers
    inside it (and only those), and :func:`run_unordered` runs its pools inside it. Loky
    itself kills the workers when a run is interrupted (an exception or a signal turned
    into one).
    """
    from joblib import parallel_config

    with parallel_config(backend="loky", initializer=watch_parent, initargs=(os.getpid(),)):
        yield


def _indexed(fn: Callable[[Any], Any], i: int, item: Any) -> tuple[int, Any]:
    return i, fn(item)


def run_unordered(
    fn: Callable[[Any], Any],
    items: Sequence[Any],
    *,
    jobs: int | None = 1,
    scheduler: Any = None,
    keys: Sequence[str] | None = None,
) -> Iterator[tuple[int, Any]]:
    """Yield ``(index, fn(items[index]))`` for every item, as each task finishes.

    Parameters
    ----------
    fn : callable
        A module-level (picklable) function of one item.
    items : sequence
        Task inputs (picklable).
    jobs : int or None
        Local worker processes (see :func:`resolve_backend`).
    scheduler : str or distributed.Client, optional
        Run on this Dask cluster instead of locally.
    keys : sequence of str, optional
        Dask task keys (one per item, unique); default ones otherwise.

    Yields
    ------
    tuple of (int, object)
        The item's index and its result.

    Raises
    ------
    ConfigError
        Bad ``jobs`` / ``scheduler``, or no Dask scheduler at the address.

    Notes
    -----
    Closing the generator early (an interrupt, an exception in the caller) cancels the
    tasks not yet finished: a local pool is shut down, Dask futures are cancelled.
    An exception raised by a task is re-raised here.
    """
    backend, n = resolve_backend(jobs, scheduler)
    items = list(items)
    if not items:
        return
    if backend == "dask":
        yield from _run_dask(fn, items, scheduler, keys, n)
    elif backend == "serial" or len(items) == 1:
        for i, item in enumerate(items):
            yield i, fn(item)
    else:
        from joblib import Parallel, delayed

        with worker_guard():
            parallel = Parallel(n_jobs=min(n, len(items)), return_as="generator_unordered")
            yield from parallel(delayed(_indexed)(fn, i, item) for i, item in enumerate(items))


def _run_dask(
    fn: Callable[[Any], Any],
    items: list[Any],
    scheduler: Any,
    keys: Sequence[str] | None,
    jobs: int | None = None,
) -> Iterator[tuple[int, Any]]:
    try:
        from distributed import Client, as_completed
    except ImportError:  # pragma: no cover - distributed is a dependency
        raise ConfigError(
            "a Dask scheduler needs the 'distributed' package; pip install 'dask[distributed]'"
        ) from None
    own = isinstance(scheduler, str)
    cluster = None
    if scheduler == LOCAL_SCHEDULER:
        cluster, client = _local_client(jobs or available_cores())
    elif own:
        check_scheduler(scheduler)
        try:
            client = Client(scheduler, timeout="10s", set_as_default=False)
        except (OSError, TimeoutError) as exc:
            raise ConfigError(
                f"cannot connect to the Dask scheduler at {scheduler!r}: {exc}"
            ) from None
    else:
        client = scheduler
    futures = []
    try:
        if keys is None:
            futures = client.map(fn, items, pure=False)
        else:
            futures = client.map(fn, items, key=list(keys))
        index = {f.key: i for i, f in enumerate(futures)}
        for fut in as_completed(futures, loop=client.loop):
            result = fut.result()
            yield index[fut.key], result
            fut.release()
    finally:
        pending = [f for f in futures if not f.done()]
        if pending:
            client.cancel(pending)
        if own:
            client.close()
        if cluster is not None:
            cluster.close()


def _local_client(n_workers: int) -> tuple[Any, Any]:
    """A LocalCluster of ``n_workers`` single-threaded worker processes and its client.

    The nannies and the scheduler run in this process; each worker process watches a
    pipe from it and exits when it closes (this process died, SIGKILL included), so
    no worker is left behind (no extra watch needed). The dashboard is off.
    """
    import logging

    from distributed import Client, LocalCluster

    cluster = LocalCluster(
        n_workers=n_workers, threads_per_worker=1, processes=True, dashboard_address=None,
        silence_logs=logging.ERROR,
    )
    try:
        client = Client(cluster, set_as_default=False)
    except BaseException:
        cluster.close()
        raise
    return cluster, client
