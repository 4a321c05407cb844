"""Confidence intervals and paired model comparisons, resampling subjects.

Snapshots of one subject share that subject's physiology, so their errors are
correlated; treating them as independent would make every interval too narrow. Every
interval and test here is a *cluster* bootstrap: subjects are drawn with replacement
and all of a drawn subject's snapshots come along [1]_.

Repeated cross-validation
    Each repeat of grouped K-fold predicts every snapshot exactly once. A metric is
    computed **per repeat and averaged over repeats** (the reported value); its
    interval is the percentile interval of that repeat-averaged metric when subjects
    are resampled (the same subjects in every repeat of one resample). Predictions are
    *not* averaged over repeats first: that would score an ensemble of the repeats'
    models, which is better than any one model the protocol fits.

Vectorised
    Every metric used here is a ratio of per-subject sums (RMSE is the square root of
    one), so a resample is a vector of subject multiplicities ``w`` and a metric is
    ``(w @ sums) / (w @ counts)``; 2,000 resamples are a few matrix products.

Paired comparisons
    Every model is compared with a reference (the best by RMSE) on the *same* resamples:
    the percentile interval of the RMSE difference, a two-sided bootstrap p-value (the
    share of centred resampled differences at least as large as the observed one [2]_,
    with the +1 correction) and a Wilcoxon signed-rank test on per-subject RMSEs as a
    rank-based check. p-values are Holm-adjusted over the family of comparisons [3]_;
    ``significant`` is the adjusted bootstrap p-value below ``alpha``.

References
----------
.. [1] Field CA, Welsh AH. Bootstrapping clustered data. J R Stat Soc B 69(3):369-390,
   2007. doi:10.1111/j.1467-9868.2007.00593.x
.. [2] Hall P, Wilson SR. Two guidelines for bootstrap hypothesis testing. Biometrics
   47(2):757-762, 1991. doi:10.2307/2532163
.. [3] Holm S. A simple sequentially rejective multiple test procedure. Scand J Stat
   6(2):65-70, 1979.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pandas as pd
from numpy.typing import ArrayLike, NDArray

from ..exceptions import ConfigError, DataError
from .error_grids import clarke_zones, parkes_zones

__all__ = [
    "CI_METRICS",
    "DEFAULT_N_BOOT",
    "PAIRED_COLUMNS",
    "SubjectSums",
    "subject_sums",
    "bootstrap_weights",
    "repeat_subject_cells",
    "subject_draws",
    "resampled_ratios",
    "metric_draws",
    "cluster_bootstrap_metrics",
    "holm",
    "ci_stem",
    "compare_models",
]

#: Columns of :func:`compare_models`, one row per (model, reference) pair.
PAIRED_COLUMNS = (
    "model",
    "reference_model",
    "rmse_mgdl",
    "reference_rmse_mgdl",
    "rmse_diff_mgdl",
    "ci_low",
    "ci_high",
    "p_value",
    "p_holm",
    "p_wilcoxon",
    "p_wilcoxon_holm",
    "significant",
)

#: Resamples used by default.
DEFAULT_N_BOOT = 2000

# Per-sample terms whose per-subject sums every metric is built from.
_TERMS = ("se", "are", "err", "err2", "clarke_a", "clarke_ab", "parkes_a", "within15", "iso")
_T = {name: k for k, name in enumerate(_TERMS)}

#: Metrics that get a bootstrap interval (keys of :func:`nirglucose.metrics.summary`).
CI_METRICS = (
    "rmse_mgdl",
    "mard_pct",
    "bias_mgdl",
    "clarke_a_pct",
    "clarke_ab_pct",
    "parkes_a_pct",
    "within15_pct",
    "iso15197_pct",
)


def _sample_terms(ref: NDArray[np.float64], pred: NDArray[np.float64]) -> NDArray[np.float64]:
    """Per-sample terms (n, len(_TERMS)); definitions as in :mod:`nirglucose.metrics`."""
    d = pred - ref
    ad = np.abs(d)
    clarke = clarke_zones(ref, pred)
    parkes = parkes_zones(ref, pred, diabetes_type=1)
    cols = {
        "se": d * d,
        "are": ad / ref,
        "err": d,
        "err2": d * d,
        "clarke_a": clarke == "A",
        "clarke_ab": np.isin(clarke, ("A", "B")),
        "parkes_a": parkes == "A",
        # |d| <= 15 % of ref, as metrics.within_percent (100 |d| <= 15 ref)
        "within15": 100.0 * ad <= 15.0 * ref,
        # ISO 15197:2013: |d| <= 15 mg/dL below 100 mg/dL, else <= 15 %
        "iso": (ad <= 15.0) | (100.0 * ad <= 15.0 * ref),
    }
    return np.column_stack([np.asarray(cols[t], dtype=float) for t in _TERMS])


@dataclass(frozen=True)
class SubjectSums:
    """Per-subject sums of the per-sample terms, per repeat.

    Attributes
    ----------
    subjects : numpy.ndarray
        Sorted subject ids, (S,).
    counts : numpy.ndarray
        Snapshots per subject and repeat, (R, S).
    sums : numpy.ndarray
        Sums of the terms, (R, S, K).
    """

    subjects: NDArray
    counts: NDArray[np.float64]
    sums: NDArray[np.float64]


def subject_sums(
    y_true: ArrayLike, y_pred: ArrayLike, groups: ArrayLike, repeat: ArrayLike | None = None
) -> SubjectSums:
    """Per-subject sums of the error terms, one layer per repeat.

    Parameters
    ----------
    y_true, y_pred : array_like
        Reference and predicted glucose; predictions must be non-negative. [mg/dL]
    groups : array_like
        Subject id of each pair. [-]
    repeat : array_like, optional
        Repeat index of each pair (repeated CV); every repeat must cover the same
        subjects. [-]
    """
    ref = np.asarray(y_true, dtype=float)
    pred = np.asarray(y_pred, dtype=float)
    g = np.asarray(groups)
    if not (ref.shape == pred.shape == g.shape) or ref.ndim != 1 or ref.size == 0:
        raise DataError(
            f"y_true, y_pred and groups must be 1-D of one length, got {ref.shape}, "
            f"{pred.shape}, {g.shape}"
        )
    rep = np.zeros(len(ref), dtype=np.intp) if repeat is None else np.asarray(repeat)
    if rep.shape != ref.shape:
        raise DataError(f"repeat must have the length of y_true, got {rep.shape}")
    terms = _sample_terms(ref, pred)
    subjects, s_idx = np.unique(g, return_inverse=True)
    repeats, r_idx = np.unique(rep, return_inverse=True)
    n_s, n_r = len(subjects), len(repeats)
    flat = r_idx * n_s + s_idx
    counts = np.bincount(flat, minlength=n_r * n_s).reshape(n_r, n_s).astype(float)
    if np.any(counts == 0):
        raise DataError(
            "every repeat must predict every subject (a subject is missing in a repeat)"
        )
    sums = np.stack(
        [
            np.bincount(flat, weights=terms[:, k], minlength=n_r * n_s)
            for k in range(terms.shape[1])
        ],
        axis=-1,
    ).reshape(n_r, n_s, -1)
    return SubjectSums(subjects=subjects, counts=counts, sums=sums.astype(np.float64))


def bootstrap_weights(
    n_subjects: int, n_boot: int = DEFAULT_N_BOOT, seed: int = 0
) -> NDArray[np.float64]:
    """Subject multiplicities of ``n_boot`` cluster resamples, (n_boot, n_subjects).

    Row ``b`` counts how often each subject was drawn in resample ``b`` (each row sums
    to ``n_subjects``). Seeded by ``SeedSequence([seed, n_subjects])``.
    """
    if n_boot < 1:
        raise ConfigError(f"n_boot must be a positive integer, got {n_boot}")
    rng = np.random.default_rng(np.random.SeedSequence([0xB007, int(seed), int(n_subjects)]))
    p = np.full(n_subjects, 1.0 / n_subjects)
    return rng.multinomial(n_subjects, p, size=int(n_boot)).astype(float)


def repeat_subject_cells(
    values: ArrayLike, repeat_idx: ArrayLike, subject_idx: ArrayLike, shape: tuple[int, int]
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Sums of ``values`` and row counts per (repeat, subject) cell, each of ``shape``."""
    sums = np.zeros(shape)
    counts = np.zeros(shape)
    cells = (np.asarray(repeat_idx, dtype=np.intp), np.asarray(subject_idx, dtype=np.intp))
    np.add.at(sums, cells, values)
    np.add.at(counts, cells, 1.0)
    return sums, counts


