"""``fit_twin``: the simulator fitted to a device's own file, with its uncertainty."""

from __future__ import annotations

import contextlib
import time
import warnings
from dataclasses import asdict
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from ..dataset import Dataset, load_dataset
from ..exceptions import DataError
from .checks import file_errors, posterior_predictive, twin_bound
from .device import TwinDevice, device_of
from .inference import REACH_QUANTILES, InferenceSettings, load_or_train
from .parameters import IDENTIFIED_WIDTH_RATIO, fitted_parameters, held_parameters
from .summaries import summaries, summary_names
from .twin import INTERVAL, Twin, parameter_entry

__all__ = ["fit_twin"]

#: Posterior draws stored in ``twin.json`` (what ``--twin-mode posterior`` draws from).
_STORED_DRAWS = 500


def _read(data: Any, adc_bits: int | None, glucose_unit: str | None) -> Dataset:
    if isinstance(data, Dataset):
        return data
    if isinstance(data, pd.DataFrame):
        return Dataset(data)
    if isinstance(data, str | Path):
        return load_dataset(data, glucose_unit=glucose_unit, adc_bits=adc_bits)
    raise DataError(f"fit_twin takes a file path, a Dataset or a DataFrame, got "
                    f"{type(data).__name__}")


def fit_twin(data: Any, *, adc_bits: int | None = None, glucose_unit: str | None = None,
             settings: InferenceSettings | None = None, n_jobs: int = 1, cache: bool = True,
             n_draws: int = 2000, ppc_devices: int = 100) -> Twin:
    """Fit the simulator to a device's own file: the posterior over its scenario parameters.

    Parameters
    ----------
    data : str, path, Dataset or DataFrame
        The device file (the format of ``docs/user_data.md``), with ``subject_id`` and a
        reference glucose.
    adc_bits : int, optional
        The ADC's resolution, where the file does not say. [bit]
    glucose_unit : {"mg/dL", "mmol/L"}, optional
        The glucose column's unit where its name does not say.
    settings : InferenceSettings, optional
        Simulations and training of the posterior estimator (defaults).
    n_jobs : int
        Worker processes for the simulations; the result does not depend on it.
    cache : bool
        Read and write the device's trained estimator in the cache (:mod:`.inference`).
    n_draws, ppc_devices : int
        Posterior draws; devices simulated for the posterior predictive checks. [-]

    Returns
    -------
    Twin

    Warns
    -----
    UserWarning
        One line each: parameters the file does not identify; summaries of the file the
        simulator does not reach (the twin is not a twin); fewer than 10 people.
    """
    t0 = time.perf_counter()
    settings = settings or InferenceSettings()
    ds = _read(data, adc_bits, glucose_unit)
    device = device_of(ds, adc_bits=adc_bits)
    params, held = fitted_parameters(device), held_parameters(device)
    stages = _Stages()
    with stages("estimator"):
        est, cached = load_or_train(device, params, settings, cache=cache, n_jobs=n_jobs)
    frame = ds.frame
    with stages("summaries"):
        x = summaries(frame, device)
    names = summary_names(device)
    if not np.isfinite(x).all():
        bad = [n for n, v in zip(names, x, strict=True) if not np.isfinite(v)]
        raise DataError(f"the file's summaries {', '.join(bad)} cannot be computed (a channel "
                        "that never changes within a person?)")
    with stages("sampling"):
        z = est.sample(x, n_draws, settings.seed)
        leakage = est.leakage
        best = z[int(np.argmax(est.log_prob(z, x)))]
    entries = [parameter_entry(p, z[:, i]) for i, p in enumerate(params)]
    entries += [parameter_entry(p, None) for p in held]
    values = np.column_stack([p.from_fit(z[:, i]) for i, p in enumerate(params)])
    map_values = np.array([p.from_fit(best[i]) for i, p in enumerate(params)], dtype=float)
    with stages("posterior_predictive"):
        ppc = posterior_predictive(device, params, z, x, frame, n_devices=ppc_devices,
                                   seed=settings.seed, n_jobs=n_jobs)
    notes = _warnings(device, entries, est.out_of_reach(x), est.meta["n_train"], leakage)
    for line in notes:
        warnings.warn(line, UserWarning, stacklevel=2)
    info = {
        "settings": {**asdict(settings), "method": "NPE (sbi, masked autoregressive flow)",
                     "interval": list(INTERVAL), "identified_width_ratio":
                     IDENTIFIED_WIDTH_RATIO, "reach_quantiles": list(REACH_QUANTILES)},
        "summaries": dict(zip(names, x.tolist(), strict=True)), "warnings": notes,
        "ppc": ppc, "source": str(ds.metadata.get("source", "")),
        "timing": {"cached_estimator": cached, "simulate_s": est.meta.get("simulate_s"),
                   "train_s": est.meta.get("train_s"), "n_train": est.meta["n_train"],
                   "total_s": round(time.perf_counter() - t0, 1)},
    }
    keep = np.linspace(0, len(values) - 1, min(_STORED_DRAWS, len(values))).astype(int)
    twin = Twin(device, entries, values[keep], map_values, info)
    with stages("bound"):
        twin.info["bound"] = twin_bound(twin.scenario("map"))
    with stages("file_errors"):
        twin.info["file_errors_mgdl"] = file_errors(ds)
    twin.info["timing"]["stages_s"] = stages.seconds
    twin.info["timing"]["total_s"] = round(time.perf_counter() - t0, 1)
    return twin


class _Stages:
    """Wall seconds of a fit's named stages (``timing.stages_s`` of ``twin.json``)."""

    def __init__(self) -> None:
        self.seconds: dict[str, float] = {}

    @contextlib.contextmanager
    def __call__(self, name: str):
        t0 = time.perf_counter()
        try:
            yield
        finally:
            self.seconds[name] = round(time.perf_counter() - t0, 2)


#: Share of the estimator's draws outside the priors above which a fit says so.
_LEAKAGE_WARN = 0.5


def _warnings(device: TwinDevice, entries: list[dict], reach: list[str], n_train: int,
              leakage: float):
    """The fit's one-line warnings (see :func:`fit_twin`)."""
    out = []
    loose = [e["key"] for e in entries if e["fitted"] and not e["identified"]]
    if loose:
        out.append(f"not identified by this file (posterior ~ prior, reported as such): "
                   f"{', '.join(loose)}")
    if reach:
        lo, hi = (100 * q for q in REACH_QUANTILES)
        out.append(f"the twin is not a twin: the file's {', '.join(reach)} lie outside what "
                   f"the simulator reaches ({lo:g}-{hi:g} % of {n_train} prior simulations); "
                   "its posterior is the nearest the simulator gets"
                   + (f" ({100 * leakage:.0f} % of the estimator's draws fell outside the "
                      "priors and were clipped to them)" if leakage > _LEAKAGE_WARN else ""))
    elif leakage > _LEAKAGE_WARN:
        out.append(f"{100 * leakage:.0f} % of the posterior estimator's draws fell outside "
                   "the priors (clipped to them): the file is far from the simulations")
    if device.n_subjects < 10:
        out.append(f"{device.n_subjects} people: below the small-data policy's 10, the "
                   "between-person spread is loosely known")
    return out
