"""Fixtures of the CLI bad-input tests (helpers in cli_helpers.py)."""

from cli_helpers import cli, workdir  # noqa: F401
