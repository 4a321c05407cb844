"""Sweeps: how each model degrades as the noise grows, ablations, and domain shift.

A sweep is a list of *scenarios* (dotted config overrides on a preset) crossed with
seeds and models. Each ``(scenario, seed, model)`` is one independent *task*: it
simulates its dataset from the scenario and the seed, then runs
:func:`~nirglucose.evaluation.benchmark.run_benchmark` for that one model (one worker
inside the task), or, for the domain-shift study, fits on a training cohort and
scores on a shifted test cohort. :func:`run_sweep` runs the tasks in this process, on
a local process pool or on a Dask cluster (:mod:`~nirglucose.evaluation.executors`)
and gathers one row per task.

Studies (:data:`STUDIES`)
    ``noise-scale``
        ``noise_scale`` (every noise source together) over 0.25, 0.5, 1, 2, 4.
    ``pmf-noise``
        ``noise.pmf_measurement.scale`` (the error of the measured physiological
        vector) over 0, 0.5, 1, 2, 4.
    ``ablation``
        Every noise source of :data:`~nirglucose.config.NOISE_SOURCES` switched off
        alone (``off``), and switched on alone (``only``), besides all sources on
        (``all-on``) and all off (``all-off``). :func:`ablation_effects` turns these
        into ΔRMSE per source, paired by seed.
    ``cohort``
        Domain shift. ``fitzpatrick``: train on measured Fitzpatrick types I–III, test
        on I–III (in domain) and on IV–VI (shifted); ``temperature``: train at
        20–25 °C ambient, test at 20–25 °C and at 5–35 °C. Training and test cohorts
        are simulated separately (the test seed is derived from the task's seed), so
        no subject is in both. :func:`shift_effects` gives the ΔRMSE of the shift.
    ``device``
        Each device capability (:data:`~nirglucose.config.DEVICE_CAPABILITIES`)
        switched off alone in ``paper`` and on alone in ``wearable``, besides both
        presets as they are; each scenario sets every key distinguishing the two.
    ``data-size``
        RMSE against the number of training subjects (:data:`DATA_SIZE_SUBJECTS`) on
        each preset of :data:`DATA_SIZE_PRESETS`: every model is trained on a draw of
        that many subjects and tested on an independent draw of
        :data:`DATA_SIZE_TEST_SUBJECTS` subjects (another seed, derived from the
        task's). :func:`ranking_crossings` says between which sizes two models swap
        places.
    Any other grid comes from ``vary={"dotted.key": [values]}`` (several keys make a
    Cartesian product), e.g. ``{"hardware.adc_bits": [10, 12, 14]}``.

Determinism
    A task draws every random number from its own specification (the dataset from the
    sweep seed, splits and models from ``run_benchmark``'s seeding), never from the
    order or the place it ran, so results are identical for ``jobs=1``, a process
    pool or a Dask cluster. The same seed in every scenario gives common random
    numbers: with :mod:`~nirglucose.simulate._random`'s per-source streams, switching
    one noise source off leaves every other draw unchanged, so scenario differences
    are paired.

Resumability
    With ``out`` given, each finished task is written atomically to
    ``out/.tasks/<model>-s<seed>-<hash>.json``; the hash covers the task's full
    specification (preset, resolved overrides and the SHA-256 of the resolved config,
    seed, model, protocol options, bootstrap size, package version, a digest of the
    package's source (:func:`source_digest`), task format). A
    rerun loads finished tasks instead of recomputing them; a file whose checksum,
    specification or schema does not match is recomputed (and counted). Files are
    written by the process that gathers results, so a remote cluster needs no shared
    file system, and an interrupt loses only the tasks that were running.

Outputs (:meth:`SweepResult.save`)
    ``sweep.csv`` (one row per scenario × seed × model, the scenario's varied values
    as columns, then every metric of :data:`SWEEP_METRICS`), ``summary.csv`` (mean,
    SD and a 95 % t-interval over seeds per scenario × model), ``effects.csv``
    (ablation or shift effects, when the study has them) and ``sweep_meta.json``.
"""

from __future__ import annotations

import functools
import hashlib
import inspect
import itertools
import json
import math
import time
import warnings
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from ..dataset import Dataset, atomic_write
from ..exceptions import ConfigError, DataError, unknown_name
from .benchmark import METRIC_COLUMNS
from .progress import TaskProgress

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

#: Built-in studies (``--study``).
STUDIES = ("noise-scale", "ablation", "pmf-noise", "cohort", "device", "data-size")
#: The varied key and default values of the one-key studies.
STUDY_GRIDS: dict[str, tuple[str, tuple[float, ...]]] = {
    "noise-scale": ("noise_scale", (0.25, 0.5, 1.0, 2.0, 4.0)),
    "pmf-noise": ("noise.pmf_measurement.scale", (0.0, 0.5, 1.0, 2.0, 4.0)),
}
#: Domain shifts of the ``cohort`` study: training domain, in-domain and shifted test.
COHORT_SHIFTS: dict[str, dict[str, Any]] = {
    "fitzpatrick": {
        "column": "fitzpatrick_type",  # the measured (self-reported) type, 1-6
        "train": ("I-III", (1, 2, 3)),
        "in_domain": ("I-III", (1, 2, 3)),
        "shifted": ("IV-VI", (4, 5, 6)),
    },
    "temperature": {
        "key": "environment.temperature_c",
        "train": ("20-25 degC", (20.0, 25.0)),
        "in_domain": ("20-25 degC", (20.0, 25.0)),
        "shifted": ("5-35 degC", (5.0, 35.0)),
    },
}
#: Training-set sizes of the ``data-size`` study (subjects; a bigger setting:
#: ``vary={"n_train_subjects": [80, 160, 320, 640, 1280, 2560]}`` and several seeds).
DATA_SIZE_SUBJECTS = (80, 320, 1280)
#: Subjects of the independent test draw of the ``data-size`` study.
DATA_SIZE_TEST_SUBJECTS = 200
#: Presets of the ``data-size`` study when none are named.
DATA_SIZE_PRESETS = ("paper", "wearable")

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
    c for c in METRIC_COLUMNS
    if c not in ("model", "label", "latency_single_ms", "latency_single_p90_ms",
                 "throughput_per_s", "latency_input", "rmse_vs_oracle", "fit_time_s")
)
#: Metrics :func:`summarize_sweep` aggregates over seeds by default.
SUMMARY_METRICS = (
    "rmse_mgdl",
    "mard_pct",
    "clarke_a_pct",
    "within15_pct",
    "bias_mgdl",
    "rmse_vs_oracle",
)
#: Files :meth:`SweepResult.save` writes.
SWEEP_FILES = ("sweep.csv", "summary.csv", "effects.csv", "sweep_meta.json")
#: Version of the task-file layout (part of every task hash).
TASK_FORMAT = 1

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


