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
    (:mod:`~nirglucose.evaluation.sweep.transfer`, after Wang, Veltkamp & Kowalski 1991).

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

from ...api import simulate
from ...config import resolve_config
from ...dataset import Dataset
from ...design.fleet import FleetTolerances, draw_units, simulate_unit
from ...exceptions import ConfigError, DataError, unknown_name
from ...metrics import summary
from ...metrics.resampling import cluster_bootstrap_metrics
from ...models.registry import get_model_class
from ...models.tuning import preset_params
from ..benchmark.aggregate import count_invalid, fallback_mgdl, scored
from ..engine import tasks
from ..estimators import seeded_params
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
FLEET_TOLERANCE_SCALES = (0.0, 0.25, 0.5, 1.0, 2.0)
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
    params = {**preset_params(spec["model"], spec["preset"]), **spec["model_params"]}
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


def _tolerances(fleet: Mapping[str, Any]) -> FleetTolerances | None:
    """The task's own half-widths at scale 1 (``fleet["tolerances"]``), else the default."""
    given = fleet.get("tolerances")
    if given is None:
        return None
    known = set(FleetTolerances.__dataclass_fields__)
    if not isinstance(given, Mapping) or not set(given) <= known:
        raise ConfigError(
            f"fleet.tolerances must map some of {sorted(known)} to values, got {given!r}"
        )
    return FleetTolerances(**given)


def fleet_metrics(spec: Mapping[str, Any]) -> dict[str, Any]:
    """Metrics of one fleet task: one model, one variant, one tolerance scale, one seed.

    Parameters
    ----------
    spec : mapping
        A sweep task specification of kind ``"fleet"``: ``preset``, ``overrides``,
        ``n_subjects`` (training subjects in all), ``per_subject``, ``seed``,
        ``model``, ``model_params``, ``n_boot`` and ``fleet`` (``tolerance_scale``,
        ``variant``, the keys of :data:`FLEET_DEFAULTS` and, optionally,
        ``tolerances``: fields of :class:`~nirglucose.design.fleet.FleetTolerances`
        replacing the default half-widths, e.g. ``{"wavelength_half_width_nm": 30}``).

    Returns
    -------
    dict
        The sweep's metrics (RMSE and its subject-bootstrap CI, MARD, ...) and
        ``n_train``.
    """
    fleet = spec["fleet"]
    _check_fleet(fleet)
    k, n_sub = fleet["n_train_units"], int(spec["n_subjects"])
    if n_sub < 2 * k:
        raise ConfigError(
            f"the fleet study spreads {n_sub} training subjects over {k} units; give at "
            f"least {2 * k} (--subjects)"
        )
    design = resolve_config(spec["preset"], dict(spec["overrides"]))
    units = draw_units(spec["preset"], k + fleet["n_test_units"],
                       float(fleet["tolerance_scale"]), int(spec["seed"]),
                       overrides=dict(spec["overrides"]), tolerances=_tolerances(fleet))
    read = _reader(spec, units, int(design.hardware.adc_bits))
    test_units = units[k:]
    tests = [read(u, fleet["test_subjects_per_unit"], "test") for u in test_units]
    preds: list = []
    if fleet["variant"] == "same-unit":
        for u, test in zip(test_units, tests, strict=True):
            train = read(u, n_sub, "same-unit")
            preds.append((*_fit_predict(spec, train, test), fallback_mgdl(train)))
    else:
        sizes = [n_sub // k + (1 if i < n_sub % k else 0) for i in range(k)]
        parts = [read(u, n, "train") for u, n in zip(units[:k], sizes, strict=True)]
        train = _concat(parts, design, int(spec["seed"]))
        for test in tests:
            preds.append((*_fit_predict(spec, train, test), fallback_mgdl(train)))
    models = [m for _, m, _ in preds]
    out = _score(spec, _concat(tests, design, int(spec["seed"])), preds)
    out.update(n_parameters=int(getattr(models[0], "n_parameters", -1)), n_train=len(train))
    return out


def _reader(spec: Mapping[str, Any], units: Sequence[Any], bits: int):
    """``read(unit, n_subjects, tag)``: a unit's readings of distinct subjects (seeded by
    the task's seed, the tag and the unit), after its factory reference in the transfer
    variants (fitted here on the transfer standards, once per unit)."""

    fleet, preset, base = spec["fleet"], spec["preset"], dict(spec["overrides"])
    seed, per = int(spec["seed"]), int(spec["per_subject"])
    transfers = {}
    if fleet["variant"] in ("bias", "slope-bias"):
        t_seed = tasks.derived_seed(seed, "fleet", "transfer")
        n_t = fleet["transfer_subjects"]
        golden = simulate(preset, n_t, per, t_seed, overrides=base)
        for u in units:
            own = simulate_unit(u, preset, n_t, per, t_seed, overrides=base)
            transfers[u.index] = fit_transfer(own.frame, golden.frame, fleet["variant"])

    def read(unit, n_subjects: int, tag: str) -> Dataset:
        ds = simulate_unit(unit, preset, n_subjects, per,
                           tasks.derived_seed(seed, "fleet", tag, unit.index), overrides=base)
        if unit.index not in transfers:
            return ds
        frame = transfers[unit.index].apply(ds.frame, bits)
        return Dataset(frame, config=ds.config, seed=ds.seed)

    return read


def _score(spec: Mapping[str, Any], test: Dataset, preds) -> dict[str, Any]:
    """The sweep's metrics of the pooled predictions, with subject-bootstrap intervals."""
    raw = np.concatenate([p for p, _, _ in preds])
    y = np.concatenate([scored(p, fb) for p, _, fb in preds])
    ref = test.frame["glucose_mgdl"].to_numpy(float)
    if len(ref) != len(y):
        raise DataError("the fleet task's predictions do not match its test readings")
    point = summary(ref, y)
    ci = cluster_bootstrap_metrics(
        ref, y, test.frame["subject_id"].to_numpy(), n_boot=spec["n_boot"], seed=spec["seed"]
    )
    out = {**point, **{key: v for key, v in ci.items() if "_ci_" in key}}
    out.update(n_predictions=len(ref), n_invalid_predictions=count_invalid(raw))
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
