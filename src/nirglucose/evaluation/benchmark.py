"""The benchmark: every model, the same subject-grouped splits, honest statistics.

:func:`run_benchmark` fits each model on each split of the protocol
(:mod:`~nirglucose.evaluation.splits`), scores the held-out predictions with cluster
bootstrap intervals and paired comparisons (:mod:`~nirglucose.evaluation.stats`),
times every model the same way (:mod:`~nirglucose.evaluation.timing`) and measures
per-wavelength permutation importance (:mod:`~nirglucose.evaluation.importance`).
It computes only; figures and the report read the :class:`BenchmarkResult`.

Tasks
    Each (model, repeat, fold) is an independent task seeded from ``(seed, model,
    repeat, fold)``, so results are the same for any number of worker processes. Torch
    runs on one thread inside a task (the same arithmetic whatever ``jobs`` is).
    With ``out`` given, each task's result is written atomically to
    ``out/.tasks/<model>-r<repeat>-f<fold>-<hash>.json`` as it finishes, the hash
    covering its full specification (dataset hash, model, parameters, protocol, folds,
    seed, repeat, fold, package version, a hash of the estimator code); a rerun loads
    finished tasks instead of recomputing them, and a corrupt or mismatching file is
    recomputed.

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
    built with the tuned hyper-parameters of the data's preset (:func:`_model_params`),
    overridden by ``model_params``. ``ablation=True`` also runs every PINN of
    :data:`PINN_MODELS` with its physics term off (``lambda_phys=0``; everything else
    identical: the same folds, the same seeds, the same other parameters) as the row
    ``<name>/no-physics``; ``ablation.csv`` holds the paired RMSE difference (with
    physics minus without) with its cluster-bootstrap CI and Holm-adjusted p-value.

Scoring
    Predictions below 0 mg/dL are scored as 0 and non-finite ones as the median
    training target of their fold (the error grids need a non-negative number); both
    are counted in ``n_invalid_predictions`` and the raw value is kept in
    ``predictions``. Metrics are computed per repeat and averaged over repeats.
    Latency and batch throughput are measured on the first fold of the first repeat;
    ``n_parameters`` is the fitted model's count there.
"""

from __future__ import annotations

import hashlib
import inspect
import json
import math
import sys
import time
import warnings
from collections.abc import Callable, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from ..dataset import Dataset, atomic_write
from ..exceptions import ConfigError, DataError
from .calibration import CALIBRATION_COLUMNS, check_k, personal_calibration
from .conformal import LEVELS, coverage_summary, out_of_fold_intervals
from .progress import TaskProgress
from .reference import MODEL_LABELS, STUDY_ORDER, STUDY_PROTOCOL, STUDY_TABLE
from .splits import Split, check_protocol, effective_layout, make_splits
from .stats import DEFAULT_N_BOOT, PAIRED_COLUMNS, cluster_bootstrap_metrics, compare_models

__all__ = [
    "BenchmarkResult",
    "run_benchmark",
    "METRIC_COLUMNS",
    "PREDICTION_COLUMNS",
    "COMPARISON_COLUMNS",
    "IMPORTANCE_COLUMNS",
    "OUTPUT_FILES",
    "TASK_FORMAT",
    "ORACLE",
    "REFERENCE_MODELS",
    "PINN_MODELS",
    "NO_PHYSICS",
    "ABLATION_COLUMNS",
]

#: Version of the task-file layout (part of every task hash).
TASK_FORMAT = 2
#: Registry name of the oracle bound.
ORACLE = "oracle"
#: Reference learners added by ``references=True`` (no skill and off-the-shelf).
REFERENCE_MODELS = ("mean", "gp", "gbr")
#: The physics-informed networks of the study (ablated by ``ablation=True``).
PINN_MODELS = ("original-pinn", "optimized-pinn", "rte-pinn", "selective-rte-pinn")
#: Suffix of a PINN's row with its physics term off.
NO_PHYSICS = "/no-physics"
#: Columns of ``ablation.csv``: one row per PINN, with physics minus without.
ABLATION_COLUMNS = (
    "model",
    "ablated_model",
    "rmse_mgdl",
    "ablated_rmse_mgdl",
    "rmse_diff_mgdl",
    "ci_low",
    "ci_high",
    "p_value",
    "p_holm",
    "p_wilcoxon",
    "significant",
    "physics_helps",
)

#: Columns of ``BenchmarkResult.metrics`` / ``metrics.csv``, in order.
METRIC_COLUMNS = (
    "model",
    "label",
    "rmse_mgdl",
    "rmse_ci_low",
    "rmse_ci_high",
    "mard_pct",
    "mard_ci_low",
    "mard_ci_high",
    "clarke_a_pct",
    "clarke_a_ci_low",
    "clarke_a_ci_high",
    "clarke_ab_pct",
    "parkes_a_pct",
    "parkes_ab_pct",
    "within15_pct",
    "within15_ci_low",
    "within15_ci_high",
    "within20_pct",
    "iso15197_pct",
    "bias_mgdl",
    "bias_ci_low",
    "bias_ci_high",
    "loa_low_mgdl",
    "loa_high_mgdl",
    "n_parameters",
    "latency_single_ms",
    "latency_single_p90_ms",
    "throughput_per_s",
    "latency_input",
    "rmse_vs_oracle",
    "fit_time_s",
    "n_predictions",
    "n_invalid_predictions",
    "coverage90_pct",
    "coverage90_ci_low",
    "coverage90_ci_high",
    "width90_mgdl",
    "coverage80_pct",
    "width80_mgdl",
)
#: Columns of ``predictions.parquet``.
PREDICTION_COLUMNS = (
    "model",
    "subject_id",
    "measurement_id",
    "repeat",
    "fold",
    "reference_mgdl",
    "predicted_mgdl",
    "scored_mgdl",
    "lower90_mgdl",
    "upper90_mgdl",
)
#: Columns of ``comparisons.csv``.
COMPARISON_COLUMNS = ("family", *PAIRED_COLUMNS, "study_holds")
#: Columns of ``importance.csv``.
IMPORTANCE_COLUMNS = (
    "model",
    "wavelength_nm",
    "rmse_increase_mgdl",
    "rmse_increase_sd_mgdl",
    "n_tasks",
)
#: Files :meth:`BenchmarkResult.save` writes.
OUTPUT_FILES = (
    "metrics.csv",
    "metrics.json",
    "table.md",
    "predictions.parquet",
    "comparisons.csv",
    "histories.json",
    "importance.csv",
    "ablation.csv",
    "calibration.csv",
    "dataset.parquet",
    "meta.json",
)

