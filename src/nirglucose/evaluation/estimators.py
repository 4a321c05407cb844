"""The models a benchmark or a sweep is given: registered names or estimator objects.

:func:`~nirglucose.evaluation.benchmark.run_benchmark` and
:func:`~nirglucose.evaluation.sweep.run_sweep` take, as scikit-learn's
``cross_validate`` takes one estimator, a list whose entries are

* a registered name (``"ebl"``; :func:`~nirglucose.models.registry.available_models`),
  built per task with the preset's tuned parameters, as before;
* an unfitted estimator object (anything with ``fit``, ``predict`` and ``get_params``,
  e.g. a scikit-learn :class:`~sklearn.pipeline.Pipeline`), whose row is labelled with
  the registry name of its class (``make_model("pls")`` -> ``"pls"``) or else the class
  name (``Pipeline``);
* a ``(label, estimator)`` pair, as the steps of a scikit-learn Pipeline, to name the row.

Each task fits its own :func:`sklearn.base.clone` of an object, so the caller's object
stays unfitted. An object is fitted **as given**: no tuning grid, no preset's tuned
parameters (``model_params[label]`` still applies, through ``set_params``), and no
physics ablation. The task's seed reaches it through its ``random_state`` parameters
(:func:`build_estimator`).

What an object is fed
    An estimator of a registered class (or a subclass of one: the package's own
    estimators) takes the fold's :class:`~nirglucose.dataset.Dataset`, exactly as a
    registered name does, so ``make_model("pls")`` and ``"pls"`` give the same numbers.
    Any other estimator is called as scikit-learn calls it: ``fit(X, y)`` and
    ``predict(X)``, with ``X`` the device's measured columns as a DataFrame
    (:func:`measured_frame`: ADC codes, references and the measured physiology, never
    ``true_*``, ids or the target) and ``y`` the reference glucose. [mg/dL]

Identity and caching
    A task's cache key covers an object through :func:`estimator_identity`: its class
    path, the hash of the file defining each class outside the package, and its
    ``get_params(deep=False)`` values, described recursively and deterministically
    (arrays by their SHA-256). A value without a stable description (a lambda, a local
    function, an object whose ``repr`` holds an address) keeps its ``repr``, which
    differs between processes: that task is then recomputed on a rerun, never wrongly
    reused.
"""

from __future__ import annotations

import hashlib
import inspect
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import pandas as pd
from sklearn.base import clone

from ..dataset import Dataset
from ..dataset.columns import (
    KNOWN_PHYSIOLOGY,
    adc_columns,
    has_reference_columns,
    led_wavelengths_in,
    ref_columns,
)
from ..exceptions import ConfigError
from ..models.registry import available_models, get_model_class
from .engine.tasks import derived_seed, external_code_digest

__all__ = [
    "OBJECT_TUNING",
    "ModelEntry",
    "build_estimator",
    "check_object_params",
    "describe_entries",
    "estimator_identity",
    "fit_history",
    "fit_model",
    "measured_frame",
    "predict_model",
    "resolve_entries",
    "resolve_rows",
    "seeded_params",
    "takes_dataset",
]

#: How an estimator object is tuned (recorded in the results' metadata).
OBJECT_TUNING = "none: fitted as given (no tuning grid, no preset's tuned parameters)"


@dataclass(frozen=True)
class ModelEntry:
    """One row's model: a registered ``name`` or the caller's ``estimator``.

    Attributes
    ----------
    label : str
        The row's name in every table.
    estimator : object or None
        The caller's unfitted estimator (cloned per task, never fitted itself); None
        for a registered name (then ``label`` is that name).
    """

    label: str
    estimator: Any = None


def _class_path(cls: type) -> str:
    return f"{cls.__module__}.{cls.__qualname__}"


def _default_label(est: Any) -> str:
    """The registry name of ``est``'s class when it is registered as such, else its class name."""
    cls = type(est)
    name = cls.__dict__.get("registry_name")
    if isinstance(name, str) and get_model_class(name) is cls:
        return name
    return cls.__name__


