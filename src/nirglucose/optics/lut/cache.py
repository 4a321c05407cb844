"""The table's disk cache.

Cache: ``<cache dir>/lut-<key>.npz``, where the key (:func:`~.grid.lut_key`) hashes the
geometry, the grid and the solver settings; the directory is ``$NIRGLUCOSE_CACHE``, else
``$XDG_CACHE_HOME/nirglucose``, else ``~/.cache/nirglucose``. Files are written
atomically (temporary file + rename) and read with ``allow_pickle=False``. The grid is
``$NIRGLUCOSE_LUT_GRID`` (default ``"default"``) where none is named, and the white Monte
Carlo's threads ``$NIRGLUCOSE_MC_THREADS`` (:func:`mc_threads_from_env`); all are read in
:mod:`nirglucose.optics._environment`.
"""

from __future__ import annotations

import contextlib
import json
import logging
import os
import tempfile
from functools import lru_cache
from pathlib import Path

import numpy as np

from .._environment import (
    cache_dir_from_env,
    lut_grid_from_env,
    lut_grid_named_in_env,
    mc_threads_from_env,
)
from .build import build_lut
from .grid import SkinLUT, _mc_photons, _resolve_grid, grid_name, lut_key

__all__ = ["mc_threads_from_env", "lut_grid_named_in_env", "cache_dir", "load_or_build_lut",
           "get_lut"]

_log = logging.getLogger(__name__)

#: CPU time of a Monte Carlo build of the named grids, measured on the development
#: machine (2-core AMD EPYC; ``docs/user_guide/optics.md``).
_BUILD_CPU = {"default": "2 hours", "swir": "1.5 hours"}


def cache_dir() -> Path:
    """``$NIRGLUCOSE_CACHE``, else ``$XDG_CACHE_HOME/nirglucose``, else ``~/.cache/nirglucose``."""
    return cache_dir_from_env()


def _save(lut: SkinLUT, path: Path) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=path.name, suffix=".tmp")
    try:
        with os.fdopen(fd, "wb") as fh:
            np.savez(
                fh,
                values=lut.values,
                nodes=np.concatenate(lut.nodes),
                shape=np.array(lut.shape, dtype=np.int64),
                grid=np.array(json.dumps(lut.grid, sort_keys=True)),
                geometry=np.array(json.dumps(lut.geometry, sort_keys=True)),
                key=np.array(lut.key),
                n_solves=np.array(lut.n_solves, dtype=np.int64),
                solver=np.array(lut.solver),
            )
        os.chmod(tmp, 0o644)  # mkstemp makes it private; a cache is for every reader
        os.replace(tmp, path)  # atomic on POSIX: readers see the old file or the new one
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise


def _load(path: Path, key: str) -> SkinLUT | None:
    try:
        with np.load(path, allow_pickle=False) as f:
            if str(f["key"]) != key:
                return None
            return SkinLUT(
                values=f["values"].copy(),
                nodes=tuple(np.split(f["nodes"].copy(), np.cumsum(f["shape"])[:-1])),
                shape=tuple(int(v) for v in f["shape"]),
                grid={k: tuple(v) for k, v in json.loads(str(f["grid"])).items()},
                geometry=json.loads(str(f["geometry"])),
                key=key,
                n_solves=int(f["n_solves"]),
                solver=str(f["solver"]) if "solver" in f.files else "monte-carlo",
            )
    except (OSError, ValueError, KeyError) as exc:
        _log.warning("ignoring unreadable LUT cache file %s (%s)", path, exc)
        return None


def load_or_build_lut(
    separation_cm: float,
    epidermis_thickness_cm: float,
    n_tissue: float = 1.4,
    n_ambient: float = 1.0,
    *,
    grid: str | dict = "default",
    directory: str | os.PathLike | None = None,
    solver: str = "monte-carlo",
) -> SkinLUT:
    """The table for a geometry: read from the disk cache, or built and written there.

    Parameters
    ----------
    separation_cm, epidermis_thickness_cm, n_tissue, n_ambient
        See :func:`build_lut`.
    grid : str or dict, optional
        Grid name or spec. Default "default".
    solver : {'monte-carlo', 'diffusion'}, optional
        What solves the nodes (:data:`LUT_SOLVERS`). Default "monte-carlo".
    directory : path, optional
        Cache directory; :func:`cache_dir` when omitted.

    Returns
    -------
    SkinLUT
        ``build_seconds`` is 0 when it came from the cache.
    """
    key = lut_key(separation_cm, epidermis_thickness_cm, n_tissue, n_ambient, grid,
                  solver=solver)
    path = Path(directory) if directory is not None else cache_dir()
    path = path / f"lut-{key}.npz"
    if path.exists():
        lut = _load(path, key)
        if lut is not None:
            return lut
    if solver == "monte-carlo":  # minutes to hours: say so where it shows
        spec = _resolve_grid(grid)
        runs = spec["musp_ratio"][2] * spec["skin_transport_thickness"][2]
        name = grid_name(grid) or "custom"
        cost = f" (about {_BUILD_CPU[name]} of CPU)" if name in _BUILD_CPU else ""
        _log.warning("building the rte-lut skin table %s (grid %s) by Monte Carlo: %d runs "
                     "of %d photons%s, once per probe geometry, cached in %s; "
                     "optics.lut_solver=diffusion builds one in about 40 s", key, name, runs,
                     _mc_photons(grid, None), cost, path.parent)
    else:
        _log.info("building the skin LUT %s (grid %s, solver %s)", key,
                  grid if isinstance(grid, str) else "custom", solver)
    lut = build_lut(separation_cm, epidermis_thickness_cm, n_tissue, n_ambient, grid=grid,
                    solver=solver)
    try:
        _save(lut, path)
    except OSError as exc:  # a read-only home still simulates, it just rebuilds next time
        _log.warning("could not write the LUT cache %s (%s)", path, exc)
    return lut


@lru_cache(maxsize=8)
def _get_lut(separation_cm, epidermis_thickness_cm, n_tissue, n_ambient, grid, directory,
             solver):
    return load_or_build_lut(separation_cm, epidermis_thickness_cm, n_tissue, n_ambient,
                             grid=grid, directory=directory, solver=solver)


def get_lut(
    separation_cm: float,
    epidermis_thickness_cm: float,
    n_tissue: float = 1.4,
    n_ambient: float = 1.0,
    *,
    grid: str | None = None,
    solver: str = "monte-carlo",
) -> SkinLUT:
    """:func:`load_or_build_lut`, memoised per process, for the current cache directory.

    ``grid`` defaults to ``$NIRGLUCOSE_LUT_GRID``, else ``"default"``.
    """
    grid = grid or lut_grid_from_env()
    return _get_lut(float(separation_cm), float(epidermis_thickness_cm), float(n_tissue),
                    float(n_ambient), grid, str(cache_dir()), solver)


