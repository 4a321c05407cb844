"""The benchmark: every model, the same subject-grouped splits, honest statistics.

:func:`run_benchmark` fits each model on each split of the protocol
(:mod:`~nirglucose.evaluation.splits`), scores the held-out predictions with cluster
bootstrap intervals and paired comparisons (:mod:`~nirglucose.metrics.resampling`),
times every model the same way (:mod:`~nirglucose.evaluation.benchmark.timing`) and refits
chosen models without each LED (:mod:`~nirglucose.evaluation.benchmark.drop_one`).
It computes only; figures and the report read the :class:`BenchmarkResult`.

Tasks
    Each (model, repeat, fold) is an independent task seeded from ``(seed, model,
    repeat, fold)``, so results are the same for any number of worker processes. Torch
    runs on one thread inside a task (the same arithmetic whatever ``jobs`` is).
    With ``out`` given, each task's result is written atomically to
    ``out/.tasks/<model>-r<repeat>-f<fold>-<hash>.json`` as it finishes by the task
    engine (:mod:`~nirglucose.evaluation.engine.tasks`, shared with the sweep), the hash
    covering its full specification (dataset hash, model, parameters, protocol, folds,
    seed, repeat, fold, and the engine's identity: task format, package version and
    the digest of the whole package source); a rerun loads finished tasks instead of
    recomputing them, and a corrupt or mismatching file is recomputed.

Estimator objects
    Besides registered names, ``models`` takes unfitted estimator objects and
    ``(label, estimator)`` pairs (:mod:`~nirglucose.evaluation.estimators`): each task
    fits a clone as given; the task key covers the object's class and parameters.

Validation
    Under ``paper-split`` the validation part (20 % of subjects) is passed as
    ``fit(train, X_val=..., y_val=...)`` to estimators whose ``fit`` takes ``X_val``
    (the networks: early stopping); the others fit on the training part only (60 %),
    choosing their hyper-parameters by inner cross-validation there. Under
    ``grouped-cv`` every estimator gets the training folds only and the networks take
    their own inner validation split by subject from them.

Reference rows and the physics ablation
    ``references=True`` adds :data:`REFERENCE_MODELS` (no skill, a Gaussian process
    with one length scale per input, gradient boosting) to the models. Every model is
    built with the tuned hyper-parameters of the data's preset
    (:func:`~nirglucose.models.tuning.preset_params`),
    overridden by ``model_params``. ``ablation=True`` also runs every PINN (a
    network with a ``lambda_phys``, :func:`~nirglucose.models.registry.is_pinn`; the
    study's are :data:`PINN_MODELS`) with its physics term off (``lambda_phys=0``; everything else
    identical: the same folds, the same seeds, the same other parameters) as the row
    ``<name>/no-physics``; ``ablation.csv`` holds the paired RMSE difference (with
    physics minus without) with its cluster-bootstrap CI and Holm-adjusted p-value.
    Where the PINN's own ``lambda_phys`` is 0 (tuning chose it) it *is* its no-physics
    fit (the two rows share one fit): that pair is untested, with no verdict, and the
    PINN is also run at the best λ > 0 of the tuning's validation curve
    (:func:`~nirglucose.models.tuning.best_positive_lambda`) as ``<name>/lambda=<λ>``,
    paired against ``<name>/no-physics``.

Drop-one-LED refits
    Each model of ``drop_one_models`` (by default
    :data:`~nirglucose.evaluation.benchmark.drop_one.DEFAULT_DROP_ONE_MODELS` among the models:
    EBL, PLS and the oracle, each a fraction of a second per fit)
    is refitted once per LED on the data without that LED's columns
    (:func:`~nirglucose.evaluation.benchmark.drop_one.without_led`): one task per model × fold ×
    LED, on the folds of the first repeat only
    (:data:`~nirglucose.evaluation.benchmark.drop_one.DROP_ONE_REPEATS`; all repeats would triple
    the cost for little), with the seeds and parameters of the model's own task of that
    fold, cached and run like every other task (tag ``r<repeat>-f<fold>-no<nm>``).
    ``drop_one.csv`` holds the paired RMSE difference (without the LED − with every LED,
    the latter from the same repeat's predictions) with its cluster-bootstrap CI.
    ``drop_one_models="none"`` runs none (what a sweep asks for), ``"all"`` every row.

Scoring
    Predictions below 0 mg/dL are scored as 0 and non-finite ones as the median
    training target of their fold (the error grids need a non-negative number); both
    are counted in ``n_invalid_predictions`` and the raw value is kept in
    ``predictions``. Metrics are computed per repeat and averaged over repeats.
    Latency and batch throughput are measured on the first fold of the first repeat;
    ``n_parameters`` is the fitted model's count there.
"""