def _check_estimator(entry: Any, label: str | None) -> None:
    where = f"models entry {label!r} ({type(entry).__name__})" if label else (
        f"models entry {type(entry).__name__}")
    if isinstance(entry, type):
        raise ConfigError(f"models entry {entry.__name__} is a class; give an instance, e.g. "
                          f"{entry.__name__}()")
    if not (callable(getattr(entry, "fit", None)) and callable(getattr(entry, "predict", None))):
        raise ConfigError(
            f"{where} has no fit/predict methods; give a registered name "
            f"({', '.join(available_models())}) or an estimator with fit, predict and get_params"
        )
    if not callable(getattr(entry, "get_params", None)):
        raise ConfigError(f"{where} has no get_params, so it cannot be cloned per fold; derive "
                          "it from sklearn.base.BaseEstimator")


def _entry(item: Any) -> ModelEntry:
    """One entry of ``models`` as a :class:`ModelEntry` (checked)."""
    if isinstance(item, str):
        get_model_class(item)  # raises ConfigError listing the valid names
        return ModelEntry(item)
    if isinstance(item, tuple) and len(item) == 2 and not hasattr(item, "fit"):
        label, est = item
        if not isinstance(label, str) or not label.strip():
            raise ConfigError(f"a (label, estimator) pair needs a non-empty text label, got "
                              f"{label!r}")
        _check_estimator(est, label)
    else:
        _check_estimator(item, None)
        label, est = _default_label(item), item
    if "/" in label:  # '/' marks the ablation rows (<pinn>/no-physics)
        raise ConfigError(f"model label {label!r} may not contain '/'; rename it")
    return ModelEntry(label, est)


def resolve_entries(models: Any, default: Sequence[str]) -> list[ModelEntry]:
    """The rows of ``models``: names, estimator objects and ``(label, estimator)`` pairs.

    Parameters
    ----------
    models : sequence, str, estimator or None
        A list of registered names, estimator objects and ``(label, estimator)`` pairs;
        a comma-separated string of names; one estimator object; None for ``default``.
    default : sequence of str
        Registered names taken when ``models`` is None.

    Returns
    -------
    list of ModelEntry
        In the given order; a name given twice is one row (as before).

    Raises
    ------
    ConfigError
        No models, an unknown name, an entry without ``fit``/``predict`` or
        ``get_params`` (a class instead of an instance), a bad label, or two rows
        with one label.

    Examples
    --------
    >>> from sklearn.linear_model import Ridge
    >>> [e.label for e in resolve_entries(["pls", ("ridge", Ridge()), Ridge()], [])]
    ['pls', 'ridge', 'Ridge']
    >>> resolve_entries(["pls", ("pls", Ridge())], [])  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    nirglucose.exceptions.ConfigError: two models share the label 'pls'; name each with a ...
    """
    if models is None:
        if not default:
            raise ConfigError("no models are registered")
        models = list(default)
    if isinstance(models, str):
        models = [m.strip() for m in models.split(",") if m.strip()]
    elif hasattr(models, "fit"):  # one estimator (a Pipeline is also a sequence of steps)
        models = [models]
    entries: dict[str, ModelEntry] = {}
    for item in models:
        e = _entry(item)
        if e.label in entries and (e.estimator is not None or
                                   entries[e.label].estimator is not None):
            raise ConfigError(f"two models share the label {e.label!r}; name each with a "
                              "(label, estimator) pair")
        entries.setdefault(e.label, e)
    if not entries:
        raise ConfigError(f"no models given; valid: {', '.join(available_models())}")
    return list(entries.values())


def check_object_params(objects: Mapping[str, Any], params: Mapping[str, Any]) -> None:
    """Refuse ``model_params`` that are no mapping, or that an estimator object does not
    take, before any task runs.

    Raises
    ------
    ConfigError
        A value of ``params`` is not a mapping, or ``set_params`` of a clone refuses
        ``params[label]`` (the message is its reason).
    """
    for label, value in params.items():
        if not isinstance(value, Mapping):
            raise ConfigError(f"model_params[{label!r}] must be a mapping of parameter names "
                              f"to values, got {type(value).__name__}")
    for label, est in objects.items():
        if params.get(label):
            try:
                clone(est).set_params(**params[label])
            except ValueError as exc:
                raise ConfigError(f"model_params[{label!r}]: {' '.join(str(exc).split())}"
                                  ) from None


