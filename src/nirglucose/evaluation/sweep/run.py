"""Sweeps: how each model degrades as the noise grows, ablations, and domain shift.

A sweep is a list of *scenarios* (dotted config overrides on a preset) crossed with
seeds and models. Each ``(scenario, seed, model)`` is one independent *task*: it
simulates its dataset from the scenario and the seed, then runs
:func:`~nirglucose.evaluation.benchmark.run_benchmark` for that one model (one worker
inside the task), or, for the domain-shift study, fits on a training cohort and
scores on a shifted test cohort. :func:`run_sweep` runs the tasks in this process, on
a local process pool or on a Dask cluster (:mod:`~nirglucose.evaluation.engine.executors`)
and gathers one row per task.

Studies
    The built-in studies (:data:`STUDIES`) are described in
    :mod:`~nirglucose.evaluation.sweep.studies`, where they are defined.

Determinism
    A task draws every random number from its own specification (the dataset from the
    sweep seed, splits and models from ``run_benchmark``'s seeding), never from the
    order or the place it ran, so results are identical for ``jobs=1``, a process
    pool or a Dask cluster. The same seed in every scenario gives common random
    numbers: with :mod:`~nirglucose.simulation._random`'s per-source streams, switching
    one noise source off leaves every other draw unchanged, so scenario differences
    are paired.

Resumability
    With ``out`` given, each finished task is written atomically to
    ``out/.tasks/<model>-s<seed>-<hash>.json`` by the task engine
    (:mod:`~nirglucose.evaluation.engine.tasks`, shared with the benchmark); the hash covers
    the task's full specification (preset, resolved overrides and the SHA-256 of the
    resolved config, seed, model, protocol options, bootstrap size) and the engine's
    identity (task format, package version, the digest of the package's source,
    :func:`~nirglucose.evaluation.engine.tasks.source_digest`). A rerun loads finished tasks
    instead of recomputing them; a file whose checksum, specification or schema does
    not match is recomputed (and counted). Files are written by the process that
    gathers results, so a remote cluster needs no shared file system, and an interrupt
    loses only the tasks that were running.

Layout
    Scenarios and studies live in :mod:`~nirglucose.evaluation.sweep.studies`, the analysis
    of results (summaries, effects, crossings) in
    :mod:`~nirglucose.evaluation.sweep.analysis`; both are re-exported here.

Outputs (:meth:`SweepResult.save`)
    ``sweep.csv`` (one row per scenario × seed × model, the scenario's varied values
    as columns, then every metric of :data:`SWEEP_METRICS`), ``summary.csv`` (mean,
    SD and a 95 % t-interval over seeds per scenario × model), ``effects.csv``
    (ablation or shift effects, the ``mismatch`` study's table across seeds
    (:func:`~nirglucose.evaluation.sweep.analysis.mismatch_table`), when the study has
    them) and ``sweep_meta.json`` (its ``tuning``: how each model's hyper-parameters were
    chosen, where a study re-tunes them).
"""

from __future__ import annotations

import json
import math
import time
import warnings
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from ..._version import __version__
from ...api import simulate
from ...config import resolve_config
from ...dataset import Dataset
from ...dataset.files import check_result_table
from ...exceptions import ConfigError, DataError
from ...metrics import summary
from ...metrics.resampling import cluster_bootstrap_metrics
from ...models.registry import get_model_class
from ...models.tuning import preset_params
from ..benchmark import METRIC_COLUMNS, run_benchmark
from ..benchmark.aggregate import count_invalid, fallback_mgdl, scored
from ..benchmark.result import _dumps, _write_csv, _write_text
from ..engine import tasks
from ..engine.executors import check_scheduler, resolve_backend, run_unordered
from ..engine.progress import task_hooks
from ..engine.tasks import TASK_FORMAT, source_digest
from ..estimators import (
    build_estimator,
    describe_entries,
    estimator_identity,
    fit_model,
    predict_model,
    resolve_rows,
)
from ..protocol import Protocol, sweep_protocol
from ..splits import effective_layout
from .analysis import (
    SUMMARY_METRICS,
    ablation_effects,
    mismatch_table,
    ranking_crossings,
    shift_effects,
    summarize_sweep,
    threshold_crossing,
)
from .fleet import fleet_metrics, fleet_table
from .studies import (
    COHORT_SHIFTS,
    DATA_SIZE_PRESETS,
    DATA_SIZE_SUBJECTS,
    DATA_SIZE_TEST_SUBJECTS,
    MISMATCH_SUBJECTS,
    STUDIES,
    STUDY_GRIDS,
    STUDY_MODELS,
    Scenario,
    grid_scenarios,
    parse_vary,
    resolve_scenarios,
    study_model_params,
    study_scenarios,
)
from .wavelengths import wavelength_designs

