"""Confirming named designs by simulation: the oracle and the estimators beside the bounds.

A design the requirements study names (:mod:`~nirglucose.design.requirements`) is
simulated in its preset with its levers (averaging emulated by
:func:`~nirglucose.design.averaging.averaging_overrides`) and scored by the benchmark
(:func:`~nirglucose.evaluation.benchmark.run_benchmark`: subject-grouped K-fold, cluster
bootstrap 95 % intervals) for each model of :data:`CONFIRM_MODELS`:

* ``oracle`` (privileged: the true nuisances), to set beside the oracle-conditioned
  bound;
* ``physics-inversion`` (privileged: it reads the scenario's forward model, as the bounds
  do, but estimates the nuisances), to set beside the per-state bound;
* ``ebl`` and ``pls``, deployable: what a data-driven device estimator reaches today.

Caveat, measured: both privileged estimators add a residual-variance floor of a 12-bit
code's quantisation (2e-8 in ln units; ``_VAR_FLOOR`` in models/oracle.py and
models/inversion.py) to their noise covariance, so on a design whose noise is below a
12-bit code's (more ADC bits, or readings averaged) they cannot use the extra
resolution and stay above the bounds; their RMSE there confirms the data, not the bound.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import pandas as pd

from ...api import simulate
from ...config import resolve_config
from ...design.averaging import averaging_overrides
from ...exceptions import check_positive_int
from ..benchmark import run_benchmark
from ..protocol import Protocol

__all__ = ["CONFIRM_MODELS", "confirm_design"]

#: Models scoring a confirmed design (module docstring).
CONFIRM_MODELS: tuple[str, ...] = ("oracle", "physics-inversion", "ebl", "pls")
#: Reported columns of the benchmark's metrics.
_METRICS = ("rmse_mgdl", "rmse_ci_low", "rmse_ci_high", "mard_pct")


def confirm_design(preset: str, overrides: dict[str, Any], n_readings: int = 1, *,
                   n_subjects: int = 60, per_subject: int = 3, seed: int = 0,
                   models: Sequence[str] = CONFIRM_MODELS, n_splits: int = 5,
                   n_boot: int = 500, jobs: int = 1) -> pd.DataFrame:
    """Simulate one design and score ``models`` on it with grouped cross-validation.

    Parameters
    ----------
    preset : str
        Scenario preset.
    overrides : dict
        The design's dotted overrides (one reading).
    n_readings : int
        Readings the design averages per estimate (emulated in the simulator). [-]
    n_subjects, per_subject : int
        Simulated subjects and snapshots each. [-]
    seed : int
        Seed of the simulation and the benchmark (folds, bootstrap).
    models : sequence of str
        Registered model names.
    n_splits : int
        Folds of the subject-grouped cross-validation (one repeat). [-]
    n_boot : int
        Cluster-bootstrap resamples of the 95 % intervals. [-]
    jobs : int
        Worker processes of the benchmark (results identical for any value).

    Returns
    -------
    pandas.DataFrame
        One row per model: ``model``, ``rmse_mgdl``, ``rmse_ci_low``, ``rmse_ci_high``,
        ``mard_pct`` [mg/dL], [%], and ``n_readings_emulated``, ``n_rows``.
    """
    n = check_positive_int("n_readings", n_readings)
    cfg = resolve_config(preset, overrides)
    ov = {**overrides, **averaging_overrides(cfg, n)}
    ds = simulate(preset, n_subjects=n_subjects, per_subject=per_subject, seed=seed,
                  overrides=ov)
    protocol = Protocol(n_splits=n_splits, repeats=1, seed=seed, resamples=n_boot)
    res = run_benchmark(ds, list(models), protocol=protocol, jobs=jobs,
                        drop_one_models="none", oracle_reference=False)
    out = res.metrics[["model", *_METRICS]].copy()
    out["n_readings_emulated"] = n
    out["n_rows"] = len(ds)
    return out.reset_index(drop=True)