def resolve_rows(models: Any, default: Sequence[str], params: Mapping[str, Any] | None
                 ) -> tuple[list[str], dict[str, Any]]:
    """The rows' labels, in order, and label -> estimator object, with ``params`` checked
    against the objects (:func:`resolve_entries`, :func:`check_object_params`): what the
    benchmark and the sweep both start from.

    Examples
    --------
    >>> from sklearn.linear_model import Ridge
    >>> labels, objects = resolve_rows(["pls", Ridge()], [], {"Ridge": {"alpha": 2.0}})
    >>> labels, list(objects)
    (['pls', 'Ridge'], ['Ridge'])
    """
    entries = resolve_entries(models, default)
    objects = {e.label: e.estimator for e in entries if e.estimator is not None}
    check_object_params(objects, params or {})
    return [e.label for e in entries], objects


def describe_entries(objects: Mapping[str, Any]) -> dict[str, dict[str, str]]:
    """Label -> how an estimator object's row was built (class, repr, input, tuning), for
    the results' metadata."""
    return {
        label: {
            "class": _class_path(type(est)),
            "estimator": repr(est),
            "input": "dataset" if takes_dataset(est) else "measured columns (X, y)",
            "tuning": OBJECT_TUNING,
        }
        for label, est in objects.items()
    }


def _describe(value: Any) -> Any:
    """A JSON-able, deterministic description of one parameter value."""
    if value is None or isinstance(value, str | bool | int | float):
        return value
    if isinstance(value, np.ndarray):
        data = np.ascontiguousarray(value)
        return {"array_sha256": hashlib.sha256(data.tobytes()).hexdigest(),
                "dtype": str(data.dtype), "shape": list(data.shape)}
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, list | tuple):
        return [_describe(v) for v in value]
    if isinstance(value, Mapping):
        return {str(k): _describe(v) for k, v in value.items()}
    if isinstance(value, type):
        return {"class": _class_path(value), "code": external_code_digest(value)}
    if callable(getattr(value, "get_params", None)):
        return estimator_identity(value)
    name = getattr(value, "__qualname__", None)
    if inspect.isfunction(value) and name and "<" not in name:  # a named module-level function
        return {"function": f"{value.__module__}.{name}",
                "code": external_code_digest(value)}  # type: ignore[arg-type]
    return repr(value)


def estimator_identity(est: Any) -> dict[str, Any]:
    """The deterministic, JSON-able identity of an estimator object (its task key part).

    Parameters
    ----------
    est : estimator
        Anything with ``get_params``.

    Returns
    -------
    dict
        ``{"class", "code", "params"}``: the class path, the SHA-256 (16 hex digits) of
        the file defining the class when it lies outside the package (None inside), and
        ``get_params(deep=False)`` with nested estimators described the same way.

    Examples
    --------
    >>> from sklearn.linear_model import Ridge
    >>> ident = estimator_identity(Ridge(alpha=2.0))
    >>> ident["class"], ident["params"]["alpha"]
    ('sklearn.linear_model._ridge.Ridge', 2.0)
    """
    cls = type(est)
    params = est.get_params(deep=False)
    return {
        "class": _class_path(cls),
        "code": external_code_digest(cls),
        "params": {str(k): _describe(params[k]) for k in sorted(params)},
    }


def seeded_params(cls: type, params: Mapping[str, Any], seed: int) -> dict[str, Any]:
    """``params`` with ``random_state=seed`` added when ``cls`` takes one and none is given."""
    params = dict(params)
    if "random_state" in inspect.signature(cls).parameters and "random_state" not in params:
        params["random_state"] = seed
    return params