__all__ = [
    "STUDIES",
    "STUDY_GRIDS",
    "COHORT_SHIFTS",
    "DEFAULT_MODELS",
    "SWEEP_METRICS",
    "CALIBRATION_METRICS",
    "SUMMARY_METRICS",
    "SWEEP_FILES",
    "TASK_FORMAT",
    "source_digest",
    "Scenario",
    "SweepResult",
    "parse_vary",
    "grid_scenarios",
    "study_scenarios",
    "plan_sweep",
    "run_sweep_task",
    "run_sweep",
    "load_sweep",
    "summarize_sweep",
    "ablation_effects",
    "shift_effects",
    "threshold_crossing",
    "ranking_crossings",
    "DATA_SIZE_SUBJECTS",
    "DATA_SIZE_TEST_SUBJECTS",
    "DATA_SIZE_PRESETS",
]

#: Models of a sweep when none are named (the fast linear ones and the bound).
DEFAULT_MODELS = ("ebl", "pls", "oracle")
#: Metric columns of ``sweep.csv``, in order (timing columns are left out: they depend
#: on the machine, the metrics do not).
#: Personal-calibration metrics of a cv task run with ``calibration=k`` (the later
#: readings only: uncalibrated, one offset per person, and the difference ridge);
#: sweep.csv has them only then.
CALIBRATION_METRICS = (
    "later_rmse_mgdl",
    "offset_rmse_mgdl",
    "offset_gain_mgdl",
    "difference_ridge_rmse_mgdl",
)
SWEEP_METRICS = tuple(
    c
    for c in METRIC_COLUMNS
    if c
    not in (
        "model",
        "label",
        "privileged",  # text: what the estimator knows beyond the measured columns
        "latency_single_ms",
        "latency_single_p90_ms",
        "throughput_per_s",
        "latency_input",
        "rmse_vs_oracle",
        "macs_counted",  # text: how the MACs were counted
        "fit_time_s",
    )
)
#: Files :meth:`SweepResult.save` writes.
SWEEP_FILES = ("sweep.csv", "summary.csv", "effects.csv", "sweep_meta.json")

#: ``run_benchmark`` timing options inside a sweep task: the latency is not reported
#: (it depends on the machine), so it is measured as cheaply as possible.
_FAST_TIMING = {
    "n_single": 1,
    "min_single": 1,
    "time_budget_s": 0.0,
    "warmup": 0,
    "batch_rows": 32,
    "batch_repeats": 1,
}
_DEFAULT_N_BOOT = 1000


# --------------------------------------------------------------------------- plan
def _config_sha(preset: str, overrides: Mapping[str, Any]) -> str:
    return tasks.sha256_hex(resolve_config(preset, overrides).to_json())[:16]


def _scenario_fields(
    sc: Scenario, preset: str, n_subjects: int, base: Mapping[str, Any], layout: dict[str, Any]
) -> dict[str, Any]:
    """The part of a task specification one scenario fixes (configs resolved: checked)."""
    preset = sc.preset or preset
    overrides = tasks.canonical({**base, **sc.overrides})
    cfg_sha = _config_sha(preset, overrides)
    test_overrides = test_sha = None
    if sc.test_overrides is not None:
        test_overrides = tasks.canonical({**base, **sc.test_overrides})
        test_sha = _config_sha(preset, test_overrides)
    proto = (
        layout if sc.kind == "cv" else {"protocol": "train-test", "n_splits": 1, "repeats": 1}
    )
    if sc.fleet is not None:  # the fleet study's scale, variant and layout
        proto = {**proto, "fleet": tasks.canonical(sc.fleet)}
    sizes = {} if sc.n_test_subjects is None else {"test_n_subjects": sc.n_test_subjects}
    return {
        "kind": sc.kind,
        "preset": preset,
        "overrides": overrides,
        "config_sha256": cfg_sha,
        "test_overrides": test_overrides,
        "test_config_sha256": test_sha,
        "train_filter": tasks.canonical(sc.train_filter),
        "test_filter": tasks.canonical(sc.test_filter),
        "n_subjects": int(sc.n_subjects or n_subjects),
        **proto,
        **sizes,
    }


