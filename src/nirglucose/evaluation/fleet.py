"""The ``fleet`` study: train on some units, test on units the model never saw.

One task of the study (:func:`fleet_metrics`) draws a fleet of ``n_train_units +
n_test_units`` units of the design (:func:`~nirglucose.design.fleet.draw_units`) at one
tolerance scale, simulates distinct subjects on each, and scores one model under one
variant (:data:`FLEET_VARIANTS`):

``same-unit``
    The reference: for each test unit, a model trained on ``n_subjects`` other subjects
    measured by that same unit, tested on its test subjects (one fit per test unit,
    the predictions pooled).
``no-transfer``
    One model trained on ``n_subjects`` subjects spread over the training units, tested
    on the test units' subjects as they read.
``bias`` / ``slope-bias``
    The same, after a factory reference: every unit (training and test) measures the
    same ``transfer_subjects`` transfer standards as the design's golden (nominal)
    unit, and a per-channel offset (``bias``) or slope and offset (``slope-bias``) in
    absorbance maps its readings onto the golden unit's
    (:mod:`~nirglucose.evaluation.transfer`, after Wang, Veltkamp & Kowalski 1991).

The test subjects, test units and training data are the same in every variant and at
every tolerance scale (the unit draws are scaled, not redrawn), so differences are
paired. The transfer standards are simulated subjects measured by the golden unit and
each unit with the same seed: the same subjects and, through the simulator's common
random numbers, much the same noise draws, so the fitted transfer is less noisy than
with independent readings of a physical phantom (an optimistic assumption).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
import pandas as pd

from ..config import resolve_config
from ..dataset import Dataset
from ..design.fleet import draw_units, simulate_unit
from ..exceptions import ConfigError, DataError, unknown_name
from ..metrics import summary
from ..models.registry import get_model_class
from . import tasks
from .benchmark import _model_params, seeded_params
from .benchmark_aggregate import count_invalid, fallback_mgdl, scored
from .stats import cluster_bootstrap_metrics
from .transfer import fit_transfer

__all__ = [
    "FLEET_VARIANTS",
    "FLEET_TOLERANCE_SCALES",
    "FLEET_DEFAULTS",
    "fleet_metrics",
    "fleet_table",
    "format_fleet_table",
]

#: Variants of the fleet study, in table order.
FLEET_VARIANTS = ("same-unit", "no-transfer", "bias", "slope-bias")
#: Default tolerance scales (0: identical units; 1: FleetTolerances as stated).
FLEET_TOLERANCE_SCALES = (0.0, 0.5, 1.0, 2.0)
#: Default fleet layout: units to train and to test on, test subjects per test unit,
#: and the transfer standards (subjects) each unit measures.
FLEET_DEFAULTS: dict[str, int] = {
    "n_train_units": 4,
    "n_test_units": 3,
    "test_subjects_per_unit": 20,
    "transfer_subjects": 4,
}


def _concat(parts: Sequence[Dataset], config, seed: int) -> Dataset:
    """Datasets of several units as one, subject ids made unique per unit."""
    frames = []
    offset = 0
    for ds in parts:
        f = ds.frame.copy()
        f["subject_id"] = f["subject_id"].to_numpy() + offset
        offset = int(f["subject_id"].max()) + 1
        frames.append(f)
    frame = pd.concat(frames, ignore_index=True)
    frame["measurement_id"] = np.arange(len(frame), dtype=np.int64)
    return Dataset(frame, config=config, seed=int(seed))


def _fit_predict(spec: Mapping[str, Any], train: Dataset, test: Dataset) -> tuple[np.ndarray, Any]:
    cls = get_model_class(spec["model"])
    params = {**_model_params(spec["model"], spec["preset"]), **spec["model_params"]}
    seed = tasks.derived_seed(spec["seed"], f"model|{spec['model']}")
    model = cls(**seeded_params(cls, params, seed)).fit(train)
    return np.asarray(model.predict(test), dtype=float).ravel(), model


def _check_fleet(fleet: Mapping[str, Any]) -> None:
    if fleet.get("variant") not in FLEET_VARIANTS:
        raise ConfigError(unknown_name("fleet variant", fleet.get("variant"), FLEET_VARIANTS))
    for key in FLEET_DEFAULTS:
        v = fleet.get(key)
        if isinstance(v, bool) or not isinstance(v, int) or v < 1:
            raise ConfigError(f"fleet.{key} must be a positive integer, got {v!r}")
    if fleet["transfer_subjects"] < 2:
        raise ConfigError("fleet.transfer_subjects must be at least 2 (a line needs two points)")


def fleet_metrics(spec: Mapping[str, Any]) -> dict[str, Any]:
    """Metrics of one fleet task: one model, one variant, one tolerance scale, one seed.

    Parameters
    ----------
    spec : mapping
        A sweep task specification of kind ``"fleet"``: ``preset``, ``overrides``,
        ``n_subjects`` (training subjects in all), ``per_subject``, ``seed``,
        ``model``, ``model_params``, ``n_boot`` and ``fleet`` (``tolerance_scale``,
        ``variant`` and the keys of :data:`FLEET_DEFAULTS`).

    Returns
    -------
    dict
        The sweep's metrics (RMSE and its subject-bootstrap CI, MARD, ...) and
        ``n_train``.
    """
    fleet = spec["fleet"]
    _check_fleet(fleet)
    preset, base, seed = spec["preset"], dict(spec["overrides"]), int(spec["seed"])
    per, n_sub = int(spec["per_subject"]), int(spec["n_subjects"])
    k, m = fleet["n_train_units"], fleet["n_test_units"]
    if n_sub < 2 * k:
        raise ConfigError(
            f"the fleet study spreads {n_sub} training subjects over {k} units; give at "
            f"least {2 * k} (--subjects)"
        )
    design = resolve_config(preset, base)
    bits = int(design.hardware.adc_bits)
    units = draw_units(preset, k + m, float(fleet["tolerance_scale"]), seed, overrides=base)

    def sim(unit, n, tag):
        return simulate_unit(unit, preset, n, per, tasks.derived_seed(seed, "fleet", tag,
                                                                       unit.index), overrides=base)

    variant = fleet["variant"]
    transfers = {}
    if variant in ("bias", "slope-bias"):
        from ..api import simulate

        t_seed = tasks.derived_seed(seed, "fleet", "transfer")
        golden = simulate(preset, fleet["transfer_subjects"], per, t_seed, overrides=base)
        for u in units:
            own = simulate_unit(u, preset, fleet["transfer_subjects"], per, t_seed, overrides=base)
            transfers[u.index] = fit_transfer(own.frame, golden.frame, variant)

    def read(unit, ds):  # what the unit reports, after its factory reference if any
        if unit.index not in transfers:
            return ds
        return Dataset(transfers[unit.index].apply(ds.frame, bits), config=ds.config,
                       seed=ds.seed)

    test_units = units[k:]
    tests = [read(u, sim(u, fleet["test_subjects_per_unit"], "test")) for u in test_units]
    preds, models, n_train = [], [], 0
    if variant == "same-unit":
        for u, test in zip(test_units, tests, strict=True):
            train = sim(u, n_sub, "same-unit")
            y, model = _fit_predict(spec, train, test)
            preds.append((y, fallback_mgdl(train)))
            models.append(model)
            n_train = len(train)
    else:
        sizes = [n_sub // k + (1 if i < n_sub % k else 0) for i in range(k)]
        train = _concat([read(u, sim(u, n, "train")) for u, n in zip(units[:k], sizes,
                                                                          strict=True)],
                        design, seed)
        n_train = len(train)
        for test in tests:
            y, model = _fit_predict(spec, train, test)
            preds.append((y, fallback_mgdl(train)))
            models.append(model)
    test_all = _concat(tests, design, seed)
    raw = np.concatenate([p for p, _ in preds])
    y = np.concatenate([scored(p, fb) for p, fb in preds])
    ref = test_all.frame["glucose_mgdl"].to_numpy(float)
    if len(ref) != len(y):
        raise DataError("the fleet task's predictions do not match its test readings")
    point = summary(ref, y)
    ci = cluster_bootstrap_metrics(
        ref, y, test_all.frame["subject_id"].to_numpy(), n_boot=spec["n_boot"], seed=seed
    )
    out = {**point, **{key: v for key, v in ci.items() if "_ci_" in key}}
    out.update(
        n_parameters=int(getattr(models[0], "n_parameters", -1)),
        n_predictions=len(ref),
        n_invalid_predictions=count_invalid(raw),
        n_train=n_train,
    )
    return out


def fleet_table(frame: pd.DataFrame) -> pd.DataFrame:
    """The fleet study's table: RMSE per tolerance scale × variant × model, with its CI.

    With several seeds the value is the mean over seeds and the interval a Student-t
    95 % interval of that mean; with one seed, the task's subject-bootstrap 95 %
    interval.

    Parameters
    ----------
    frame : pandas.DataFrame
        ``sweep.csv`` rows of a fleet sweep (``tolerance_scale``, ``variant``, ``model``,
        ``seed``, ``rmse_mgdl``, ``rmse_ci_low``, ``rmse_ci_high``).

    Returns
    -------
    pandas.DataFrame
        ``tolerance_scale``, ``variant``, ``model``, ``n_seeds``, ``rmse_mgdl``,
        ``rmse_ci_low``, ``rmse_ci_high``, ``rmse_vs_same_unit`` (the ratio to the
        same-unit RMSE at that scale).
    """
    need = {"tolerance_scale", "variant", "model", "seed", "rmse_mgdl"}
    if not need <= set(frame.columns):
        raise DataError(f"not a fleet sweep: missing columns {sorted(need - set(frame.columns))}")
    from scipy import stats

    rows = []
    for (scale, variant, model), g in frame.groupby(
        ["tolerance_scale", "variant", "model"], sort=False
    ):
        v = g["rmse_mgdl"].to_numpy(float)
        mean = float(np.mean(v))
        if len(v) > 1:
            half = float(stats.t.ppf(0.975, len(v) - 1) * np.std(v, ddof=1) / np.sqrt(len(v)))
            lo, hi = mean - half, mean + half
        else:
            lo = float(g["rmse_ci_low"].iloc[0]) if "rmse_ci_low" in g else np.nan
            hi = float(g["rmse_ci_high"].iloc[0]) if "rmse_ci_high" in g else np.nan
        rows.append({"tolerance_scale": float(scale), "variant": variant, "model": model,
                     "n_seeds": int(g["seed"].nunique()), "rmse_mgdl": mean,
                     "rmse_ci_low": lo, "rmse_ci_high": hi})
    out = pd.DataFrame(rows)
    order = {v: i for i, v in enumerate(FLEET_VARIANTS)}
    out = out.sort_values(["tolerance_scale", "variant", "model"],
                          key=lambda s: s.map(order) if s.name == "variant" else s,
                          kind="stable").reset_index(drop=True)
    same = out[out["variant"] == "same-unit"].set_index(["tolerance_scale", "model"])["rmse_mgdl"]
    idx = pd.MultiIndex.from_frame(out[["tolerance_scale", "model"]])
    out["rmse_vs_same_unit"] = out["rmse_mgdl"].to_numpy() / same.reindex(idx).to_numpy()
    return out


def format_fleet_table(table: pd.DataFrame) -> str:
    """The table as Markdown: one row per scale × variant, one column per model.

    Each cell is ``RMSE [CI low, high]`` in mg/dL.
    """
    models = list(dict.fromkeys(table["model"]))
    head = "| tolerance scale | variant | " + " | ".join(f"{m} RMSE mg/dL [95 % CI]"
                                                       for m in models) + " |"
    lines = [head, "|---|---|" + "---|" * len(models)]
    for (scale, variant), g in table.groupby(["tolerance_scale", "variant"], sort=False):
        cells = []
        for m in models:
            r = g[g["model"] == m]
            if not len(r):
                cells.append("")
                continue
            r = r.iloc[0]
            cells.append(f"{r.rmse_mgdl:.1f} [{r.rmse_ci_low:.1f}, {r.rmse_ci_high:.1f}]")
        lines.append(f"| {scale:g} | {variant} | " + " | ".join(cells) + " |")
    return "\n".join(lines)
