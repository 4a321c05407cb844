"""Inputs and sections of the diagnostic figures: agreement scatter, residuals, spread.

The agreement scatter replaces the Clarke, Parkes and linearity grids (the same points
drawn three times): one panel per model on shared axes, the Clarke zone lines as an
overlay, and each model's zone shares and fit written in the panel.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
import pandas as pd

from .inputs import (
    _finite_pairs,
    error_grid_inputs,
    linearity_inputs,
    model_order,
    pooled,
    scored_column,
)
from .page import Page

__all__ = ["scatter_inputs", "residual_inputs", "fold_scores"]


def scatter_inputs(predictions: pd.DataFrame, models: Sequence[str]
                   ) -> tuple[dict[str, dict[str, Any]], int]:
    """Panels of the agreement scatter: points, Clarke shares, Parkes A, the fit.

    Every repeat's predictions pooled (each repeat predicts every snapshot once, so the
    shares equal the table's per-repeat averages); the Parkes A share uses the type-1
    grid for every snapshot, as the table's column does. ``coverage_pct`` is the share
    of references inside their 90 % prediction interval, when the run has intervals.
    Returns the panels and the count of negative predictions placed at 0.
    """
    clarke, clipped = error_grid_inputs(predictions, models, kind="clarke")
    parkes, _ = error_grid_inputs(predictions, models, kind="parkes", diabetes_type=1)
    lin = linearity_inputs(predictions, models)
    out: dict[str, dict[str, Any]] = {}
    for m, g in clarke.items():
        p = {"reference": g["reference"], "predicted": g["predicted"],
             "clarke_pct": g["zone_pct"],
             "parkes_a_pct": parkes.get(m, {}).get("zone_pct", {}).get("A", np.nan)}
        fit = lin.get(m, {})
        p.update({k: fit[k] for k in ("slope", "intercept", "r_squared", "slope_ci")
                  if k in fit})
        if "lower" in fit:
            ref = np.asarray(fit["reference"], float)
            p["coverage_pct"] = float(100.0 * np.mean((ref >= fit["lower"])
                                                      & (ref <= fit["upper"])))
        out[m] = p
    return out, clipped


def residual_inputs(predictions: pd.DataFrame, models: Sequence[str], *, n_bins: int = 8
                    ) -> dict[str, dict[str, Any]]:
    """Residual (reference − prediction) against prediction, with binned medians.

    Bins are quantiles of each model's predictions (``n_bins``, at least 5 points each);
    the median residual of each bin is drawn against the bin's median prediction.
    """
    col = scored_column(predictions)
    out: dict[str, dict[str, Any]] = {}
    for m in models:
        ref, pred, _ = _finite_pairs(pooled(predictions, m), col)
        if ref.size < 3:
            continue
        resid = ref - pred
        panel: dict[str, Any] = {"predicted": pred, "residual": resid}
        k = int(min(n_bins, ref.size // 5))
        if k >= 2 and np.ptp(pred) > 0:
            edges = np.unique(np.quantile(pred, np.linspace(0, 1, k + 1)))
            idx = np.clip(np.searchsorted(edges, pred, side="right") - 1, 0, len(edges) - 2)
            keep = [b for b in range(len(edges) - 1) if np.any(idx == b)]
            panel["bin_centre"] = np.array([np.median(pred[idx == b]) for b in keep])
            panel["bin_median"] = np.array([np.median(resid[idx == b]) for b in keep])
        out[m] = panel
    return out


def fold_scores(predictions: pd.DataFrame, models: Sequence[str]) -> pd.DataFrame:
    """RMSE of each model on each fold of each repeat (``model, repeat, fold, rmse_mgdl``).

    Examples
    --------
    >>> p = pd.DataFrame({"model": "a", "repeat": 0, "fold": [0, 0, 1],
    ...                   "reference_mgdl": [100.0, 100.0, 100.0],
    ...                   "scored_mgdl": [103.0, 97.0, 110.0]})
    >>> fold_scores(p, ["a"])["rmse_mgdl"].tolist()
    [3.0, 10.0]
    """
    col = scored_column(predictions)
    keys = [k for k in ("repeat", "fold") if k in predictions.columns]
    p = predictions[predictions["model"].isin(list(models))]
    p = p[np.isfinite(p[col]) & np.isfinite(p["reference_mgdl"])]
    if not keys or not len(p):
        return pd.DataFrame(columns=["model", "repeat", "fold", "rmse_mgdl"])
    sq = (p[col] - p["reference_mgdl"]) ** 2
    t = sq.groupby([p["model"], *(p[k] for k in keys)]).mean().pow(0.5)
    return t.rename("rmse_mgdl").reset_index()


def section_scatter(page: Page) -> None:
    """The agreement scatter (replaces the Clarke, Parkes and linearity grids)."""
    from ...plots import diagnostics

    panels, clipped = scatter_inputs(page.preds, page.pred_models)
    clip_txt = f" {clipped} negative predictions are placed at 0 mg/dL." if clipped else ""
    cover = " and the share of references inside their 90 % prediction interval" if any(
        "coverage_pct" in p for p in panels.values()) else ""
    page.add("scatter", "Predicted against reference glucose",
             f"One panel per model on shared axes ({page.rep_note}): the Clarke error "
             "grid's zone lines in grey, the unity line dotted and the least-squares line "
             "of prediction on reference in black. Each panel gives the shares in Clarke "
             "zones A–E and in Parkes zone A (the type-1 grid for every snapshot, as in the "
             f"table), the fitted slope with its 95 % CI and R²{cover}. These shares are "
             "the table's. The readings span the run's glucose range only: without "
             "readings below 70 mg/dL the grids' hypoglycaemia zones are not tested (see "
             f"the subgroups).{clip_txt}",
             lambda: diagnostics.figure_agreement_scatter(panels) if panels else None,
             note=None if panels else "No predictions: figure not drawn.")


def section_residuals(page: Page) -> None:
    """Residuals against prediction."""
    from ...plots import diagnostics

    panels = residual_inputs(page.preds, page.pred_models)
    page.add("residuals", "Residuals against prediction",
             f"Reference minus prediction against the prediction for each model "
             f"({page.rep_note.split(',')[0]}), on shared axes, with the median residual "
             "in eight quantile bins of the prediction (black). A slope in that line is "
             "regression to the mean: low predictions too low, high ones too high "
             "(reference above the prediction at the top).",
             lambda: diagnostics.figure_residuals(panels) if panels else None,
             note=None if panels else "Too few predictions: figure not drawn.")


def section_spread(page: Page) -> None:
    """Score spread across folds and repeats."""
    from ...plots import diagnostics

    models = model_order(page.pred_models)
    scores = fold_scores(page.preds, models)
    n_rep = int(scores["repeat"].nunique()) if "repeat" in scores and len(scores) else 0
    n_fold = int(scores["fold"].nunique()) if "fold" in scores and len(scores) else 0
    page.add("fold_spread", "Score spread across folds and repeats",
             f"RMSE of each model on each held-out fold of each repeat ({n_fold} folds × "
             f"{n_rep} repeats; one point each, jittered vertically), with a box of their "
             "quartiles. The spread is how much a single split's score can mislead; the "
             "table's RMSE pools the folds of a repeat, so it is not the mean of these "
             "points.",
             lambda: diagnostics.figure_fold_spread(scores, models) if len(scores) else None,
             note=None if len(scores) else "No fold or repeat recorded: figure not drawn.")
