"""The resumable work directory of the long optics benchmarks (``--work``)."""

from __future__ import annotations

import argparse
from pathlib import Path


def work_dir(ap: argparse.ArgumentParser, given: str | None, default: Path) -> Path:
    """``given`` (or ``default``), created; one argparse error line (exit 2) if it cannot be."""
    work = Path(given) if given else default
    try:
        work.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        ap.error(f"--work {str(work)!r} cannot be a directory here ({exc.strerror}); "
                 f"give a writable directory")
    return work