def plan_sweep(
    scenarios: Sequence[Scenario],
    *,
    preset: str = "paper",
    seeds: Sequence[int] = (0,),
    models: Sequence[str] = DEFAULT_MODELS,
    base_overrides: Mapping[str, Any] | None = None,
    protocol: str = "grouped-cv",
    n_splits: int = 5,
    repeats: int = 3,
    n_subjects: int = 80,
    per_subject: int = 3,
    n_boot: int = _DEFAULT_N_BOOT,
    model_params: Mapping[str, Mapping[str, Any]] | None = None,
    calibration: int = 0,
    estimators: Mapping[str, Any] | None = None,
) -> list[dict[str, Any]]:
    """One task specification per scenario × seed × model, in that nesting order.

    Every configuration is resolved here, so a bad value fails before anything runs.
    ``calibration`` (personal calibration readings) joins the cross-validated tasks'
    specifications only when non-zero. ``estimators`` (label -> estimator object) puts
    each object's :func:`~nirglucose.evaluation.estimators.estimator_identity` in its
    tasks' specifications (the cache key); the object travels beside them.

    Returns
    -------
    list of dict
        JSON-able task specifications (:func:`run_sweep_task` input), stamped with the
        task engine's identity (:func:`~nirglucose.evaluation.engine.tasks.stamp`); the hash
        of one names its task file.
    """
    base = dict(base_overrides or {})
    params = dict(model_params or {})
    n_eff, r_eff = effective_layout(protocol, n_splits, repeats)
    layout = {"protocol": protocol, "n_splits": n_eff, "repeats": r_eff}
    ident = {k: {"estimator": estimator_identity(v)} for k, v in (estimators or {}).items()}
    specs = []
    for sc in scenarios:
        fields = _scenario_fields(sc, preset, n_subjects, base, layout)
        if calibration and sc.kind == "cv":
            fields["calibration"] = calibration
        own = sc.model_params or {}
        for seed in seeds:
            for model in models:
                spec = {
                    **fields,
                    "per_subject": int(per_subject),
                    "seed": int(seed),
                    "model": model,
                    **ident.get(model, {}),
                    "model_params": tasks.canonical(
                        {**params.get(model, {}), **own.get(model, {})}
                    ),
                    "n_boot": int(n_boot),
                }
                specs.append(tasks.stamp(spec))
    return specs


# --------------------------------------------------------------------------- tasks
def _filtered(ds: Dataset, filt: Mapping[str, Any] | None) -> Dataset:
    if not filt:
        return ds
    mask = ds.frame[filt["column"]].isin(filt["values"]).to_numpy()
    return ds.rows(mask)


def _cv_metrics(spec: Mapping[str, Any], ds: Dataset, estimator: Any = None) -> dict[str, Any]:
    res = run_benchmark(
        ds,
        [spec["model"] if estimator is None else (spec["model"], estimator)],
        protocol=Protocol(splitter=spec["protocol"], n_splits=spec["n_splits"],
                          repeats=spec["repeats"], seed=spec["seed"], resamples=spec["n_boot"],
                          calibration=int(spec.get("calibration", 0))),
        jobs=1,
        model_params={spec["model"]: spec["model_params"]} if spec["model_params"] else None,
        timing=dict(_FAST_TIMING),
        drop_one_models="none",  # the sweep reads metrics only
        oracle_reference=False,
    )
    row = res.metrics.iloc[0]
    out = {k: row[k] for k in SWEEP_METRICS if k in row.index}
    c = res.calibration
    if len(c):
        def rmse(model, method):
            hit = c[(c["model"] == model) & (c["method"] == method)]["rmse_mgdl"]
            return float(hit.iloc[0]) if len(hit) else np.nan

        out["later_rmse_mgdl"] = rmse(spec["model"], "none")
        out["offset_rmse_mgdl"] = rmse(spec["model"], "offset")
        out["offset_gain_mgdl"] = out["later_rmse_mgdl"] - out["offset_rmse_mgdl"]
        out["difference_ridge_rmse_mgdl"] = rmse("difference-ridge", "difference-ridge")
    return out