_IMPORTANCE_REPEATS = 3


# --------------------------------------------------------------------------- result
@dataclass
class BenchmarkResult:
    """What :func:`run_benchmark` computed.

    Attributes
    ----------
    metrics : pandas.DataFrame
        One row per model (:data:`METRIC_COLUMNS`), best RMSE first.
    predictions : pandas.DataFrame
        Every out-of-fold prediction (:data:`PREDICTION_COLUMNS`).
    comparisons : pandas.DataFrame
        Paired tests (:data:`COMPARISON_COLUMNS`): family ``"vs_best"`` (every model
        against the best non-oracle model) and ``"study_order"`` (every pair the study
        ranked, worse minus better; ``study_holds`` says whether our ranking agrees).
    histories : dict
        Model -> per-epoch dicts of the first fold of the first repeat (empty list for
        models without training history).
    importance : pandas.DataFrame
        Permutation importance per model and wavelength (:data:`IMPORTANCE_COLUMNS`).
    meta : dict
        Protocol, seeds, dataset hash and config, versions, task counts, methods;
        ``study_orderings`` says which of the study's pairwise orderings hold here.
    ablation : pandas.DataFrame
        Physics ablation (:data:`ABLATION_COLUMNS`); empty without ``ablation=True``.
    dataset : Dataset, optional
        The dataset benchmarked (written to ``dataset.parquet``).
    calibration : pandas.DataFrame
        Personal calibration (:data:`~nirglucose.evaluation.calibration.CALIBRATION_COLUMNS`);
        empty without ``calibration=k``.
    """

    metrics: pd.DataFrame
    predictions: pd.DataFrame
    comparisons: pd.DataFrame
    histories: dict[str, list[dict[str, Any]]]
    importance: pd.DataFrame
    meta: dict[str, Any]
    dataset: Dataset | None = field(default=None, repr=False)
    ablation: pd.DataFrame = field(default_factory=lambda: pd.DataFrame(columns=ABLATION_COLUMNS))
    calibration: pd.DataFrame = field(
        default_factory=lambda: pd.DataFrame(columns=CALIBRATION_COLUMNS)
    )

    def table_markdown(self) -> str:
        """The study's Table 1 layout with our values (95 % CIs) beside the study's."""
        return _table_markdown(self)

    def save(self, out: str | Path) -> Path:
        """Write :data:`OUTPUT_FILES` into directory ``out`` (created if its parent exists)."""
        out = _prepare_out(out)
        _write_csv(out / "metrics.csv", self.metrics)
        _write_text(
            out / "metrics.json",
            _dumps(
                {
                    "meta": self.meta,
                    "metrics": self.metrics.to_dict(orient="records"),
                    "ablation": self.ablation.to_dict(orient="records"),
                    "calibration": self.calibration.to_dict(orient="records"),
                }
            ),
        )
        _write_text(out / "table.md", self.table_markdown())
        atomic_write(
            out / "predictions.parquet", lambda tmp: self.predictions.to_parquet(tmp, index=False)
        )
        _write_csv(out / "comparisons.csv", self.comparisons)
        _write_text(out / "histories.json", _dumps(self.histories))
        _write_csv(out / "importance.csv", self.importance)
        _write_csv(out / "ablation.csv", self.ablation)
        _write_csv(out / "calibration.csv", self.calibration)
        if self.dataset is not None:
            self.dataset.save(out / "dataset.parquet")
        _write_text(out / "meta.json", _dumps(self.meta))
        return out


