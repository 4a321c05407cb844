"""The task engine of the benchmark and the sweep: resumable, checksummed task results.

A *task* is a JSON-able specification (a dict). The engine gives every task

* one **identity**: :func:`stamp` adds the task-file format, the package version and
  :func:`source_digest` (a hash of the package's code and data files) to the
  specification, and :func:`task_key` hashes its canonical JSON (sorted keys). Editing
  any part of the package (the simulator, a model, the metrics) therefore changes
  every key and invalidates every cached task, for the benchmark and the sweep alike;
  an estimator class defined outside the package adds the hash of its own file
  (:func:`external_code_digest`);
* one **result file**: ``OUT/.tasks/<model>-<tag>-<key>.json`` holding
  ``{"spec", "checksum", "result"}``, written atomically by the process that gathers
  results (:meth:`TaskCache.save`; a remote worker needs no shared file system);
* one **load rule**: :meth:`TaskCache.load` returns the stored result only when the
  file parses, its specification equals the task's, its checksum matches and the
  caller's ``valid`` check accepts it; otherwise the task is recomputed, with a
  warning and counted as corrupt when a file was there.

The engine computes nothing itself; :mod:`~nirglucose.evaluation.benchmark` and
:mod:`~nirglucose.evaluation.sweep` plan their tasks, run the pending ones and hand
each finished result to :meth:`TaskCache.collect`.
"""

from __future__ import annotations

import functools
import hashlib
import inspect
import json
import warnings
from collections.abc import Callable, Iterable, Mapping
from pathlib import Path
from typing import Any

from ..._version import __version__
from ...dataset import atomic_write
from ...exceptions import DataError

__all__ = [
    "TASK_FORMAT",
    "TaskCache",
    "canonical",
    "clear_outputs",
    "check_worker",
    "checksum",
    "derived_seed",
    "external_code_digest",
    "prepare_out",
    "sha256_hex",
    "source_digest",
    "stamp",
    "task_key",
]

#: Version of the task-file layout (part of every task's identity).
TASK_FORMAT = 3

#: File suffixes that make up the package's "source" (code and packaged data).
_SOURCE_SUFFIXES = (".py", ".csv", ".json", ".md")
#: Hex digits kept of a task key (80 bits: no collision among a run's tasks).
_KEY_DIGITS = 20
#: Hex digits kept of a source digest.
_DIGEST_DIGITS = 16


def _package_root() -> Path:
    """The ``nirglucose`` package's folder (this module is ``evaluation/engine/tasks.py``)."""
    return Path(__file__).resolve().parents[2]


@functools.lru_cache(maxsize=1)
def source_digest() -> str:
    """SHA-256 (16 hex digits) of the installed package's code and data files.

    Part of every task's specification (:func:`stamp`), so a cached task is reused
    only by the same code, even while the version number stays the same during
    development.
    """
    root = _package_root()
    h = hashlib.sha256()
    for path in sorted(root.rglob("*")):
        if path.is_file() and path.suffix in _SOURCE_SUFFIXES:
            h.update(path.relative_to(root).as_posix().encode())
            h.update(path.read_bytes())
    return h.hexdigest()[:_DIGEST_DIGITS]


def external_code_digest(cls: type) -> str | None:
    """Hash of the file defining ``cls`` when it lies outside the package, else None.

    A package class is covered by :func:`source_digest`; a user's own estimator (a
    test's, a notebook's module) is not, so its file joins the task's identity.
    """
    try:
        path = Path(inspect.getfile(cls)).resolve()
    except (TypeError, OSError):
        return None
    if path.is_relative_to(_package_root()) or not path.is_file():
        return None
    return hashlib.sha256(path.read_bytes()).hexdigest()[:_DIGEST_DIGITS]


def canonical(obj: Any) -> Any:
    """A JSON round trip of ``obj`` (tuples become lists; other objects their repr)."""
    return json.loads(json.dumps(obj, sort_keys=True, default=repr))


def stamp(spec: Mapping[str, Any]) -> dict[str, Any]:
    """The specification with the engine's identity fields (format, version, source)."""
    return {
        **spec,
        "format": TASK_FORMAT,
        "version": __version__,
        "source_sha256": source_digest(),
    }


def check_worker(spec: Mapping[str, Any], result: Mapping[str, Any], *,
                 stacklevel: int = 5) -> None:
    """Refuse a result computed by another nirglucose version (a Dask worker's); warn
    about one computed by other code under the same version (its source digest).

    ``stacklevel`` points the warning at the caller of the run: 5 from the sweep
    (check, collect, its executor, run_sweep), 4 from the wear sweep (no executor)."""
    if result.get("version") != spec["version"]:
        raise DataError(f"a worker runs nirglucose {result.get('version')}, this process "
                        f"{spec['version']}; install the same version on every worker")
    if result.get("source_sha256") != spec["source_sha256"]:
        warnings.warn(
            "a worker runs different nirglucose code than this process (source digest "
            f"{result.get('source_sha256')} vs {spec['source_sha256']}); results may mix "
            "code versions", stacklevel=stacklevel)


def sha256_hex(text: str) -> str:
    """SHA-256 of ``text`` (UTF-8) in hex."""
    return hashlib.sha256(text.encode()).hexdigest()


def task_key(spec: Mapping[str, Any]) -> str:
    """The task's key: SHA-256 of its canonical JSON (sorted keys), 20 hex digits."""
    return sha256_hex(json.dumps(spec, sort_keys=True))[:_KEY_DIGITS]


