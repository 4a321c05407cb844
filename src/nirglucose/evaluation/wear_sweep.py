"""``sweep --study wear``: calibration schedule × days of wear × preset.

Each task simulates one worn run (:func:`nirglucose.simulate_wear`: a preset, a number
of days, a seed) and runs the worn benchmark on it
(:func:`~.wear_benchmark.run_wear_benchmark`), which scores every calibration schedule
on the same held-out readings. Tasks are cached in ``OUT/.tasks`` like every other
task (:class:`~.tasks.TaskCache`: the spec, the package's source digest and a checksum),
so an interrupted sweep resumes. The pending tasks run where the other sweeps' run
(:func:`~.executors.run_unordered`): in this process (``jobs=1``, the default), on a
pool of local processes (``jobs=N``) or on a Dask cluster (``scheduler``); each task
simulates its subjects in one process (``n_jobs=1``), seeded from its own specification,
so every backend gives the same rows. A task's memory is that of one worn run
(``n_subjects`` x days x 96 readings at 15 min, 672 rows a subject-week), and
its result, a few dozen table rows, travels back to this process, which alone writes
the cache.

Outputs: ``wear_sweep.csv`` (one row per preset, days, seed, model, variant and
schedule) and ``wear_summary.csv`` (mean RMSE over seeds with its Student-t 95 %
interval where there are two seeds or more, else the task's subject-bootstrap one).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from functools import partial
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
from scipy import stats

from .._version import __version__
from ..api import simulate_wear
from ..calibration.schedules import SCHEDULES
from ..config import resolve_config
from ..dataset import atomic_write
from ..exceptions import ConfigError
from . import tasks
from .executors import check_scheduler, resolve_backend, run_unordered
from .wear_benchmark import WEAR_MODELS, run_wear_benchmark

__all__ = ["WEAR_DAYS", "WEAR_PRESETS", "WEAR_SWEEP_FILES", "run_wear_sweep", "run_wear_task"]

#: Output files: every row, then the summary over seeds.
WEAR_SWEEP_FILES = ("wear_sweep.csv", "wear_summary.csv")

#: Default grid of the study: days of wear and presets.
WEAR_DAYS: tuple[int, ...] = (1, 3, 7)
WEAR_PRESETS: tuple[str, ...] = ("paper", "wearable")


def run_wear_task(spec: dict) -> dict:
    """One task of the study: simulate the worn run of ``spec`` and score its schedules.

    Module-level and seeded only from ``spec`` (a Dask or process-pool worker runs it).
    Returns ``{"rows": {column: values}, "version": ...}``: the schedule table's columns
    and the package version that computed them.
    """
    ds = simulate_wear(spec["preset"], spec["n_subjects"], spec["wear_days"],
                       spec["every_min"], spec["seed"])
    res = run_wear_benchmark(ds, spec["models"], preset=spec["preset"],
                             n_splits=spec["folds"], seed=spec["seed"],
                             schedules=spec["schedules"], n_boot=spec["n_boot"])
    cols = ["model", "variant", "schedule", "rmse_mgdl", "rmse_ci_low", "rmse_ci_high",
            "mard_pct", "fingersticks_per_day", "n_scored", "n_subjects"]
    return {"rows": res.schedules[cols].to_dict(orient="list"), "version": __version__,
            "source_sha256": tasks.source_digest()}


def run_wear_sweep(
    out: str | Path,
    *,
    presets: Sequence[str] = WEAR_PRESETS,
    wear_days: Sequence[int] = WEAR_DAYS,
    seeds: Sequence[int] = (0,),
    models: Sequence[str] = WEAR_MODELS,
    schedules: Sequence[str] = tuple(SCHEDULES),
    n_subjects: int = 20,
    every_min: int = 15,
    folds: int = 5,
    n_boot: int = 1000,
    on_task: Callable[[dict, bool], None] | None = None,
    jobs: int | None = 1,
    scheduler: Any = None,
) -> pd.DataFrame:
    """Run (or resume) the wear study; returns the summary (module docstring).

    Parameters
    ----------
    out : str or Path
        Output directory (created when its parent exists).
    presets, wear_days, seeds : sequences
        The grid: presets × days of wear × seeds.
    models, schedules : sequences of str
        Registered models and calibration schedules of every task.
    n_subjects, every_min, folds, n_boot : int
        Subjects per worn run, minutes between readings, subject-grouped folds and
        bootstrap resamples.
    on_task : callable, optional
        ``on_task(spec, cached)`` after each task (cached ones first, then the others
        as they finish).
    jobs : int or None
        Local worker processes for the pending tasks (1: this process; None: every
        core), as in :func:`~.sweep.run_sweep`.
    scheduler : str or distributed.Client, optional
        Dask scheduler address (``tcp://host:8786``), ``"local"`` (a Dask cluster of
        ``jobs`` processes) or a client: run the pending tasks there.

    Raises
    ------
    ConfigError
        Unknown preset or schedule, bad days, bad ``jobs`` / ``scheduler`` or a
        scheduler that does not answer (before any task runs).
    """
    for p in presets:
        resolve_config(p)  # unknown presets fail before anything runs
    bad = [d for d in wear_days if int(d) != d or d < 1]
    if not wear_days or bad:
        raise ConfigError(f"wear_days {list(wear_days)!r} is invalid; expected whole days >= 1")
    unknown = [s for s in schedules if s not in SCHEDULES]
    if unknown:
        raise ConfigError(f"unknown calibration schedule(s) {unknown}; known: {list(SCHEDULES)}")
    resolve_backend(jobs, scheduler)  # bad jobs / scheduler: one line, before anything runs
    check_scheduler(scheduler)
    specs = _plan(presets, wear_days, seeds, {
        "n_subjects": int(n_subjects), "every_min": int(every_min), "folds": int(folds),
        "models": list(models), "schedules": list(schedules), "n_boot": int(n_boot)})
    cache = tasks.TaskCache(out, valid=lambda spec, res: "rows" in res)
    tasks.clear_outputs(out, WEAR_SWEEP_FILES)
    pending = cache.lookup(specs, _tag, on_cached=(
        None if on_task is None else lambda spec: on_task(dict(spec), True)))
    stream = run_unordered(run_wear_task, [specs[k] for k in pending], jobs=jobs,
                           scheduler=scheduler,
                           keys=[f"nirglucose-wear-{k}" for k in pending])
    try:
        # no executor between collect and this function: the warning's caller is one up
        check = partial(tasks.check_worker, stacklevel=4)
        cache.collect(stream, pending, specs, _tag, check=check, on_done=(
            None if on_task is None else lambda spec, _res: on_task(dict(spec), False)))
    finally:
        stream.close()
    frames = [pd.DataFrame(cache.results[key]["rows"]).assign(
        preset=spec["preset"], wear_days=spec["wear_days"], seed=spec["seed"])
        for key, spec in specs.items()]
    sweep = pd.concat(frames, ignore_index=True)
    summary = _summary(sweep)
    out = Path(out)
    for name, table in zip(WEAR_SWEEP_FILES, (sweep, summary), strict=True):
        atomic_write(out / name, lambda tmp, t=table: t.to_csv(tmp, index=False))
    return summary


def _plan(presets, wear_days, seeds, common: dict) -> dict[str, dict]:
    """The grid's task specifications, stamped (:func:`.tasks.stamp`), by task key."""
    specs = {}
    for preset in presets:
        for days in wear_days:
            for seed in seeds:
                spec = tasks.stamp({"model": "wear", "preset": preset,
                                    "wear_days": int(days), "seed": int(seed), **common})
                specs[tasks.task_key(spec)] = spec
    return specs


def _tag(spec) -> str:
    """A task file's readable part: ``<preset>-<days>d-s<seed>``."""
    return f"{spec['preset']}-{spec['wear_days']}d-s{spec['seed']}"


def _summary(sweep: pd.DataFrame) -> pd.DataFrame:
    rows = []
    keys = ["preset", "wear_days", "model", "variant", "schedule"]
    for k, g in sweep.groupby(keys, sort=False):
        v = g["rmse_mgdl"].to_numpy(float)
        if v.size > 1:  # over seeds
            half = stats.t.ppf(0.975, v.size - 1) * v.std(ddof=1) / np.sqrt(v.size)
            low, high = v.mean() - half, v.mean() + half
        else:  # one seed: the task's own subject bootstrap
            low, high = g["rmse_ci_low"].iloc[0], g["rmse_ci_high"].iloc[0]
        rows.append({**dict(zip(keys, k, strict=True)), "rmse_mgdl": float(v.mean()),
                     "rmse_ci_low": float(low), "rmse_ci_high": float(high),
                     "n_seeds": int(v.size)})
    return pd.DataFrame(rows)