# --------------------------------------------------------------------------- scenarios
@dataclass(frozen=True)
class Scenario:
    """One simulated condition of a sweep.

    Attributes
    ----------
    name : str
        Unique, readable name (``"noise_scale=0.5"``, ``"off:shot"``).
    labels : dict
        Columns identifying the scenario in ``sweep.csv`` (the varied values).
    overrides : dict
        Dotted config overrides on top of the sweep's preset and base overrides.
    test_overrides : dict or None
        Overrides of a separately simulated test cohort; None for cross-validation on
        one dataset.
    train_filter, test_filter : dict or None
        ``{"column": name, "values": [...]}``: keep only rows whose measured column
        takes one of the values.
    preset : str or None
        Preset of this scenario (None: the sweep's).
    n_subjects, n_test_subjects : int or None
        Subjects of the training and of the test draw (None: the sweep's).
    """

    name: str
    labels: dict[str, Any] = field(default_factory=dict)
    overrides: dict[str, Any] = field(default_factory=dict)
    test_overrides: dict[str, Any] | None = None
    train_filter: dict[str, Any] | None = None
    test_filter: dict[str, Any] | None = None
    preset: str | None = None
    n_subjects: int | None = None
    n_test_subjects: int | None = None

    @property
    def kind(self) -> str:
        """``"cv"`` (cross-validation on one dataset) or ``"shift"`` (train -> test)."""
        return "cv" if self.test_overrides is None else "shift"


def _label_value(value: Any) -> Any:
    """A CSV-friendly form of a varied value (lists as compact JSON)."""
    if isinstance(value, list | tuple | dict):
        return json.dumps(value, separators=(",", ":"))
    return value


def _fmt_value(value: Any) -> str:
    if isinstance(value, float):
        return f"{value:g}"
    return str(_label_value(value)).lower() if isinstance(value, bool) else str(_label_value(value))


def parse_vary(text: str) -> tuple[str, list[Any]]:
    """Parse ``"key=v1,v2,..."`` from the command line.

    Values are read as one JSON list when they can be (so ``[5,35],[20,25]`` gives two
    ranges), else split on commas, each read as :func:`~nirglucose.config.parse_override`
    reads a value.

    Parameters
    ----------
    text : str
        ``dotted.key=value,value,...``.

    Returns
    -------
    tuple of (str, list)
        The key and its values (in order, duplicates removed).

    Raises
    ------
    ConfigError
        No ``=``, an empty key, no values, or an empty value.

    Examples
    --------
    >>> parse_vary("noise_scale=0.25,0.5,1")
    ('noise_scale', [0.25, 0.5, 1])
    >>> parse_vary("environment.temperature_c=[5,35],[20,25]")
    ('environment.temperature_c', [[5, 35], [20, 25]])
    """
    from ..config import parse_override

    if "=" not in text:
        raise ConfigError(f"--vary {text!r} must look like key=v1,v2,... e.g. noise_scale=0.5,1,2")
    key, raw = (s.strip() for s in text.split("=", 1))
    if not key:
        raise ConfigError(f"--vary {text!r} has an empty key")
    if not raw:
        raise ConfigError(f"--vary {key}= lists no values; give e.g. {key}=0.5,1,2")
    try:
        values = json.loads(f"[{raw}]")
    except json.JSONDecodeError:
        tokens = [t.strip() for t in raw.split(",")]
        if any(not t for t in tokens):
            raise ConfigError(f"--vary {key}={raw}: empty value in the list") from None
        values = [parse_override(f"{key}={t}")[1] for t in tokens]
    if not values:
        raise ConfigError(f"--vary {key}= lists no values; give e.g. {key}=0.5,1,2")
    unique: list[Any] = []
    for v in values:
        if v not in unique:
            unique.append(v)
    return key, unique


def _default_value(preset: str, key: str, base: Mapping[str, Any]) -> Any:
    from ..config import resolve_config

    node: Any = resolve_config(preset, dict(base)).model_dump(mode="json")
    for part in key.split("."):
        node = node[part]
    return node


def _is_number(v: Any) -> bool:
    return isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v)


def _check_values(preset: str, key: str, values: Sequence[Any], base: Mapping[str, Any]) -> None:
    """Check every value of a varied key against the key's type and range."""
    from ..config import is_valid_key, resolve_config

    if not is_valid_key(key):
        resolve_config(preset, {**base, key: values[0]})  # raises with a hint
    default = _default_value(preset, key, base)
    for v in values:
        if _is_number(default) and not _is_number(v):
            raise ConfigError(
                f"--vary {key}: {v!r} is not a number; {key} takes numbers (default {default!r})"
            )
        if isinstance(default, bool) and not isinstance(v, bool):
            raise ConfigError(f"--vary {key}: {v!r} is not true/false; {key} is a switch")
        resolve_config(preset, {**base, key: v})  # type and range checks


def grid_scenarios(
    vary: Mapping[str, Sequence[Any]],
    *,
    preset: str = "paper",
    base_overrides: Mapping[str, Any] | None = None,
) -> list[Scenario]:
    """The Cartesian grid of varied config values, validated.

    Parameters
    ----------
    vary : mapping of str to sequence
        Dotted config key -> values (one key: a curve; several: a grid).
    preset : str
        Preset the values apply to (for validation).
    base_overrides : mapping, optional
        Overrides every scenario shares.

    Returns
    -------
    list of Scenario

    Raises
    ------
    ConfigError
        Unknown key, empty list, a non-numeric value for a numeric key, a value out of
        range, or a key also given in ``base_overrides``.

    Examples
    --------
    >>> [s.name for s in grid_scenarios({"noise_scale": [0.5, 2]})]
    ['noise_scale=0.5', 'noise_scale=2']
    """
    base = dict(base_overrides or {})
    if not vary:
        raise ConfigError("nothing to vary: give --vary key=v1,v2,... or --study")
    for key, values in vary.items():
        if not isinstance(values, Sequence) or isinstance(values, str) or len(values) == 0:
            raise ConfigError(f"--vary {key}: give a non-empty list of values")
        if key in base:
            raise ConfigError(f"{key} is both varied and set (--set); drop one")
        _check_values(preset, key, list(values), base)
    keys = list(vary)
    out = []
    for combo in itertools.product(*(list(vary[k]) for k in keys)):
        name = ",".join(f"{k}={_fmt_value(v)}" for k, v in zip(keys, combo, strict=True))
        out.append(
            Scenario(
                name=name,
                labels={k: _label_value(v) for k, v in zip(keys, combo, strict=True)},
                overrides=dict(zip(keys, combo, strict=True)),
            )
        )
    return out