def _shift_metrics(
    spec: Mapping[str, Any], train: Dataset, test: Dataset, estimator: Any = None
) -> dict[str, Any]:
    if len(train) == 0 or len(test) == 0:
        raise DataError(
            f"the {spec['model']!r} shift task has an empty training or test "
            f"cohort ({len(train)} / {len(test)} rows); simulate more subjects"
        )
    maker = get_model_class(spec["model"]) if estimator is None else estimator
    # the preset's tuned parameters (the benchmark's one hook), then the sweep's own; an
    # estimator object is fitted as given
    tuned = preset_params(spec["model"], spec["preset"]) if estimator is None else {}
    params = {**tuned, **spec["model_params"]}
    seed = tasks.derived_seed(spec["seed"], f"model|{spec['model']}")
    model = fit_model(build_estimator(maker, params, seed), train)
    raw = predict_model(model, test)
    y = scored(raw, fallback_mgdl(train))
    ref = test.frame["glucose_mgdl"].to_numpy(float)
    point = summary(ref, y)
    ci = cluster_bootstrap_metrics(
        ref, y, test.frame["subject_id"].to_numpy(), n_boot=spec["n_boot"], seed=spec["seed"]
    )
    out = {**point, **{k: v for k, v in ci.items() if "_ci_" in k}}
    out.update(
        n_parameters=int(getattr(model, "n_parameters", -1)),
        n_predictions=len(ref),
        n_invalid_predictions=count_invalid(raw),
        n_train=len(train),
    )
    return {k: out[k] for k in (*SWEEP_METRICS, "n_train") if k in out}


def run_sweep_task(spec: Mapping[str, Any], estimator: Any = None) -> dict[str, Any]:
    """Run one sweep task (module level, so any worker process can run it).

    Parameters
    ----------
    spec : dict
        One task specification of :func:`plan_sweep`.
    estimator : estimator, optional
        The task's estimator object (cloned, never fitted); None for a registered name.

    Returns
    -------
    dict
        ``{"metrics": {...}, "version": ..., "warnings": [...], "wall_s": ...}``.
    """
    t0 = time.perf_counter()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        ds = None if spec["kind"] == "fleet" else simulate(  # a fleet task simulates its units
            spec["preset"],
            spec["n_subjects"],
            spec["per_subject"],
            spec["seed"],
            overrides=spec["overrides"],
        )
        if ds is None:
            metrics = fleet_metrics(spec)
        elif spec["kind"] == "cv":
            metrics = _cv_metrics(spec, _filtered(ds, spec["train_filter"]), estimator)
        else:
            test = simulate(
                spec["preset"],
                spec.get("test_n_subjects", spec["n_subjects"]),
                spec["per_subject"],
                tasks.derived_seed(spec["seed"], "test-cohort"),
                overrides=spec["test_overrides"],
            )
            metrics = _shift_metrics(spec, _filtered(ds, spec["train_filter"]),
                                     _filtered(test, spec["test_filter"]), estimator)
    clean = {  # numbers only: text columns (e.g. how MACs were counted) are not swept
        k: (None if v is None or (isinstance(v, float) and not math.isfinite(v)) else float(v))
        for k, v in metrics.items() if not isinstance(v, str)
    }
    return {
        "metrics": clean,
        "version": __version__,
        "source_sha256": tasks.source_digest(),
        "warnings": list(dict.fromkeys(str(w.message).replace("\n", " ") for w in caught)),
        "wall_s": time.perf_counter() - t0,
    }


def _run_sweep_item(item: tuple[Mapping[str, Any], Any]) -> dict[str, Any]:
    """:func:`run_sweep_task` of one ``(spec, estimator)`` pair (what the executors map)."""
    return run_sweep_task(*item)


