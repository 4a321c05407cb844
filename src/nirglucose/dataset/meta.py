"""Validation of the nirglucose metadata stored in a Parquet file's schema.

A file written by :meth:`nirglucose.dataset.Dataset.save` carries one JSON object
under the schema key ``nirglucose``: ``seed``, ``config`` (the resolved scenario) and
``nirglucose_version``, plus free provenance entries. A file edited by hand or by
another tool may carry anything there; :func:`parse_meta` turns every malformation
into one :class:`~nirglucose.exceptions.DataError` line naming the file and the entry.

Examples
--------
>>> parse_meta(b'{"seed": 3}', "x.parquet")
({'seed': 3}, None, 3)
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from pydantic import ValidationError

from ..config import ScenarioConfig, resolve_config
from ..exceptions import ConfigError, DataError

__all__ = ["parse_meta"]


def parse_meta(raw: bytes | str | None, path: str | Path) -> tuple[dict[str, Any], Any, Any]:
    """Metadata object, resolved config and seed of a file's nirglucose metadata.

    Parameters
    ----------
    raw : bytes or str or None
        The stored JSON text; None when the file has none.
    path : str or path-like
        The file (for messages).

    Returns
    -------
    tuple of (dict, ScenarioConfig or None, int or None)

    Raises
    ------
    DataError
        Not JSON, not an object, a seed that is not a non-negative integer, a
        version that is not text, or a config that is not a valid scenario (the
        first invalid entry is named, with its valid range).
    """
    where = repr(str(path))
    if raw is None:
        return {}, None, None
    try:
        meta = json.loads(raw)
    except (json.JSONDecodeError, UnicodeDecodeError):
        raise DataError(f"{where} has malformed nirglucose metadata (not JSON)") from None
    if not isinstance(meta, dict):
        raise DataError(
            f"{where} has malformed nirglucose metadata: a {type(meta).__name__}, not an object"
        )
    seed = meta.get("seed")
    if seed is not None and (isinstance(seed, bool) or not isinstance(seed, int) or seed < 0):
        raise DataError(f"{where}: metadata seed must be a non-negative integer, got {seed!r}")
    version = meta.get("nirglucose_version")
    if version is not None and not isinstance(version, str):
        raise DataError(f"{where}: metadata nirglucose_version must be text, got {version!r}")
    cfg = meta.get("config")
    if cfg is None or cfg == {}:
        return meta, None, seed
    if not isinstance(cfg, dict):
        raise DataError(
            f"{where}: metadata config must be an object, got a {type(cfg).__name__}"
        )

    try:
        config = resolve_config(ScenarioConfig.model_validate(cfg))
    except ValidationError as exc:
        err = exc.errors()[0]
        loc = ".".join(str(p) for p in err["loc"]) or "config"
        raise DataError(
            f"{where}: metadata config entry {loc!r} is invalid: {err['msg']} "
            f"(got {err.get('input')!r})"
        ) from None
    except ConfigError as exc:
        raise DataError(f"{where}: metadata config is invalid: {exc}") from None
    return meta, config, seed
