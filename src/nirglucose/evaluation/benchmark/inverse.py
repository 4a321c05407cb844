"""The inverse task: how well an estimator recovers the tissue state, not only glucose.

An estimator that predicts tissue state has an ``estimate_state(X)`` method returning
one row per reading with some of :data:`INVERSE_QUANTITIES`' estimate columns (the
forward-model estimator ``physics-inversion`` does). The benchmark calls it on each
task's test rows (:func:`task_state`) and :func:`inverse_table` scores the estimates
against the simulator's ``true_*`` columns -- read here, for scoring only, never by an
estimator -- as ``inverse.csv``: per model and quantity the RMSE (subject-cluster
bootstrap 95 % CI), the bias, Pearson's r and the truth's SD (an estimator that
always says the population mean has RMSE about that SD).

The RTE PINNs with the study's physics predict optical properties (absorption and
reduced scattering at the LEDs, ``predict_optics``), not these tissue fractions, so
they have no row here; with ``physics_form='forward'`` a state head predicts the
tissue state (:mod:`nirglucose.models.forward_term`) and they do.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pandas as pd

__all__ = ["INVERSE_QUANTITIES", "INVERSE_COLUMNS", "task_state", "inverse_table"]

#: Estimate column -> (truth column or prefix ending in ``*``: the mean of those
#: columns, unit). The detected blood fraction and the thickness under the probe are
#: what the light sees (the estimator's own definitions).
INVERSE_QUANTITIES: dict[str, tuple[str, str]] = {
    "blood_fraction": ("true_blood_fraction_detected", "-"),
    "water_fraction": ("true_water_fraction", "-"),
    "melanin_fraction": ("true_melanin_fraction", "-"),
    "skin_thickness_mm": ("true_skin_thickness_probe_mm", "mm"),
    "saturation": ("true_saturation", "-"),
    "subcutis_fat_fraction": ("true_subcutis_fat_fraction", "-"),
    "led_shift_nm": ("true_led_shift_nm_*", "nm"),
    "coupling": ("true_coupling", "-"),
}
#: Columns of ``inverse.csv``.
INVERSE_COLUMNS = (
    "model",
    "quantity",
    "truth_column",
    "unit",
    "n",
    "rmse",
    "rmse_ci_low",
    "rmse_ci_high",
    "bias",
    "pearson_r",
    "truth_sd",
)


def task_state(model: Any, test: Any) -> dict[str, list[float]] | None:
    """A fitted model's tissue-state estimates of the test rows (JSON-able), or None
    when it predicts no state (no ``estimate_state``, or one without state columns)."""
    estimate = getattr(model, "estimate_state", None)
    if estimate is None:
        return None
    state = estimate(test)
    out = {
        q: [float(v) for v in state[q].to_numpy(float)]
        for q in INVERSE_QUANTITIES
        if q in state.columns
    }
    return out or None  # glucose only (e.g. an RTE PINN without its state head)


def _truth(frame: pd.DataFrame, column: str) -> np.ndarray | None:
    if column.endswith("*"):
        cols = [c for c in frame.columns if c.startswith(column[:-1])]
        return frame[cols].to_numpy(float).mean(axis=1) if cols else None
    return frame[column].to_numpy(float) if column in frame else None


def _rmse_ci(err: np.ndarray, subjects: np.ndarray, n_boot: int, seed: int):
    """Subject-cluster bootstrap percentile 95 % interval of the RMSE."""
    codes, inv = np.unique(subjects, return_inverse=True)
    sq = np.bincount(inv, weights=err**2, minlength=len(codes))
    cnt = np.bincount(inv, minlength=len(codes)).astype(float)
    rng = np.random.default_rng(seed)
    w = rng.multinomial(len(codes), np.full(len(codes), 1 / len(codes)), size=n_boot)
    draws = np.sqrt((w @ sq) / np.maximum(w @ cnt, 1.0))
    return np.percentile(draws, [2.5, 97.5])


def inverse_table(
    frame: pd.DataFrame,
    runs: list[tuple[dict[str, Any], Any, dict[str, Any]]],
    names: list[str],
    *,
    n_boot: int = 1000,
    seed: int = 0,
) -> pd.DataFrame:
    """Score every row's tissue-state estimates against the truth (``inverse.csv``).

    Parameters
    ----------
    frame : pandas.DataFrame
        The benchmarked data (with ``true_*`` columns; without them the table is empty).
    runs : list of (spec, Split, result)
        The benchmark's tasks; a result's ``state`` holds its test rows' estimates.
    names : list of str
        Reported rows, in order.
    n_boot, seed : int
        Bootstrap resamples and seed of the RMSE intervals.

    Returns
    -------
    pandas.DataFrame
        :data:`INVERSE_COLUMNS`, one row per model with state and quantity.
    """
    subjects = frame["subject_id"].to_numpy()
    rows = []
    for name in names:
        parts = [(split, res["state"]) for spec, split, res in runs
                 if spec["model"] == name and res.get("state")]
        for q, (col, unit) in INVERSE_QUANTITIES.items():
            truth = _truth(frame, col)
            if truth is None or not parts or any(q not in s for _, s in parts):
                continue
            idx = np.concatenate([split.test for split, _ in parts])
            est = np.concatenate([np.asarray(s[q], float) for _, s in parts])
            err = est - truth[idx]
            ok = np.isfinite(err)
            lo, hi = _rmse_ci(err[ok], subjects[idx][ok], n_boot, seed)
            rows.append({
                "model": name, "quantity": q, "truth_column": col, "unit": unit,
                "n": int(ok.sum()), "rmse": float(np.sqrt(np.mean(err[ok] ** 2))),
                "rmse_ci_low": float(lo), "rmse_ci_high": float(hi),
                "bias": float(np.mean(err[ok])),
                "pearson_r": float(np.corrcoef(est[ok], truth[idx][ok])[0, 1])
                if np.std(est[ok]) > 0 and np.std(truth[idx][ok]) > 0 else float("nan"),
                "truth_sd": float(np.std(truth[idx][ok])),
            })
    return pd.DataFrame(rows, columns=list(INVERSE_COLUMNS))
