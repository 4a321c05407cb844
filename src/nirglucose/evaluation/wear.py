"""The benchmark of a worn device: every model on the series, smoothed, calibrated in time.

One engine for a worn run (data from :func:`nirglucose.simulate` with ``wear_days``, or a
user's own series with a time column):

1. **Subject-grouped K-fold** (one repeat;
   :func:`~nirglucose.evaluation.splits.grouped_kfold`): each model is fitted on the
   training subjects and predicts every reading of the held-out ones.
   A worn run has thousands of readings per subject, which say little more about a
   person than a few dozen do and would cost the slower models minutes; each training
   subject therefore contributes ``train_readings_per_subject`` readings evenly spread
   over the wear (all of them when it has fewer). Test readings are never thinned.
2. **The causal smoother** (:class:`~nirglucose.models.smoothing.CausalKalmanSmoother`)
   is tuned per fold with the budget of every family (its 12 configurations), on
   training subjects only: the model is fitted on four fifths of them and predicts the
   other fifth's full series, on which the smoother's grid is scored; the tuned
   smoother then filters the held-out predictions. ``smoothed`` rows show what it buys.
3. **Calibration schedules** (:mod:`~nirglucose.calibration.schedules`) on the held-out predictions,
   raw and smoothed, paired on the same readings.
4. **The standards a worn monitor is judged by** (:mod:`nirglucose.metrics.cgm`,
   :mod:`~nirglucose.metrics.trend`, :mod:`~nirglucose.metrics.time_in_range`, the DTS
   grid) for every model, variant and schedule, on the readings the schedules are
   scored on: ``wear_standards.csv`` (one row each) and ``wear_icgm.csv`` (every iCGM
   criterion with its clustered lower bound).

``sweep --study wear`` (:func:`run_wear_sweep`): calibration schedule × days of wear ×
preset. Each task simulates one worn run (:func:`nirglucose.simulate_wear`: a preset, a
number of days, a seed) and runs the worn benchmark on it (:func:`run_wear_benchmark`),
which scores every calibration schedule on the same held-out readings. Tasks are cached
in ``OUT/.tasks`` like every other task
(:class:`~nirglucose.evaluation.engine.tasks.TaskCache`: the spec, the package's source
digest and a checksum), so an interrupted sweep resumes. The pending tasks run where the
other sweeps' run (:func:`~nirglucose.evaluation.engine.executors.run_unordered`): in
this process (``jobs=1``, the default), on a pool of local processes (``jobs=N``) or on
a Dask cluster (``scheduler``); each task simulates its subjects in one process
(``n_jobs=1``), seeded from its own specification, so every backend gives the same rows.
A task's memory is that of one worn run (``n_subjects`` x days x 96 readings at 15 min,
672 rows a subject-week), and its result, a few dozen table rows, travels back to this
process, which alone writes the cache.

Outputs of the sweep: ``wear_sweep.csv`` (one row per preset, days, seed, model, variant
and schedule) and ``wear_summary.csv`` (mean RMSE over seeds with its Student-t 95 %
interval where there are two seeds or more, else the task's subject-bootstrap one).
"""

from __future__ import annotations

import json
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from functools import partial
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
from scipy import stats

from .._version import __version__
from ..api import simulate_wear
from ..calibration.schedules import SCHEDULES, apply_schedule, schedule_table
from ..config import resolve_config
from ..dataset import Dataset, atomic_write
from ..exceptions import ConfigError, DataError
from ..metrics import (
    dts_zones,
    estimated_lag,
    icgm_criteria,
    mard_by_range,
    time_in_range_agreement,
    trend_agreement,
    zone_percentages,
)
from ..models import make_model
from ..models.registry import get_model_class
from ..models.smoothing import tune_smoother
from ..models.tuning import preset_params
from .engine import tasks
from .engine.executors import check_scheduler, resolve_backend, run_unordered
from .splits import grouped_kfold

__all__ = ["WEAR_MODELS", "WearResult", "run_wear_benchmark", "WEAR_DAYS", "WEAR_PRESETS",
           "WEAR_SWEEP_FILES", "run_wear_sweep", "run_wear_task"]