from __future__ import annotations

import json
import sys
import time
import warnings
from collections.abc import Callable, Mapping, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from ..._version import __version__
from ...calibration.conformal import LEVELS
from ...calibration.personal import personal_calibration
from ...dataset import Dataset
from ...exceptions import ConfigError, DataError, check_positive_int
from ...models.registry import available_models, get_model_class, is_pinn, privileged_knowledge
from ...models.tuning import best_positive_lambda, preset_params
from ..engine import executors, tasks
from ..engine.progress import task_hooks
from ..engine.tasks import TASK_FORMAT
from ..estimators import (
    build_estimator,
    describe_entries,
    estimator_identity,
    fit_history,
    fit_model,
    measured_frame,
    predict_model,
    resolve_rows,
    takes_dataset,
)
from ..protocol import Protocol, protocol_of
from ..reference import STUDY_PROTOCOL
from ..splits import Split, effective_layout, make_splits
from .aggregate import aggregate, fallback_mgdl
from .drop_one import (
    DROP_ONE_COLUMNS,
    DROP_ONE_REPEATS,
    drop_one_table,
    led_wavelengths,
    refit_predictions,
    resolve_drop_one_models,
    without_led,
)
from .inverse import inverse_table, task_state
from .result import (
    ABLATION_COLUMNS,
    COMPARISON_COLUMNS,
    METRIC_COLUMNS,
    NO_PHYSICS,
    ORACLE,
    OUTPUT_FILES,
    PINN_MODELS,
    PREDICTION_COLUMNS,
    REFERENCE_MODELS,
    STALE_FILES,
    BenchmarkResult,
    ablation_base,
    lambda_row,
)
from .timing import measure_latency, timing_inputs

__all__ = [
    "BenchmarkResult",
    "run_benchmark",
    "METRIC_COLUMNS",
    "PREDICTION_COLUMNS",
    "COMPARISON_COLUMNS",
    "DROP_ONE_COLUMNS",
    "OUTPUT_FILES",
    "TASK_FORMAT",
    "ORACLE",
    "REFERENCE_MODELS",
    "PINN_MODELS",
    "NO_PHYSICS",
    "ABLATION_COLUMNS",
]

# --------------------------------------------------------------------------- tasks
@contextmanager
def _one_thread_torch():
    """Torch (when loaded) on one thread inside a task: the same arithmetic for any ``jobs``."""
    torch = sys.modules.get("torch")
    if torch is None:
        yield
        return
    saved = torch.get_num_threads()
    torch.set_num_threads(1)
    try:
        yield
    finally:
        torch.set_num_threads(saved)


def _task_model(maker: Any, spec: Mapping[str, Any]) -> Any:
    """The task's new estimator (:func:`~nirglucose.evaluation.estimators.build_estimator`),
    seeded from ``(seed, model, repeat, fold)``."""
    # an ablated PINN draws the same seeds as its original: a paired comparison
    seed_name = spec.get("seed_model", spec["model"])
    task_seed = tasks.derived_seed(spec["seed"], seed_name, spec["repeat"], spec["fold"])
    return build_estimator(maker, spec["params"], task_seed)


def _run_task(
    maker: Any,
    spec: dict[str, Any],
    dataset: Dataset,
    split: Split,
    timing: dict[str, Any],
) -> dict[str, Any]:
    """Fit one model (a registered class or the caller's estimator object) on one split
    and score it; the JSON-able task result."""
    if spec.get("drop_nm") is not None:
        return _run_drop_task(maker, spec, dataset, split)
    train, test = dataset.rows(split.train), dataset.rows(split.test)
    val = None if split.val is None else dataset.rows(split.val)
    cpu0, wall0 = time.process_time(), time.perf_counter()
    with _one_thread_torch():
        model = _task_model(maker, spec)
        t0 = time.perf_counter()
        fit_model(model, train, val)
        fit_time = time.perf_counter() - t0
        pred = predict_model(model, test)
        if pred.shape != (len(split.test),):
            raise DataError(
                f"model {spec['model']!r} returned {pred.shape} predictions for "
                f"{len(split.test)} rows"
            )
        # the validation predictions calibrate the conformal intervals of paper-split
        val_pred = None if val is None else predict_model(model, val)
        latency: dict[str, Any] = {}
        if spec["timed"]:
            # another library's estimator is timed on what it is fed: the measured columns
            form, data = (timing_inputs(model, test) if takes_dataset(model)
                          else ("frame", measured_frame(test)))
            latency = {**measure_latency(model, data, **timing), "latency_input": form}
        state = task_state(model, test) if takes_dataset(model) else None
    return {
        "predicted_mgdl": [float(v) for v in pred],
        "val_predicted_mgdl": None if val_pred is None else [float(v) for v in val_pred],
        "fallback_mgdl": fallback_mgdl(train),
        "n_parameters": int(getattr(model, "n_parameters", -1)),
        "fit_time_s": fit_time,
        "task_wall_s": time.perf_counter() - wall0,
        "task_cpu_s": time.process_time() - cpu0,
        "history": fit_history(model),
        "state": state,
        "timing": latency,
    }


