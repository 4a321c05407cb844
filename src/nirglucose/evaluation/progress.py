"""A rich progress bar for task runners (benchmark, sweep), on standard error."""

from __future__ import annotations

__all__ = ["TaskProgress"]


class TaskProgress:
    """Tasks done / total, elapsed time and time left, with the current task's text.

    Parameters
    ----------
    label : str
        What runs (shown in bold first), e.g. ``"benchmark"``.
    total : int
        Number of tasks, those already done included.
    done : int
        Tasks already done before the run (read back from disk).
    done_word : str
        How those are described, e.g. ``"cached"`` or ``"reused"``.
    """

    def __init__(self, label: str, total: int, done: int, done_word: str) -> None:
        from rich.console import Console
        from rich.progress import (
            BarColumn,
            MofNCompleteColumn,
            Progress,
            TextColumn,
            TimeElapsedColumn,
            TimeRemainingColumn,
        )

        self.p = Progress(
            TextColumn(f"[bold]{label}[/] {{task.description}}"),
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
        self.t = self.p.add_task(f"({done} {done_word})", total=total, completed=done)

    def advance(self, text: str) -> None:
        self.p.update(self.t, advance=1, description=text)

    def close(self) -> None:
        self.p.stop()