def checksum(result: Mapping[str, Any]) -> str:
    """SHA-256 of a result's canonical JSON (NaN allowed)."""
    return sha256_hex(json.dumps(result, sort_keys=True, allow_nan=True))


def derived_seed(*parts: Any) -> int:
    """A 31-bit seed from ``"|"``-joined parts (the same parts give the same seed)."""
    digest = hashlib.sha256("|".join(str(p) for p in parts).encode()).digest()
    return int.from_bytes(digest[:4], "little") & 0x7FFFFFFF


def prepare_out(out: str | Path) -> Path:
    """The output directory, created when its parent exists.

    Raises
    ------
    DataError
        The parent does not exist, or ``out`` exists and is not a directory.
    """
    out = Path(out)
    if out.exists() and not out.is_dir():
        raise DataError(f"--out {str(out)!r} exists and is not a directory")
    if not out.exists():
        if not out.parent.exists():
            raise DataError(f"output directory {str(out.parent)!r} does not exist; create it first")
        out.mkdir()
    return out


def clear_outputs(out: str | Path | None, names: Iterable[str]) -> None:
    """Remove a previous run's final files ``names`` from ``out`` before this run
    computes, so a run stopped half-way leaves nothing that looks complete (its finished
    task files stay in ``out/.tasks``: the rerun resumes from them)."""
    if out is None or not Path(out).is_dir():
        return
    for name in names:
        (Path(out) / name).unlink(missing_ok=True)


def _safe(text: str) -> str:
    return "".join(ch if ch.isalnum() or ch in "-_" else "_" for ch in text)


class TaskCache:
    """The task results of one run: in memory, and in ``OUT/.tasks`` when ``out`` is given.

    Parameters
    ----------
    out : str or Path, optional
        Output directory (created when its parent exists); None keeps nothing on disk.
    valid : callable, optional
        ``valid(spec, result) -> bool``: the caller's check of a stored result's shape.
    """

    def __init__(
        self,
        out: str | Path | None,
        valid: Callable[[Mapping[str, Any], Any], bool] | None = None,
    ):
        self.dir: Path | None = None
        if out is not None:
            self.dir = prepare_out(out) / ".tasks"
            self.dir.mkdir(exist_ok=True)
        self._valid = valid
        self.results: dict[str, dict[str, Any]] = {}
        self.n_corrupt = 0

    def path(self, key: str, spec: Mapping[str, Any], tag: str) -> Path | None:
        """``OUT/.tasks/<model>-<tag>-<key>.json`` (None without ``out``)."""
        if self.dir is None:
            return None
        return self.dir / f"{_safe(str(spec['model']))}-{tag}-{key}.json"

    def load(self, path: Path | None, spec: Mapping[str, Any]) -> dict[str, Any] | None:
        """A finished task's result; None when absent, corrupt, partial or another task's."""
        if path is None or not path.exists():
            return None
        try:
            doc = json.loads(path.read_text(encoding="utf-8"))
            result = doc["result"]
            ok = doc["spec"] == spec and doc["checksum"] == checksum(result)
            ok = ok and (self._valid is None or bool(self._valid(spec, result)))
        except (OSError, ValueError, KeyError, TypeError, IndexError):
            ok = False
        if ok:
            return result
        self.n_corrupt += 1
        warnings.warn(
            f"task file {path.name} is corrupt or partial; recomputing it", stacklevel=3
        )
        return None

    def lookup(
        self,
        specs: Mapping[str, Mapping[str, Any]],
        tag: Callable[[Mapping[str, Any]], str],
        on_cached: Callable[[Mapping[str, Any]], None] | None = None,
    ) -> list[str]:
        """Load every finished task of ``specs`` (key -> spec); return the pending keys."""
        pending = []
        for key, spec in specs.items():
            cached = self.load(self.path(key, spec, tag(spec)), spec)
            if cached is None:
                pending.append(key)
                continue
            self.results[key] = cached
            if on_cached is not None:
                on_cached(spec)
        return pending

    def save(self, path: Path | None, spec: Mapping[str, Any], result: Mapping[str, Any]) -> None:
        """Write ``{"spec", "checksum", "result"}`` atomically to ``path`` (no-op for None)."""
        if path is None:
            return
        text = json.dumps(
            {"spec": spec, "checksum": checksum(result), "result": result},
            sort_keys=True,
            allow_nan=True,
        )
        atomic_write(path, lambda tmp: Path(tmp).write_text(text, encoding="utf-8"))

    def collect(
        self,
        stream: Iterable[tuple[int, dict[str, Any]]],
        pending: list[str],
        specs: Mapping[str, Mapping[str, Any]],
        tag: Callable[[Mapping[str, Any]], str],
        on_done: Callable[[Mapping[str, Any], dict[str, Any]], None] | None = None,
        check: Callable[[Mapping[str, Any], dict[str, Any]], None] | None = None,
    ) -> None:
        """Save and keep each ``(index into pending, result)`` of ``stream`` as it comes.

        ``check(spec, result)`` runs first (it may raise: nothing is written);
        ``on_done(spec, result)`` runs after the file is written, so an interrupt
        raised there keeps the task.
        """
        for i, result in stream:
            key = pending[i]
            spec = specs[key]
            if check is not None:
                check(spec, result)
            self.save(self.path(key, spec, tag(spec)), spec, result)
            self.results[key] = result
            if on_done is not None:
                on_done(spec, result)
