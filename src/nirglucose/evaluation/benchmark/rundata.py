"""What the findings read from one preset's results directory, and how they name a row.

A leaf of the findings (:mod:`.findings` and :mod:`.answer` both build on it, neither
imports the other back): :class:`RunData`, whether a row is privileged (it reads the
generating scenario or the true nuisances: a reference, never the best model), a
deployable competitor or a reference, a PINN's tuned physics weight, and the name a
sentence gives a row (``physics off``, ``reference (knows …)``).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any, Final

import pandas as pd

from ...models.labels import ablation_base, knows, label, row_privilege
from .finding import Value
from .result import ORACLE

__all__ = ["NO_SKILL", "RunData", "privilege", "is_competitor", "is_reference",
           "display_name", "tuned_lambda", "truthy"]

#: Registry name of the no-skill reference (the training mean).
NO_SKILL: Final = "mean"


@dataclass
class RunData:
    """What the findings read from one preset's results directory.

    Attributes
    ----------
    preset : str
        The preset's name (also the results sub-directory).
    metrics : pandas.DataFrame
        ``metrics.json`` rows.
    meta : dict
        ``meta.json``.
    predictions : pandas.DataFrame
        ``predictions.parquet``.
    comparisons, ablation : pandas.DataFrame or None
        ``comparisons.csv``, ``ablation.csv``.
    drop_one : pandas.DataFrame or None
        ``drop_one.csv`` (the drop-one-LED refits).
    histories : mapping or None
        ``histories.json``.
    """

    preset: str
    metrics: pd.DataFrame
    meta: dict[str, Any]
    predictions: pd.DataFrame
    comparisons: pd.DataFrame | None = None
    ablation: pd.DataFrame | None = None
    no_skill: pd.DataFrame | None = field(default=None, repr=False)
    drop_one: pd.DataFrame | None = None
    #: ``histories.json`` (model -> per-epoch rows), for the physics terms' verdicts.
    histories: Mapping[str, Any] | None = field(default=None, repr=False)
    #: The competitors against the best deployable one (computed when the run's own
    #: ``vs_best`` family was ranked with a privileged row as the best).
    vs_best: pd.DataFrame | None = field(default=None, repr=False)

    @property
    def m(self) -> pd.DataFrame:
        """Metrics indexed by model."""
        return self.metrics.drop_duplicates("model").set_index("model")

    def metric(self, model: str, column: str, digits: int = 1, **kw: Any) -> Value:
        """A value of ``metrics.json`` with its source."""
        return Value(float(self.m.at[model, column]), digits,
                     (f"{self.preset}/metrics.json:{model}:{column}",), **kw)


def privilege(run: RunData | None, model: str) -> str | None:
    """What ``model`` knows beyond the measured columns on this run (None: deployable).

    The ``privileged`` column of ``metrics.json`` where the run wrote one, else the
    registry's declaration (:func:`~nirglucose.models.labels.row_privilege`); the
    oracle is always privileged.
    """
    if run is not None and "privileged" in run.metrics.columns:
        m = run.m
        if model in m.index:
            v = m.at[model, "privileged"]
            if isinstance(v, str) and v.strip():
                return v
            if model != ORACLE and row_privilege(model) is None:
                return None
    got = row_privilege(model)
    if got is None and model == ORACLE:
        return "true nuisances (true_* columns)"
    return got


def is_competitor(model: str, run: RunData | None = None) -> bool:
    """A deployable estimator's own row: not a reference, not an ablation, not privileged."""
    return (model not in (ORACLE, NO_SKILL) and ablation_base(model) is None
            and privilege(run, model) is None)


def is_reference(model: str, run: RunData | None = None) -> bool:
    """A privileged estimator's own row (the oracle included): a reference, never best."""
    return ablation_base(model) is None and model != NO_SKILL and privilege(run, model) is not None


def display_name(run: RunData, model: str) -> str:
    """A model's label as the findings write it: ``physics off`` where its tuned λ is 0,
    ``reference (knows …)`` where it is privileged."""
    name = label(model)
    if tuned_lambda(run, model) == 0.0 and ablation_base(model) is None:
        name += " (physics off: tuned λ = 0)"
    priv = privilege(run, model)
    if priv is not None and ablation_base(model) is None:
        name += f" (reference, {knows(priv)})"
    return name


def tuned_lambda(run: RunData, pinn: str) -> float | None:
    """A PINN's tuned physics weight ``lambda_phys`` (``meta.json``), None if not recorded."""
    v = (run.meta.get("model_params") or {}).get(pinn, {}).get("lambda_phys")
    return None if v is None else float(v)


def truthy(v: Any) -> bool:
    """Whether a CSV cell reads as true (``True``, ``1``, ``1.0``, any case)."""
    return str(v).strip().lower() in ("true", "1", "1.0")
