"""The package's own simulator, run for a twin: one small device per parameter vector.

Each simulated device is the file's device (:func:`.device.base_overrides`) with the
parameter values as scenario overrides, simulated by
:func:`nirglucose.simulation.simulator.simulate_frame` at the file's size (people,
readings per person) and summarised by :func:`.summaries.summaries`. Every device has
its own seed from one :class:`numpy.random.SeedSequence`, and the devices are split
into contiguous chunks over worker processes: the summaries are the same whatever the
number of workers.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from ..config import ScenarioConfig, resolve_config
from ..exceptions import ConfigError
from ..simulation.simulator import simulate_frame
from .device import BASE_PRESET, TwinDevice, base_overrides
from .summaries import summaries, summary_names

__all__ = ["scenario", "nominal_levels", "device_seeds", "simulate_summaries"]


def scenario(device: TwinDevice, values: dict[str, Any] | None = None) -> ScenarioConfig:
    """The base scenario of ``device`` with ``values`` (scenario key -> value) set."""
    return resolve_config(BASE_PRESET, {**base_overrides(device), **(values or {})})


def nominal_levels(device: TwinDevice) -> tuple[np.ndarray, np.ndarray]:
    """Noise-free tissue code and reference code of the base device, shares of full
    scale, per LED (the mean over 40 simulated people, one reading each). [-]"""
    cfg = scenario(device)
    frame = simulate_frame(cfg, 40, 1, 0)
    vref = cfg.hardware.adc_vref_v
    tissue = np.array([frame[f"true_signal_v_{w}"].mean() / vref for w in device.labels])
    ref = frame[[f"adc_ref_{w}" for w in device.labels]].mean().to_numpy() / device.full_scale
    return tissue, ref


def device_seeds(seed: int, n: int) -> np.ndarray:
    """``n`` simulation seeds drawn from one seed (:class:`numpy.random.SeedSequence`)."""
    return np.random.SeedSequence(seed).generate_state(n, dtype=np.uint32).astype(np.int64)


def _one(device: TwinDevice, keys: Sequence[str], row: np.ndarray, seed: int) -> np.ndarray:
    """Summaries of one simulated device; NaN where its values cannot be simulated."""
    values = {k: float(v) for k, v in zip(keys, row, strict=True)}
    try:
        cfg = scenario(device, values)
        frame = simulate_frame(cfg, device.n_subjects, device.per_subject, int(seed))
    except ConfigError:
        return np.full(_n_summaries(device), np.nan)
    return summaries(frame, device)


def _n_summaries(device: TwinDevice) -> int:
    return len(summary_names(device))


def _chunk(device, keys, rows, seeds) -> np.ndarray:
    return np.stack([_one(device, keys, r, s) for r, s in zip(rows, seeds, strict=True)])


def simulate_summaries(device: TwinDevice, keys: Sequence[str], values: np.ndarray,
                       seeds: np.ndarray, n_jobs: int = 1) -> np.ndarray:
    """Summaries of one simulated device per row of ``values``.

    Parameters
    ----------
    device : TwinDevice
        The file's device and size.
    keys : sequence of str
        Scenario keys, one per column of ``values``.
    values : numpy.ndarray
        (n, len(keys)) parameter values in the keys' units.
    seeds : numpy.ndarray
        (n,) one simulation seed per device.
    n_jobs : int
        Worker processes (joblib); the result does not depend on it.

    Returns
    -------
    numpy.ndarray
        (n, n_summaries); rows of NaN where a device could not be simulated.
    """
    values = np.atleast_2d(np.asarray(values, dtype=float))
    n = len(values)
    if n_jobs == 1 or n < 64:
        return _chunk(device, keys, values, seeds)
    from joblib import Parallel, delayed

    n_workers = n_jobs if n_jobs > 0 else 2
    bounds = np.linspace(0, n, 4 * n_workers + 1).astype(int)
    parts = Parallel(n_jobs=n_jobs)(
        delayed(_chunk)(device, keys, values[a:b], seeds[a:b])
        for a, b in zip(bounds[:-1], bounds[1:], strict=True) if b > a
    )
    return np.concatenate(parts)