def _clean(obj: Any) -> Any:
    """JSON-safe copy: NaN/inf -> None, numpy scalars -> Python, tuples -> lists."""
    if isinstance(obj, dict):
        return {str(k): _clean(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [_clean(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return [_clean(v) for v in obj.tolist()]
    if isinstance(obj, np.bool_ | bool):
        return bool(obj)
    if isinstance(obj, np.integer):
        return int(obj)
    if isinstance(obj, float | np.floating):
        v = float(obj)
        return v if math.isfinite(v) else None
    return obj


def _dumps(obj: Any) -> str:
    return json.dumps(_clean(obj), indent=2, sort_keys=False, allow_nan=False) + "\n"


def _write_text(path: Path, text: str) -> None:
    atomic_write(path, lambda tmp: Path(tmp).write_text(text, encoding="utf-8"))


def _write_csv(path: Path, frame: pd.DataFrame) -> None:
    atomic_write(path, lambda tmp: frame.to_csv(tmp, index=False))


def _prepare_out(out: str | Path) -> Path:
    out = Path(out)
    if not out.exists():
        if not out.parent.exists():
            raise DataError(f"output directory {str(out.parent)!r} does not exist; create it first")
        out.mkdir()
    elif not out.is_dir():
        raise DataError(f"--out {str(out)!r} exists and is not a directory")
    return out


# --------------------------------------------------------------------------- tasks
def _task_seed(seed: int, model: str, repeat: int, fold: int) -> int:
    digest = hashlib.sha256(f"{seed}|{model}|{repeat}|{fold}".encode()).digest()
    return int.from_bytes(digest[:4], "little") & 0x7FFFFFFF


def _jsonable_params(params: dict[str, Any]) -> dict[str, Any]:
    return json.loads(json.dumps(params, sort_keys=True, default=repr))


def _task_key(spec: dict[str, Any]) -> str:
    return hashlib.sha256(json.dumps(spec, sort_keys=True).encode()).hexdigest()[:20]


def _code_fingerprint(cls: type) -> str:
    """Hash of the estimator code a task result depends on.

    Every module of :mod:`nirglucose.models`, :mod:`nirglucose.features` and the file
    defining ``cls``: editing a model invalidates its cached task results (the package
    version alone does not change while developing).
    """
    from .. import __file__ as package_file

    root = Path(package_file).parent
    files = sorted((root / "models").glob("*.py")) + [root / "features.py"]
    try:
        files.append(Path(inspect.getfile(cls)))
    except (TypeError, OSError):
        pass
    h = hashlib.sha256()
    for f in dict.fromkeys(files):
        if f.is_file():
            h.update(f.name.encode())
            h.update(f.read_bytes())
    return h.hexdigest()[:16]


def _checksum(result: dict[str, Any]) -> str:
    return hashlib.sha256(json.dumps(result, sort_keys=True, allow_nan=True).encode()).hexdigest()


def _task_file(tasks_dir: Path, spec: dict[str, Any]) -> Path:
    safe = "".join(ch if ch.isalnum() or ch in "-_" else "_" for ch in spec["model"])
    return tasks_dir / f"{safe}-r{spec['repeat']}-f{spec['fold']}-{_task_key(spec)}.json"


def _load_task(path: Path, spec: dict[str, Any], n_test: int) -> dict[str, Any] | None:
    """A finished task's result, or None when absent, corrupt or not this task's."""
    if not path.exists():
        return None
    try:
        doc = json.loads(path.read_text(encoding="utf-8"))
        result = doc["result"]
        ok = (
            doc["spec"] == spec
            and doc["checksum"] == _checksum(result)
            and len(result["predicted_mgdl"]) == n_test
        )
    except (OSError, ValueError, KeyError, TypeError):
        ok = False
    if not ok:
        warnings.warn(f"task file {path.name} is corrupt or stale; recomputing it", stacklevel=3)
        return None
    return result


def _history(model: Any) -> list[dict[str, Any]]:
    hist = getattr(model, "history_", None) or []
    out = []
    for row in hist:
        if isinstance(row, dict):
            out.append(
                {
                    str(k): (
                        float(v)
                        if isinstance(v, float | np.floating)
                        else int(v)
                        if isinstance(v, int | np.integer)
                        else v
                        if isinstance(v, str | bool | None)
                        else repr(v)
                    )
                    for k, v in row.items()
                }
            )
    return out


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


def _run_task(
    cls: type,
    spec: dict[str, Any],
    dataset: Dataset,
    split: Split,
    path: Path | None,
    timing: dict[str, Any],
) -> dict[str, Any]:
    """Fit one model on one split; write the result atomically to ``path``."""
    from .importance import permutation_importance
    from .timing import measure_latency, timing_inputs

    frame = dataset.frame

    def rows(idx):
        return Dataset(
            frame.iloc[idx].reset_index(drop=True), config=dataset.config, seed=dataset.seed
        )

    params = dict(spec["params"])
    # an ablated PINN draws the same seeds as its original: a paired comparison
    seed_name = spec.get("seed_model", spec["model"])
    task_seed = _task_seed(spec["seed"], seed_name, spec["repeat"], spec["fold"])
    if "random_state" in inspect.signature(cls).parameters and "random_state" not in params:
        params["random_state"] = task_seed
    train, test = rows(split.train), rows(split.test)
    fit_kwargs: dict[str, Any] = {}
    if split.val is not None and "X_val" in inspect.signature(cls.fit).parameters:
        val = rows(split.val)
        fit_kwargs = {"X_val": val, "y_val": val.frame["glucose_mgdl"].to_numpy(float)}
    cpu0, wall0 = time.process_time(), time.perf_counter()
    with _one_thread_torch():
        model = cls(**params)
        t0 = time.perf_counter()
        model.fit(train, **fit_kwargs)
        fit_time = time.perf_counter() - t0
        pred = np.asarray(model.predict(test), dtype=float).ravel()
        if pred.shape != (len(split.test),):
            raise DataError(
                f"model {spec['model']!r} returned {pred.shape} predictions for "
                f"{len(split.test)} rows"
            )
        val_pred = None
        if split.val is not None:  # calibrates the conformal intervals of paper-split
            val_pred = np.asarray(model.predict(rows(split.val)), dtype=float).ravel()
        latency: dict[str, Any] = {}
        if spec["timed"]:
            form, data = timing_inputs(model, test)
            latency = {**measure_latency(model, data, **timing), "latency_input": form}
        imp = permutation_importance(
            model, test, n_repeats=spec["importance_repeats"], seed=task_seed
        )
    result = {
        "predicted_mgdl": [float(v) for v in pred],
        "val_predicted_mgdl": None if val_pred is None else [float(v) for v in val_pred],
        "fallback_mgdl": float(np.median(train.frame["glucose_mgdl"].to_numpy(float))),
        "n_parameters": int(getattr(model, "n_parameters", -1)),
        "fit_time_s": fit_time,
        "task_wall_s": time.perf_counter() - wall0,
        "task_cpu_s": time.process_time() - cpu0,
        "history": _history(model),
        "timing": latency,
        "importance": {
            "wavelength_nm": imp["wavelength_nm"].tolist(),
            "rmse_increase_mgdl": imp["rmse_increase_mgdl"].tolist(),
            "rmse_increase_sd_mgdl": imp["rmse_increase_sd_mgdl"].tolist(),
        },
    }
    if path is not None:
        doc = {"spec": spec, "checksum": _checksum(result), "result": result}
        text = json.dumps(doc, sort_keys=True, allow_nan=True)
        atomic_write(path, lambda tmp: Path(tmp).write_text(text, encoding="utf-8"))
    return result


def _indexed_task(i: int, *args: Any) -> tuple[int, dict[str, Any]]:
    return i, _run_task(*args)


# --------------------------------------------------------------------------- main
def _resolve_models(models: Sequence[str] | str | None) -> list[str]:
    from ..models.registry import available_models, get_model_class

    valid = available_models()
    if models is None:
        if not valid:
            raise ConfigError("no models are registered")
        return valid
    if isinstance(models, str):
        models = [m.strip() for m in models.split(",") if m.strip()]
    names = list(dict.fromkeys(models))
    if not names:
        raise ConfigError(f"no models given; valid: {', '.join(valid)}")
    for name in names:
        get_model_class(name)  # raises ConfigError listing the valid names
    return names


def _model_params(name: str, preset: str | None) -> dict[str, Any]:
    """Tuned constructor arguments of model ``name`` on ``preset`` ({} when none).

    The one place the benchmark asks for tuned hyper-parameters
    (:func:`nirglucose.models.tuned_params`).
    """
    from ..models import tuned_params

    if preset is None:
        return {}
    return dict(tuned_params(name, preset))


def _variants(names: list[str], ablation: bool) -> dict[str, tuple[str, dict[str, Any]]]:
    """Row name -> (registered model, forced parameters); PINNs twice under ablation."""
    out: dict[str, tuple[str, dict[str, Any]]] = {n: (n, {}) for n in names}
    if ablation:
        for n in names:
            if n in PINN_MODELS:
                out[n + NO_PHYSICS] = (n, {"lambda_phys": 0.0})
    return out


def _check_positive(name: str, value: Any) -> int:
    if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < 1:
        raise ConfigError(f"{name} must be a positive integer, got {value!r}")
    return int(value)


def run_benchmark(
    dataset: Dataset | pd.DataFrame,
    models: Sequence[str] | str | None = None,
    *,
    protocol: str = "grouped-cv",
    n_splits: int = 5,
    repeats: int = 3,
    seed: int = 0,
    out: str | Path | None = None,
    jobs: int = 1,
    progress: bool = False,
    model_params: dict[str, dict[str, Any]] | None = None,
    n_boot: int = DEFAULT_N_BOOT,
    alpha: float = 0.05,
    timing: dict[str, Any] | None = None,
    importance_repeats: int = _IMPORTANCE_REPEATS,
    oracle_reference: bool = True,
    on_task: Callable[[dict[str, Any], bool], None] | None = None,
    references: bool = False,
    ablation: bool = False,
    calibration: int = 0,
) -> BenchmarkResult:
    """Fit and score every model on subject-grouped splits.

    Parameters
    ----------
    dataset : Dataset or pandas.DataFrame
        Snapshots with ``subject_id`` and ``glucose_mgdl``.
    models : sequence of str or comma-separated str, optional
        Registry names (default: every registered model).
    protocol : {"grouped-cv", "paper-split"}
        See :mod:`~nirglucose.evaluation.splits`.
    n_splits, repeats : int
        Folds and repeats of ``grouped-cv`` (``paper-split`` runs one split).
    seed : int
        Seed of splits, model initialisation and bootstrap.
    out : str or Path, optional
        Directory for the task cache (``out/.tasks``) and the result files.
    jobs : int
        Worker processes over tasks (results identical for any value).
    progress : bool
        Show a rich progress bar on stderr.
    model_params : dict, optional
        Model name -> constructor keyword arguments (over the preset's tuned ones).
    n_boot : int
        Bootstrap resamples for intervals and paired tests.
    alpha : float
        Family-wise significance level of the paired tests.
    timing : dict, optional
        Keyword arguments of :func:`~nirglucose.evaluation.timing.measure_latency`.
    importance_repeats : int
        Permutations per wavelength channel.
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
    calibration : int
        Personal calibration protocol: each test subject's first ``calibration``
        readings (1 or 2) calibrate that person and only their later readings are
        scored (:mod:`~nirglucose.evaluation.calibration`; ``calibration.csv``);
        0 (default) runs none. The main metrics always score every held-out reading.

    Returns
    -------
    BenchmarkResult
    """
    from .. import __version__
    from ..models.registry import available_models, get_model_class

    t_start = time.perf_counter()
    if isinstance(dataset, pd.DataFrame):
        dataset = Dataset(dataset)
    if not isinstance(dataset, Dataset):
        raise DataError(f"expected a Dataset or DataFrame, got {type(dataset).__name__}")
    frame = dataset.frame
    missing = [c for c in ("subject_id", "glucose_mgdl") if c not in frame]
    if missing:
        raise DataError(f"the benchmark needs columns {missing}")
    check_protocol(protocol)
    n_splits = _check_positive("n_splits", n_splits)
    repeats = _check_positive("repeats", repeats)
    jobs = _check_positive("jobs", jobs)
    n_boot = _check_positive("n_boot", n_boot)
    calibration = check_k(calibration)
    names = _resolve_models(models)
    if references:
        names += [m for m in REFERENCE_MODELS if m not in names]
    explicit = dict(model_params or {})
    unknown = sorted(set(explicit) - set(names) - {ORACLE})
    if unknown:
        raise ConfigError(f"model_params for models not benchmarked: {unknown}; models: {names}")
    preset = getattr(dataset.config, "preset", None)
    model_params = {
        n: {**_model_params(n, preset), **explicit.get(n, {})} for n in [*names, ORACLE]
    }
    variants = _variants(names, ablation)
    for row, (base, forced) in variants.items():
        if row != base:
            model_params[row] = {**model_params[base], **forced}
    names = list(variants)
    n_splits_eff, repeats_eff = effective_layout(protocol, n_splits, repeats)

    has_truth = any(c.startswith("true_") for c in frame.columns)
    aux: list[str] = []
    oracle_note = None
    if ORACLE not in names:
        if not oracle_reference:
            oracle_note = "the oracle was not run (oracle_reference=False); rmse_vs_oracle is NaN"
        elif not has_truth:
            oracle_note = (
                "no true_* columns in the data: the oracle cannot run; rmse_vs_oracle is NaN"
            )
        elif dataset.config is None:
            oracle_note = (
                "the data carries no scenario config (a CSV or a user's own data): the "
                "oracle cannot run; rmse_vs_oracle is NaN"
            )
        elif ORACLE not in available_models():
            oracle_note = "the oracle model is not registered; rmse_vs_oracle is NaN"
        else:
            aux = [ORACLE]
    elif not has_truth:
        raise DataError(
            "the oracle needs the true_* columns, which this data lacks; "
            "drop 'oracle' from the models"
        )
    if oracle_note and oracle_reference:
        warnings.warn(oracle_note, stacklevel=2)

    groups = frame["subject_id"].to_numpy()
    splits = make_splits(groups, protocol, n_splits=n_splits, repeats=repeats, seed=seed)
    data_hash = dataset.content_hash()
    timing = dict(timing or {})
    base_of = {**{n: variants[n][0] for n in names}, **{a: a for a in aux}}
    code = {name: _code_fingerprint(get_model_class(base_of[name])) for name in [*names, *aux]}
    tasks = []
    for split in splits:
        for name in [*names, *aux]:
            spec = {
                "format": TASK_FORMAT,
                "version": __version__,
                "code": code[name],
                "dataset": data_hash,
                "model": name,
                "seed_model": base_of[name],
                "params": _jsonable_params(model_params.get(name, {})),
                "protocol": protocol,
                "n_splits": n_splits_eff,
                "seed": int(seed),
                "repeat": split.repeat,
                "fold": split.fold,
                "timed": split.repeat == 0 and split.fold == 0,
                "timing": _jsonable_params(timing),
                "importance_repeats": int(importance_repeats),
            }
            tasks.append((spec, split, get_model_class(base_of[name])))

    tasks_dir = None
    if out is not None:
        tasks_dir = _prepare_out(out) / ".tasks"
        tasks_dir.mkdir(exist_ok=True)

    results: dict[int, dict[str, Any]] = {}
    pending = []
    n_corrupt = 0
    for i, (spec, split, _cls) in enumerate(tasks):
        if tasks_dir is None:
            pending.append(i)
            continue
        path = _task_file(tasks_dir, spec)
        existed = path.exists()
        cached = _load_task(path, spec, len(split.test))
        if cached is None:
            n_corrupt += int(existed)
            pending.append(i)
        else:
            results[i] = cached
            if on_task is not None:
                on_task(spec, True)

    bar = TaskProgress("benchmark", len(tasks), len(results), "cached") if progress else None

    def args(i):
        spec, split, cls = tasks[i]
        path = None if tasks_dir is None else _task_file(tasks_dir, spec)
        return cls, spec, dataset, split, path, timing

    try:
        with warnings.catch_warnings():
            # loky replaces a worker whose memory grew, and says so; results are unaffected
            warnings.filterwarnings("ignore", message="A worker stopped while some jobs")
            if jobs == 1 or len(pending) <= 1:
                stream = (_indexed_task(i, *args(i)) for i in pending)
            else:
                from joblib import Parallel, delayed

                stream = Parallel(n_jobs=jobs, return_as="generator_unordered")(
                    delayed(_indexed_task)(i, *args(i)) for i in pending
                )
            for i, res in stream:
                results[i] = res
                if on_task is not None:
                    on_task(tasks[i][0], False)
                if bar is not None:
                    spec = tasks[i][0]
                    bar.advance(f"{spec['model']} r{spec['repeat']} f{spec['fold']}")
    finally:
        if bar is not None:
            bar.close()

    meta = {
        "protocol": protocol,
        "n_splits": n_splits_eff,
        "repeats": repeats_eff,
        "seed": int(seed),
        "preset": getattr(dataset.config, "preset", None),
        "dataset_hash": data_hash,
        "dataset_seed": dataset.seed,
        "n_subjects": int(pd.unique(groups).size),
        "n_snapshots": int(len(frame)),
        "version": __version__,
        "config": None if dataset.config is None else json.loads(dataset.config.to_json()),
        "models": names,
        "auxiliary_models": aux,
        "model_params": _jsonable_params({k: v for k, v in model_params.items() if v}),
        "references": [m for m in REFERENCE_MODELS if m in names],
        "ablation": [n for n in names if n.endswith(NO_PHYSICS)],
        "ablation_method": (
            "each PINN refitted with lambda_phys=0, everything else identical (same "
            "splits, seeds and other parameters); paired cluster bootstrap of the RMSE "
            "difference (with physics minus without), Holm over the PINNs"
        ),
        "n_boot": n_boot,
        "alpha": alpha,
        "ci_level": 0.95,
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
        "oracle_note": oracle_note,
        "study_protocol": STUDY_PROTOCOL,
        "jobs": jobs,
        "tasks_total": len(tasks),
        "tasks_cached": len(tasks) - len(pending),
        "tasks_computed": len(pending),
        "tasks_corrupt": n_corrupt,
        "tasks_cpu_s": float(sum(r.get("task_cpu_s", np.nan) for r in results.values())),
    }
    meta["interval_method"] = (
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
    meta["interval_levels_pct"] = [round(100 * a) for a in LEVELS]
    meta["calibration_readings"] = calibration
    result = _aggregate(
        dataset, tasks, results, names, aux, meta, n_boot=n_boot, alpha=alpha, seed=seed
    )
    if calibration:
        result.calibration = personal_calibration(
            dataset, result.predictions, splits, calibration, n_boot=n_boot, seed=seed
        )
    result.meta["wall_time_s"] = time.perf_counter() - t_start
    if out is not None:
        result.save(out)
    return result

# --------------------------------------------------------------------------- aggregation
def _aggregate(
    dataset, tasks, results, names, aux, meta, *, n_boot, alpha, seed
) -> BenchmarkResult:
    from ..metrics import summary

    frame = dataset.frame
    sid = frame["subject_id"].to_numpy()
    mid = frame["measurement_id"].to_numpy() if "measurement_id" in frame else np.arange(len(frame))
    yref = frame["glucose_mgdl"].to_numpy(float)
    parts = []
    val_parts = []
    by_model: dict[str, list[tuple[dict, dict]]] = {}
    for i, (spec, split, _cls) in enumerate(tasks):
        res = results[i]
        raw = np.asarray(res["predicted_mgdl"], dtype=float)
        scored = np.where(np.isfinite(raw), np.maximum(raw, 0.0), res["fallback_mgdl"])
        parts.append(
            pd.DataFrame(
                {
                    "model": spec["model"],
                    "subject_id": sid[split.test],
                    "measurement_id": mid[split.test],
                    "repeat": split.repeat,
                    "fold": split.fold,
                    "reference_mgdl": yref[split.test],
                    "predicted_mgdl": raw,
                    "scored_mgdl": scored,
                }
            )
        )
        by_model.setdefault(spec["model"], []).append((spec, res))
        val_raw = res.get("val_predicted_mgdl")
        if split.val is not None and val_raw is not None:
            vraw = np.asarray(val_raw, dtype=float)
            val_parts.append(
                pd.DataFrame(
                    {
                        "model": spec["model"],
                        "subject_id": sid[split.val],
                        "repeat": split.repeat,
                        "fold": split.fold,
                        "reference_mgdl": yref[split.val],
                        "scored_mgdl": np.where(
                            np.isfinite(vraw), np.maximum(vraw, 0.0), res["fallback_mgdl"]
                        ),
                    }
                )
            )
    preds_all = pd.concat(parts, ignore_index=True)
    val_cal = pd.concat(val_parts, ignore_index=True) if val_parts else None
    preds_all = out_of_fold_intervals(preds_all, val_cal)
    preds_all["lower90_mgdl"] = np.maximum(preds_all["scored_mgdl"] - preds_all["half90_mgdl"], 0)
    preds_all["upper90_mgdl"] = preds_all["scored_mgdl"] + preds_all["half90_mgdl"]
    order = {m: k for k, m in enumerate([*names, *aux])}
    preds_all = (
        preds_all.assign(_o=preds_all["model"].map(order))
        .sort_values(["_o", "repeat", "fold", "measurement_id"], kind="stable")
        .drop(columns="_o")
        .reset_index(drop=True)
    )

    rows = []
    for name in [*names, *aux]:
        p = preds_all[preds_all["model"] == name]
        per_rep = [
            summary(g["reference_mgdl"].to_numpy(), g["scored_mgdl"].to_numpy())
            for _, g in p.groupby("repeat", sort=True)
        ]
        point = {k: float(np.mean([s[k] for s in per_rep])) for k in per_rep[0]}
        ci = cluster_bootstrap_metrics(
            p["reference_mgdl"],
            p["scored_mgdl"],
            p["subject_id"],
            p["repeat"],
            n_boot=n_boot,
            seed=seed,
        )
        cov = {a: coverage_summary(p, a, n_boot=n_boot, seed=seed) for a in LEVELS}
        first = next(res for spec, res in by_model[name] if spec["timed"])
        t = first["timing"]
        raw = p["predicted_mgdl"].to_numpy()
        rows.append(
            {
                **point,
                **{k: v for k, v in ci.items() if "_ci_" in k},
                "model": name,
                "label": _label(name),
                "n_parameters": int(first["n_parameters"]),
                "latency_single_ms": t.get("latency_single_ms", np.nan),
                "latency_single_p90_ms": t.get("latency_single_p90_ms", np.nan),
                "throughput_per_s": t.get("throughput_per_s", np.nan),
                "latency_input": t.get("latency_input", ""),
                "fit_time_s": float(np.mean([res["fit_time_s"] for _, res in by_model[name]])),
                "n_predictions": int(len(p)),
                "n_invalid_predictions": int(np.count_nonzero(~np.isfinite(raw) | (raw < 0))),
                "coverage90_pct": cov[0.9]["coverage"],
                "coverage90_ci_low": cov[0.9]["ci_low"],
                "coverage90_ci_high": cov[0.9]["ci_high"],
                "width90_mgdl": cov[0.9]["width"],
                "coverage80_pct": cov[0.8]["coverage"],
                "width80_mgdl": cov[0.8]["width"],
            }
        )
    allm = pd.DataFrame(rows)
    oracle_rmse = (
        float(allm.loc[allm["model"] == ORACLE, "rmse_mgdl"].iloc[0])
        if ORACLE in set(allm["model"])
        else np.nan
    )
    allm["rmse_vs_oracle"] = allm["rmse_mgdl"] / oracle_rmse
    meta["oracle_rmse_mgdl"] = oracle_rmse
    metrics = (
        allm[allm["model"].isin(names)]
        .sort_values("rmse_mgdl", kind="stable")
        .reset_index(drop=True)
    )
    metrics = metrics[list(METRIC_COLUMNS)]

    preds = preds_all[preds_all["model"].isin(names)].reset_index(drop=True)
    preds = preds[list(PREDICTION_COLUMNS)]
    comparisons = _comparisons(preds, names, n_boot=n_boot, alpha=alpha, seed=seed)
    meta["best_model"] = (
        comparisons.loc[comparisons["family"] == "vs_best", "reference_model"].iloc[0]
        if (comparisons["family"] == "vs_best").any()
        else (metrics["model"].iloc[0] if len(metrics) else None)
    )

    ablation = _ablation(preds, names, n_boot=n_boot, alpha=alpha, seed=seed)
    meta["study_orderings"] = _study_orderings(comparisons)

    histories = {}
    imp_rows = []
    for name in names:
        histories[name] = next(res for spec, res in by_model[name] if spec["timed"])["history"]
        for _spec, res in by_model[name]:
            imp = res["importance"]
            imp_rows.append(pd.DataFrame({"model": name, **imp}))
    imp_all = pd.concat(imp_rows, ignore_index=True)
    importance = (
        imp_all.groupby(["model", "wavelength_nm"], sort=False)
        .agg(
            rmse_increase_mgdl=("rmse_increase_mgdl", "mean"),
            rmse_increase_sd_mgdl=("rmse_increase_sd_mgdl", "mean"),
            n_tasks=("rmse_increase_mgdl", "size"),
        )
        .reset_index()
    )[list(IMPORTANCE_COLUMNS)]
    return BenchmarkResult(
        metrics=metrics,
        predictions=preds,
        comparisons=comparisons,
        histories=histories,
        importance=importance,
        meta=meta,
        dataset=dataset,
        ablation=ablation,
    )


def _label(name: str) -> str:
    if name.endswith(NO_PHYSICS):
        base = name[: -len(NO_PHYSICS)]
        return f"{MODEL_LABELS.get(base, base)} (no physics)"
    return MODEL_LABELS.get(name, name)


def _ablation(preds, names, *, n_boot, alpha, seed) -> pd.DataFrame:
    """Each PINN against itself without physics: paired RMSE difference (with − off)."""
    pairs = [(n[: -len(NO_PHYSICS)], n) for n in names if n.endswith(NO_PHYSICS)]
    if not pairs:
        return pd.DataFrame(columns=list(ABLATION_COLUMNS))
    c = compare_models(
        preds, pairs=pairs, pred_col="scored_mgdl", n_boot=n_boot, seed=seed, alpha=alpha
    )
    c = c.rename(
        columns={"reference_model": "ablated_model", "reference_rmse_mgdl": "ablated_rmse_mgdl"}
    )
    c["physics_helps"] = c["rmse_diff_mgdl"] < 0
    return c[list(ABLATION_COLUMNS)].reset_index(drop=True)


def _study_orderings(comparisons: pd.DataFrame) -> dict[str, Any]:
    """Which of the study's pairwise RMSE orderings hold here, and which significantly."""
    so = comparisons[comparisons["family"] == "study_order"]
    pairs = [
        {
            "better": r["reference_model"],
            "worse": r["model"],
            "holds": bool(r["study_holds"]),
            "significant": bool(r["significant"]),
            "rmse_diff_mgdl": r["rmse_diff_mgdl"],
            "ci_low": r["ci_low"],
            "ci_high": r["ci_high"],
            "p_holm": r["p_holm"],
        }
        for _, r in so.iterrows()
    ]
    return {
        "study_order": [m for m in STUDY_ORDER],
        "n_pairs": len(pairs),
        "n_hold": sum(p["holds"] for p in pairs),
        "n_hold_significant": sum(p["holds"] and p["significant"] for p in pairs),
        "n_reversed_significant": sum((not p["holds"]) and p["significant"] for p in pairs),
        "pairs": pairs,
    }


def _comparisons(preds, names, *, n_boot, alpha, seed) -> pd.DataFrame:
    frames = []
    if len(names) > 1:
        vs_best = compare_models(
            preds,
            pred_col="scored_mgdl",
            n_boot=n_boot,
            seed=seed,
            alpha=alpha,
            exclude_from_best=(ORACLE,),
        )
        vs_best.insert(0, "family", "vs_best")
        vs_best["study_holds"] = None
        frames.append(vs_best)
    in_study = [m for m in STUDY_ORDER if m in names]
    pairs = [(worse, better) for k, better in enumerate(in_study) for worse in in_study[k + 1 :]]
    if pairs:
        so = compare_models(
            preds, pairs=pairs, pred_col="scored_mgdl", n_boot=n_boot, seed=seed, alpha=alpha
        )
        so.insert(0, "family", "study_order")
        so["study_holds"] = so["rmse_diff_mgdl"] > 0
        frames.append(so)
    if not frames:
        return pd.DataFrame(columns=list(COMPARISON_COLUMNS))
    return pd.concat(frames, ignore_index=True)[list(COMPARISON_COLUMNS)]


# --------------------------------------------------------------------------- table.md
def _fmt(v: Any, digits: int = 1) -> str:
    if v is None or (isinstance(v, float) and not math.isfinite(v)):
        return "–"
    if isinstance(v, int | np.integer):
        return f"{int(v):,}"
    return f"{float(v):.{digits}f}"


def _fmt_ms(v: Any) -> str:
    if v is None or not math.isfinite(float(v)):
        return "–"
    v = float(v)
    return f"{v:.3f}" if v < 0.1 else f"{v:.2f}" if v < 10 else f"{v:.1f}"


def _table_markdown(res: BenchmarkResult) -> str:
    study = {row["model"]: row for row in STUDY_TABLE}
    m = res.meta
    layout = (
        "one 60/20/20 split by subject"
        if m["protocol"] == "paper-split"
        else f"grouped {m['n_splits']}-fold CV × {m['repeats']} repeats"
    )
    lines = [
        "# Benchmark against the reference study (Table 1)",
        "",
        f"Ours: {layout} (protocol `{m['protocol']}`, seed {m['seed']}), "
        f"{m['n_subjects']} subjects, {m['n_snapshots']} snapshots, preset "
        f"`{m['preset']}`, dataset {m['dataset_hash']}; 95 % CIs from a cluster bootstrap "
        f"over subjects ({m['n_boot']:,} resamples). Study: one 60/20/20 split by subject, "
        f"test n = 48. Inference: our median single-sample `predict` time.",
        "",
        "| Model | RMSE mg/dL | study | MARD % | study | Clarke A % | study | ±15 % | study "
        "| Params | study | Inference ms | study | RMSE / oracle |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for _, r in res.metrics.iterrows():
        s = study.get(r["model"], {})

        def ci(stem, col, r=r):
            return f"{_fmt(r[col])} [{_fmt(r[stem + '_ci_low'])}, {_fmt(r[stem + '_ci_high'])}]"

        lines.append(
            f"| {r['label']} | {ci('rmse', 'rmse_mgdl')} | {_fmt(s.get('rmse_mgdl'))} "
            f"| {ci('mard', 'mard_pct')} | {_fmt(s.get('mard_pct'))} "
            f"| {ci('clarke_a', 'clarke_a_pct')} | {_fmt(s.get('clarke_a_pct'))} "
            f"| {ci('within15', 'within15_pct')} | {_fmt(s.get('within15_pct'))} "
            f"| {_fmt(int(r['n_parameters']))} | {_fmt(s.get('n_parameters'))} "
            f"| {_fmt_ms(r['latency_single_ms'])} | {_fmt_ms(s.get('latency_single_ms', np.nan))} "
            f"| {_fmt(r['rmse_vs_oracle'], 2)} |"
        )
    lines.append("")
    lines.extend(_significance_lines(res))
    lines.extend(_ablation_lines(res))
    return "\n".join(lines) + "\n"


def _ablation_lines(res: BenchmarkResult) -> list[str]:
    a = res.ablation
    if a is None or not len(a):
        return []
    label = {r["model"]: r["label"] for _, r in res.metrics.iterrows()}
    out = [
        "",
        "## Physics ablation",
        "",
        "Each PINN refitted with its physics term off (`lambda_phys = 0`), everything else "
        "identical (same splits, seeds and parameters). Δ RMSE = with physics − without "
        "(negative: the physics term helps); paired cluster bootstrap over subjects, "
        f"Holm over the {len(a)} PINNs, α = {res.meta['alpha']}.",
        "",
        "| PINN | RMSE with physics | RMSE without | Δ RMSE mg/dL [95 % CI] | p_holm | verdict |",
        "|---|---|---|---|---|---|",
    ]
    for _, r in a.iterrows():
        if r["significant"]:
            verdict = "physics helps" if r["physics_helps"] else "physics hurts"
        else:
            verdict = "no significant difference"
        out.append(
            f"| {label.get(r['model'], r['model'])} | {_fmt(r['rmse_mgdl'])} "
            f"| {_fmt(r['ablated_rmse_mgdl'])} | {r['rmse_diff_mgdl']:+.2f} "
            f"[{r['ci_low']:+.2f}, {r['ci_high']:+.2f}] | {r['p_holm']:.3g} | {verdict} |"
        )
    return out


def _significance_lines(res: BenchmarkResult) -> list[str]:
    c = res.comparisons
    label = {r["model"]: r["label"] for _, r in res.metrics.iterrows()}
    out = []
    vb = c[c["family"] == "vs_best"]
    if len(vb):
        best = vb["reference_model"].iloc[0]
        worse = vb["significant"] & (vb["rmse_diff_mgdl"] > 0)
        better = vb["significant"] & (vb["rmse_diff_mgdl"] < 0)

        def names(mask):
            return ", ".join(label[m] for m in vb.loc[mask, "model"]) or "none"

        out.append(
            f"Significant rankings (paired cluster bootstrap of the RMSE difference over "
            f"subjects, Holm-adjusted, α = {res.meta['alpha']}): best model is {label[best]}; "
            f"significantly worse than it: {names(worse)}; "
            f"not distinguishable from it: {names(~vb['significant'])}"
            + (
                f"; significantly better (a bound, not a competitor): {names(better)}."
                if better.any()
                else "."
            )
        )
    so = c[c["family"] == "study_order"]
    if len(so):
        n_hold = int(so["study_holds"].sum())
        n_sig = int((so["study_holds"] & so["significant"]).sum())
        out += [
            "",
            f"Study orderings (study: row model better than column model): "
            f"{n_hold} of {len(so)} hold here, {n_sig} of them significantly:",
            "",
        ]
        for _, r in so.iterrows():
            verdict = "holds" if r["study_holds"] else "reversed"
            sig = "significant" if r["significant"] else "not significant"
            out.append(
                f"- {label[r['reference_model']]} < {label[r['model']]}: {verdict} "
                f"(Δ RMSE {r['rmse_diff_mgdl']:+.1f} mg/dL [{r['ci_low']:+.1f}, "
                f"{r['ci_high']:+.1f}], p_holm = {r['p_holm']:.3g}, {sig})"
            )
    if res.meta.get("oracle_note"):
        out += ["", f"Note: {res.meta['oracle_note']}."]
    return out