def subject_draws(n_subjects: int, n_boot: int, entropy: Sequence[int]) -> NDArray[np.int64]:
    """Subject indices of ``n_boot`` cluster resamples, (n_boot, n_subjects).

    Seeded by ``SeedSequence(entropy)``; the same draws serve every model of a run, so
    the differences between them are paired.
    """
    rng = np.random.default_rng(np.random.SeedSequence([int(e) for e in entropy]))
    return rng.integers(0, n_subjects, size=(n_boot, n_subjects))


def resampled_ratios(
    sums: NDArray[np.float64], counts: NDArray[np.float64], draws: NDArray[np.int64]
) -> NDArray[np.float64]:
    """Per-repeat sum/count over the subjects of each resample, (repeats, n_boot).

    ``sums`` and ``counts`` are (repeats, subjects) cells (:func:`repeat_subject_cells`);
    a row of ``draws`` of ``arange(n_subjects)`` gives the point value.
    """
    return sums[:, draws].sum(2) / counts[:, draws].sum(2)


def metric_draws(sums: SubjectSums, weights: NDArray[np.float64]) -> dict[str, NDArray[np.float64]]:
    """Every metric of :data:`CI_METRICS` under subject weights, averaged over repeats.

    Parameters
    ----------
    sums : SubjectSums
    weights : numpy.ndarray
        (B, S) subject multiplicities; a row of ones gives the plain estimate.

    Returns
    -------
    dict of str to numpy.ndarray
        Each metric, shape (B,).
    """
    w = np.atleast_2d(np.asarray(weights, dtype=float))
    n = np.einsum("bs,rs->br", w, sums.counts)  # (B, R)
    m = np.einsum("bs,rsk->brk", w, sums.sums) / n[..., None]  # (B, R, K) means
    sd_bias = n / np.maximum(n - 1.0, 1.0)
    per_repeat = {
        "rmse_mgdl": np.sqrt(m[..., _T["se"]]),
        "mard_pct": 100.0 * m[..., _T["are"]],
        "bias_mgdl": m[..., _T["err"]],
        "clarke_a_pct": 100.0 * m[..., _T["clarke_a"]],
        "clarke_ab_pct": 100.0 * m[..., _T["clarke_ab"]],
        "parkes_a_pct": 100.0 * m[..., _T["parkes_a"]],
        "within15_pct": 100.0 * m[..., _T["within15"]],
        "iso15197_pct": 100.0 * m[..., _T["iso"]],
        "_sd_err": np.sqrt(np.maximum(m[..., _T["err2"]] - m[..., _T["err"]] ** 2, 0.0) * sd_bias),
    }
    return {k: v.mean(axis=1) for k, v in per_repeat.items()}