def _valid_result(spec: Mapping[str, Any], result: Any) -> bool:
    if not isinstance(result, dict) or not isinstance(result.get("metrics"), dict):
        return False
    m = result["metrics"]
    return all(k in m for k in ("rmse_mgdl", "mard_pct", "n_predictions")) and all(
        v is None or isinstance(v, int | float) for v in m.values()
    )


def _task_tag(spec: Mapping[str, Any]) -> str:
    return f"s{spec['seed']}"


# --------------------------------------------------------------------------- result
@dataclass
class SweepResult:
    """What :func:`run_sweep` computed.

    Attributes
    ----------
    frame : pandas.DataFrame
        ``sweep.csv``: one row per scenario × seed × model: ``study``, ``scenario``,
        the label columns (``meta["label_columns"]``), ``seed``, ``model``, then
        :data:`SWEEP_METRICS` and ``rmse_vs_oracle``.
    summary : pandas.DataFrame
        :func:`summarize_sweep` of ``frame``.
    effects : pandas.DataFrame or None
        :func:`ablation_effects` or :func:`shift_effects` for those studies.
    meta : dict
        Study, preset, seeds, models, protocol, version, task counts, wall time.
    """

    frame: pd.DataFrame
    summary: pd.DataFrame
    effects: pd.DataFrame | None
    meta: dict[str, Any]

    def save(self, out: str | Path) -> Path:
        """Write :data:`SWEEP_FILES` into directory ``out`` (created if its parent exists)."""
        out = tasks.prepare_out(out)
        for name, frame in (
            ("sweep.csv", self.frame),
            ("summary.csv", self.summary),
            ("effects.csv", self.effects),
        ):
            if frame is not None:
                _write_csv(out / name, frame)
            else:
                (out / name).unlink(missing_ok=True)
        _write_text(out / "sweep_meta.json", _dumps(self.meta))
        return out


def load_sweep(sweep_dir: str | Path) -> SweepResult:
    """Read a sweep directory written by :meth:`SweepResult.save`.

    Raises
    ------
    DataError
        The directory or its ``sweep.csv`` / ``sweep_meta.json`` is missing or unreadable.
    """
    d = Path(sweep_dir)
    try:
        meta = json.loads((d / "sweep_meta.json").read_text(encoding="utf-8"))
        frame = pd.read_csv(d / "sweep.csv")
    except (OSError, ValueError) as exc:
        raise DataError(
            f"{str(d)!r} is not a sweep directory (sweep.csv and sweep_meta.json): {exc}"
        ) from None
    if not isinstance(meta, dict):
        raise DataError(f"sweep_meta.json in {str(d)!r} must hold a JSON object; rerun the sweep")
    labels = meta.get("label_columns", [])
    check_result_table(frame, f"sweep.csv in {str(d)!r}", ("scenario", "model", "seed"),
                       text=("study", "scenario", "model", *labels))
    summary = summarize_sweep(frame, labels)
    effects = None
    if (d / "effects.csv").exists():
        effects = pd.read_csv(d / "effects.csv")
    return SweepResult(frame, summary, effects, meta)


# --------------------------------------------------------------------------- runner
def _resolve_seeds(seeds: int | Sequence[int]) -> list[int]:
    if isinstance(seeds, int | np.integer) and not isinstance(seeds, bool):
        if seeds < 1:
            raise ConfigError(f"seeds must be a positive count, got {seeds}")
        return list(range(int(seeds)))
    out = [int(s) for s in seeds]
    if not out or any(s < 0 for s in out) or len(set(out)) != len(out):
        raise ConfigError(f"seeds must be distinct non-negative integers, got {list(seeds)}")
    return out


