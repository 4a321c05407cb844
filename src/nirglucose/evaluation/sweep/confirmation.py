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
* ``device-inversion`` (deployable: the forward-model estimator that reads only the
  device's declared parts and published tables), ``ebl`` and ``pls`` (deployable,
  data-driven): what a device estimator reaches today.

The privileged estimators' residual-variance floor is the quantisation of the data's
declared ADC bits (:func:`~nirglucose.models._inversion_solver.residual_var_floor`,
LSB^2 / 12: 2e-8 in ln units at 12 bits, a quarter per extra bit), and the averaging
emulation raises those bits by log4 of the readings averaged, so on a quieter design
they can use the extra resolution the bound credits it with. (Before issue 40 the floor
was fixed at a 12-bit code's, and on such designs they stayed above the bounds.)
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
CONFIRM_MODELS: tuple[str, ...] = ("oracle", "physics-inversion", "device-inversion", "ebl",
                                   "pls")
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