#: Models a worn benchmark runs by default: the physics baseline, the linear and
#: off-the-shelf references, no skill and the oracle bound.
WEAR_MODELS = ("ebl", "pls", "gp", "mean", "oracle")
#: Output files of :meth:`WearResult.save`.
WEAR_FILES = ("wear_predictions.csv", "wear_schedules.csv", "wear_by_day.csv",
              "wear_smoothers.csv", "wear_standards.csv", "wear_icgm.csv", "wear_meta.json")


@dataclass
class WearResult:
    """Held-out predictions and tables of a worn benchmark (files: :data:`WEAR_FILES`)."""

    predictions: pd.DataFrame
    schedules: pd.DataFrame
    by_day: pd.DataFrame
    smoothers: pd.DataFrame
    standards: pd.DataFrame
    icgm: pd.DataFrame
    meta: dict[str, Any] = field(default_factory=dict)

    def save(self, out: str | Path) -> Path:
        """Write every table atomically into the existing directory ``out``."""
        out = Path(out)
        for name, frame in (("wear_predictions.csv", self.predictions),
                            ("wear_schedules.csv", self.schedules),
                            ("wear_by_day.csv", self.by_day),
                            ("wear_smoothers.csv", self.smoothers),
                            ("wear_standards.csv", self.standards),
                            ("wear_icgm.csv", self.icgm)):
            atomic_write(out / name, lambda tmp, f=frame: f.to_csv(tmp, index=False))
        atomic_write(out / "wear_meta.json",
                     lambda tmp: Path(tmp).write_text(json.dumps(self.meta, indent=2,
                                                                 sort_keys=True)))
        return out


def _thin(frame: pd.DataFrame, rows: np.ndarray, per_subject: int, time: str) -> np.ndarray:
    """Row positions of ``rows``: at most ``per_subject`` per subject, evenly over time."""
    sub = frame.iloc[rows]
    keep = []
    for _, g in sub.groupby("subject_id", sort=True):
        pos = frame.index.get_indexer(g.sort_values(time, kind="stable").index)
        if pos.size > per_subject:
            pos = pos[np.linspace(0, pos.size - 1, per_subject).round().astype(int)]
        keep.append(pos)
    return np.sort(np.concatenate(keep))


#: Calibrated predictions below this are scored as this value: the CGM metrics take
#: positive readings (MARD's and the grids' ratios), and an offset can push a low
#: prediction to or below 0. Not a clinical limit. [mg/dL]
_FLOOR_MGDL = 1.0


def _standards(g: pd.DataFrame, schedule: str, a: pd.DataFrame, time: str, n_boot: int,
               seed: int) -> tuple[dict, pd.DataFrame]:
    """One model, variant and schedule: a row of ``wear_standards.csv`` and its iCGM table.

    ``a`` is :func:`~nirglucose.calibration.schedules.apply_schedule` of ``schedule`` on
    ``g``. Accuracy is scored on every held-out reading after the subject's first that is
    not one of this schedule's fingersticks; trend agreement and lag on the whole series.
    """
    first = g.groupby("subject_id")[time].transform("min")
    keep = ((g[time] > first) & ~a["is_calibration"]).to_numpy()
    ref = g["glucose_mgdl"].to_numpy(float)[keep]
    est = np.clip(a["calibrated_mgdl"].to_numpy(float)[keep], _FLOOR_MGDL, None)
    sid = g["subject_id"].to_numpy()[keep]
    # the series' shape (trend, lag) on every reading, fingersticks included: the
    # estimators need uniform sampling
    all_ref, all_sid, all_t = (g["glucose_mgdl"].to_numpy(float), g["subject_id"].to_numpy(),
                               g[time].to_numpy(float))
    all_est = np.clip(a["calibrated_mgdl"].to_numpy(float), _FLOOR_MGDL, None)
    icgm = icgm_criteria(ref, est, sid, n_boot=n_boot, seed=seed)
    mard = mard_by_range(ref, est).set_index("range")["mard_pct"]
    tir = time_in_range_agreement(ref, est, sid)
    tir_diff = tir[tir["metric"] == "tir_70_180_pct"]["difference_pct"]
    row = {
        "schedule": schedule,
        "mard_pct": float(mard["overall"]),
        **{f"mard_{k}_pct": float(mard.get(k, np.nan)) for k in ("<70", "70-180", ">180")},
        "icgm_passed": int(icgm["passes"].sum()),
        "icgm_criteria": len(icgm),
        "trend_agreement_pct": float(
            trend_agreement(all_ref, all_est, all_sid, all_t).agreement_pct),
        "lag_median_min": float(estimated_lag(all_ref, all_est, all_sid, all_t).median_min),
        "tir_difference_pct_median": float(np.median(tir_diff)) if len(tir_diff) else np.nan,
        "dts_a_pct": float(zone_percentages(dts_zones(ref, est)).get("A", 0.0)),
        "n_scored": int(keep.sum()),
        "n_below_70": int((ref < 70).sum()),
    }
    return row, icgm.assign(schedule=schedule)


