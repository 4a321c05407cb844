"""Export fitted models for embedded targets (C99 source + header for linear models)."""

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

__all__ = [
    "EXPORTABLE_MODELS",
    "HEADER_NAME",
    "SOURCE_NAME",
    "PROTOTYPE",
    "prototype",
    "c_float",
    "export_c",
    "generate_c",
]