def _run_drop_task(
    maker: Any, spec: dict[str, Any], dataset: Dataset, split: Split
) -> dict[str, Any]:
    """Refit one model on one split without the LED ``spec["drop_nm"]``; score it.

    The seeds and parameters are those of the model's own task of that split
    (``seed_model``, ``repeat``, ``fold``), the validation part (``paper-split``) goes
    without the LED too, and the held-out rows are the same: a paired comparison.
    """
    data = without_led(dataset, spec["drop_nm"])
    train, test = data.rows(split.train), data.rows(split.test)
    val = None if split.val is None else data.rows(split.val)
    cpu0, wall0 = time.process_time(), time.perf_counter()
    with _one_thread_torch():
        model = fit_model(_task_model(maker, spec), train, val)
        fit_time = time.perf_counter() - wall0
        pred = predict_model(model, test)
    if pred.shape != (len(split.test),):
        raise DataError(
            f"model {spec['model']!r} without the {spec['drop_nm']:g} nm LED returned "
            f"{pred.shape} predictions for {len(split.test)} rows"
        )
    return {
        "predicted_mgdl": [float(v) for v in pred],
        "fallback_mgdl": fallback_mgdl(train),
        "fit_time_s": fit_time,
        "task_wall_s": time.perf_counter() - wall0,
        "task_cpu_s": time.process_time() - cpu0,
    }


def _run_task_of(args: tuple[Any, ...]) -> dict[str, Any]:
    """:func:`_run_task` of one argument tuple (what :func:`executors.run_unordered` maps)."""
    return _run_task(*args)


def _task_tag(spec: Mapping[str, Any]) -> str:
    drop = spec.get("drop_nm")
    return f"r{spec['repeat']}-f{spec['fold']}" + ("" if drop is None else f"-no{drop:g}")


# --------------------------------------------------------------------------- plan
def _variants(
    names: list[str], ablation: bool, params: Mapping[str, dict[str, Any]], preset: str | None,
    objects: Mapping[str, Any],
) -> tuple[dict[str, tuple[str, dict[str, Any]]], list[dict[str, Any]]]:
    """Row name -> (registered model, forced parameters), and the ablation's pairs.

    Under ablation every PINN (a network with a ``lambda_phys``) gets a
    ``<name>/no-physics`` row (λ = 0). Where its own λ is 0 (tuning chose it, or the
    caller did) the PINN *is* that fit: the pair is kept untested, and the PINN is also
    run at the best λ > 0 of the tuning's validation curve
    (:func:`~nirglucose.models.tuning.best_positive_lambda`) as ``<name>/lambda=<λ>``,
    paired against ``<name>/no-physics``. Estimator objects (``objects``) are not ablated.
    """
    out: dict[str, tuple[str, dict[str, Any]]] = {n: (n, {}) for n in names}
    pairs: list[dict[str, Any]] = []
    if not ablation:
        return out, pairs
    for n in (n for n in names if n not in objects and is_pinn(n)):
        off = n + NO_PHYSICS
        out[off] = (n, {"lambda_phys": 0.0})
        lam = params[n].get("lambda_phys")
        lam = float(get_model_class(n)().lambda_phys if lam is None else lam)
        tuned = preset is not None and "lambda_phys" in preset_params(n, preset)
        source = "tuned" if tuned and preset_params(n, preset)["lambda_phys"] == lam else "given"
        pairs.append({"model": n, "ablated_model": off, "lambda_phys": lam,
                      "lambda_source": source, "tested": lam > 0})
        best = best_positive_lambda(n, preset) if (lam == 0 and preset is not None) else None
        if best is not None:
            row = lambda_row(n, best)
            out[row] = (n, {"lambda_phys": best})
            pairs.append({"model": row, "ablated_model": off, "lambda_phys": best,
                          "lambda_source": "best > 0 on the tuning curve", "tested": True})
    return out, pairs


