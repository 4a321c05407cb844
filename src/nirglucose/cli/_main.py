"""The console-script entry point: runs the app and maps every error to one line.

Exit status 2 and one ``error:`` line for anything the user can cause, 130 after
Ctrl-C and 143 after SIGTERM (each with one line); no traceback.
"""

from __future__ import annotations

import signal

import typer
from typer.exceptions import TyperException

from ..exceptions import NirGlucoseError
from ._app import app
from ._common import _say


class _Signals:
    """Turns SIGINT / SIGTERM into KeyboardInterrupt once, remembering which came."""

    def __init__(self) -> None:
        self.received: int | None = None
        self.saved: dict[int, object] = {}

    def _handler(self, signum, frame) -> None:
        if self.received is not None:  # a second signal while stopping: keep stopping
            return
        self.received = signum
        raise KeyboardInterrupt

    def __enter__(self) -> _Signals:
        import threading

        if threading.current_thread() is threading.main_thread():
            for sig in (signal.SIGINT, signal.SIGTERM):
                self.saved[sig] = signal.signal(sig, self._handler)
        return self

    def __exit__(self, *exc) -> None:
        for sig, old in self.saved.items():
            signal.signal(sig, old)


def _interrupted(signals: _Signals) -> int:
    if signals.received == signal.SIGTERM:
        _say("error: terminated (SIGTERM); finished results were kept, rerun to resume")
        return 128 + signal.SIGTERM
    _say("error: interrupted; finished results were kept, rerun to resume")
    return 130


def _user_path(name: object) -> str:
    """The file the user named, for an atomic write's temporary ``DIR/.NAME.xxxx.tmp``."""
    import re

    m = re.fullmatch(r"(.*/)?\.(.+)\.[A-Za-z0-9_]+\.tmp", str(name))
    return f"{m.group(1) or ''}{m.group(2)}" if m else str(name)


def _one_line(text: object) -> str:
    return " ".join(str(text).split())


def _typer_error(exc: TyperException) -> int:
    """A usage error: one line naming the help (none when help was shown already)."""
    fmt = getattr(exc, "format_message", None)
    msg = _one_line(fmt() if fmt else exc)
    if msg:  # empty: help was shown for a bare command
        _say(f"error: {msg} (see `nirglucose --help`)")
    return 2


def _os_error(exc: OSError) -> int:
    """A file the user named cannot be read or written."""
    where = f" {_user_path(exc.filename)!r}" if exc.filename else ""
    _say(f"error: cannot access{where}: {exc.strerror or _one_line(exc)}")
    return 2


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``nirglucose`` console script.

    Returns
    -------
    int
        0 on success, 2 for any user error (one line on stderr), 130 after Ctrl-C,
        143 after SIGTERM.
    """
    import numpy as np

    with _Signals() as signals:
        try:
            # numpy's overflow chatter would add lines; a result that overflowed is
            # refused by the library (non-finite ADC input, model checks) in one line
            with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
                rv = app(args=argv, standalone_mode=False)
        except typer.Exit as exc:
            return int(getattr(exc, "exit_code", 0) or 0)
        except typer.Abort:
            return _interrupted(signals)
        except TyperException as exc:
            return _typer_error(exc)
        except NirGlucoseError as exc:
            _say(f"error: {_one_line(exc)}")
            return 2
        except KeyboardInterrupt:
            return _interrupted(signals)
        except MemoryError:
            _say("error: out of memory; use fewer subjects, measurements or jobs")
            return 2
        except OSError as exc:
            return _os_error(exc)
    code = rv if isinstance(rv, int) and not isinstance(rv, bool) else 0
    if code == 130:  # typer turns KeyboardInterrupt into exit 130 and returns it
        return _interrupted(signals)
    return code
