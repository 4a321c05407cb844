"""The ``nirglucose`` console script's first step: Ctrl-C and SIGTERM are one line from
the first instant.

Importing :mod:`nirglucose` loads numpy, pandas, scipy and torch (about 1.5 s), and
Python imports a package before any of its modules, so :func:`nirglucose.cli.main`,
which maps a signal to one line and exit 130 / 143, starts only after that. This module
lies outside the package: it installs the same mapping before the import, then hands
over (``nirglucose.cli.main`` installs its own handlers and restores these on return).
"""

from __future__ import annotations

import signal
import sys


def _stop_while_starting(signum: int, frame: object) -> None:
    name = "terminated (SIGTERM)" if signum == signal.SIGTERM else "interrupted"
    sys.stderr.write(f"error: {name} while starting; nothing was run\n")
    raise SystemExit(128 + signum)


def main() -> int:
    """Entry point of the ``nirglucose`` console script (:func:`nirglucose.cli.main`)."""
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, _stop_while_starting)
    from nirglucose.cli import main as run

    return run()


if __name__ == "__main__":
    sys.exit(main())