def build_estimator(maker: Any, params: Mapping[str, Any], seed: int) -> Any:
    """A new, unfitted estimator for one task.

    Parameters
    ----------
    maker : type or estimator
        A registered class (built as ``maker(**params)``), or the caller's estimator
        object (built as ``clone(maker).set_params(**params)``).
    params : mapping
        Constructor or ``set_params`` keyword arguments.
    seed : int
        The task's seed. A class taking ``random_state`` gets ``random_state=seed``
        unless ``params`` gives one (:func:`seeded_params`). An object's
        ``random_state`` parameters that are None after ``params`` (its own, and its
        steps' ``<step>__random_state``) get a seed: ``seed`` itself for the top-level
        one, as a registered class, and ``derived_seed(seed, key)`` for each nested one
        (independent streams); an integer or generator the caller set is kept. [-]

    Examples
    --------
    >>> from sklearn.pipeline import make_pipeline
    >>> from sklearn.ensemble import RandomForestRegressor
    >>> from sklearn.preprocessing import StandardScaler
    >>> pipe = make_pipeline(StandardScaler(), RandomForestRegressor(random_state=None))
    >>> m = build_estimator(pipe, {}, seed=7)
    >>> m.get_params()["randomforestregressor__random_state"] is not None, m is pipe
    (True, False)
    """
    if isinstance(maker, type):
        return maker(**seeded_params(maker, params, seed))
    model = clone(maker)
    if params:
        model.set_params(**params)
    seeds = {
        key: seed if key == "random_state" else derived_seed(seed, key)
        for key, value in model.get_params(deep=True).items()
        if (key == "random_state" or key.endswith("__random_state"))
        and value is None and key not in params
    }
    if seeds:
        model.set_params(**seeds)
    return model


def takes_dataset(model: Any) -> bool:
    """Whether ``model`` (an object or a class) is one of the package's own estimators (a
    registered class or a subclass of one): it takes a Dataset, as registered names do."""
    cls = model if isinstance(model, type) else type(model)
    return isinstance(getattr(cls, "registry_name", None), str)


def measured_frame(data: Dataset) -> pd.DataFrame:
    """The device's measured columns of ``data`` (what any other estimator gets as ``X``).

    ``adc_<nm>`` for each LED, ascending, and ``adc_ref_<nm>`` where the device has them,
    then the measured physiology it records (:data:`~nirglucose.dataset.columns.KNOWN_PHYSIOLOGY`),
    in that order; never ``true_*``, ids or ``glucose_mgdl``. The LEDs and references are
    read by the schema's rule (:func:`~nirglucose.dataset.columns.led_wavelengths_in`,
    :func:`~nirglucose.dataset.columns.has_reference_columns`), so a reference learner sees the
    channels a package model sees, in the same order whatever the file's column order.

    Raises
    ------
    DataError
        Reference codes for some LEDs only, or two columns naming one LED.
    """
    frame = data.frame
    wl = led_wavelengths_in(frame.columns)
    refs = ref_columns(wl) if has_reference_columns(frame.columns, wl) else []
    cols = [*adc_columns(wl), *refs, *(c for c in KNOWN_PHYSIOLOGY if c in frame)]
    return frame[cols]


def fit_model(model: Any, train: Dataset, val: Dataset | None = None) -> Any:
    """Fit ``model`` on ``train`` (in place; returns it).

    A package estimator gets the Dataset, and the validation part as
    ``X_val``/``y_val`` when its ``fit`` takes ``X_val``; any other estimator gets
    ``fit(X, y)`` on the training part only (:func:`measured_frame`, ``glucose_mgdl``).
    """
    if not takes_dataset(model):
        model.fit(measured_frame(train), train.frame["glucose_mgdl"].to_numpy(float))
        return model
    kwargs: dict[str, Any] = {}
    if val is not None and "X_val" in inspect.signature(type(model).fit).parameters:
        kwargs = {"X_val": val, "y_val": val.frame["glucose_mgdl"].to_numpy(float)}
    model.fit(train, **kwargs)
    return model


def fit_history(model: Any) -> list[dict[str, Any]]:
    """A fitted model's ``history_`` (per-epoch rows) as JSON-able dicts; [] without one."""
    hist = getattr(model, "history_", None)
    if not isinstance(hist, list | tuple):  # none, or another library's own kind of record
        return []
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


def predict_model(model: Any, data: Dataset) -> np.ndarray:
    """``model``'s predictions for ``data`` as a flat float array. [mg/dL]"""
    X = data if takes_dataset(model) else measured_frame(data)
    return np.asarray(model.predict(X), dtype=float).ravel()
