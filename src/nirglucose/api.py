"""The top-level entry points re-exported by :mod:`nirglucose`."""

from __future__ import annotations

from typing import Any

from .config import ScenarioConfig, resolve_config
from .dataset import Dataset
from .exceptions import ConfigError, check_positive_int

__all__ = ["simulate"]


def simulate(
    preset: str | ScenarioConfig = "paper",
    n_subjects: int = 80,
    per_subject: int = 3,
    seed: int = 0,
    *,
    n_jobs: int = 1,
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
    from .resources import check_simulation_size
    from .simulate.simulator import simulate_frame

    for name, value in (("n_subjects", n_subjects), ("per_subject", per_subject)):
        check_positive_int(name, value)
    if not isinstance(seed, int) or isinstance(seed, bool) or seed < 0:
        raise ConfigError(f"seed must be a non-negative integer, got {seed!r}")
    check_simulation_size(n_subjects, per_subject)  # refuse up front, not by OOM (issue 20)
    if overrides is not None and not isinstance(overrides, dict):
        raise ConfigError(
            f"overrides must be a dict of dotted keys to values, e.g. "
            f"{{'hardware.adc_bits': 14}}, got a {type(overrides).__name__}: {overrides!r}"
        )
    all_overrides = dict(overrides or {})
    all_overrides.update({k.replace("__", "."): v for k, v in dotted.items()})
    cfg = resolve_config(preset, all_overrides)
    frame = simulate_frame(cfg, int(n_subjects), int(per_subject), int(seed), n_jobs=n_jobs)
    return Dataset(frame, config=cfg, seed=int(seed))
