"""Command-line interface: parses into a config, calls the library, maps errors to exit 2.

Every error a user can cause (bad option, unknown preset or key, malformed data file,
an output path that cannot be written) ends the program with exit status 2 and one
line on stderr saying what is wrong and how to fix it; no traceback. Ctrl-C ends it
with status 130 and SIGTERM with 143, each with one line; worker processes never
outlive the command (the commands that start them run inside
:func:`nirglucose.evaluation.engine.executors.worker_guard`). Text
that came from the user or a file is printed without Rich markup.

One module per command group, registered on :data:`app` in the order ``--help``
lists them: :mod:`.data_commands` (simulate, keys, models), :mod:`.benchmark_command`,
:mod:`.wear_command` (wear-benchmark),
:mod:`.sweep_command`, :mod:`.device_commands` (fit, predict, export-c), :mod:`.export_commands`
(export-onnx) and
:mod:`.report_command`; the shared options and checks live in :mod:`._common`, the
entry point and its error mapping in :mod:`._main`.
"""

from __future__ import annotations

from ._app import app, console, out_console
from ._common import _PRESET_NAMES, _STUDY_NAMES, DEFAULT_RESAMPLES, UserError
from ._main import main

# isort: off
# importing a command module registers its commands: this order is the order of --help
from .data_commands import keys, list_models, list_parts, simulate
from .benchmark_command import benchmark
from .wear_command import wear_benchmark
from .sweep_command import sweep
from .device_commands import export_c_source, fit_model, predict_glucose
from .export_commands import export_onnx_file
from .report_command import report
from .twin_command import twin

# isort: on

__all__ = ["app", "main"]

__all__ += [  # also importable, as before the split into a package
    "DEFAULT_RESAMPLES",
    "UserError",
    "benchmark",
    "console",
    "export_c_source",
    "export_onnx_file",
    "fit_model",
    "keys",
    "list_models",
    "list_parts",
    "out_console",
    "predict_glucose",
    "report",
    "simulate",
    "sweep",
    "twin",
    "wear_benchmark",
    "_PRESET_NAMES",
    "_STUDY_NAMES",
]
