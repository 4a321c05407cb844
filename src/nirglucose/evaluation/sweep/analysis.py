"""Analysis of sweep results: summaries over seeds, ablation and shift effects, crossings.

Everything here reads ``sweep.csv`` rows (or their :func:`summarize_sweep`) and
computes; nothing simulates or fits. Intervals over seeds are Student-t intervals of
the mean (paired by seed for the effects).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
import pandas as pd
from scipy.stats import t as student_t

from ...config import NOISE_SOURCES

__all__ = [
    "SUMMARY_METRICS",
    "summarize_sweep",
    "ablation_effects",
    "shift_effects",
    "threshold_crossing",
    "ranking_crossings",
    "mismatch_table",
    "NO_SKILL_MODEL",
]

#: Metrics :func:`summarize_sweep` aggregates over seeds by default.
SUMMARY_METRICS = (
    "rmse_mgdl",
    "mard_pct",
    "clarke_a_pct",
    "within15_pct",
    "bias_mgdl",
    "rmse_vs_oracle",
)

def _t_interval(values: np.ndarray, level: float) -> tuple[float, float, float, float]:
    """Mean, SD and a t-interval of the mean; NaN interval for fewer than 2 values."""
    v = np.asarray(values, dtype=float)
    v = v[np.isfinite(v)]
    if v.size == 0:
        return (np.nan,) * 4
    mean = float(v.mean())
    if v.size < 2:
        return mean, np.nan, np.nan, np.nan
    sd = float(v.std(ddof=1))
    half = float(student_t.ppf(0.5 + level / 2, v.size - 1)) * sd / math.sqrt(v.size)
    return mean, sd, mean - half, mean + half


def summarize_sweep(
    frame: pd.DataFrame,
    label_columns: Sequence[str] = (),
    metrics: Sequence[str] = SUMMARY_METRICS,
    *,
    level: float = 0.95,
) -> pd.DataFrame:
    """Mean, SD and t-interval over seeds per scenario × model.

    Parameters
    ----------
    frame : pandas.DataFrame
        ``sweep.csv`` rows.
    label_columns : sequence of str
        The scenario's label columns (kept in the output).
    metrics : sequence of str
        Metric columns to aggregate (missing ones are skipped).
    level : float
        Confidence level of the interval over seeds. [-]

    Returns
    -------
    pandas.DataFrame
        ``scenario``, the label columns, ``model``, ``n_seeds``, then for every metric
        ``<metric>_mean``, ``<metric>_sd``, ``<metric>_ci_low``, ``<metric>_ci_high``
        (in the metric's unit), in the order the scenarios first appear.

    Examples
    --------
    >>> f = pd.DataFrame({"scenario": ["a", "a"], "model": ["m", "m"], "seed": [0, 1],
    ...                   "rmse_mgdl": [10.0, 12.0]})
    >>> summarize_sweep(f, metrics=["rmse_mgdl"])["rmse_mgdl_mean"].tolist()
    [11.0]
    """
    keys = ["scenario", *[c for c in label_columns if c in frame], "model"]
    rows = []
    for ident, g in frame.groupby(keys, sort=False, dropna=False):
        row = dict(zip(keys, ident, strict=True))
        row["n_seeds"] = int(g["seed"].nunique()) if "seed" in g else len(g)
        for m in metrics:
            if m not in g:
                continue
            mean, sd, lo, hi = _t_interval(g[m].to_numpy(dtype=float), level)
            row.update({f"{m}_mean": mean, f"{m}_sd": sd, f"{m}_ci_low": lo, f"{m}_ci_high": hi})
        rows.append(row)
    return pd.DataFrame(rows)


def _paired(frame: pd.DataFrame, a: str, b: str, metric: str) -> pd.Series:
    """``metric(a) - metric(b)`` per seed (scenarios ``a``, ``b``)."""
    x = frame[frame["scenario"] == a].set_index("seed")[metric]
    y = frame[frame["scenario"] == b].set_index("seed")[metric]
    return (x - y).dropna()


def ablation_effects(
    frame: pd.DataFrame, metric: str = "rmse_mgdl", *, level: float = 0.95
) -> pd.DataFrame:
    """ΔRMSE per noise source from an ablation sweep, paired by seed.

    ``delta_off`` = metric(all sources on) − metric(this source off): what the source
    costs on top of all the others. ``delta_only`` = metric(this source alone on) −
    metric(all sources off): what it costs on its own.

    Parameters
    ----------
    frame : pandas.DataFrame
        ``sweep.csv`` rows of the ``ablation`` study.
    metric : str
        Metric column (``rmse_mgdl`` [mg/dL], ``mard_pct`` [%], ...).
    level : float
        Confidence level of the paired t-interval over seeds. [-]

    Returns
    -------
    pandas.DataFrame
        ``model``, ``source``, ``metric``, ``delta_off``, ``delta_off_ci_low``,
        ``delta_off_ci_high``, ``delta_only``, ``delta_only_ci_low``,
        ``delta_only_ci_high``, ``all_on``, ``all_off`` (means over seeds, in the
        metric's unit) and ``n_seeds``; per model, the most costly source (by
        ``delta_off``) first.
    """
    rows = []
    for model, g in frame.groupby("model", sort=False):
        all_on = g.loc[g["scenario"] == "all-on", metric].mean()
        all_off = g.loc[g["scenario"] == "all-off", metric].mean()
        for s in NOISE_SOURCES:
            if f"off:{s}" not in set(g["scenario"]):
                continue
            d_off = _paired(g, "all-on", f"off:{s}", metric)
            d_only = _paired(g, f"only:{s}", "all-off", metric)
            m_off, _, lo_off, hi_off = _t_interval(d_off.to_numpy(), level)
            m_only, _, lo_only, hi_only = _t_interval(d_only.to_numpy(), level)
            rows.append(
                {
                    "model": model,
                    "source": s,
                    "metric": metric,
                    "delta_off": m_off,
                    "delta_off_ci_low": lo_off,
                    "delta_off_ci_high": hi_off,
                    "delta_only": m_only,
                    "delta_only_ci_low": lo_only,
                    "delta_only_ci_high": hi_only,
                    "all_on": all_on,
                    "all_off": all_off,
                    "n_seeds": int(len(d_off)),
                }
            )
    out = pd.DataFrame(rows)
    if len(out):
        order = {m: k for k, m in enumerate(dict.fromkeys(out["model"]))}
        out = (
            out.assign(_o=out["model"].map(order))
            .sort_values(["_o", "delta_off"], ascending=[True, False], kind="stable")
            .drop(columns="_o")
            .reset_index(drop=True)
        )
    return out


def shift_effects(
    frame: pd.DataFrame, metric: str = "rmse_mgdl", *, level: float = 0.95
) -> pd.DataFrame:
    """In-domain vs shifted test performance of the ``cohort`` study, paired by seed.

    Returns
    -------
    pandas.DataFrame
        ``model``, ``shift``, ``train_domain``, ``test_domain`` (shifted), ``metric``,
        ``in_domain``, ``shifted``, ``delta``, ``delta_ci_low``, ``delta_ci_high``
        (shifted − in domain; means over seeds in the metric's unit), ``n_seeds``.
    """
    rows = []
    for (model, shift), g in frame.groupby(["model", "shift"], sort=False):
        a, b = f"{shift}:shifted", f"{shift}:in-domain"
        d = _paired(g, a, b, metric)
        mean, _, lo, hi = _t_interval(d.to_numpy(), level)
        test_domain = g.loc[g["scenario"] == a, "test_domain"]
        rows.append(
            {
                "model": model,
                "shift": shift,
                "train_domain": g["train_domain"].iloc[0],
                "test_domain": test_domain.iloc[0] if len(test_domain) else "",
                "metric": metric,
                "in_domain": g.loc[g["scenario"] == b, metric].mean(),
                "shifted": g.loc[g["scenario"] == a, metric].mean(),
                "delta": mean,
                "delta_ci_low": lo,
                "delta_ci_high": hi,
                "n_seeds": int(len(d)),
            }
        )
    return pd.DataFrame(rows)


def threshold_crossing(
    summary: pd.DataFrame,
    x: str,
    metric: str = "mard_pct",
    threshold: float = 15.0,
    *,
    log_x: bool = True,
) -> pd.DataFrame:
    """Where each model's mean metric first rises through ``threshold`` along ``x``.

    Linear interpolation between the two grid points that bracket the crossing (in
    log x when ``log_x`` and all x are positive).

    Parameters
    ----------
    summary : pandas.DataFrame
        :func:`summarize_sweep` output with a numeric column ``x``.
    x : str
        The varied key (e.g. ``"noise_scale"``).
    metric : str
        Metric whose ``<metric>_mean`` is compared. [its unit]
    threshold : float
        Threshold in the metric's unit (15 % MARD by default). [its unit]
    log_x : bool
        Interpolate in log x.

    Returns
    -------
    pandas.DataFrame
        ``model``, ``crossing`` (x at the crossing; NaN when there is none in the
        grid) and ``status``: ``"crosses"``, ``"above at every x"`` or
        ``"below at every x"``.

    Examples
    --------
    >>> s = pd.DataFrame({"model": ["m"] * 3, "noise_scale": [1.0, 2.0, 4.0],
    ...                   "mard_pct_mean": [10.0, 20.0, 30.0]})
    >>> round(float(threshold_crossing(s, "noise_scale")["crossing"][0]), 3)
    1.414
    """
    rows = []
    for model, g in summary.groupby("model", sort=False):
        g = g.assign(_x=pd.to_numeric(g[x], errors="coerce")).dropna(subset=["_x"])
        g = g.sort_values("_x")
        xs = g["_x"].to_numpy(float)
        ys = g[f"{metric}_mean"].to_numpy(float)
        use_log = log_x and bool(np.all(xs > 0))
        tx = np.log(xs) if use_log else xs
        crossing, status = np.nan, "below at every x"
        if len(ys) and ys[0] > threshold:
            status = "above at every x"
        else:
            for k in range(1, len(ys)):
                if ys[k - 1] <= threshold < ys[k]:
                    f = (threshold - ys[k - 1]) / (ys[k] - ys[k - 1])
                    t = tx[k - 1] + f * (tx[k] - tx[k - 1])
                    crossing, status = float(np.exp(t) if use_log else t), "crosses"
                    break
        rows.append({"model": model, "crossing": crossing, "status": status})
    return pd.DataFrame(rows, columns=["model", "crossing", "status"])


def ranking_crossings(
    summary: pd.DataFrame, metric: str = "rmse_mgdl_mean", exclude: Sequence[str] = ("oracle",)
) -> pd.DataFrame:
    """Where two models swap places as the training set grows (``data-size`` study).

    Parameters
    ----------
    summary : pandas.DataFrame
        :func:`summarize_sweep` of a ``data-size`` sweep (columns ``preset``,
        ``n_train_subjects``, ``model`` and ``metric``).
    metric : str
        Column ranked, lower is better (mean RMSE over seeds by default). [mg/dL]
    exclude : sequence of str
        Models left out (the oracle is a bound, not a competitor).

    Returns
    -------
    pandas.DataFrame
        One row per crossing: ``preset``, ``n_before``, ``n_after`` (consecutive
        training sizes between which the order changes), ``overtaker`` (worse before,
        better after), ``overtaken``, ``diff_before``, ``diff_after`` (overtaker minus
        overtaken, in the metric's unit).

    Examples
    --------
    >>> s = pd.DataFrame({"preset": "p", "n_train_subjects": [80, 320, 80, 320],
    ...                   "model": ["a", "a", "b", "b"], "rmse_mgdl_mean": [20., 10, 15, 12]})
    >>> ranking_crossings(s)[["overtaker", "overtaken", "n_before", "n_after"]].values.tolist()
    [['a', 'b', 80, 320]]
    """
    cols = ["preset", "n_before", "n_after", "overtaker", "overtaken", "diff_before", "diff_after"]
    rows = []
    s = summary[~summary["model"].isin(exclude)]
    for preset, g in s.groupby("preset", sort=False):
        table = g.pivot_table(index="n_train_subjects", columns="model", values=metric)
        table = table.sort_index()
        sizes = table.index.tolist()
        models = list(dict.fromkeys(g["model"]))
        for i, a in enumerate(models):
            for b in models[i + 1 :]:
                d = (table[a] - table[b]).to_numpy(dtype=float)
                for k in range(len(sizes) - 1):
                    d0, d1 = d[k], d[k + 1]
                    if not (np.isfinite(d0) and np.isfinite(d1)) or d0 * d1 >= 0:
                        continue
                    over, under = (a, b) if d0 > 0 else (b, a)
                    sign = 1.0 if over == a else -1.0
                    rows.append(
                        {
                            "preset": preset,
                            "n_before": int(sizes[k]),
                            "n_after": int(sizes[k + 1]),
                            "overtaker": over,
                            "overtaken": under,
                            "diff_before": sign * d0,
                            "diff_after": sign * d1,
                        }
                    )
    return pd.DataFrame(rows, columns=cols)


#: The no-skill reference of :func:`mismatch_table` (the training mean).
NO_SKILL_MODEL = "mean"


def mismatch_table(frame: pd.DataFrame, subjects: Sequence[str] = ()) -> pd.DataFrame:
    """The ``mismatch`` study across seeds: per data model, each inversion and reference.

    Claims about mismatch rest on several simulated datasets (seeds), not on one
    dataset's bootstrap: every row gives the mean, SD and range of the RMSE over seeds,
    the paired difference from no skill (:data:`NO_SKILL_MODEL`, same seed and folds)
    with its Student-t 95 % interval over seeds, in how many seeds the model scored
    below no skill, and in how many it was worse than no skill beyond its own subject
    bootstrap interval (``rmse_ci_low`` above no skill's RMSE).

    Parameters
    ----------
    frame : pandas.DataFrame
        ``sweep.csv`` rows of the ``mismatch`` study (``data_model``,
        ``assumed_model``, ``model``, ``seed``, ``rmse_mgdl``, ``rmse_ci_low``).
    subjects : sequence of str
        The estimators whose assumed forward model varies (one row per assumed model);
        every other model's rows do not depend on it (one row per data model).

    Returns
    -------
    pandas.DataFrame
        ``data_model``, ``model``, ``assumed_model`` (empty for a reference),
        ``matched`` (assumed = data model; None for a reference), ``n_seeds``,
        ``rmse_mean``, ``rmse_sd``, ``rmse_min``, ``rmse_max`` [mg/dL],
        ``delta_no_skill``, ``delta_no_skill_ci_low``, ``delta_no_skill_ci_high`` (RMSE
        minus no skill's, mean over seeds) [mg/dL], ``seeds_below_no_skill``,
        ``seeds_worse_beyond_ci``; empty without those columns.
    """
    need = {"data_model", "assumed_model", "model", "seed", "rmse_mgdl"}
    if not need <= set(frame.columns) or frame.empty:
        return pd.DataFrame()
    f = frame.copy()
    if "rmse_ci_low" not in f:
        f["rmse_ci_low"] = np.nan
    ref_rows = f[~f["model"].isin(subjects)]
    # a reference's rows are one task per (data model, seed): keep one copy
    ref_rows = ref_rows.drop_duplicates(["data_model", "model", "seed"])
    ref_rows = ref_rows.assign(assumed_model="")
    rows = pd.concat([f[f["model"].isin(subjects)], ref_rows], ignore_index=True)
    base = (f[f["model"] == NO_SKILL_MODEL].drop_duplicates(["data_model", "seed"])
            .set_index(["data_model", "seed"])["rmse_mgdl"])
    out = []
    for (made, model, assumed), g in rows.groupby(
            ["data_model", "model", "assumed_model"], sort=False):
        r = g["rmse_mgdl"].to_numpy(float)
        ns = base.reindex(pd.MultiIndex.from_arrays(
            [g["data_model"], g["seed"]])).to_numpy(float)
        mean, sd, _, _ = _t_interval(r, 0.95)
        d_mean, _, d_lo, d_hi = _t_interval(r - ns, 0.95)
        out.append({
            "data_model": made, "model": model, "assumed_model": assumed,
            "matched": None if assumed == "" else bool(assumed == made),
            "n_seeds": int(np.isfinite(r).sum()), "rmse_mean": mean, "rmse_sd": sd,
            "rmse_min": float(np.nanmin(r)), "rmse_max": float(np.nanmax(r)),
            "delta_no_skill": d_mean, "delta_no_skill_ci_low": d_lo,
            "delta_no_skill_ci_high": d_hi,
            "seeds_below_no_skill": int(np.sum(r < ns)),
            "seeds_worse_beyond_ci": int(np.sum(g["rmse_ci_low"].to_numpy(float) > ns)),
        })
    return pd.DataFrame(out)