@dataclass(frozen=True)
class _Task:
    """One planned task: its key, specification, split and estimator (a registered class,
    or the caller's object, cloned by the task)."""

    key: str
    spec: dict[str, Any]
    split: Split
    maker: Any


def _class_of(maker: Any) -> type:
    return maker if isinstance(maker, type) else type(maker)


@dataclass(frozen=True)
class _Plan:
    """What a benchmark runs: its rows, their parameters, the oracle and the tasks."""

    names: list[str]
    aux: list[str]
    model_params: dict[str, dict[str, Any]]
    oracle_note: str | None
    protocol: str
    n_splits: int
    repeats: int
    data_hash: str
    splits: list[Split]
    tasks: list[_Task]
    ablation_pairs: list[dict[str, Any]]
    #: The drop-one-LED refits (models × first-repeat folds × LEDs).
    drop_tasks: list[_Task]
    drop_one_models: list[str]
    #: Label -> the caller's estimator object (rows given as objects).
    objects: dict[str, Any]

    def specs(self) -> dict[str, dict[str, Any]]:
        """Task key -> specification, in plan order (a shared fit: its first row's)."""
        out: dict[str, dict[str, Any]] = {}
        for t in [*self.tasks, *self.drop_tasks]:
            out.setdefault(t.key, t.spec)
        return out


def _as_dataset(dataset: Dataset | pd.DataFrame) -> Dataset:
    if isinstance(dataset, pd.DataFrame):
        dataset = Dataset(dataset)
    if not isinstance(dataset, Dataset):
        raise DataError(f"expected a Dataset or DataFrame, got {type(dataset).__name__}")
    missing = [c for c in ("subject_id", "glucose_mgdl") if c not in dataset.frame]
    if missing:
        raise DataError(f"the benchmark needs columns {missing}")
    return dataset


def _row_params(
    names: list[str],
    objects: Mapping[str, Any],
    explicit: Mapping[str, dict[str, Any]] | None,
    preset: str | None,
    ablation: bool,
) -> tuple[list[str], dict[str, str], dict[str, dict[str, Any]], list[dict[str, Any]]]:
    """Rows (PINNs two or three times under ablation), each row's registered model (or
    estimator object's label) and parameters (an object's: ``explicit`` only, it is
    fitted as given), and the ablation's pairs (:func:`_variants`)."""
    explicit = dict(explicit or {})
    unknown = sorted(set(explicit) - set(names) - {ORACLE})
    if unknown:
        raise ConfigError(f"model_params for models not benchmarked: {unknown}; models: {names}")
    params = {n: {**({} if n in objects else preset_params(n, preset)), **explicit.get(n, {})}
              for n in [*names, ORACLE]}
    variants, pairs = _variants(names, ablation, params, preset, objects)
    for row, (base, forced) in variants.items():
        if row != base:
            params[row] = {**params[base], **forced}
    return list(variants), {n: variants[n][0] for n in variants}, params, pairs


def default_models(dataset: Dataset) -> list[str]:
    """The rows when no models are given: every registered model, less, on data that
    carries no scenario (a device's own file), the privileged ones: they read the
    generating scenario or the true_* columns, which such a file does not have
    (:func:`~nirglucose.models.registry.privileged_knowledge`)."""
    names = available_models()
    if dataset.config is not None:
        return names
    return [n for n in names if privileged_knowledge(n) is None]


def _oracle_rows(
    dataset: Dataset, names: list[str], oracle_reference: bool
) -> tuple[list[str], str | None]:
    """The auxiliary oracle row (for ``rmse_vs_oracle``) or the note why there is none."""
    has_truth = any(c.startswith("true_") for c in dataset.frame.columns)
    if ORACLE in names:
        if not has_truth:
            raise DataError(
                "the oracle needs the true_* columns, which this data lacks; "
                "drop 'oracle' from the models"
            )
        return [], None
    if not oracle_reference and dataset.config is None:  # user data, not requested: no note
        return [], None
    if not oracle_reference:
        note = "the oracle was not run (oracle_reference=False); rmse_vs_oracle is NaN"
    elif not has_truth:
        note = "no true_* columns in the data: the oracle cannot run; rmse_vs_oracle is NaN"
    elif dataset.config is None:
        note = (
            "the data carries no scenario config (a CSV or a user's own data): the "
            "oracle cannot run; rmse_vs_oracle is NaN"
        )
    elif ORACLE not in available_models():
        note = "the oracle model is not registered; rmse_vs_oracle is NaN"
    else:
        return [ORACLE], None
    if oracle_reference:
        warnings.warn(note, stacklevel=4)
    return [], note