def cluster_bootstrap_metrics(
    y_true: ArrayLike,
    y_pred: ArrayLike,
    groups: ArrayLike,
    repeat: ArrayLike | None = None,
    *,
    n_boot: int = DEFAULT_N_BOOT,
    seed: int = 0,
    level: float = 0.95,
) -> dict[str, float]:
    """Metrics with percentile cluster-bootstrap intervals over subjects.

    Parameters
    ----------
    y_true, y_pred : array_like
        Reference and predicted glucose. [mg/dL]
    groups : array_like
        Subject id of each pair. [-]
    repeat : array_like, optional
        Repeat index of each pair; metrics are computed per repeat and averaged. [-]
    n_boot : int
        Resamples. [-]
    seed : int
        Seed of the resamples. [-]
    level : float
        Confidence level of the intervals, in (0, 1). [-]

    Returns
    -------
    dict of str to float
        For each metric of :data:`CI_METRICS`: ``<metric>`` (estimate),
        ``<metric>_ci_low`` and ``<metric>_ci_high``, with the metric's suffix dropped
        before ``_ci`` (``rmse_ci_low``, ``mard_ci_high``, ...).

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> ref = rng.uniform(80, 300, 120); groups = np.repeat(np.arange(40), 3)
    >>> out = cluster_bootstrap_metrics(ref, ref + rng.normal(0, 10, 120), groups, n_boot=500)
    >>> out["rmse_ci_low"] < out["rmse_mgdl"] < out["rmse_ci_high"]
    True
    """
    if not 0.0 < level < 1.0:
        raise ConfigError(f"level must lie in (0, 1), got {level}")
    sums = subject_sums(y_true, y_pred, groups, repeat)
    point = metric_draws(sums, np.ones((1, len(sums.subjects))))
    boot = metric_draws(sums, bootstrap_weights(len(sums.subjects), n_boot, seed))
    q = [(1.0 - level) / 2.0, (1.0 + level) / 2.0]
    out: dict[str, float] = {}
    for name in CI_METRICS:
        stem = ci_stem(name)
        lo, hi = np.quantile(boot[name], q)
        out[name] = float(point[name][0])
        out[f"{stem}_ci_low"] = float(lo)
        out[f"{stem}_ci_high"] = float(hi)
    return out