def _execute(
    cache: tasks.TaskCache,
    pending: list[str],
    specs: Mapping[str, dict[str, Any]],
    *,
    jobs: int | None,
    scheduler: Any,
    progress: bool,
    on_task: Callable[[dict[str, Any], bool], None] | None,
    objects: Mapping[str, Any],
) -> None:
    """Run the pending tasks (here, on local processes or on Dask) into ``cache``; a task
    of an estimator object (``objects``: label -> object) gets the object beside its spec."""
    check_scheduler(scheduler)  # one line, before the progress starts
    hooks = task_hooks(
        "sweep", len(specs), len(cache.results), "reused", show=progress,
        describe=lambda spec: f"{spec['model']} seed {spec['seed']}", on_task=on_task,
    )
    with hooks as done:
        stream = run_unordered(
            _run_sweep_item,
            [(specs[k], objects.get(specs[k]["model"])) for k in pending],
            jobs=jobs,
            scheduler=scheduler,
            keys=[f"nirglucose-sweep-{k}" for k in pending],
        )
        try:
            cache.collect(stream, pending, specs, _task_tag, on_done=done, check=tasks.check_worker)
        finally:
            stream.close()


def _frame(
    scenarios: list[Scenario],
    seed_list: list[int],
    models: list[str],
    results: list[dict[str, Any]],
    study_name: str,
    label_columns: list[str],
) -> pd.DataFrame:
    """``sweep.csv``: one row per scenario × seed × model (plan order)."""
    rows = []
    k = 0
    for sc in scenarios:
        for seed in seed_list:
            for model in models:
                res = results[k]
                k += 1
                rows.append(
                    {
                        "study": study_name,
                        "scenario": sc.name,
                        **{c: sc.labels.get(c) for c in label_columns},
                        "seed": seed,
                        "model": model,
                        **{
                            m: res["metrics"].get(m)
                            for m in (*SWEEP_METRICS, *CALIBRATION_METRICS, "n_train")
                            if m in res["metrics"]
                        },
                    }
                )
    frame = pd.DataFrame(rows)
    for m in (*SWEEP_METRICS, *CALIBRATION_METRICS):
        if m in frame:
            frame[m] = pd.to_numeric(frame[m], errors="coerce")
    if "oracle" in models:
        oracle = frame[frame["model"] == "oracle"].set_index(["scenario", "seed"])["rmse_mgdl"]
        idx = pd.MultiIndex.from_frame(frame[["scenario", "seed"]])
        frame["rmse_vs_oracle"] = frame["rmse_mgdl"].to_numpy() / oracle.reindex(idx).to_numpy()
    else:
        frame["rmse_vs_oracle"] = np.nan
    return frame


def _effects(study: str | None, frame: pd.DataFrame, summary: pd.DataFrame) -> pd.DataFrame | None:
    if study == "ablation":
        return ablation_effects(frame)
    if study == "cohort":
        return shift_effects(frame)
    if study == "data-size":
        return ranking_crossings(summary)
    if study == "wavelengths":
        return wavelength_designs(frame)
    if study == "fleet":
        return fleet_table(frame)
    if study == "mismatch":
        return mismatch_table(frame, MISMATCH_SUBJECTS)
    return None


def _sweep_meta(
    scenarios: list[Scenario], cache: tasks.TaskCache, n_pending: int, opts: dict[str, Any]
) -> dict[str, Any]:
    """``sweep_meta.json``: what ran, where, and how many tasks were reused."""
    study, results = opts["study"], cache.results
    n_total = len(results)
    backend = opts["backend"]
    return {
        "study": study or "grid",
        "preset": (
            opts["preset"]
            if study != "data-size"
            else list(dict.fromkeys(s.preset for s in scenarios))
        ),
        "base_overrides": tasks.canonical(opts["base"]),
        "scenarios": [s.name for s in scenarios],
        "label_columns": opts["label_columns"],
        "varied": (
            [STUDY_GRIDS[study][0]]
            if study in STUDY_GRIDS
            else list(opts["vary"] or {})
            if study is None
            else []
        ),
        **{k: opts[k] for k in ("seeds", "models", "protocol", "n_splits", "repeats")},
        "estimators": opts["estimators"],  # rows given as estimator objects: fitted as given
        # how each model's hyper-parameters were chosen, where the study re-tunes them
        **({"tuning": opts["tuning"]} if opts["tuning"] else {}),
        **{k: opts[k] for k in ("n_subjects", "per_subject", "n_boot")},
        "version": __version__,
        "task_format": TASK_FORMAT,
        "backend": backend,
        "workers": opts["n_workers"] if backend != "dask" else None,
        "scheduler": opts["scheduler"] if isinstance(opts["scheduler"], str) else None,
        "tasks_total": n_total,
        "tasks_cached": n_total - n_pending,
        "tasks_computed": n_pending,
        "tasks_corrupt": cache.n_corrupt,
        "task_wall_s_total": float(sum(r.get("wall_s", 0.0) for r in results.values())),
        "wall_time_s": time.perf_counter() - opts["t_start"],
        "warnings": list(dict.fromkeys(w for r in results.values() for w in r.get("warnings", []))),
        "summary_method": "mean over seeds with a Student-t 95 % interval of the mean",
        # a twin's sweep only: the other sweeps' metadata keep their bytes
        **({"twin": opts["twin"], "twin_led_fields": dict(opts["led_fields"] or {})}
           if opts.get("twin") is not None else {}),
    }