def _plan(
    dataset: Dataset,
    models: Sequence[Any] | str | None,
    opts: dict[str, Any],
) -> _Plan:
    """Resolve the rows, the oracle, the splits and every task's specification."""
    names, objects = resolve_rows(models, default_models(dataset), opts["model_params"])
    if opts["references"]:  # the references last
        names += [m for m in REFERENCE_MODELS if m not in names]
    preset = getattr(dataset.config, "preset", None)
    names, base_of, params, pairs = _row_params(
        names, objects, opts["model_params"], preset, opts["ablation"]
    )
    aux, oracle_note = _oracle_rows(dataset, names, opts["oracle_reference"])
    base_of.update({a: a for a in aux})
    protocol = opts["protocol"]
    n_eff, r_eff = effective_layout(protocol, opts["n_splits"], opts["repeats"])
    splits = make_splits(dataset.frame["subject_id"].to_numpy(), protocol,
                         n_splits=opts["n_splits"], repeats=opts["repeats"], seed=opts["seed"])
    data_hash = dataset.content_hash()
    common = {
        "dataset": data_hash,
        "protocol": protocol,
        "n_splits": n_eff,
        "seed": int(opts["seed"]),
        "timing": tasks.canonical(dict(opts["timing"])),
    }
    makers = {n: objects[n] if n in objects else get_model_class(base_of[n])
              for n in [*names, *aux]}
    # a row's code outside the package, and an estimator object's class and parameters
    ident = {n: {"code": tasks.external_code_digest(_class_of(m)),
                 **({"estimator": estimator_identity(objects[n])} if n in objects else {})}
             for n, m in makers.items()}
    planned = []
    for split in splits:
        for name in [*names, *aux]:
            spec = tasks.stamp(
                {
                    **common,
                    **ident[name],
                    "model": name,
                    "seed_model": base_of[name],
                    "params": tasks.canonical(dict(params.get(name, {}))),
                    "repeat": split.repeat,
                    "fold": split.fold,
                    "timed": split.repeat == 0 and split.fold == 0,
                }
            )
            # a row whose fit is its PINN's (a no-physics row of a PINN at λ = 0) shares
            # that fit's task: the same model, seeds and parameters, fitted once
            same = base_of[name] != name and params.get(name) == params.get(base_of[name])
            key = tasks.task_key({**spec, "model": base_of[name]} if same else spec)
            planned.append(_Task(key, spec, split, makers[name]))
    drop_models = resolve_drop_one_models(opts["drop_one_models"], names)
    if opts["drop_one_models"] is None and len(led_wavelengths(dataset)) < 2:
        drop_models = []  # the default asks nothing of a one-LED device; a request is refused
    drops = _drop_tasks(dataset, drop_models, splits, planned)
    return _Plan(
        names, aux, params, oracle_note, protocol, n_eff, r_eff, data_hash, splits, planned,
        pairs, drops, drop_models, objects,
    )


def _drop_tasks(
    dataset: Dataset, models: list[str], splits: list[Split], planned: list[_Task]
) -> list[_Task]:
    """One refit per model × fold of the first repeat(s) × LED, from the model's own task
    of that fold (same specification but ``drop_nm`` and untimed)."""
    if not models:
        return []
    wavelengths = led_wavelengths(dataset)
    if len(wavelengths) < 2:
        raise DataError(
            f"drop-one-LED refits need a device with two LEDs or more; this one has "
            f"{len(wavelengths)}: give drop_one_models='none' (CLI --drop-one none)"
        )
    own = {(t.spec["model"], t.split.repeat, t.split.fold): t for t in planned}
    out = []
    for split in splits:
        if split.repeat >= DROP_ONE_REPEATS:
            continue
        for name in models:
            base = own[(name, split.repeat, split.fold)]
            for w in wavelengths:
                spec = {**base.spec, "timed": False, "drop_nm": w}
                out.append(_Task(tasks.task_key(spec), spec, split, base.maker))
    return out