def ci_stem(metric: str) -> str:
    """Name stem of a metric's interval columns: ``rmse_mgdl`` -> ``rmse``."""
    for suffix in ("_mgdl", "_pct"):
        if metric.endswith(suffix):
            return metric[: -len(suffix)]
    return metric


def holm(p_values: ArrayLike) -> NDArray[np.float64]:
    """Holm step-down adjusted p-values (family-wise error control).

    Examples
    --------
    >>> holm([0.01, 0.04, 0.03]).round(2).tolist()
    [0.03, 0.06, 0.06]
    """
    p = np.asarray(p_values, dtype=float)
    m = p.size
    if m == 0:
        return p.copy()
    order = np.argsort(p, kind="stable")
    adj_sorted = np.minimum(1.0, np.maximum.accumulate((m - np.arange(m)) * p[order]))
    out = np.empty(m)
    out[order] = adj_sorted
    return out


def _per_subject_rmse(sums: SubjectSums) -> NDArray[np.float64]:
    # mean squared error per subject, averaged over repeats, then the root
    mse = sums.sums[..., _T["se"]] / sums.counts
    return np.sqrt(mse.mean(axis=0))


def _wilcoxon(a: NDArray[np.float64], b: NDArray[np.float64]) -> float:
    from scipy.stats import wilcoxon

    d = a - b
    if not np.any(d != 0):
        return 1.0
    return float(wilcoxon(a, b, zero_method="wilcox", alternative="two-sided").pvalue)