def study_scenarios(
    study: str, values: Sequence[Any] | None = None, presets: Sequence[str] | None = None
) -> list[Scenario]:
    """The scenarios of a built-in study (:data:`STUDIES`).

    Parameters
    ----------
    study : str
        One of :data:`STUDIES`.
    values : sequence, optional
        Replace the default values of a one-key study (``noise-scale``, ``pmf-noise``)
        or the training sizes of ``data-size``.
    presets : sequence of str, optional
        Presets of the ``data-size`` study (default :data:`DATA_SIZE_PRESETS`).

    Returns
    -------
    list of Scenario

    Examples
    --------
    >>> [s.name for s in study_scenarios("ablation")][:3]
    ['all-on', 'all-off', 'off:led_thermal_drift']
    """
    from ..config import NOISE_SOURCES

    if study not in STUDIES:
        raise ConfigError(unknown_name("study", study, STUDIES))
    if study in STUDY_GRIDS:
        key, default = STUDY_GRIDS[study]
        return grid_scenarios({key: list(values if values is not None else default)})
    if study == "data-size":
        return _data_size_scenarios(values, presets)
    if values is not None:
        raise ConfigError(f"the {study!r} study takes no values")
    if study == "ablation":

        def off(sources):
            return {f"noise.{s}.enabled": False for s in sources}

        out = [
            Scenario("all-on", {"ablation": "all-on", "source": "all"}, {}),
            Scenario("all-off", {"ablation": "all-off", "source": "none"}, off(NOISE_SOURCES)),
        ]
        out += [
            Scenario(f"off:{s}", {"ablation": "off", "source": s}, off([s])) for s in NOISE_SOURCES
        ]
        out += [
            Scenario(
                f"only:{s}",
                {"ablation": "only", "source": s},
                off([o for o in NOISE_SOURCES if o != s]),
            )
            for s in NOISE_SOURCES
        ]
        return out
    if study == "device":
        return _device_scenarios()
    out = []
    for shift, d in COHORT_SHIFTS.items():
        train_label, train = d["train"]
        for which in ("in_domain", "shifted"):
            test_label, test = d[which]
            labels = {
                "shift": shift,
                "train_domain": train_label,
                "test_domain": test_label,
                "shifted": which == "shifted",
            }
            name = f"{shift}:{which.replace('_', '-')}"
            if "column" in d:
                out.append(
                    Scenario(
                        name,
                        labels,
                        {},
                        {},
                        {"column": d["column"], "values": list(train)},
                        {"column": d["column"], "values": list(test)},
                    )
                )
            else:
                out.append(Scenario(name, labels, {d["key"]: list(train)}, {d["key"]: list(test)}))
    return out


def _device_scenarios() -> list[Scenario]:
    """The ``device`` study: each capability off alone in ``paper``, on alone in ``wearable``.

    Every scenario sets all the keys that distinguish the two presets (the glucose gain
    and each :data:`~nirglucose.config.DEVICE_CAPABILITIES` key), so it is the same
    scenario on either base preset.
    """
    from ..config import DEVICE_CAPABILITIES, PRESETS

    keys = ["glucose.signal_gain"] + [key for key, _, _ in DEVICE_CAPABILITIES.values()]

    def scenario(base, switch, capability):
        over = {k: PRESETS[base][k] for k in keys}
        if capability is not None:
            key, v_on, v_off = DEVICE_CAPABILITIES[capability]
            over[key] = v_on if switch == "on" else v_off
        name = base if capability is None else f"{base}:{switch}:{capability}"
        labels = {"base": base, "switch": switch, "capability": capability or "none"}
        return Scenario(name, labels, over)

    out = [scenario("paper", "base", None), scenario("wearable", "base", None)]
    out += [scenario("paper", "off", c) for c in DEVICE_CAPABILITIES]
    out += [scenario("wearable", "on", c) for c in DEVICE_CAPABILITIES]
    return out


def _data_size_scenarios(
    sizes: Sequence[Any] | None, presets: Sequence[str] | None
) -> list[Scenario]:
    from ..config import PRESETS

    sizes = list(DATA_SIZE_SUBJECTS if sizes is None else sizes)
    presets = list(DATA_SIZE_PRESETS if presets is None else presets)
    if not sizes or any(
        isinstance(n, bool) or not isinstance(n, int | np.integer) or n < 2 for n in sizes
    ):
        raise ConfigError(f"data-size training sizes must be integers >= 2, got {sizes!r}")
    bad = [p for p in presets if p not in PRESETS]
    if not presets or bad:
        raise ConfigError(
            f"unknown preset(s) {bad or presets!r} for the data-size study; valid: "
            f"{', '.join(PRESETS)}"
        )
    return [
        Scenario(
            f"{p}:n={int(n)}",
            {"preset": p, "n_train_subjects": int(n)},
            {},
            {},
            preset=p,
            n_subjects=int(n),
            n_test_subjects=DATA_SIZE_TEST_SUBJECTS,
        )
        for p in dict.fromkeys(presets)
        for n in dict.fromkeys(sizes)
    ]


# --------------------------------------------------------------------------- tasks
def _sha(text: str) -> str:
    return hashlib.sha256(text.encode()).hexdigest()


@functools.lru_cache(maxsize=1)
def source_digest() -> str:
    """SHA-256 (16 hex digits) of the installed package's code and data files.

    Part of every task's specification, so a cached task is reused only by the same
    code, even while the version number stays the same during development.
    """
    root = Path(__file__).resolve().parents[1]
    h = hashlib.sha256()
    for path in sorted(root.rglob("*")):
        if path.is_file() and path.suffix in (".py", ".csv", ".json", ".md"):
            h.update(path.relative_to(root).as_posix().encode())
            h.update(path.read_bytes())
    return h.hexdigest()[:16]


