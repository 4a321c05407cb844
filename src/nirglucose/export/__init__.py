"""Export fitted models: C99 source + header for a microcontroller (linear models) and one
ONNX graph for any other runtime (:mod:`.onnx_export`)."""

from __future__ import annotations

from .c_codegen import (
    EXPORTABLE_MODELS,
    HEADER_NAME,
    PROTOTYPE,
    SOURCE_NAME,
    c_float,
    export_c,
    generate_c,
    prototype,
)
from .onnx_export import NO_ONNX_PATH, ONNX_MODELS, export_onnx, onnx_graph_bytes

__all__ = [
    "EXPORTABLE_MODELS",
    "HEADER_NAME",
    "SOURCE_NAME",
    "PROTOTYPE",
    "prototype",
    "c_float",
    "export_c",
    "generate_c",
    "ONNX_MODELS",
    "NO_ONNX_PATH",
    "export_onnx",
    "onnx_graph_bytes",
]
