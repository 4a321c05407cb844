"""Posterior predictive checks: the file's summaries against the twin's.

Devices are simulated at posterior draws (the file's size, fresh seeds) and summarised
as the file is (:mod:`.summaries`). For each summary the check gives the twin's central
90 % range and the share of twin devices below the file's value (a posterior predictive
p-value, Gelman, Meng & Stern, Statistica Sinica 6, 733 (1996): near 0 or 1 the twin
does not reproduce that feature of the file). For each channel it also gives the code
distribution (quantiles) of the file and of the twin's devices pooled.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pandas as pd

from ..design import design_bound
from ..exceptions import ConfigError
from ..models import make_model
from ..simulation.simulator import simulate_frame
from .device import TwinDevice
from .parameters import Parameter
from .simulate import device_seeds, scenario, simulate_summaries
from .summaries import summaries, summary_names

__all__ = ["CODE_QUANTILES", "PPC_RANGE", "PPC_MIN_PARALLEL", "FILE_MODELS", "posterior_predictive",
           "code_quantiles", "file_errors", "twin_bound"]

#: Deployable estimators whose subject-grouped CV error on the file a twin reports
#: beside its device bound (with no skill, the training mean).
FILE_MODELS = ("ebl", "pls")
#: Folds of that CV (at most the file's people). [-]
_FILE_FOLDS = 5

#: Quantiles of the code distributions compared per channel. [-]
CODE_QUANTILES = (0.05, 0.25, 0.5, 0.75, 0.95)
#: The twin's central range a file's summary is compared with. [-]
PPC_RANGE = (0.05, 0.95)
#: Posterior devices whose codes are pooled for the code distributions. [-]
_CODE_DEVICES = 10
#: Fewest posterior predictive devices simulated on worker processes; fewer run in this
#: process. A device costs about 13 ms of CPU (25 people x 8 readings), starting two
#: workers seconds (each imports the package): measured on the second file of a device,
#: 100 devices took 18 s on two fresh workers and 2.8 s in the process (2 loaded cores,
#: benchmarks/twin.py). [-]
PPC_MIN_PARALLEL = 1000


def code_quantiles(frame: pd.DataFrame, device: TwinDevice) -> dict[str, list[float]]:
    """Per channel, :data:`CODE_QUANTILES` of the codes. [code]"""
    return {w: np.quantile(frame[f"adc_{w}"].to_numpy(float), CODE_QUANTILES).tolist()
            for w in device.labels}


def posterior_predictive(device: TwinDevice, params: list[Parameter], draws: np.ndarray,
                         x_obs: np.ndarray, file_frame: pd.DataFrame, *, n_devices: int = 100,
                         seed: int = 0, n_jobs: int = 1) -> dict[str, Any]:
    """Simulate ``n_devices`` devices at posterior draws and compare with the file.

    Parameters
    ----------
    device : TwinDevice
        The file's device.
    params : list of Parameter
        The fitted parameters, one per column of ``draws``.
    draws : numpy.ndarray
        Posterior draws on the fitting scale, (n, len(params)).
    x_obs : numpy.ndarray
        The file's summaries.
    file_frame : pandas.DataFrame
        The file's rows (for the code distributions).
    n_devices : int
        Twin devices simulated. [-]
    seed, n_jobs : int
        Seed of the draws and simulations; worker processes.

    Returns
    -------
    dict
        ``summaries``: name -> {file, twin_low, twin_median, twin_high, p_below};
        ``codes``: channel -> {file, twin} quantiles; ``n_devices``.
    """
    rng = np.random.default_rng(np.random.SeedSequence([seed, 3]))
    pick = draws[rng.integers(0, len(draws), size=n_devices)]
    values = np.column_stack([p.from_fit(pick[:, i]) for i, p in enumerate(params)])
    keys = [p.key for p in params]
    seeds = device_seeds(seed + 7919, n_devices)
    n_code = min(_CODE_DEVICES, n_devices)
    # the first devices' frames give the code distributions too (simulated once)
    frames = [_frame(device, keys, values[i], int(seeds[i])) for i in range(n_code)]
    nan = np.full(len(summary_names(device)), np.nan)
    x = np.stack([nan if f is None else summaries(f, device) for f in frames])
    if n_devices > n_code:
        x = np.concatenate([x, simulate_summaries(
            device, keys, values[n_code:], seeds[n_code:],
            n_jobs if n_devices - n_code >= PPC_MIN_PARALLEL else 1)])
    frames = [f for f in frames if f is not None]
    x = x[np.isfinite(x).all(axis=1)]
    lo, mid, hi = np.quantile(x, (PPC_RANGE[0], 0.5, PPC_RANGE[1]), axis=0)
    out = {
        name: {"file": float(v), "twin_low": float(a), "twin_median": float(m),
               "twin_high": float(b), "p_below": float(np.mean(x[:, j] < v))}
        for j, (name, v, a, m, b) in enumerate(zip(summary_names(device), x_obs, lo, mid, hi,
                                                    strict=True))
    }
    twin_q = code_quantiles(pd.concat(frames, ignore_index=True), device)
    file_q = code_quantiles(file_frame, device)
    codes = {w: {"file": file_q[w], "twin": twin_q[w]} for w in device.labels}
    return {"summaries": out, "codes": codes, "n_devices": int(len(x)),
            "quantiles": list(CODE_QUANTILES)}


def _frame(device: TwinDevice, keys: list[str], row: np.ndarray, seed: int):
    """One simulated device's frame; None where its values cannot be simulated."""
    try:
        cfg = scenario(device, dict(zip(keys, row.tolist(), strict=True)))
        return simulate_frame(cfg, device.n_subjects, device.per_subject, seed)
    except ConfigError:
        return None


def file_errors(ds, *, folds: int = _FILE_FOLDS) -> dict[str, float]:
    """Subject-grouped ``folds``-fold CV RMSE on the file of each of :data:`FILE_MODELS`
    and of no skill (the training fold's mean glucose). [mg/dL]

    Out-of-fold predictions only: no row is scored by a model that saw its person.
    """
    from sklearn.base import clone
    from sklearn.model_selection import GroupKFold

    frame = ds.frame
    y = frame["glucose_mgdl"].to_numpy(float)
    groups = frame["subject_id"].to_numpy()
    k = min(folds, len(np.unique(groups)))
    bits = ds.metadata.get("adc_bits")
    out: dict[str, float] = {}
    for name in (*FILE_MODELS, "mean"):
        model = make_model(name) if name == "mean" else make_model(name, adc_bits=bits)
        pred = np.empty(len(y))
        for tr, te in GroupKFold(n_splits=k).split(y, y, groups):
            fitted = clone(model).fit(ds.rows(tr))
            pred[te] = np.asarray(fitted.predict(ds.rows(te)), dtype=float)
        out[name] = float(np.sqrt(np.mean((pred - y) ** 2)))
    return out


def twin_bound(cfg) -> dict[str, float]:
    """The twin's device bound (:func:`nirglucose.design.design_bound`, what the device's
    readings can tell of glucose, and the oracle's) for the twin's scenario. [mg/dL]"""
    dev, orc = (design_bound(cfg, condition=c, n_states=128) for c in ("device", "oracle"))
    return {"device_mgdl": float(dev.rmse_mgdl), "oracle_mgdl": float(orc.rmse_mgdl),
            "glucose_sd_mgdl": float(dev.glucose_sd_mgdl),
            "saturated_fraction": float(dev.saturated_fraction)}