def _fit_predict(name: str, params: dict, data: Dataset, train: np.ndarray,
                 test: np.ndarray, seed: int) -> np.ndarray:
    """Fit on rows ``train`` of ``data`` (a Dataset keeps the ADC resolution), predict ``test``."""
    model = make_model(name, **params)
    if "random_state" in model.get_params():
        model.set_params(random_state=seed)
    model.fit(data.rows(train))
    return np.asarray(model.predict(data.rows(test)), dtype=float)


def _tuned_smoother(name, params, data, train, per_subject, time, seed):
    """The smoother's grid scored on a fifth of the training subjects (module docstring)."""
    frame = data.frame
    subjects = np.unique(frame["subject_id"].to_numpy()[train])
    rng = np.random.default_rng(np.random.SeedSequence([seed, 17]))
    val_subjects = rng.choice(subjects, size=max(1, subjects.size // 5), replace=False)
    in_val = np.isin(frame["subject_id"].to_numpy()[train], val_subjects)
    fit_rows = _thin(frame, train[~in_val], per_subject, time)
    val_rows = train[in_val]
    pred = _fit_predict(name, params, data, fit_rows, val_rows, seed)
    val = frame.iloc[val_rows][["subject_id", time, "glucose_mgdl"]].copy()
    val["predicted_glucose_mgdl"] = pred
    return tune_smoother(val, time=time)


def run_wear_benchmark(
    data: Dataset | pd.DataFrame,
    models: Sequence[str] = WEAR_MODELS,
    *,
    preset: str | None = None,
    n_splits: int = 5,
    seed: int = 0,
    schedules: Sequence[str] = tuple(SCHEDULES),
    train_readings_per_subject: int = 48,
    n_boot: int = 1000,
    time: str = "time_min",
) -> WearResult:
    """Every model on a worn run's series, smoothed and calibrated (module docstring).

    Parameters
    ----------
    data : Dataset or DataFrame
        A worn run: ``subject_id``, ``time`` [min], ``glucose_mgdl`` (the reference) and
        the device's measured columns.
    models : sequence of str
        Registered model names (:data:`WEAR_MODELS` by default).
    preset : str, optional
        Tuned hyper-parameters of this preset where the package has them.
    n_splits, seed : int
        Subject-grouped folds and the seed of splits, fits and the bootstrap.
    schedules : sequence of str
        Calibration schedules (:data:`~nirglucose.calibration.schedules.SCHEDULES`).
    train_readings_per_subject : int
        Readings each training subject contributes (step 1 of the module docstring).
    n_boot : int
        Subject-bootstrap resamples of the schedules' CIs.

    Returns
    -------
    WearResult
    """
    data = data if isinstance(data, Dataset) else Dataset(data)
    data = data.rows(np.arange(len(data)))  # renumbered from 0
    frame = data.frame
    missing = [c for c in ("subject_id", time, "glucose_mgdl") if c not in frame.columns]
    if missing:
        raise DataError(f"a worn benchmark needs the columns {missing}; simulate with "
                        "wear_days (nirglucose simulate --wear-days D) or add them")
    if int(n_boot) < 100:
        raise ConfigError(f"n_boot = {n_boot!r} is too few for a lower confidence bound; "
                          "expected an integer >= 100")
    if int(train_readings_per_subject) < 2:
        raise ConfigError(f"train_readings_per_subject = {train_readings_per_subject!r} is "
                          "invalid; expected an integer >= 2")
    for name in models:
        get_model_class(name)  # unknown names: one ConfigError listing the valid ones
    splits = grouped_kfold(frame["subject_id"].to_numpy(), n_splits=n_splits, repeats=1,
                           seed=seed)
    preds, smoothers = [], []
    for name in models:
        params = preset_params(name, preset)
        for sp in splits:
            fold_seed = seed * 1000 + sp.fold
            train = _thin(frame, sp.train, int(train_readings_per_subject), time)
            raw = _fit_predict(name, params, data, train, sp.test, fold_seed)
            smoother, scores = _tuned_smoother(name, params, data, sp.train,
                                               int(train_readings_per_subject), time, fold_seed)
            test = frame.iloc[sp.test][["subject_id", time, "glucose_mgdl"]].copy()
            smooth = smoother.smooth(raw, test[time], test["subject_id"])
            for variant, values in (("raw", raw), ("smoothed", smooth)):
                preds.append(test.assign(model=name, variant=variant, fold=sp.fold,
                                         predicted_glucose_mgdl=values))
            smoothers.append({"model": name, "fold": sp.fold,
                              **{k: float(scores.loc[0, k]) for k in scores.columns}})
    predictions = pd.concat(preds, ignore_index=True)
    tables, days, standards, icgm = _scored(predictions, schedules, time, n_boot, seed)
    meta = {"models": list(models), "preset": preset, "n_splits": n_splits, "seed": seed,
            "schedules": list(schedules), "n_subjects": int(frame["subject_id"].nunique()),
            "n_readings": len(frame), "train_readings_per_subject": train_readings_per_subject,
            "n_boot": n_boot}
    return WearResult(predictions, tables, days, pd.DataFrame(smoothers), standards, icgm, meta)


def _scored(predictions: pd.DataFrame, schedules: Sequence[str], time: str, n_boot: int,
            seed: int) -> tuple[pd.DataFrame, pd.DataFrame, pd.DataFrame, pd.DataFrame]:
    """Schedules, error by day, standards and iCGM criteria of every model and variant."""
    tables, days, standards, icgm = [], [], [], []
    for (name, variant), g in predictions.groupby(["model", "variant"], sort=False):
        g = g.reset_index(drop=True)
        applied = {s: apply_schedule(g, s, time=time) for s in schedules}  # once, for both
        summary, by_day = schedule_table(g, schedules, time=time, n_boot=n_boot, seed=seed,
                                         applied=applied)
        tables.append(summary.assign(model=name, variant=variant))
        days.append(by_day.assign(model=name, variant=variant))
        for sched in schedules:
            row, crit = _standards(g, sched, applied[sched], time, n_boot, seed)
            standards.append({"model": name, "variant": variant, **row})
            icgm.append(crit.assign(model=name, variant=variant))
    return (pd.concat(tables, ignore_index=True), pd.concat(days, ignore_index=True),
            pd.DataFrame(standards), pd.concat(icgm, ignore_index=True))


# --------------------------------------------------------------------------- sweep
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
                       spec["every_min"], spec["seed"], overrides=spec.get("overrides"))
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
    overrides: Mapping[str, Any] | None = None,
    label: str | None = None,
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
        core), as in :func:`~nirglucose.evaluation.sweep.run.run_sweep`.
    scheduler : str or distributed.Client, optional
        Dask scheduler address (``tcp://host:8786``), ``"local"`` (a Dask cluster of
        ``jobs`` processes) or a client: run the pending tasks there.
    overrides : mapping, optional
        Scenario overrides of every preset (a device's twin:
        :meth:`nirglucose.twin.Twin.study_start`).
    label : str, optional
        The ``preset`` column's value in the tables in place of the preset's name
        (``twin``).

    Raises
    ------
    ConfigError
        Unknown preset or schedule, bad days, bad ``jobs`` / ``scheduler`` or a
        scheduler that does not answer (before any task runs).
    """
    extra = {} if overrides is None else {"overrides": tasks.canonical(dict(overrides))}
    for p in presets:
        resolve_config(p, extra.get("overrides"))  # unknown presets fail before anything runs
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
        "models": list(models), "schedules": list(schedules), "n_boot": int(n_boot),
        **extra})
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
        preset=label or spec["preset"], wear_days=spec["wear_days"], seed=spec["seed"])
        for key, spec in specs.items()]
    sweep = pd.concat(frames, ignore_index=True)
    summary = _summary(sweep)
    out = Path(out)
    for name, table in zip(WEAR_SWEEP_FILES, (sweep, summary), strict=True):
        atomic_write(out / name, lambda tmp, t=table: t.to_csv(tmp, index=False))
    return summary


def _plan(presets, wear_days, seeds, common: dict) -> dict[str, dict]:
    """The grid's task specifications, stamped
    (:func:`~nirglucose.evaluation.engine.tasks.stamp`), by task key."""
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
