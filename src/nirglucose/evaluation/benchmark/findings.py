"""The findings of a benchmark run, computed from its results files (no HTML here).

A finding is one sentence: a template with a placeholder per number, the numbers with
the file, row and column each was read from (or the operation that derived it from
such values), and the anchor of the figure or table behind it. The report renders the
sentences (:mod:`nirglucose.report.findings`); tests re-derive every number from the
files named in its source.

Everything is read from what ``nirglucose benchmark --out`` wrote for each preset:
``metrics.json`` (one row per model), ``comparisons.csv`` (the paired cluster-bootstrap
comparisons against the best model, Holm-adjusted, and the study's orderings),
``ablation.csv`` (each PINN against itself without physics), ``drop_one.csv`` (each
model refitted without each LED), ``meta.json`` (the tuned
parameters, among them each PINN's physics weight ``lambda_phys``, and the resolved
configuration) and the predictions (subjects and reference glucose). The statistics are
the benchmark's own (:mod:`nirglucose.metrics.resampling`); no test is re-run here except
the paired comparison of each model with no skill (:func:`no_skill_comparisons`), which
uses :func:`~nirglucose.metrics.resampling.compare_models` on the same predictions.

Sources
    ``"<preset>/metrics.json:<model>:<column>"``,
    ``"<preset>/comparisons.csv:<family>:<model>:<reference>:<column>"``,
    ``"<preset>/ablation.csv:<model>:<column>"``,
    ``"<preset>/drop_one.csv:<model>:<wavelength>:<column>"``,
    ``"<preset>/meta.json:<dotted key>"``,
    ``"<preset>/predictions.parquet:<what>"``; a derived value names its operation
    (``diff``: first minus second, ``ratio``, ``share_removed``: ``1 - a / b``, ``count``).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any, Final

import numpy as np
import pandas as pd

from ...config.presets import DEVICE_CAPABILITIES
from ...dataset.small_data import significance_withheld
from ...metrics.resampling import compare_models
from ...models.labels import LAMBDA_ROW, knows, label
from ..reference import STUDY_ORDER, STUDY_TABLE
from .answer import physics_answer, physics_verdicts, term_findings, term_verdicts
from .drop_one import drop_one_findings
from .finding import Finding, Value
from .result import ORACLE
from .rundata import (
    NO_SKILL,
    RunData,
    display_name,
    privilege,
    truthy,
)
from .rundata import is_competitor as _is_competitor
from .rundata import is_reference as _is_reference
from .rundata import tuned_lambda as _lambda

__all__ = [
    "HYPO_MGDL",
    "NO_SKILL",
    "Value",
    "Finding",
    "RunData",
    "best_and_tied",
    "distance_table",
    "no_skill_comparisons",
    "physics_verdicts",
    "privilege",
    "display_name",
    "term_verdicts",
    "physics_answer",
    "study_claims",
    "preset_separation",
    "subject_floor",
    "glucose_range",
    "compute_findings",
    "headline_table",
]

#: Hypoglycaemia threshold (ISO 15197:2013; ADA level 1). [mg/dL]
HYPO_MGDL: Final = 70.0

#: Anchors (element ids of the report) that findings point to.
ANCHOR_HEADLINE: Final = "fig-headline"
#: The wavelength-utilisation figure (a preset after the first: ``_<preset>`` appended).
ANCHOR_LEDS: Final = "fig-wavelengths"
ANCHOR_DISTANCE: Final = "distance-table"



def _ref_anchor(preset: str) -> str:
    return f"reproduced-table-{preset}"


# --------------------------------------------------------------------------- best model


def best_and_tied(run: RunData) -> tuple[str | None, list[str], list[str], list[str]]:
    """The best model of a run and the competitors tied with it.

    From the ``vs_best`` family of ``comparisons.csv``: the reference model is the best
    deployable one (lowest RMSE; the oracle and every privileged row excluded, see
    :func:`privilege`); a competitor is *tied* when its Holm-adjusted bootstrap p is not
    below alpha. Reference rows (oracle, no skill, privileged estimators) and ablation
    rows are not competitors.

    Returns
    -------
    best : str or None
    tied : list of str
        Tied competitors, best first.
    worse : list of str
        Competitors significantly worse than the best.
    unadjusted : list of str
        Tied competitors whose 95 % CI of the difference excludes 0 before the Holm
        adjustment.
    """
    vb = _vs_best(run)
    if vb is None:
        return None, [], [], []
    best = str(vb["reference_model"].iloc[0])
    vb = vb[vb["model"].astype(str).map(lambda m: _is_competitor(m, run))]
    vb = vb.sort_values("rmse_diff_mgdl")
    sig = vb["significant"].astype(str).str.lower().isin(("true", "1"))
    tied = [str(m) for m in vb.loc[~sig, "model"]]
    worse = [str(m) for m in vb.loc[sig, "model"]]
    excl = (vb["ci_low"] > 0) | (vb["ci_high"] < 0)
    unadjusted = [str(m) for m in vb.loc[~sig & excl, "model"]]
    return best, tied, worse, unadjusted


def _vs_best(run: RunData, *, n_boot: int = 2000, seed: int = 0) -> pd.DataFrame | None:
    """The ``vs_best`` comparisons against the best *deployable* model.

    The run's own family when its reference is deployable; when a privileged row was
    ranked best (results written before the benchmark excluded them), the competitors
    are compared here with the best deployable one, as the benchmark does
    (:func:`~nirglucose.metrics.resampling.compare_models`, Holm over the pairs).
    """
    if run.vs_best is not None:
        return run.vs_best if len(run.vs_best) else None
    c = run.comparisons
    if c is None or not len(c) or "family" not in c or not (c["family"] == "vs_best").any():
        return None
    vb = c[c["family"] == "vs_best"]
    if _is_competitor(str(vb["reference_model"].iloc[0]), run):
        run.vs_best = vb
        return vb
    comp = [str(m) for m in run.m.index if _is_competitor(str(m), run)]
    p = run.predictions
    comp = [m for m in comp if m in set(p["model"].astype(str))]
    if len(comp) < 2:
        run.vs_best = pd.DataFrame()
        return None
    best = min(comp, key=lambda m: float(run.m.at[m, "rmse_mgdl"]))
    col = "scored_mgdl" if "scored_mgdl" in p.columns else "predicted_mgdl"
    got = compare_models(p[p["model"].isin(comp)], pairs=[(m, best) for m in comp if m != best],
                         pred_col=col, n_boot=n_boot, seed=seed)
    got.insert(0, "family", "vs_best")
    run.vs_best = got
    return got


def _best_finding(run: RunData) -> Finding | None:
    best, tied, worse, unadj = best_and_tied(run)
    if best is None or best not in run.m.index:
        return None
    p = run.preset
    vals = [run.metric(best, "rmse_mgdl"), run.metric(best, "rmse_ci_low"),
            run.metric(best, "rmse_ci_high")]
    text = (f"On {p}, the best deployable estimator (it reads only the measured columns) is "
            f"{display_name(run, best)}, {{}} mg/dL [95 % CI {{}}, {{}}]; ")
    if tied:
        vals.append(Value(len(tied), 0, (f"{p}/comparisons.csv:vs_best:significant=False",),
                          op="count"))
        names = []
        for t in tied:
            vals.append(run.metric(t, "rmse_mgdl"))
            names.append(f"{display_name(run, t)} {{}}")
        text += ("{} " + ("competitor is" if len(tied) == 1 else "competitors are")
                 + " not distinguishable from it (paired cluster bootstrap "
                 "over subjects, Holm-adjusted p ≥ 0.05): " + ", ".join(names) + " mg/dL")
        if unadj:
            vals.append(Value(len(unadj), 0, (f"{p}/comparisons.csv:vs_best:ci_excludes_0",),
                              op="count"))
            text += ("; for {} of them the unadjusted 95 % CI of the difference excludes 0, "
                     "a difference the Holm adjustment does not confirm")
        text += ". It is not a clear winner."
    else:
        vals.append(Value(len(worse), 0, (f"{p}/comparisons.csv:vs_best:significant=True",),
                          op="count"))
        text += ("every other deployable competitor ({}) is significantly worse (paired "
                 "cluster bootstrap over subjects, Holm-adjusted).")
    return Finding("best", p, text, tuple(vals), ANCHOR_HEADLINE)


def _reference_finding(run: RunData) -> Finding | None:
    """The privileged rows of a run, worded as references: what each knows, its RMSE."""
    refs = [str(x) for x in run.m.index if _is_reference(str(x), run)]
    if not refs:
        return None
    refs.sort(key=lambda m: (m != ORACLE, float(run.m.at[m, "rmse_mgdl"])))
    vals = tuple(run.metric(m, "rmse_mgdl") for m in refs)
    names = "; ".join(f"{label(m)} {{}} mg/dL ({knows(privilege(run, m) or '')})"
                      for m in refs)
    return Finding("best", run.preset, (
        f"References on {run.preset}, not competitors: they read what no device measures, "
        f"so none of them is ranked or called best: {names}."), vals, ANCHOR_HEADLINE)


# --------------------------------------------------------------------------- distances


def no_skill_comparisons(run: RunData, *, n_boot: int = 2000, seed: int = 0,
                         alpha: float = 0.05) -> pd.DataFrame:
    """Each competitor against no skill: paired cluster bootstrap, Holm-adjusted.

    :func:`~nirglucose.metrics.resampling.compare_models` with the pairs
    ``(model, "mean")`` on the run's scored predictions (empty without a no-skill row).
    """
    p = run.predictions
    models = [m for m in dict.fromkeys(p["model"].astype(str)) if _is_competitor(m, run)]
    if significance_withheld(int(p["subject_id"].nunique())):  # small-data policy
        return pd.DataFrame()
    if NO_SKILL not in set(p["model"]) or not models:
        return pd.DataFrame()
    col = "scored_mgdl" if "scored_mgdl" in p.columns else "predicted_mgdl"
    keep = p[p["model"].isin([*models, NO_SKILL])]
    return compare_models(keep, pairs=[(m, NO_SKILL) for m in models], pred_col=col,
                          n_boot=n_boot, seed=seed, alpha=alpha)


def distance_table(runs: Sequence[RunData]) -> pd.DataFrame:
    """Each competitor's distance from no skill and from the oracle, on every preset.

    Columns: ``preset``, ``model``, ``rmse`` (Value), ``below_no_skill`` (no-skill RMSE
    minus the model's, Value), ``share_removed`` (``1 - RMSE / RMSE_no-skill``, Value),
    ``vs_oracle`` (``rmse_vs_oracle`` of ``metrics.json``, Value), ``beats_no_skill``
    (True, False, or None when not tested) and ``privileged`` (None for a deployable
    competitor; what a privileged reference knows, its rows after the competitors').
    """
    rows = []
    for run in runs:
        m = run.m
        ns = run.no_skill if run.no_skill is not None else pd.DataFrame()
        sig = ({str(r["model"]): bool(r["significant"]) and r["rmse_diff_mgdl"] < 0
                for _, r in ns.iterrows()} if len(ns) else {})
        rows_of = ([x for x in m.index if _is_competitor(str(x), run)]
                   + [x for x in m.index if _is_reference(str(x), run) and x != ORACLE])
        for model in rows_of:
            rmse = run.metric(model, "rmse_mgdl")
            row: dict[str, Any] = {"preset": run.preset, "model": model, "rmse": rmse,
                                   "below_no_skill": None, "share_removed": None,
                                   "vs_oracle": None, "beats_no_skill": sig.get(model),
                                   "privileged": privilege(run, str(model))}
            if NO_SKILL in m.index:
                ref = float(m.at[NO_SKILL, "rmse_mgdl"])
                src = (f"{run.preset}/metrics.json:{NO_SKILL}:rmse_mgdl", rmse.sources[0])
                row["below_no_skill"] = Value(ref - rmse.value, 1, src, op="diff")
                row["share_removed"] = Value(1.0 - rmse.value / ref, 0, src[::-1],
                                             op="share_removed", scale=100.0)
            if "rmse_vs_oracle" in m.columns and np.isfinite(m.at[model, "rmse_vs_oracle"]):
                row["vs_oracle"] = run.metric(model, "rmse_vs_oracle")
            rows.append(row)
    return pd.DataFrame(rows)


def _distance_findings(run: RunData, table: pd.DataFrame) -> list[Finding]:
    t = table[table["preset"] == run.preset]
    if len(t) and "privileged" in t.columns:
        t = t[t["privileged"].isna()]
    if not len(t) or NO_SKILL not in run.m.index:
        return []
    p = run.preset
    share = [v for v in t["share_removed"] if v is not None]
    lo, hi = min(share, key=lambda v: v.value), max(share, key=lambda v: v.value)
    vals = [run.metric(NO_SKILL, "rmse_mgdl"), lo, hi]
    text = (f"On {p}, no skill (the training mean) scores {{}} mg/dL; the deployable "
            f"competitors remove "
            f"between {{}} % ({label(_model_of(t, lo))}) and {{}} % "
            f"({label(_model_of(t, hi))}) of that error")
    beats = [b for b in t["beats_no_skill"] if b is not None]
    if beats:
        vals.append(Value(sum(beats), 0, (f"{p}/predictions.parquet:paired vs mean",),
                          op="count"))
        vals.append(Value(len(beats), 0, (f"{p}/predictions.parquet:paired vs mean",),
                          op="count"))
        text += ", and {} of {} are significantly better than it (paired cluster bootstrap, Holm)"
    vo = [v for v in t["vs_oracle"] if v is not None]
    if ORACLE in run.m.index and vo:
        vals += [run.metric(ORACLE, "rmse_mgdl", 2), min(vo, key=lambda v: v.value),
                 max(vo, key=lambda v: v.value)]
        text += ("; the oracle (true nuisances, a bound) reaches {} mg/dL, and the competitors "
                 "sit {}× to {}× above it")
    return [Finding("distance", p, text + ".", tuple(vals), ANCHOR_DISTANCE)]


def _model_of(t: pd.DataFrame, v: Value) -> str:
    return str(t.loc[t["share_removed"].map(lambda x: x is v), "model"].iloc[0])


# --------------------------------------------------------------------------- physics



def _physics_findings(run: RunData) -> list[Finding]:
    p = run.preset
    verdicts = physics_verdicts(run)
    if not verdicts:
        return term_findings(run)
    off = [v for v in verdicts if not v["tested"]]
    anchor = f"ablation-{p}"
    tested = [v for v in verdicts if v["tested"]]
    src = f"{p}/ablation.csv"
    summary = (f"Physics ablations on {p}: of {{}} ablation pairs (each PINN against "
               "itself without physics, at its tuned λ and, where tuning chose 0, at the "
               "best λ > 0), {} tested physics at a weight above 0")
    vals = [Value(len(verdicts), 0, (f"{src}:rows",), op="count"),
            Value(len(tested), 0, (f"{src}:tested",), op="count")]
    if tested:
        vals += [Value(sum(v["verdict"] == "physics helps" for v in tested), 0,
                       (f"{src}:helps",), op="count"),
                 Value(sum(v["verdict"] == "physics hurts" for v in tested), 0,
                       (f"{src}:hurts",), op="count")]
        summary += ("; it helps significantly in {} and hurts significantly in {} of them "
                    "(Holm-adjusted)")
    else:
        summary += ": the question is not asked on this preset"
    out = [Finding("physics", p, summary + ".", tuple(vals), anchor)]
    if off:
        names = ", ".join(label(v["model"]) for v in off)
        out.append(Finding("physics", p, (
            f"Physics on {p}: physics off by tuning — not tested for {names} (the tuned "
            f"physics weight λ is 0, so with and without physics are the same fit; no verdict)."
            if all(v["lambda"] == 0.0 for v in off) else
            f"Physics on {p}: not tested for {names} (with and without physics are the "
            f"same fit; no verdict)."), (), anchor))
    for v in (v for v in verdicts if v["tested"]):
        r, m = v["row"], v["model"]
        src = f"{p}/ablation.csv:{m}"
        vals = (Value(float(v["lambda"]), 2, (f"{p}/meta.json:model_params.{m}.lambda_phys",))
                if v["lambda"] is not None else None,
                Value(float(r["rmse_diff_mgdl"]), 2, (f"{src}:rmse_diff_mgdl",), sign=True),
                Value(float(r["ci_low"]), 2, (f"{src}:ci_low",), sign=True),
                Value(float(r["ci_high"]), 2, (f"{src}:ci_high",), sign=True),
                Value(float(r["p_holm"]), 3, (f"{src}:p_holm",)))
        lam_txt = " (tuned λ = {})" if vals[0] is not None else ""
        if LAMBDA_ROW in m:  # λ is in the label; it is the curve's best > 0, not the tuned one
            vals = (None, *vals[1:])
            lam_txt = " (the best λ > 0 of the tuning's validation curve; the tuning chose 0)"
        unadj = (v["verdict"] == "no significant difference"
                 and (float(r["ci_low"]) > 0 or float(r["ci_high"]) < 0))
        out.append(Finding("physics", p, (
            f"Physics on {p}, {label(m)}{lam_txt}: with minus without physics Δ RMSE "
            f"{{}} mg/dL [95 % CI {{}}, {{}}], Holm-adjusted p = {{}}: {v['verdict']}"
            + (" (the unadjusted CI excludes 0; the Holm adjustment over the PINNs does not "
               "confirm it)" if unadj else "") + "."),
            tuple(x for x in vals if x is not None), anchor))
    return out + term_findings(run)


# --------------------------------------------------------------------------- the study


def study_claims(run: RunData) -> dict[str, Any]:
    """The study's claims tested on a run.

    Returns a dict: ``pairs`` (the ``study_order`` rows of ``comparisons.csv``),
    ``n_pairs``, ``n_hold``, ``n_hold_sig``, ``reversed_sig`` (list of (better, worse)
    in the study's order that are significantly reversed here), ``in_ci`` and
    ``study_models`` (the study's models run here whose reported RMSE lies inside this
    run's 95 % CI, and all the study's models run here).
    """
    c = run.comparisons
    so = (c[c["family"] == "study_order"] if c is not None and len(c) and "family" in c
          else pd.DataFrame())
    holds = so["study_holds"].map(truthy) if len(so) else pd.Series(dtype=bool)
    sig = so["significant"].map(truthy) if len(so) else pd.Series(dtype=bool)
    study = {str(r["model"]): float(r["rmse_mgdl"]) for r in STUDY_TABLE}
    m = run.m
    models = [s for s in STUDY_ORDER if s in m.index]
    in_ci = [s for s in models
             if float(m.at[s, "rmse_ci_low"]) <= study[s] <= float(m.at[s, "rmse_ci_high"])]
    return {"pairs": so, "n_pairs": len(so), "n_hold": int(holds.sum()),
            "n_hold_sig": int((holds & sig).sum()),
            "reversed_sig": [(str(r["reference_model"]), str(r["model"]))
                             for (_, r), h, s in zip(so.iterrows(), holds, sig, strict=True)
                             if s and not h],
            "in_ci": in_ci, "study_models": models}


def _claims_findings(run: RunData) -> list[Finding]:
    p = run.preset
    cl = study_claims(run)
    out = []
    if cl["n_pairs"]:
        src = f"{p}/comparisons.csv:study_order"
        vals = [Value(cl["n_hold"], 0, (f"{src}:study_holds",), op="count"),
                Value(cl["n_pairs"], 0, (f"{src}:rows",), op="count"),
                Value(cl["n_hold_sig"], 0, (f"{src}:study_holds&significant",), op="count")]
        text = (
            f"On {p}, {{}} of the study's {{}} pairwise RMSE orderings hold, "
            f"{{}} of them significantly (paired, Holm-adjusted)")
        rev = cl["reversed_sig"]
        if rev:
            text += "; significantly reversed here: " + ", ".join(
                f"the study's {display_name(run, b)} better than {display_name(run, w)}"
                for b, w in rev)
        ebl_rows = cl["pairs"][cl["pairs"]["reference_model"] == "ebl"]
        if len(ebl_rows):
            n_sig = int((ebl_rows["significant"].map(truthy)
                         & ebl_rows["study_holds"].map(truthy)).sum())
            vals += [Value(n_sig, 0, (f"{src}:ebl&study_holds&significant",), op="count"),
                     Value(len(ebl_rows), 0, (f"{src}:ebl:rows",), op="count")]
            text += ("; the study's headline, Enhanced Beer–Lambert better than every network, "
                     "holds significantly against {} of {}")
        out.append(Finding("claims", p, text + ".", tuple(vals), f"study-orderings-{p}"))
    if cl["study_models"]:
        vals = (Value(len(cl["in_ci"]), 0, (f"{p}/metrics.json:rmse_ci vs study",), op="count"),
                Value(len(cl["study_models"]), 0, (f"{p}/metrics.json:study models",),
                      op="count"))
        names = ", ".join(label(s) for s in cl["in_ci"]) or "none"
        out.append(Finding("claims", p, (
            f"On {p}, the study's reported RMSE lies inside this run's 95 % CI for {{}} of "
            f"its {{}} models ({names})."), vals, _ref_anchor(p)))
    return out


# --------------------------------------------------------------------------- presets


def _flat(d: Any, prefix: str = "") -> dict[str, Any]:
    if isinstance(d, dict):
        out: dict[str, Any] = {}
        for k, v in d.items():
            out.update(_flat(v, f"{prefix}{k}."))
        return out
    return {prefix[:-1]: d}


def device_capabilities_of(meta: Mapping[str, Any]) -> list[str] | None:
    """Device capabilities switched on in a run's recorded configuration (None: unknown)."""
    flat = _flat(meta.get("config") or {})
    if not flat:
        return None
    return [name for name, (key, on, _) in DEVICE_CAPABILITIES.items() if flat.get(key) == on]


def _skill(run: RunData, model: str) -> Value | None:
    """``1 - (RMSE / RMSE_no-skill)²``: the share of the no-skill variance explained."""
    m = run.m
    if NO_SKILL not in m.index or model not in m.index:
        return None
    r = float(m.at[model, "rmse_mgdl"]) / float(m.at[NO_SKILL, "rmse_mgdl"])
    return Value(1.0 - r * r, 2, (f"{run.preset}/metrics.json:{model}:rmse_mgdl",
                                  f"{run.preset}/metrics.json:{NO_SKILL}:rmse_mgdl"),
                 op="skill")


def preset_separation(a: RunData, b: RunData) -> Finding | None:
    """What separates two presets: their settings and the resulting errors."""
    fa, fb = _flat(a.meta.get("config") or {}), _flat(b.meta.get("config") or {})
    diffs = [k for k in sorted(set(fa) | set(fb)) if k != "preset" and fa.get(k) != fb.get(k)]
    vals: list[Value] = [Value(len(diffs), 0, (f"{a.preset}/meta.json:config",
                                               f"{b.preset}/meta.json:config"), op="count")]
    text = f"What separates {a.preset} from {b.preset}: {{}} simulation settings differ"
    caps = [device_capabilities_of(r.meta) for r in (a, b)]
    if caps[0] is not None and caps[1] is not None:
        def _names(c: list[str]) -> str:
            return ", ".join(x.replace("_", " ") for x in c) or "none"

        text += (f"; device capabilities on {a.preset}: {_names(caps[0])}; on {b.preset}: "
                 f"{_names(caps[1])}")
    key = "glucose.signal_gain"
    if key in fa and key in fb and fa[key] != fb[key]:
        vals += [Value(float(fa[key]), 1, (f"{a.preset}/meta.json:config.{key}",)),
                 Value(float(fb[key]), 1, (f"{b.preset}/meta.json:config.{key}",))]
        text += "; the glucose signal gain is {} against {}"
    best = [best_and_tied(r)[0] for r in (a, b)]
    if all(best) and all(bb in r.m.index for bb, r in zip(best, (a, b), strict=True)):
        vals += [a.metric(best[0], "rmse_mgdl"), b.metric(best[1], "rmse_mgdl")]
        text += (f". The lowest RMSE goes from {{}} mg/dL ({label(best[0])}) to {{}} mg/dL "
                 f"({label(best[1])})")
        skills = [_skill(r, bb) for r, bb in zip((a, b), best, strict=True)]
        if all(skills):
            vals += skills  # type: ignore[arg-type]
            text += ", its skill 1 − (RMSE / no-skill RMSE)² from {} to {}"
    if all(ORACLE in r.m.index for r in (a, b)):
        vals += [a.metric(ORACLE, "rmse_mgdl"), b.metric(ORACLE, "rmse_mgdl")]
        text += ", and the oracle bound from {} to {} mg/dL"
    return Finding("presets", None, text + ".", tuple(vals), "presets")


# --------------------------------------------------------------------------- data


def subject_floor(runs: Sequence[RunData]) -> Finding | None:
    """The fewest test subjects behind any significance or best-model statement."""
    counts = []
    for r in runs:
        p = r.predictions
        if "subject_id" not in p.columns or not len(p):
            continue
        keep = p[p["model"].astype(str).map(lambda m, r=r: _is_competitor(m, r))]
        per_model = keep.groupby("model")["subject_id"].nunique()
        snaps = (keep.groupby("model")["measurement_id"].nunique()
                 if "measurement_id" in keep.columns else None)
        if len(per_model):
            m = str(per_model.idxmin())
            counts.append((r, int(per_model[m]), None if snaps is None else int(snaps[m])))
    if not counts:
        return None
    run, n, snaps = min(counts, key=lambda c: c[1])
    src = f"{run.preset}/predictions.parquet"
    vals = [Value(n, 0, (f"{src}:subject_id:nunique",), op="count")]
    text = ("Every significance and best-model statement above rests on at least {} "
            "test subjects")
    if snaps is not None:
        vals.append(Value(snaps, 0, (f"{src}:measurement_id:nunique",), op="count"))
        text += " ({} snapshots)"
    meta = run.meta
    if meta.get("n_splits") and meta.get("repeats"):
        vals += [Value(int(meta["repeats"]), 0, (f"{run.preset}/meta.json:repeats",)),
                 Value(int(meta["n_splits"]), 0, (f"{run.preset}/meta.json:n_splits",))]
        text += (", each predicted once in each of {} repeats of subject-grouped {}-fold "
                 "cross-validation, resampled by subject for every interval and test")
    proto = meta.get("study_protocol") or {}
    if proto.get("n_test") and proto.get("per_subject"):
        vals += [Value(int(proto["n_test"]) // int(proto["per_subject"]), 0,
                       (f"{run.preset}/meta.json:study_protocol.n_test",
                        f"{run.preset}/meta.json:study_protocol.per_subject"), op="ratio"),
                 Value(int(proto["n_test"]), 0, (f"{run.preset}/meta.json:study_protocol.n_test",))]
        text += "; the study's test set held {} subjects ({} snapshots)"
    return Finding("subjects", None, text + ".", tuple(vals), "run-info")


def glucose_range(run: RunData) -> dict[str, float]:
    """Reference glucose of the run's snapshots: ``min``, ``max``, ``n``, ``n_hypo`` (< 70)."""
    p = run.predictions
    if "measurement_id" in p.columns:
        p = p.drop_duplicates("measurement_id")
    ref = p["reference_mgdl"].to_numpy(float)
    ref = ref[np.isfinite(ref)]
    return {"min": float(ref.min()), "max": float(ref.max()), "n": int(ref.size),
            "n_hypo": int((ref < HYPO_MGDL).sum())}


def _range_finding(run: RunData) -> Finding | None:
    p = run.preset
    if not len(run.predictions):
        return None
    g = glucose_range(run)
    src = f"{p}/predictions.parquet:reference_mgdl"
    vals = [Value(g["min"], 0, (f"{src}:min",)), Value(g["max"], 0, (f"{src}:max",))]
    text = f"On {p}, reference glucose spans {{}}–{{}} mg/dL"
    comp = [m for m in run.m.index if _is_competitor(str(m), run)]
    if g["n_hypo"] == 0:
        text += "; no reading is below 70 mg/dL, so"
        if "clarke_ab_pct" in run.m.columns and comp:
            ab = run.m.loc[comp, "clarke_ab_pct"].astype(float)
            lo, hi = (run.metric(str(ab.idxmin()), "clarke_ab_pct"),
                      run.metric(str(ab.idxmax()), "clarke_ab_pct"))
            if lo.text() == hi.text():
                vals.append(lo)
                text += " a Clarke A+B of {} % for every competitor"
            else:
                vals += [lo, hi]
                text += " a Clarke A+B of {}–{} % across the competitors"
        else:
            text += " the error grids"
        text += " says nothing about hypoglycaemia, where an error matters most"
    else:
        vals += [Value(g["n_hypo"], 0, (f"{src}:<70",), op="count"),
                 Value(g["n"], 0, (f"{src}:count",), op="count")]
        text += "; {} of its {} readings are below 70 mg/dL (hypoglycaemia)"
    return Finding("range", p, text + ".", tuple(vals), f"extra-table-{p}")


# --------------------------------------------------------------------------- all of them


def headline_table(runs: Sequence[RunData]) -> tuple[pd.DataFrame, dict[str, dict[str, float]]]:
    """Inputs of the headline figure: competitors × presets, and each preset's references.

    Returns
    -------
    table : pandas.DataFrame
        ``preset``, ``model``, ``rmse_mgdl``, ``rmse_ci_low``, ``rmse_ci_high`` and
        ``status`` (``"best"`` deployable, ``"tied"`` with it, ``"worse"``, ``""`` when
        the run has no comparisons, or ``"reference"`` for a privileged estimator other
        than the oracle, which is drawn as a line); ``label``, which says ``physics
        off on <presets>`` for a PINN tuned to λ = 0 there.
    references : dict
        Preset -> ``{"mean": no-skill RMSE, "oracle": oracle RMSE}`` (those present).
    """
    rows, refs = [], {}
    for run in runs:
        best, tied, worse, _ = best_and_tied(run)
        status = {best: "best", **dict.fromkeys(tied, "tied"), **dict.fromkeys(worse, "worse")}
        m = run.m
        shown = ([x for x in m.index if _is_competitor(str(x), run)]
                 + [x for x in m.index if _is_reference(str(x), run) and x != ORACLE])
        for model in shown:
            rows.append({"preset": run.preset, "model": str(model),
                         **{c: float(m.at[model, c]) if c in m.columns else float("nan")
                            for c in ("rmse_mgdl", "rmse_ci_low", "rmse_ci_high")},
                         "status": ("reference" if _is_reference(str(model), run)
                                    else status.get(str(model), ""))})
        refs[run.preset] = {r: float(m.at[r, "rmse_mgdl"]) for r in (NO_SKILL, ORACLE)
                            if r in m.index}
    table = pd.DataFrame(rows)
    if len(table):  # a PINN trained without its physics term says so, with the presets
        off = {str(x): [r.preset for r in runs if _lambda(r, str(x)) == 0.0]
               for x in table["model"]}
        table["label"] = [label(x) + (f" (physics off on {', '.join(off[x])})" if off[x] else "")
                          for x in table["model"]]
    return table, refs


def compute_findings(runs: Sequence[RunData], *, n_boot: int = 2000, seed: int = 0
                     ) -> tuple[list[Finding], pd.DataFrame]:
    """Every finding of the runs (one per preset, the primary first), and the distances.

    Parameters
    ----------
    runs : sequence of RunData
        One per preset.
    n_boot, seed : int
        Resamples and seed of the paired comparisons with no skill (the benchmark's own
        defaults: 2,000 and 0).

    Returns
    -------
    findings : list of Finding
        In reading order: best model per preset, distance from no skill and the oracle,
        physics, the LED whose removal costs most, the study's claims, what separates
        the presets, glucose range, and the fewest subjects behind a statement.
    distances : pandas.DataFrame
        :func:`distance_table`.
    """
    for run in runs:
        if run.no_skill is None:
            run.no_skill = no_skill_comparisons(run, n_boot=n_boot, seed=seed)
    dist = distance_table(runs)
    out: list[Finding] = []
    for step in (_best_finding, _reference_finding, lambda r: _distance_findings(r, dist),
                 lambda r: physics_answer(r, n_boot=n_boot, seed=seed), _physics_findings,
                 _claims_findings):
        for run in runs:
            got = step(run)
            out.extend(got if isinstance(got, list) else [got] if got else [])
        if step is _physics_findings:
            for k, run in enumerate(runs):
                anchor = ANCHOR_LEDS + ("" if k == 0 else f"_{run.preset}")
                out.extend(drop_one_findings(run.preset, run.drop_one, anchor))
    for other in runs[1:]:  # each preset against the primary (paper, then the others)
        sep = preset_separation(runs[0], other)
        if sep is not None:
            out.append(sep)
    out.extend(f for f in (_range_finding(r) for r in runs) if f is not None)
    floor = subject_floor(runs)
    if floor is not None:
        out.append(floor)
    return out, dist