def _sweep_models(models: Any, study: str | None, scenarios: list[Scenario],
                  params: Mapping[str, Any] | None
                  ) -> tuple[list[str], dict[str, Any], dict[str, Any], dict[str, str]]:
    """The rows' labels (a study's subjects first), label -> estimator object, and the
    models' parameters and tuning notes (:func:`~.studies.study_model_params`)."""
    labels, objects = resolve_rows(models, STUDY_MODELS.get(study, DEFAULT_MODELS), params)
    if objects and any(sc.kind == "fleet" for sc in scenarios):
        raise ConfigError(f"the fleet study takes registered model names, not estimator "
                          f"objects ({', '.join(objects)}); run the objects in a grid study")
    if study == "mismatch":  # the study's subjects always run
        labels = [*(m for m in MISMATCH_SUBJECTS if m not in labels), *labels]
    own, tuning = study_model_params(study, [m for m in labels if m not in objects], params)
    return labels, objects, own, tuning


def run_sweep(
    vary: Mapping[str, Sequence[Any]] | None = None,
    *,
    study: str | None = None,
    preset: str | None = None,
    seeds: int | Sequence[int] = 5,
    models: Sequence[Any] | str | None = None,
    overrides: Mapping[str, Any] | None = None,
    protocol: str | Protocol = "grouped-cv",
    n_splits: int = 5,
    repeats: int = 3,
    n_subjects: int = 80,
    per_subject: int = 3,
    n_boot: int = _DEFAULT_N_BOOT,
    model_params: Mapping[str, Mapping[str, Any]] | None = None,
    out: str | Path | None = None,
    jobs: int | None = None,
    scheduler: Any = None,
    progress: bool = False,
    on_task: Callable[[dict[str, Any], bool], None] | None = None,
    calibration: int = 0,
    led_fields: Mapping[str, Any] | None = None, twin: str | None = None,
) -> SweepResult:
    """Run a grid of scenarios × seeds × models (local processes or a Dask cluster).

    Parameters
    ----------
    vary : mapping of str to sequence, optional
        Dotted config key -> values; several keys make a grid. Exclusive with ``study``.
    study : str, optional
        A built-in study (:data:`STUDIES`); ``vary`` sets only the sizes of
        ``data-size`` and the scales of ``fleet`` (a one-key study and ``vary`` of its
        key are refused together: that grid is ``vary`` alone).
    preset : str, optional
        Scenario preset every task starts from (default ``paper``); for the
        ``data-size`` study a comma-separated list (default :data:`DATA_SIZE_PRESETS`).
    seeds : int or sequence of int
        Number of seeds (0, 1, ...) or the seeds themselves.
    models : sequence or comma-separated str, optional
        Registry names (default :data:`DEFAULT_MODELS`; a study of
        :data:`~nirglucose.evaluation.sweep.studies.STUDY_MODELS`: its own), unfitted
        estimator objects and ``(label, estimator)`` pairs, as ``run_benchmark``
        takes them (:mod:`~nirglucose.evaluation.estimators`; the fleet study takes
        names only). Objects are pickled to local workers, as joblib sends them; a
        Dask cluster needs them picklable (cloudpickle), their classes importable
        there (or defined in ``__main__``). The cache keys on class path + parameters.
    overrides : mapping, optional
        Dotted overrides shared by every scenario (``--set``).
    protocol, n_splits, repeats : str, int, int
        Protocol of :func:`~nirglucose.evaluation.benchmark.run_benchmark` per task, or one
        :class:`~nirglucose.evaluation.protocol.Protocol` (seed 0: the sweep's are ``seeds``).
    n_subjects, per_subject : int
        Size of each simulated dataset. [-]
    n_boot : int
        Bootstrap resamples of each task's intervals. [-]
    model_params : mapping, optional
        Model name -> constructor keyword arguments.
    out : str or Path, optional
        Directory for the task cache (``out/.tasks``) and :data:`SWEEP_FILES`.
    jobs : int, optional
        Local worker processes (default: the available cores); ignored with
        ``scheduler``.
    scheduler : str or distributed.Client, optional
        Dask scheduler address (``tcp://host:8786``) or client: run the tasks there.
    progress : bool
        Show a rich progress bar (done / total, time left) on stderr.
    on_task : callable, optional
        Called as ``on_task(spec, cached)`` for every task as it is loaded or finished.
    calibration : int
        Personal calibration readings per test subject (0, 1 or 2) of every
        cross-validated task (:mod:`~nirglucose.calibration.personal`): adds
        :data:`CALIBRATION_METRICS` (shift tasks leave them empty).
    led_fields : mapping, optional
        ``wavelengths`` study only: fields every LED it chooses takes (a device's twin's
        per-LED values, :meth:`nirglucose.twin.Twin.study_start`).
    twin : str, optional
        The twin the scenarios start from (``preset`` and ``overrides`` are its), kept
        in ``sweep_meta.json``.

    Returns
    -------
    SweepResult

    Raises
    ------
    ConfigError
        Bad key, value, study, model, protocol or count; an unreachable scheduler.
    DataError
        A worker running another ``nirglucose`` version; unwritable ``out``.
    """
    t_start = time.perf_counter()
    base = dict(overrides or {})
    scenarios, preset = resolve_scenarios(vary, study, preset, base, led_fields)
    models, objects, model_params, tuning = _sweep_models(models, study, scenarios, model_params)
    proto = sweep_protocol(protocol, seeds, (n_subjects, per_subject), _DEFAULT_N_BOOT, dict(
        n_splits=n_splits, repeats=repeats, resamples=n_boot, calibration=calibration))
    seed_list = _resolve_seeds(seeds)
    backend, n_workers = resolve_backend(jobs, scheduler)
    specs = plan_sweep(
        scenarios, preset=preset, seeds=seed_list, models=models, base_overrides=base,
        protocol=proto.splitter, n_splits=proto.n_splits, repeats=proto.repeats,
        n_subjects=n_subjects, per_subject=per_subject, n_boot=proto.resamples,
        model_params=model_params, calibration=proto.calibration, estimators=objects,
    )
    keys = [tasks.task_key(s) for s in specs]
    spec_of = dict(zip(keys, specs, strict=True))
    cache = tasks.TaskCache(out, valid=_valid_result)
    tasks.clear_outputs(out, SWEEP_FILES)
    pending = cache.lookup(spec_of, _task_tag,
                           None if on_task is None else lambda spec: on_task(spec, True))
    _execute(cache, pending, spec_of, jobs=jobs, scheduler=scheduler, progress=progress,
             on_task=on_task, objects=objects)
    label_columns = list(dict.fromkeys(k for s in scenarios for k in s.labels))
    frame = _frame(scenarios, seed_list, models, [cache.results[k] for k in keys],
                   study or "grid", label_columns)
    summary = summarize_sweep(frame, label_columns)
    opts = dict(study=study, preset=preset, base=base, vary=vary, seeds=seed_list, models=models,
                protocol=proto.splitter, n_splits=proto.n_splits, repeats=proto.repeats,
                n_subjects=n_subjects, per_subject=per_subject, n_boot=proto.resamples,
                label_columns=label_columns, backend=backend, n_workers=n_workers,
                scheduler=scheduler, t_start=t_start, estimators=describe_entries(objects),
                twin=twin, led_fields=led_fields, tuning=tuning)
    result = SweepResult(frame=frame, summary=summary, effects=_effects(study, frame, summary),
                         meta=_sweep_meta(scenarios, cache, len(pending), opts))
    if out is not None:
        result.save(out)
    return result