# --------------------------------------------------------------------------- run
def _execute(
    plan: _Plan,
    cache: tasks.TaskCache,
    pending: list[str],
    dataset: Dataset,
    opts: dict[str, Any],
) -> None:
    """Run the pending tasks (serially or on ``jobs`` processes) into ``cache``."""
    by_key: dict[str, _Task] = {}
    for t in [*plan.tasks, *plan.drop_tasks]:  # a shared fit runs as its first row
        by_key.setdefault(t.key, t)
    items = [
        (by_key[k].maker, by_key[k].spec, dataset, by_key[k].split, opts["timing"]) for k in pending
    ]
    hooks = task_hooks(
        "benchmark", len(by_key), len(cache.results), "cached", show=opts["progress"],
        describe=lambda spec: f"{spec['model']} {_task_tag(spec).replace('-', ' ')}",
        on_task=opts["on_task"],
    )
    with hooks as done, warnings.catch_warnings():
        # loky replaces a worker whose memory grew, and says so; results are unaffected
        warnings.filterwarnings("ignore", message="A worker stopped while some jobs")
        stream = executors.run_unordered(_run_task_of, items, jobs=opts["jobs"])
        cache.collect(stream, pending, plan.specs(), _task_tag, on_done=done)


def _valid_result(spec: Mapping[str, Any], result: Any) -> bool:
    return isinstance(result, dict) and isinstance(result.get("predicted_mgdl"), list)


def _meta(
    dataset: Dataset, plan: _Plan, cache: tasks.TaskCache, n_pending: int, opts: dict[str, Any]
) -> dict[str, Any]:
    """The run's metadata (``meta.json``): protocol, data, models, methods, task counts."""
    n_total = len(plan.specs())  # fits: a shared fit counts once
    return {
        "protocol": plan.protocol,
        "n_splits": plan.n_splits,
        "repeats": plan.repeats,
        "seed": int(opts["seed"]),
        "preset": getattr(dataset.config, "preset", None),
        "dataset_hash": plan.data_hash,
        "dataset_seed": dataset.seed,
        "n_subjects": int(pd.unique(dataset.frame["subject_id"].to_numpy()).size),
        "n_snapshots": int(len(dataset.frame)),
        "adc_bits": dataset.metadata.get("adc_bits", getattr(
            getattr(dataset.config, "hardware", None), "adc_bits", None)),  # issue 28
        "version": __version__,
        "config": None if dataset.config is None else json.loads(dataset.config.to_json()),
        "models": plan.names,
        "estimators": describe_entries(plan.objects),  # rows given as objects: fitted as given
        "auxiliary_models": plan.aux,
        "model_params": tasks.canonical({k: v for k, v in plan.model_params.items() if v}),
        "references": [m for m in REFERENCE_MODELS if m in plan.names],
        "ablation": [n for n in plan.names if ablation_base(n) is not None],
        "ablation_pairs": plan.ablation_pairs,
        "ablation_method": _METHODS["ablation_method"],
        "drop_one_models": plan.drop_one_models,
        "drop_one_method": _METHODS["drop_one_method"],
        "n_boot": opts["n_boot"],
        "alpha": opts["alpha"],
        "ci_level": 0.95,
        "ci_method": _METHODS["ci_method"],
        "comparison_method": _METHODS["comparison_method"],
        "timing_method": _METHODS["timing_method"],
        "oracle_note": plan.oracle_note,
        "study_protocol": STUDY_PROTOCOL,
        "jobs": opts["jobs"],
        "tasks_total": n_total,
        "tasks_cached": n_total - n_pending,
        "tasks_computed": n_pending,
        "tasks_corrupt": cache.n_corrupt,
        "tasks_cpu_s": float(sum(r.get("task_cpu_s", np.nan) for r in cache.results.values())),
        "interval_method": _interval_method(plan.protocol),
        "interval_levels_pct": [round(100 * a) for a in LEVELS],
        "calibration_readings": opts["calibration"],
    }


#: The methods ``meta.json`` names (the same for every run).
_METHODS = {
    "ablation_method": (
        "each PINN refitted with lambda_phys=0, everything else identical (same "
        "splits, seeds and other parameters); paired cluster bootstrap of the RMSE "
        "difference (with physics minus without), Holm over the tested pairs; a PINN "
        "tuned to lambda_phys=0 is its no-physics fit (untested, no verdict) and is also "
        "run at the best lambda_phys > 0 of the tuning's validation curve"
    ),
    "drop_one_method": (
        "each model refitted without one LED's columns (adc_<nm>, adc_ref_<nm>; the "
        "scenario's LED record removed), on the folds of the first repeat with the same "
        "seeds and parameters, scored on the same held-out subjects; paired cluster "
        "bootstrap of the RMSE difference (without the LED minus with every LED, the "
        "latter on the same repeat), Holm over each model's LEDs"
    ),
    "ci_method": (
        "percentile cluster bootstrap over subjects; metrics computed per "
        "repeat and averaged over repeats (same resampled subjects in every "
        "repeat)"
    ),
    "comparison_method": (
        "paired cluster bootstrap of the RMSE difference (two-sided, "
        "centred) and Wilcoxon signed-rank on per-subject RMSE; Holm "
        "within each family; significant = bootstrap p_holm < alpha"
    ),
    "timing_method": (
        "median of single-row predict calls after warm-up, batch "
        "throughput on 10,000 tiled rows; first fold of the first repeat; "
        "torch on one thread"
    ),
}