def compare_models(
    predictions: pd.DataFrame,
    *,
    reference: str | None = None,
    pairs: Sequence[tuple[str, str]] | None = None,
    exclude_from_best: Sequence[str] = ("oracle",),
    n_boot: int = DEFAULT_N_BOOT,
    seed: int = 0,
    alpha: float = 0.05,
    pred_col: str = "predicted_mgdl",
) -> pd.DataFrame:
    """Paired cluster-bootstrap comparisons of RMSE, Holm-adjusted.

    Parameters
    ----------
    predictions : pandas.DataFrame
        Columns ``model``, ``subject_id``, ``reference_mgdl``, ``pred_col`` and
        optionally ``repeat``; all models scored on the same subjects.
    reference : str, optional
        Model every other is compared with; by default the one with the lowest RMSE
        among those not in ``exclude_from_best`` (the oracle is a bound, not a
        competitor).
    pairs : sequence of (model, reference_model), optional
        Explicit pairs instead of "every model against the reference".
    n_boot, seed : int
        Resamples and their seed (the same resamples for every model: paired).
    alpha : float
        Family-wise significance level. [-]

    Returns
    -------
    pandas.DataFrame
        One row per pair: ``model``, ``reference_model``, ``rmse_mgdl``,
        ``reference_rmse_mgdl``, ``rmse_diff_mgdl`` (model minus reference), ``ci_low``,
        ``ci_high``, ``p_value`` (bootstrap), ``p_holm``, ``p_wilcoxon``,
        ``p_wilcoxon_holm``, ``significant`` (``p_holm < alpha``).
    """
    models, sums = _model_sums(predictions, pred_col)
    ones = np.ones((1, len(sums[models[0]].subjects)))
    point = {m: float(metric_draws(sums[m], ones)["rmse_mgdl"][0]) for m in models}
    if pairs is None:
        pairs = _pairs_against_reference(models, point, reference, exclude_from_best)
    cols = list(PAIRED_COLUMNS)
    if not pairs:
        return pd.DataFrame(columns=cols)
    w = bootstrap_weights(len(sums[models[0]].subjects), n_boot, seed)
    draws = {m: metric_draws(sums[m], w)["rmse_mgdl"] for m in {x for p in pairs for x in p}}
    out = pd.DataFrame([_paired_row(m, ref, point, draws, sums, alpha) for m, ref in pairs])
    out["p_holm"] = holm(out["p_value"].to_numpy())
    out["p_wilcoxon_holm"] = holm(out["p_wilcoxon"].to_numpy())
    out["significant"] = out["p_holm"] < alpha
    return out[cols]


def _model_sums(predictions: pd.DataFrame, pred_col: str):
    """The models in order of appearance and each one's per-subject sums.

    Raises :class:`DataError` on missing columns or models scored on other subjects
    (a paired comparison needs the same subjects).
    """
    needed = {"model", "subject_id", "reference_mgdl", pred_col}
    missing = needed - set(predictions.columns)
    if missing:
        raise DataError(f"predictions lack columns {sorted(missing)}")
    models = list(dict.fromkeys(predictions["model"]))
    sums: dict[str, SubjectSums] = {}
    for name, part in predictions.groupby("model", sort=False):
        rep = part["repeat"].to_numpy() if "repeat" in part else None
        sums[str(name)] = subject_sums(
            part["reference_mgdl"], part[pred_col], part["subject_id"], rep
        )
    subjects = sums[models[0]].subjects
    for name in models[1:]:
        if not np.array_equal(sums[name].subjects, subjects):
            raise DataError(f"model {name!r} was scored on other subjects than {models[0]!r}")
    return models, sums


def _pairs_against_reference(models, point: dict, reference, exclude_from_best):
    """Every model against ``reference`` (by default the best not excluded)."""
    if reference is None:
        candidates = [m for m in models if m not in exclude_from_best] or models
        reference = min(candidates, key=lambda m: point[m])
    elif reference not in {str(m) for m in models}:  # the keys of the sums
        raise ConfigError(f"reference model {reference!r} not among {models}")
    return [(m, reference) for m in models if m != reference]


def _paired_row(m: str, ref: str, point: dict, draws: dict, sums: dict, alpha: float) -> dict:
    """One comparison: RMSE difference, its percentile CI, bootstrap and Wilcoxon p."""
    diff = point[m] - point[ref]
    d = draws[m] - draws[ref]
    lo, hi = np.quantile(d, [alpha / 2.0, 1.0 - alpha / 2.0])
    extreme = np.count_nonzero(np.abs(d - diff) >= abs(diff) - 1e-12)
    return {
        "model": m,
        "reference_model": ref,
        "rmse_mgdl": point[m],
        "reference_rmse_mgdl": point[ref],
        "rmse_diff_mgdl": diff,
        "ci_low": float(lo),
        "ci_high": float(hi),
        "p_value": (1.0 + extreme) / (len(d) + 1.0),
        "p_wilcoxon": _wilcoxon(_per_subject_rmse(sums[m]), _per_subject_rmse(sums[ref])),
    }
