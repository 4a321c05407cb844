"""The Typer application and the two consoles every command prints to."""

from __future__ import annotations

from typing import Annotated

import typer
from rich.console import Console

__all__ = ["app", "console", "out_console"]

app = typer.Typer(
    name="nirglucose",
    help="Simulate a noise-stressed NIR glucose sensor and benchmark estimators on it.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
)
#: Errors, warnings and progress.
console = Console(stderr=True)
#: Results: tables and the final "wrote ..." line.
out_console = Console()


def _version_callback(value: bool) -> None:
    if value:
        from .. import __version__

        out_console.print(f"nirglucose {__version__}", markup=False, highlight=False)
        raise typer.Exit(0)


@app.callback()
def _root(
    version: Annotated[
        bool,
        typer.Option(
            "--version", help="Print the version and exit.", callback=_version_callback,
            is_eager=True,
        ),
    ] = False,
) -> None:
    """Simulate a noise-stressed NIR glucose sensor and benchmark estimators on it."""