def _interval_method(protocol: str) -> str:
    return (
        "subject-grouped conformal, no extra fit: each test fold's half-width is the "
        "conformal quantile (subjects weighted equally) of the absolute held-out residuals "
        + (
            "of the validation subjects"
            if protocol == "paper-split"
            else "of the other folds of the same repeat"
        )
        + "; coverage per repeat averaged over repeats, 95 % CI by cluster bootstrap over "
        "subjects; width = mean interval width"
    )


def _checked_options(proto: Protocol, **rest: Any) -> dict[str, Any]:
    """:func:`run_benchmark`'s options by keyword: the Protocol's, then the rest."""
    opts = {"protocol": proto.splitter, "n_splits": proto.n_splits, "repeats": proto.repeats,
            "seed": proto.seed, "n_boot": proto.resamples, "calibration": proto.calibration,
            **rest}
    opts["jobs"] = check_positive_int("jobs", opts["jobs"])
    opts["timing"] = dict(opts["timing"] or {})
    return opts


def run_benchmark(
    dataset: Dataset | pd.DataFrame,
    models: Sequence[Any] | str | None = None,
    *,
    protocol: str | Protocol = "grouped-cv",
    out: str | Path | None = None,
    jobs: int = 1,
    progress: bool = False,
    model_params: dict[str, dict[str, Any]] | None = None,
    alpha: float = 0.05,
    timing: dict[str, Any] | None = None,
    drop_one_models: Sequence[str] | str | None = None,
    oracle_reference: bool = True,
    on_task: Callable[[dict[str, Any], bool], None] | None = None,
    references: bool = False,
    ablation: bool = False,
    **protocol_options: Any,
) -> BenchmarkResult:
    """Fit and score every model on subject-grouped splits.

    Parameters
    ----------
    dataset : Dataset or pandas.DataFrame
        Snapshots with ``subject_id`` and ``glucose_mgdl``.
    models : sequence, comma-separated str or estimator, optional
        Registry names (default: every registered model; on data without a scenario,
        a device's own file, every deployable one: :func:`default_models`) and, as scikit-learn's
        ``cross_validate`` takes, unfitted estimator objects (anything with ``fit``,
        ``predict`` and ``get_params``) or ``(label, estimator)`` pairs
        (:mod:`~nirglucose.evaluation.estimators`). An object's row is labelled by the
        pair's label, else its class's registry name, else its class name; two rows
        with one label are refused. Each task fits its own ``sklearn.base.clone`` (the
        caller's object stays unfitted), with the task's seed in every ``random_state``
        left None; it is fitted as given (no tuning grid or tuned parameters, no
        physics ablation; ``model_params[label]`` applies through ``set_params``), which
        ``meta["estimators"]`` records. The package's own estimators take the Dataset,
        as registered names do; any other gets ``fit(X, y)`` with ``X`` the measured
        columns. With ``jobs > 1`` the objects are pickled to the worker processes.
    protocol : Protocol or {"grouped-cv", "paper-split"}
        How the models are evaluated
        (:class:`~nirglucose.evaluation.protocol.Protocol`: the splitter, its folds and
        repeats, the seed of splits, model initialisation and bootstrap, the bootstrap
        resamples and the personal calibration readings), or a splitter name for that
        splitter with the Protocol's defaults.
    out : str or Path, optional
        Directory for the task cache (``out/.tasks``) and the result files.
    jobs : int
        Worker processes over tasks (results identical for any value).
    progress : bool
        Show a rich progress bar on stderr.
    model_params : dict, optional
        Model name (row label) -> constructor keyword arguments (over the preset's
        tuned ones), or ``set_params`` arguments of an estimator object.
    alpha : float
        Family-wise significance level of the paired tests.
    timing : dict, optional
        Keyword arguments of :func:`~nirglucose.evaluation.benchmark.timing.measure_latency`.
    drop_one_models : sequence of str, comma-separated str, or None
        Models refitted without each LED (``drop_one``, see *Drop-one-LED refits*
        above): None takes :data:`~nirglucose.evaluation.benchmark.drop_one.DEFAULT_DROP_ONE_MODELS`
        among ``models``; ``"none"`` runs no refit (an empty ``drop_one``: what a sweep,
        which reads the metrics only, asks for); ``"all"`` refits every row.
    oracle_reference : bool
        Fit the oracle for ``rmse_vs_oracle`` when it is not among ``models`` (and the
        data has ``true_*`` columns); False leaves the ratio NaN.
    on_task : callable, optional
        Called as ``on_task(spec, cached)`` for every task (progress hooks, tests).
    references : bool
        Add :data:`REFERENCE_MODELS` to ``models``.
    ablation : bool
        Also run every PINN among the models with ``lambda_phys=0`` (rows
        ``<name>/no-physics``, paired differences in ``ablation``).
    **protocol_options
        Deprecated (removed in 0.3): the Protocol's options as keywords, ``n_splits``,
        ``repeats``, ``seed``, ``n_boot`` (its ``resamples``) and ``calibration``; they
        warn and are folded into the Protocol. Give ``protocol=Protocol(...)``.

    Returns
    -------
    BenchmarkResult
        Built once, with every table of the run: metrics, predictions, comparisons,
        ablation, personal calibration (``Protocol.calibration`` readings of each test
        subject calibrate that person and only their later readings are scored,
        :mod:`~nirglucose.calibration.personal`; empty when 0), the inverse task and
        the drop-one-LED refits. The main metrics always score every held-out reading.

    Examples
    --------
    >>> import nirglucose as ng
    >>> from nirglucose.evaluation import Protocol
    >>> ds = ng.simulate("paper", n_subjects=10, per_subject=2, seed=0)
    >>> res = run_benchmark(ds, ["mean"], protocol=Protocol(repeats=1, resamples=100),
    ...                     oracle_reference=False, drop_one_models="none")
    >>> list(res.metrics["model"]), res.meta["repeats"]
    (['mean'], 1)
    """
    t_start = time.perf_counter()
    dataset = _as_dataset(dataset)
    proto = protocol_of(protocol, protocol_options)
    opts = _checked_options(proto, out=out, jobs=jobs, progress=progress, alpha=alpha,
                            model_params=model_params, timing=timing, on_task=on_task,
                            drop_one_models=drop_one_models, references=references,
                            oracle_reference=oracle_reference, ablation=ablation)
    plan = _plan(dataset, models, opts)
    cache = tasks.TaskCache(out, valid=_valid_result)
    tasks.clear_outputs(out, STALE_FILES)
    specs = plan.specs()
    pending = cache.lookup(
        specs, _task_tag, None if on_task is None else lambda spec: on_task(spec, True)
    )
    _execute(plan, cache, pending, dataset, opts)
    meta = _meta(dataset, plan, cache, len(pending), opts)
    result = _result(dataset, plan, cache, meta, opts, t_start)
    if out is not None:
        result.save(out)
    return result