def _canonical(obj: Any) -> Any:
    return json.loads(json.dumps(obj, sort_keys=True))


def _task_key(spec: Mapping[str, Any]) -> str:
    return _sha(json.dumps(spec, sort_keys=True))[:20]


def _derived_seed(seed: int, name: str) -> int:
    digest = hashlib.sha256(f"{seed}|{name}".encode()).digest()
    return int.from_bytes(digest[:4], "little") & 0x7FFFFFFF


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
) -> list[dict[str, Any]]:
    """One task specification per scenario × seed × model, in that nesting order.

    Every configuration is resolved here, so a bad value fails before anything runs.

    Returns
    -------
    list of dict
        JSON-able task specifications (:func:`run_sweep_task` input); the hash of one
        names its task file.
    """
    from .. import __version__
    from ..config import resolve_config
    from .splits import effective_layout

    base = dict(base_overrides or {})
    params = dict(model_params or {})
    specs = []
    sweep_preset, sweep_subjects = preset, n_subjects
    for sc in scenarios:
        preset = sc.preset or sweep_preset
        n_subjects = sc.n_subjects or sweep_subjects
        sizes = {} if sc.n_test_subjects is None else {"test_n_subjects": sc.n_test_subjects}
        overrides = _canonical({**base, **sc.overrides})
        cfg_sha = _sha(resolve_config(preset, overrides).to_json())[:16]
        test_overrides = test_sha = None
        if sc.test_overrides is not None:
            test_overrides = _canonical({**base, **sc.test_overrides})
            test_sha = _sha(resolve_config(preset, test_overrides).to_json())[:16]
        if sc.kind == "cv":
            n_eff, r_eff = effective_layout(protocol, n_splits, repeats)
            proto = {"protocol": protocol, "n_splits": n_eff, "repeats": r_eff}
        else:
            proto = {"protocol": "train-test", "n_splits": 1, "repeats": 1}
        for seed in seeds:
            for model in models:
                specs.append(
                    {
                        "format": TASK_FORMAT,
                        "version": __version__,
                        "source_sha256": source_digest(),
                        "kind": sc.kind,
                        "preset": preset,
                        "overrides": overrides,
                        "config_sha256": cfg_sha,
                        "test_overrides": test_overrides,
                        "test_config_sha256": test_sha,
                        "train_filter": _canonical(sc.train_filter),
                        "test_filter": _canonical(sc.test_filter),
                        "n_subjects": int(n_subjects),
                        "per_subject": int(per_subject),
                        "seed": int(seed),
                        "model": model,
                        "model_params": _canonical(dict(params.get(model, {}))),
                        **proto,
                        "n_boot": int(n_boot),
                        **sizes,
                    }
                )
    return specs


def _filtered(ds: Dataset, filt: Mapping[str, Any] | None) -> Dataset:
    if not filt:
        return ds
    mask = ds.frame[filt["column"]].isin(filt["values"]).to_numpy()
    return Dataset(
        ds.frame.loc[mask].reset_index(drop=True),
        config=ds.config,
        seed=ds.seed,
        metadata=ds.metadata,
    )


