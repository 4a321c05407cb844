"""The top-level entry points re-exported by :mod:`nirglucose`."""

from __future__ import annotations

from typing import Any

import numpy as np

from .config import ScenarioConfig, resolve_config
from .config.overrides import check_overrides
from .dataset import Dataset, load_dataset
from .exceptions import ConfigError, check_positive_int, check_seed
from .resources import check_simulation_size

__all__ = ["simulate", "simulate_wear"]


def simulate(
    preset: str | ScenarioConfig = "paper",
    n_subjects: int = 80,
    per_subject: int = 3,
    seed: int = 0,
    *,
    n_jobs: int = 1,
    wear_days: int | None = None,
    every_min: int | None = None,
    overrides: dict[str, Any] | None = None,
    **dotted: Any,
) -> Dataset:
    """Simulate snapshots of the noise-stressed NIR sensor.

    Parameters
    ----------
    preset : str or ScenarioConfig
        'paper', 'physical', 'lab', 'field', or a resolved config.
    n_subjects : int
        Number of subjects (traits fixed per subject). [-]
    per_subject : int
        Measurements per subject. [-]
    seed : int
        Seed of every random stream. [-]
    n_jobs : int
        Worker processes; the result does not depend on it.
    wear_days, every_min : int, optional
        Simulate a device worn ``wear_days`` days with a reading every ``every_min``
        minutes (default 5) instead of snapshots: :func:`simulate_wear` (``per_subject``
        must then stay at its default). [d], [min]
    overrides : dict, optional
        Dotted config keys to values, e.g. ``{"hardware.adc_bits": 14}``.
    **dotted
        Overrides as keywords, with ``__`` for dots: ``hardware__adc_bits=14``.

    Returns
    -------
    Dataset

    Examples
    --------
    >>> ds = simulate("paper", n_subjects=4, per_subject=2, seed=1)
    >>> len(ds), ds.frame["adc_850"].dtype.kind
    (8, 'i')
    """
    # deferred: the simulator loads scipy.special (~0.2 s), which ``import nirglucose``
    # skips until the first simulation (tests/test_layout.py, SLOW_MODULES)
    from .simulation.simulator import simulate_frame

    if wear_days is not None or every_min is not None:
        if wear_days is None:
            raise ConfigError("every_min applies to a worn device; give wear_days too")
        if per_subject != 3:
            raise ConfigError("per_subject does not apply with wear_days: each subject has "
                              "wear_days x 1440 / every_min readings")
        return simulate_wear(preset, n_subjects, wear_days, 5 if every_min is None else every_min,
                             seed, n_jobs=n_jobs, overrides=overrides, **dotted)
    for name, value in (("n_subjects", n_subjects), ("per_subject", per_subject)):
        check_positive_int(name, value)
    _check_seed_and_jobs(seed, n_jobs)
    check_simulation_size(n_subjects, per_subject)  # refuse up front, not by OOM (issue 20)
    cfg = _resolve(preset, overrides, dotted)
    frame = simulate_frame(cfg, int(n_subjects), int(per_subject), int(seed), n_jobs=n_jobs)
    return Dataset(frame, config=cfg, seed=int(seed))


def _check_seed_and_jobs(seed: Any, n_jobs: Any) -> None:
    """Refuse (one line) a seed that is no non-negative integer, and worker counts other
    than a positive integer or -1 (every core, joblib's convention)."""
    check_seed(seed)
    if (not isinstance(n_jobs, int | np.integer) or isinstance(n_jobs, bool)
            or not (n_jobs >= 1 or n_jobs == -1)):
        raise ConfigError(f"n_jobs must be a positive integer or -1 (every core), got {n_jobs!r}")


def _resolve(preset, overrides, dotted) -> ScenarioConfig:
    """The scenario of a preset (or config) with dict and keyword overrides."""
    all_overrides = check_overrides(overrides)
    all_overrides.update({k.replace("__", "."): v for k, v in dotted.items()})
    return resolve_config(preset, all_overrides)


def simulate_wear(
    preset: str | ScenarioConfig = "paper",
    n_subjects: int = 10,
    wear_days: int = 14,
    every_min: int = 5,
    seed: int = 0,
    *,
    out: str | None = None,
    n_jobs: int = 1,
    overrides: dict[str, Any] | None = None,
    **dotted: Any,
) -> Dataset:
    """Simulate each subject wearing one device for days, a reading every few minutes.

    Glucose follows the UVA/Padova meal model (plasma glucose in ``glucose_mgdl``, the
    optics seeing the interstitial glucose), the device drifts and is re-seated daily,
    the environment and heart rate follow the day (:mod:`nirglucose.simulation.wear`).
    Each row carries ``time_min``, ``wear_day`` and ``seating_id``.

    Parameters
    ----------
    preset : str or ScenarioConfig
        'paper', 'physical', 'lab', 'field', or a resolved config.
    n_subjects : int
        Number of subjects (each wears one device). [-]
    wear_days : int
        Days of wear. [d]
    every_min : int
        Minutes between readings; must divide a day (1440 min). [min]
    seed : int
        Seed of every random stream. [-]
    out : str or path-like, optional
        A directory to write partitioned Parquet to, chunk by chunk in bounded memory
        (then the returned dataset reads its rows on first use). Without it the rows are
        simulated in memory, refused up front when they cannot fit.
    n_jobs : int
        Worker processes; the result does not depend on it.
    overrides : dict, optional
        Dotted config keys to values.
    **dotted
        Overrides as keywords, with ``__`` for dots.

    Returns
    -------
    Dataset
        ``metadata["wear"]`` records the wear's settings.

    Examples
    --------
    >>> ds = simulate_wear("paper", n_subjects=1, wear_days=1, every_min=60, seed=0)
    >>> len(ds), list(ds.frame.columns[2:5])
    (24, ['time_min', 'wear_day', 'seating_id'])
    """
    # deferred: the wear simulator loads scipy.signal (~0.8 s), which ``import
    # nirglucose`` skips until the first worn-device simulation (SLOW_MODULES)
    from .simulation import wear

    check_positive_int("n_subjects", n_subjects)
    n_t = wear.readings_per_subject(wear_days, every_min)
    _check_seed_and_jobs(seed, n_jobs)
    cfg = _resolve(preset, overrides, dotted)
    meta = {"wear": wear.wear_metadata(wear_days, every_min, None)}
    if out is not None:
        wear.write_wear_partitioned(cfg, out, int(n_subjects), wear_days, every_min, seed,
                                    n_jobs=n_jobs)
        return load_dataset(out)
    check_simulation_size(n_subjects, n_t)  # refuse up front: give `out` (issue 31)
    frame = wear.simulate_wear_frame(cfg, int(n_subjects), wear_days, every_min, seed,
                                     n_jobs=n_jobs)
    return Dataset(frame, config=cfg, seed=int(seed), metadata=meta)