def _result(dataset: Dataset, plan: _Plan, cache: tasks.TaskCache, meta: dict[str, Any],
            opts: dict[str, Any], t_start: float) -> BenchmarkResult:
    """The :class:`BenchmarkResult` of the finished tasks, built once with every table
    (``t_start``: when the run began, for ``meta["wall_time_s"]``)."""
    seed, n_boot, alpha = opts["seed"], opts["n_boot"], opts["alpha"]
    runs = [(t.spec, t.split, cache.results[t.key]) for t in plan.tasks]
    tables = aggregate(dataset, runs, plan.names, plan.aux, meta, n_boot=n_boot, alpha=alpha,
                       seed=seed)
    preds = tables["predictions"]
    if opts["calibration"]:
        tables["calibration"] = personal_calibration(
            dataset, preds, plan.splits, opts["calibration"], n_boot=n_boot, seed=seed)
    tables["inverse"] = inverse_table(dataset.frame, runs, plan.names, n_boot=n_boot,
                                      seed=seed)
    drops = [(t.spec, t.split, cache.results[t.key]) for t in plan.drop_tasks]
    tables["drop_one"] = drop_one_table(preds, refit_predictions(dataset.frame, drops),
                                        n_boot=n_boot, seed=seed, alpha=alpha)
    meta["wall_time_s"] = time.perf_counter() - t_start
    return BenchmarkResult(**tables)
