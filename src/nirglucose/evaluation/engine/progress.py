"""Progress of task runners (benchmark, sweep) on standard error.

On a terminal: a rich progress bar. Otherwise (a log file, CI, ``make``): one plain
line per finished task, throttled so that a long run writes at most about
:data:`MAX_LINES` lines, so a log still shows how far a run got and how fast.
"""

from __future__ import annotations

import sys
import time
from collections.abc import Callable, Iterator, Mapping
from contextlib import contextmanager
from typing import Any

__all__ = ["MAX_LINES", "TaskProgress", "task_hooks"]

#: Most progress lines a run writes when standard error is not a terminal (besides
#: its first and last). [-]
MAX_LINES = 50


def _clock(seconds: float) -> str:
    seconds = int(round(seconds))
    return f"{seconds // 3600}:{seconds // 60 % 60:02d}:{seconds % 60:02d}"


class TaskProgress:
    """Tasks done / total, elapsed time and time left, with the current task's text.

    Parameters
    ----------
    label : str
        What runs (shown first), e.g. ``"benchmark"``.
    total : int
        Number of tasks, those already done included.
    done : int
        Tasks already done before the run (read back from disk).
    done_word : str
        How those are described, e.g. ``"cached"`` or ``"reused"``.
    stream : file-like, optional
        Where lines go when it is not a terminal (default ``sys.stderr``).
    """

    def __init__(
        self, label: str, total: int, done: int, done_word: str, stream=None
    ) -> None:
        self.label, self.total, self.done = label, int(total), int(done)
        self.start_done = self.done
        self.stream = sys.stderr if stream is None else stream
        self.t0 = time.perf_counter()
        isatty = getattr(self.stream, "isatty", None)
        self.p = None
        if stream is None and isatty is not None and isatty():
            self._start_bar(label, done_word)
        else:
            todo = max(self.total - self.done, 1)
            self.every = max(1, -(-todo // MAX_LINES))
            self._line(f"{self.done}/{self.total} tasks ({self.done} {done_word}); starting")

    def _start_bar(self, label: str, done_word: str) -> None:
        from rich.console import Console
        from rich.markup import escape
        from rich.progress import (
            BarColumn,
            MofNCompleteColumn,
            Progress,
            TextColumn,
            TimeElapsedColumn,
            TimeRemainingColumn,
        )

        self.p = Progress(
            TextColumn(f"[bold]{escape(label)}[/] {{task.description}}"),
            BarColumn(),
            MofNCompleteColumn(),
            TextColumn("tasks"),
            TimeElapsedColumn(),
            TextColumn("left"),
            TimeRemainingColumn(),
            console=Console(stderr=True),
            transient=False,
        )
        self.p.start()
        self.t = self.p.add_task(escape(f"({self.done} {done_word})"), total=self.total,
                                 completed=self.done)

    def _line(self, text: str) -> None:
        print(f"{self.label}: {text}", file=self.stream, flush=True)

    def advance(self, text: str) -> None:
        """Count one finished task, described by ``text``."""
        self.done += 1
        if self.p is not None:
            from rich.markup import escape

            self.p.update(self.t, advance=1, description=escape(text))
            return
        new = self.done - self.start_done
        if new % self.every and self.done != self.total:
            return
        elapsed = time.perf_counter() - self.t0
        left = elapsed / new * (self.total - self.done)
        self._line(f"{self.done}/{self.total} tasks ({text}); {_clock(elapsed)} elapsed, "
                   f"{_clock(left)} left")

    def close(self) -> None:
        """Stop the bar (a terminal) or write the final line (otherwise)."""
        if self.p is not None:
            self.p.stop()
        else:
            word = "done" if self.done >= self.total else "stopped"
            self._line(f"{self.done}/{self.total} tasks; {word} after "
                       f"{_clock(time.perf_counter() - self.t0)}")


@contextmanager
def task_hooks(
    label: str,
    total: int,
    done: int,
    done_word: str,
    *,
    show: bool,
    describe: Callable[[Mapping[str, Any]], str],
    on_task: Callable[[Mapping[str, Any], bool], None] | None,
) -> Iterator[Callable[[Mapping[str, Any], Any], None]]:
    """The ``on_done(spec, result)`` hook of a task runner: ``on_task`` and the progress.

    Parameters
    ----------
    label, total, done, done_word
        As :class:`TaskProgress`.
    show : bool
        Show a :class:`TaskProgress` (closed on leaving the block).
    describe : callable
        ``describe(spec)``: the finished task's text in the progress.
    on_task : callable, optional
        Called as ``on_task(spec, False)`` for every finished task.
    """
    bar = TaskProgress(label, total, done, done_word) if show else None

    def finished(spec: Mapping[str, Any], _result: Any) -> None:
        if on_task is not None:
            on_task(spec, False)
        if bar is not None:
            bar.advance(describe(spec))

    try:
        yield finished
    finally:
        if bar is not None:
            bar.close()