def _cv_metrics(spec: Mapping[str, Any], ds: Dataset) -> dict[str, Any]:
    from .benchmark import run_benchmark

    res = run_benchmark(
        ds,
        [spec["model"]],
        protocol=spec["protocol"],
        n_splits=spec["n_splits"],
        repeats=spec["repeats"],
        seed=spec["seed"],
        jobs=1,
        model_params={spec["model"]: spec["model_params"]} if spec["model_params"] else None,
        n_boot=spec["n_boot"],
        timing=dict(_FAST_TIMING),
        importance_repeats=1,
        oracle_reference=False,
        calibration=int(spec.get("calibration", 0)),
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


def _shift_metrics(spec: Mapping[str, Any], train: Dataset, test: Dataset) -> dict[str, Any]:
    from ..metrics import summary
    from ..models.registry import get_model_class
    from .stats import cluster_bootstrap_metrics

    if len(train) == 0 or len(test) == 0:
        raise DataError(
            f"the {spec['model']!r} shift task has an empty training or test "
            f"cohort ({len(train)} / {len(test)} rows); simulate more subjects"
        )
    from .benchmark import _model_params

    cls = get_model_class(spec["model"])
    # the preset's tuned parameters (the benchmark's one hook), then the sweep's own
    params = {**_model_params(spec["model"], spec["preset"]), **spec["model_params"]}
    if "random_state" in inspect.signature(cls).parameters and "random_state" not in params:
        params["random_state"] = _derived_seed(spec["seed"], f"model|{spec['model']}")
    model = cls(**params).fit(train)
    raw = np.asarray(model.predict(test), dtype=float).ravel()
    fallback = float(np.median(train.frame["glucose_mgdl"].to_numpy(float)))
    scored = np.where(np.isfinite(raw), np.maximum(raw, 0.0), fallback)
    ref = test.frame["glucose_mgdl"].to_numpy(float)
    point = summary(ref, scored)
    ci = cluster_bootstrap_metrics(
        ref, scored, test.frame["subject_id"].to_numpy(), n_boot=spec["n_boot"], seed=spec["seed"]
    )
    out = {**point, **{k: v for k, v in ci.items() if "_ci_" in k}}
    out.update(
        n_parameters=int(getattr(model, "n_parameters", -1)),
        n_predictions=len(ref),
        n_invalid_predictions=int(np.count_nonzero(~np.isfinite(raw) | (raw < 0))),
        n_train=len(train),
    )
    return {k: out[k] for k in (*SWEEP_METRICS, "n_train") if k in out}


def run_sweep_task(spec: Mapping[str, Any]) -> dict[str, Any]:
    """Run one sweep task (module level, so any worker process can run it).

    Parameters
    ----------
    spec : dict
        One task specification of :func:`plan_sweep`.

    Returns
    -------
    dict
        ``{"metrics": {...}, "version": ..., "warnings": [...], "wall_s": ...}``.
    """
    from .. import __version__
    from ..api import simulate

    t0 = time.perf_counter()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        ds = simulate(
            spec["preset"],
            spec["n_subjects"],
            spec["per_subject"],
            spec["seed"],
            overrides=spec["overrides"],
        )
        if spec["kind"] == "cv":
            metrics = _cv_metrics(spec, _filtered(ds, spec["train_filter"]))
        else:
            test = simulate(
                spec["preset"],
                spec.get("test_n_subjects", spec["n_subjects"]),
                spec["per_subject"],
                _derived_seed(spec["seed"], "test-cohort"),
                overrides=spec["test_overrides"],
            )
            metrics = _shift_metrics(
                spec, _filtered(ds, spec["train_filter"]), _filtered(test, spec["test_filter"])
            )
    clean = {
        k: (None if v is None or (isinstance(v, float) and not math.isfinite(v)) else float(v))
        for k, v in metrics.items()
    }
    return {
        "metrics": clean,
        "version": __version__,
        "source_sha256": source_digest(),
        "warnings": list(dict.fromkeys(str(w.message).replace("\n", " ") for w in caught)),
        "wall_s": time.perf_counter() - t0,
    }


def _task_file(tasks_dir: Path, spec: Mapping[str, Any], key: str) -> Path:
    safe = "".join(ch if ch.isalnum() or ch in "-_" else "_" for ch in spec["model"])
    return tasks_dir / f"{safe}-s{spec['seed']}-{key}.json"


def _checksum(result: Mapping[str, Any]) -> str:
    return _sha(json.dumps(result, sort_keys=True, allow_nan=True))


def _valid_result(result: Any) -> bool:
    if not isinstance(result, dict) or not isinstance(result.get("metrics"), dict):
        return False
    m = result["metrics"]
    return all(k in m for k in ("rmse_mgdl", "mard_pct", "n_predictions")) and all(
        v is None or isinstance(v, int | float) for v in m.values()
    )


def _load_task(path: Path, spec: Mapping[str, Any]) -> dict[str, Any] | None:
    """A finished task's result; None when absent, corrupt, partial or another task's."""
    if not path.exists():
        return None
    try:
        doc = json.loads(path.read_text(encoding="utf-8"))
        ok = (
            doc["spec"] == spec
            and doc["checksum"] == _checksum(doc["result"])
            and _valid_result(doc["result"])
        )
    except (OSError, ValueError, KeyError, TypeError):
        ok = False
    return doc["result"] if ok else None


def _save_task(path: Path, spec: Mapping[str, Any], result: Mapping[str, Any]) -> None:
    text = json.dumps(
        {"spec": spec, "checksum": _checksum(result), "result": result},
        sort_keys=True,
        allow_nan=True,
    )
    atomic_write(path, lambda tmp: Path(tmp).write_text(text, encoding="utf-8"))


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
        out = _prepare_out(out)
        for name, frame in (
            ("sweep.csv", self.frame),
            ("summary.csv", self.summary),
            ("effects.csv", self.effects),
        ):
            if frame is not None:
                atomic_write(out / name, lambda tmp, f=frame: f.to_csv(tmp, index=False))
            else:
                (out / name).unlink(missing_ok=True)
        text = json.dumps(_json_clean(self.meta), indent=2) + "\n"
        atomic_write(
            out / "sweep_meta.json", lambda tmp: Path(tmp).write_text(text, encoding="utf-8")
        )
        return out


def _json_clean(obj: Any) -> Any:
    if isinstance(obj, dict):
        return {str(k): _json_clean(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [_json_clean(v) for v in obj]
    if isinstance(obj, np.integer):
        return int(obj)
    if isinstance(obj, float | np.floating):
        return float(obj) if math.isfinite(obj) else None
    return obj


def _prepare_out(out: str | Path) -> Path:
    out = Path(out)
    if out.exists() and not out.is_dir():
        raise DataError(f"--out {str(out)!r} exists and is not a directory")
    if not out.exists():
        if not out.parent.exists():
            raise DataError(f"output directory {str(out.parent)!r} does not exist; create it first")
        out.mkdir()
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
    labels = meta.get("label_columns", [])
    summary = summarize_sweep(frame, labels)
    effects = None
    if (d / "effects.csv").exists():
        effects = pd.read_csv(d / "effects.csv")
    return SweepResult(frame, summary, effects, meta)


# --------------------------------------------------------------------------- aggregation
def _t_interval(values: np.ndarray, level: float) -> tuple[float, float, float, float]:
    """Mean, SD and a t-interval of the mean; NaN interval for fewer than 2 values."""
    from scipy.stats import t as student_t

    v = np.asarray(values, dtype=float)
    v = v[np.isfinite(v)]
    if v.size == 0:
        return (np.nan,) * 4
    mean = float(v.mean())
    if v.size < 2:
        return mean, np.nan, np.nan, np.nan
    sd = float(v.std(ddof=1))
    half = float(student_t.ppf(0.5 + level / 2, v.size - 1)) * sd / math.sqrt(v.size)
    return mean, sd, mean - half, mean + half


def summarize_sweep(
    frame: pd.DataFrame,
    label_columns: Sequence[str] = (),
    metrics: Sequence[str] = SUMMARY_METRICS,
    *,
    level: float = 0.95,
) -> pd.DataFrame:
    """Mean, SD and t-interval over seeds per scenario × model.

    Parameters
    ----------
    frame : pandas.DataFrame
        ``sweep.csv`` rows.
    label_columns : sequence of str
        The scenario's label columns (kept in the output).
    metrics : sequence of str
        Metric columns to aggregate (missing ones are skipped).
    level : float
        Confidence level of the interval over seeds. [-]

    Returns
    -------
    pandas.DataFrame
        ``scenario``, the label columns, ``model``, ``n_seeds``, then for every metric
        ``<metric>_mean``, ``<metric>_sd``, ``<metric>_ci_low``, ``<metric>_ci_high``
        (in the metric's unit), in the order the scenarios first appear.

    Examples
    --------
    >>> f = pd.DataFrame({"scenario": ["a", "a"], "model": ["m", "m"], "seed": [0, 1],
    ...                   "rmse_mgdl": [10.0, 12.0]})
    >>> summarize_sweep(f, metrics=["rmse_mgdl"])["rmse_mgdl_mean"].tolist()
    [11.0]
    """
    keys = ["scenario", *[c for c in label_columns if c in frame], "model"]
    rows = []
    for ident, g in frame.groupby(keys, sort=False, dropna=False):
        row = dict(zip(keys, ident, strict=True))
        row["n_seeds"] = int(g["seed"].nunique()) if "seed" in g else len(g)
        for m in metrics:
            if m not in g:
                continue
            mean, sd, lo, hi = _t_interval(g[m].to_numpy(dtype=float), level)
            row.update({f"{m}_mean": mean, f"{m}_sd": sd, f"{m}_ci_low": lo, f"{m}_ci_high": hi})
        rows.append(row)
    return pd.DataFrame(rows)


def _paired(frame: pd.DataFrame, a: str, b: str, metric: str) -> pd.Series:
    """``metric(a) - metric(b)`` per seed (scenarios ``a``, ``b``)."""
    x = frame[frame["scenario"] == a].set_index("seed")[metric]
    y = frame[frame["scenario"] == b].set_index("seed")[metric]
    return (x - y).dropna()


def ablation_effects(
    frame: pd.DataFrame, metric: str = "rmse_mgdl", *, level: float = 0.95
) -> pd.DataFrame:
    """ΔRMSE per noise source from an ablation sweep, paired by seed.

    ``delta_off`` = metric(all sources on) − metric(this source off): what the source
    costs on top of all the others. ``delta_only`` = metric(this source alone on) −
    metric(all sources off): what it costs on its own.

    Parameters
    ----------
    frame : pandas.DataFrame
        ``sweep.csv`` rows of the ``ablation`` study.
    metric : str
        Metric column (``rmse_mgdl`` [mg/dL], ``mard_pct`` [%], ...).
    level : float
        Confidence level of the paired t-interval over seeds. [-]

    Returns
    -------
    pandas.DataFrame
        ``model``, ``source``, ``metric``, ``delta_off``, ``delta_off_ci_low``,
        ``delta_off_ci_high``, ``delta_only``, ``delta_only_ci_low``,
        ``delta_only_ci_high``, ``all_on``, ``all_off`` (means over seeds, in the
        metric's unit) and ``n_seeds``; per model, the most costly source (by
        ``delta_off``) first.
    """
    from ..config import NOISE_SOURCES

    rows = []
    for model, g in frame.groupby("model", sort=False):
        all_on = g.loc[g["scenario"] == "all-on", metric].mean()
        all_off = g.loc[g["scenario"] == "all-off", metric].mean()
        for s in NOISE_SOURCES:
            if f"off:{s}" not in set(g["scenario"]):
                continue
            d_off = _paired(g, "all-on", f"off:{s}", metric)
            d_only = _paired(g, f"only:{s}", "all-off", metric)
            m_off, _, lo_off, hi_off = _t_interval(d_off.to_numpy(), level)
            m_only, _, lo_only, hi_only = _t_interval(d_only.to_numpy(), level)
            rows.append(
                {
                    "model": model,
                    "source": s,
                    "metric": metric,
                    "delta_off": m_off,
                    "delta_off_ci_low": lo_off,
                    "delta_off_ci_high": hi_off,
                    "delta_only": m_only,
                    "delta_only_ci_low": lo_only,
                    "delta_only_ci_high": hi_only,
                    "all_on": all_on,
                    "all_off": all_off,
                    "n_seeds": int(len(d_off)),
                }
            )
    out = pd.DataFrame(rows)
    if len(out):
        order = {m: k for k, m in enumerate(dict.fromkeys(out["model"]))}
        out = (
            out.assign(_o=out["model"].map(order))
            .sort_values(["_o", "delta_off"], ascending=[True, False], kind="stable")
            .drop(columns="_o")
            .reset_index(drop=True)
        )
    return out


def shift_effects(
    frame: pd.DataFrame, metric: str = "rmse_mgdl", *, level: float = 0.95
) -> pd.DataFrame:
    """In-domain vs shifted test performance of the ``cohort`` study, paired by seed.

    Returns
    -------
    pandas.DataFrame
        ``model``, ``shift``, ``train_domain``, ``test_domain`` (shifted), ``metric``,
        ``in_domain``, ``shifted``, ``delta``, ``delta_ci_low``, ``delta_ci_high``
        (shifted − in domain; means over seeds in the metric's unit), ``n_seeds``.
    """
    rows = []
    for (model, shift), g in frame.groupby(["model", "shift"], sort=False):
        a, b = f"{shift}:shifted", f"{shift}:in-domain"
        d = _paired(g, a, b, metric)
        mean, _, lo, hi = _t_interval(d.to_numpy(), level)
        test_domain = g.loc[g["scenario"] == a, "test_domain"]
        rows.append(
            {
                "model": model,
                "shift": shift,
                "train_domain": g["train_domain"].iloc[0],
                "test_domain": test_domain.iloc[0] if len(test_domain) else "",
                "metric": metric,
                "in_domain": g.loc[g["scenario"] == b, metric].mean(),
                "shifted": g.loc[g["scenario"] == a, metric].mean(),
                "delta": mean,
                "delta_ci_low": lo,
                "delta_ci_high": hi,
                "n_seeds": int(len(d)),
            }
        )
    return pd.DataFrame(rows)


def threshold_crossing(
    summary: pd.DataFrame,
    x: str,
    metric: str = "mard_pct",
    threshold: float = 15.0,
    *,
    log_x: bool = True,
) -> pd.DataFrame:
    """Where each model's mean metric first rises through ``threshold`` along ``x``.

    Linear interpolation between the two grid points that bracket the crossing (in
    log x when ``log_x`` and all x are positive).

    Parameters
    ----------
    summary : pandas.DataFrame
        :func:`summarize_sweep` output with a numeric column ``x``.
    x : str
        The varied key (e.g. ``"noise_scale"``).
    metric : str
        Metric whose ``<metric>_mean`` is compared. [its unit]
    threshold : float
        Threshold in the metric's unit (15 % MARD by default). [its unit]
    log_x : bool
        Interpolate in log x.

    Returns
    -------
    pandas.DataFrame
        ``model``, ``crossing`` (x at the crossing; NaN when there is none in the
        grid) and ``status``: ``"crosses"``, ``"above at every x"`` or
        ``"below at every x"``.

    Examples
    --------
    >>> s = pd.DataFrame({"model": ["m"] * 3, "noise_scale": [1.0, 2.0, 4.0],
    ...                   "mard_pct_mean": [10.0, 20.0, 30.0]})
    >>> round(float(threshold_crossing(s, "noise_scale")["crossing"][0]), 3)
    1.414
    """
    rows = []
    for model, g in summary.groupby("model", sort=False):
        g = g.assign(_x=pd.to_numeric(g[x], errors="coerce")).dropna(subset=["_x"])
        g = g.sort_values("_x")
        xs = g["_x"].to_numpy(float)
        ys = g[f"{metric}_mean"].to_numpy(float)
        use_log = log_x and bool(np.all(xs > 0))
        tx = np.log(xs) if use_log else xs
        crossing, status = np.nan, "below at every x"
        if len(ys) and ys[0] > threshold:
            status = "above at every x"
        else:
            for k in range(1, len(ys)):
                if ys[k - 1] <= threshold < ys[k]:
                    f = (threshold - ys[k - 1]) / (ys[k] - ys[k - 1])
                    t = tx[k - 1] + f * (tx[k] - tx[k - 1])
                    crossing, status = float(np.exp(t) if use_log else t), "crosses"
                    break
        rows.append({"model": model, "crossing": crossing, "status": status})
    return pd.DataFrame(rows, columns=["model", "crossing", "status"])


# --------------------------------------------------------------------------- runner

def ranking_crossings(
    summary: pd.DataFrame, metric: str = "rmse_mgdl_mean", exclude: Sequence[str] = ("oracle",)
) -> pd.DataFrame:
    """Where two models swap places as the training set grows (``data-size`` study).

    Parameters
    ----------
    summary : pandas.DataFrame
        :func:`summarize_sweep` of a ``data-size`` sweep (columns ``preset``,
        ``n_train_subjects``, ``model`` and ``metric``).
    metric : str
        Column ranked, lower is better (mean RMSE over seeds by default). [mg/dL]
    exclude : sequence of str
        Models left out (the oracle is a bound, not a competitor).

    Returns
    -------
    pandas.DataFrame
        One row per crossing: ``preset``, ``n_before``, ``n_after`` (consecutive
        training sizes between which the order changes), ``overtaker`` (worse before,
        better after), ``overtaken``, ``diff_before``, ``diff_after`` (overtaker minus
        overtaken, in the metric's unit).

    Examples
    --------
    >>> s = pd.DataFrame({"preset": "p", "n_train_subjects": [80, 320, 80, 320],
    ...                   "model": ["a", "a", "b", "b"], "rmse_mgdl_mean": [20., 10, 15, 12]})
    >>> ranking_crossings(s)[["overtaker", "overtaken", "n_before", "n_after"]].values.tolist()
    [['a', 'b', 80, 320]]
    """
    cols = ["preset", "n_before", "n_after", "overtaker", "overtaken", "diff_before", "diff_after"]
    rows = []
    s = summary[~summary["model"].isin(exclude)]
    for preset, g in s.groupby("preset", sort=False):
        table = g.pivot_table(index="n_train_subjects", columns="model", values=metric)
        table = table.sort_index()
        sizes = table.index.tolist()
        models = list(dict.fromkeys(g["model"]))
        for i, a in enumerate(models):
            for b in models[i + 1 :]:
                d = (table[a] - table[b]).to_numpy(dtype=float)
                for k in range(len(sizes) - 1):
                    d0, d1 = d[k], d[k + 1]
                    if not (np.isfinite(d0) and np.isfinite(d1)) or d0 * d1 >= 0:
                        continue
                    over, under = (a, b) if d0 > 0 else (b, a)
                    sign = 1.0 if over == a else -1.0
                    rows.append(
                        {
                            "preset": preset,
                            "n_before": int(sizes[k]),
                            "n_after": int(sizes[k + 1]),
                            "overtaker": over,
                            "overtaken": under,
                            "diff_before": sign * d0,
                            "diff_after": sign * d1,
                        }
                    )
    return pd.DataFrame(rows, columns=cols)


def _resolve_seeds(seeds: int | Sequence[int]) -> list[int]:
    if isinstance(seeds, int | np.integer) and not isinstance(seeds, bool):
        if seeds < 1:
            raise ConfigError(f"seeds must be a positive count, got {seeds}")
        return list(range(int(seeds)))
    out = [int(s) for s in seeds]
    if not out or any(s < 0 for s in out) or len(set(out)) != len(out):
        raise ConfigError(f"seeds must be distinct non-negative integers, got {list(seeds)}")
    return out


def _check_positive(name: str, value: Any) -> int:
    if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < 1:
        raise ConfigError(f"{name} must be a positive integer, got {value!r}")
    return int(value)


def run_sweep(
    vary: Mapping[str, Sequence[Any]] | None = None,
    *,
    study: str | None = None,
    preset: str | None = None,
    seeds: int | Sequence[int] = 5,
    models: Sequence[str] | str | None = None,
    overrides: Mapping[str, Any] | None = None,
    protocol: str = "grouped-cv",
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
) -> SweepResult:
    """Run a grid of scenarios × seeds × models (local processes or a Dask cluster).

    Parameters
    ----------
    vary : mapping of str to sequence, optional
        Dotted config key -> values; several keys make a grid. Exclusive with ``study``.
    study : str, optional
        A built-in study (:data:`STUDIES`); with ``vary`` naming the study's own key,
        its values replace the default ones.
    preset : str, optional
        Scenario preset every task starts from (default ``paper``); for the
        ``data-size`` study a comma-separated list (default :data:`DATA_SIZE_PRESETS`).
    seeds : int or sequence of int
        Number of seeds (0, 1, ...) or the seeds themselves.
    models : sequence of str or comma-separated str, optional
        Registry names (default :data:`DEFAULT_MODELS`).
    overrides : mapping, optional
        Dotted overrides shared by every scenario (``--set``).
    protocol, n_splits, repeats : str, int, int
        Protocol of :func:`~nirglucose.evaluation.benchmark.run_benchmark` per task.
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
        cross-validated task (:mod:`~nirglucose.evaluation.calibration`): adds
        :data:`CALIBRATION_METRICS` (shift tasks leave them empty).

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
    from .. import __version__
    from ..models.registry import get_model_class
    from .executors import resolve_backend, run_unordered
    from .splits import check_protocol

    t_start = time.perf_counter()
    base = dict(overrides or {})
    presets = None
    if study == "data-size" and preset is not None:
        presets = [p.strip() for p in str(preset).split(",") if p.strip()]
    preset = "paper" if preset is None or study == "data-size" else preset
    if study == "data-size":
        if vary and set(vary) != {"n_train_subjects"}:
            raise ConfigError(
                "--vary cannot be combined with --study data-size (except to set its "
                "sizes: --vary n_train_subjects=80,320,...)"
            )
        scenarios = study_scenarios(
            study, list(vary["n_train_subjects"]) if vary else None, presets
        )
    elif study is not None:
        if study not in STUDIES:
            raise ConfigError(unknown_name("study", study, STUDIES))
        values = None
        if vary:
            key = STUDY_GRIDS.get(study, (None,))[0]
            if key is None or set(vary) != {key}:
                raise ConfigError(
                    f"--vary cannot be combined with --study {study}"
                    + (f" (except to set its values: --vary {key}=...)" if key else "")
                )
            values = list(vary[key])
        if study in STUDY_GRIDS:
            key, default = STUDY_GRIDS[study]
            scenarios = grid_scenarios(
                {key: values if values is not None else list(default)},
                preset=preset,
                base_overrides=base,
            )
        else:
            scenarios = study_scenarios(study)
    else:
        scenarios = grid_scenarios(vary or {}, preset=preset, base_overrides=base)
    if models is None:
        models = list(DEFAULT_MODELS)
    elif isinstance(models, str):
        models = [m.strip() for m in models.split(",") if m.strip()]
    models = list(dict.fromkeys(models))
    if not models:
        raise ConfigError("no models given")
    for m in models:
        get_model_class(m)
    check_protocol(protocol)
    for name, value in (
        ("n_splits", n_splits),
        ("repeats", repeats),
        ("n_subjects", n_subjects),
        ("per_subject", per_subject),
        ("n_boot", n_boot),
    ):
        _check_positive(name, value)
    seed_list = _resolve_seeds(seeds)
    backend, n_workers = resolve_backend(jobs, scheduler)
    specs = plan_sweep(
        scenarios,
        preset=preset,
        seeds=seed_list,
        models=models,
        base_overrides=base,
        protocol=protocol,
        n_splits=n_splits,
        repeats=repeats,
        n_subjects=n_subjects,
        per_subject=per_subject,
        n_boot=n_boot,
        model_params=model_params,
    )
    from .calibration import check_k

    calibration = check_k(calibration)
    if calibration:  # only then: task hashes without it stay as they were
        for s in specs:
            if s["kind"] == "cv":
                s["calibration"] = calibration
    keys = [_task_key(s) for s in specs]
    unique = list(dict.fromkeys(keys))
    spec_of = dict(zip(keys, specs, strict=True))

    tasks_dir = None
    if out is not None:
        tasks_dir = _prepare_out(out) / ".tasks"
        tasks_dir.mkdir(exist_ok=True)
    results: dict[str, dict[str, Any]] = {}
    pending: list[str] = []
    n_corrupt = 0
    for key in unique:
        if tasks_dir is None:
            pending.append(key)
            continue
        path = _task_file(tasks_dir, spec_of[key], key)
        cached = _load_task(path, spec_of[key])
        if cached is None:
            if path.exists():
                n_corrupt += 1
                warnings.warn(
                    f"task file {path.name} is corrupt or partial; recomputing it", stacklevel=2
                )
            pending.append(key)
        else:
            results[key] = cached
            if on_task is not None:
                on_task(spec_of[key], True)

    bar = TaskProgress("sweep", len(unique), len(results), "reused") if progress else None
    try:
        stream = run_unordered(
            run_sweep_task,
            [spec_of[k] for k in pending],
            jobs=jobs,
            scheduler=scheduler,
            keys=[f"nirglucose-sweep-{k}" for k in pending],
        )
        try:
            for i, res in stream:
                key = pending[i]
                spec = spec_of[key]
                if res.get("version") != spec["version"]:
                    raise DataError(
                        f"a worker runs nirglucose {res.get('version')}, this "
                        f"process {spec['version']}; install the same version "
                        "on every worker"
                    )
                if res.get("source_sha256") != spec["source_sha256"]:
                    warnings.warn(
                        "a worker runs different nirglucose code than this process "
                        f"(source digest {res.get('source_sha256')} vs "
                        f"{spec['source_sha256']}); results may mix code versions",
                        stacklevel=2,
                    )
                if tasks_dir is not None:
                    _save_task(_task_file(tasks_dir, spec, key), spec, res)
                results[key] = res
                if on_task is not None:
                    on_task(spec, False)
                if bar is not None:
                    bar.advance(f"{spec['model']} seed {spec['seed']}")
        finally:
            stream.close()
    finally:
        if bar is not None:
            bar.close()

    label_columns = list(dict.fromkeys(k for s in scenarios for k in s.labels))
    rows = []
    study_name = study or "grid"
    k = 0
    for sc in scenarios:
        for seed in seed_list:
            for model in models:
                res = results[keys[k]]
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
    summary = summarize_sweep(frame, label_columns)
    effects = None
    if study == "ablation":
        effects = ablation_effects(frame)
    elif study == "cohort":
        effects = shift_effects(frame)
    elif study == "data-size":
        effects = ranking_crossings(summary)
    task_warnings = list(dict.fromkeys(w for r in results.values() for w in r.get("warnings", [])))
    meta = {
        "study": study_name,
        "preset": (
            preset if study != "data-size" else list(dict.fromkeys(s.preset for s in scenarios))
        ),
        "base_overrides": _canonical(base),
        "scenarios": [s.name for s in scenarios],
        "label_columns": label_columns,
        "varied": (
            [STUDY_GRIDS[study][0]]
            if study in STUDY_GRIDS
            else list(vary or {})
            if study is None
            else []
        ),
        "seeds": seed_list,
        "models": models,
        "protocol": protocol,
        "n_splits": n_splits,
        "repeats": repeats,
        "n_subjects": n_subjects,
        "per_subject": per_subject,
        "n_boot": n_boot,
        "version": __version__,
        "task_format": TASK_FORMAT,
        "backend": backend,
        "workers": n_workers if backend != "dask" else None,
        "scheduler": scheduler if isinstance(scheduler, str) else None,
        "tasks_total": len(unique),
        "tasks_cached": len(unique) - len(pending),
        "tasks_computed": len(pending),
        "tasks_corrupt": n_corrupt,
        "task_wall_s_total": float(sum(r.get("wall_s", 0.0) for r in results.values())),
        "wall_time_s": time.perf_counter() - t_start,
        "warnings": task_warnings,
        "summary_method": "mean over seeds with a Student-t 95 % interval of the mean",
    }
    result = SweepResult(frame=frame, summary=summary, effects=effects, meta=meta)
    if out is not None:
        result.save(out)
    return result
