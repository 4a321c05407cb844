"""``export-onnx``: a fitted model as one ONNX file (``export-c`` is in :mod:`.device_commands`)."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from ._app import app
from ._common import UserError, _check_out_file, _say


@app.command("export-onnx")
def export_onnx_file(
    model: Annotated[Path, typer.Option(help="Model file from `fit` (.json).")],
    out: Annotated[Path, typer.Option(help="ONNX file to write (.onnx).")],
) -> None:
    """Write a fitted model as one ONNX file: raw device columns in, glucose and a status out.

    Models with an ONNX path: ebl, the torch networks, gp, pls, mean and ebl+gp.
    """
    from ..export.onnx_export import export_onnx

    if out.suffix != ".onnx":
        raise UserError(f"--out {str(out)!r}: the model is written as .onnx")
    _check_out_file(out)
    path = export_onnx(model, out)  # a model file's path: loaded there
    _say(f"wrote {path} (input 'raw', outputs 'glucose_mgdl' [mg/dL] and 'status')", err=False)
