"""The physics in a run: each ablation's verdict, each PINN's physics term measured
during training, and one line per preset answering "does physics help?".

Built on :mod:`.rundata` (what a run holds) and :mod:`.finding` (a sentence with its
numbers); :mod:`.findings` composes these with the other findings.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any, Final

import pandas as pd

from ...dataset.small_data import significance_withheld
from ...metrics.resampling import compare_models
from ...models.labels import ablation_base, label
from ...models.physics_effect import physics_verdict
from .finding import Finding, Value
from .rundata import RunData, privilege, truthy, tuned_lambda

__all__ = ["physics_verdicts", "term_verdicts", "term_findings", "physics_answer"]

#: Anchor of the headline figure (the answer's link where a run has no ablation).
_ANCHOR_HEADLINE: Final = "fig-headline"


def physics_verdicts(run: RunData) -> list[dict[str, Any]]:
    """Per ablated PINN: its tuned physics weight and whether physics was tested.

    One dict per row of ``ablation.csv``: ``model``, ``lambda`` (the tuned
    ``lambda_phys`` of ``meta.json``, None when not recorded), ``tested`` (False when
    tuning set λ = 0, or the two fits are identical: no question was asked), and
    ``verdict``: ``"physics off by tuning — not tested"``, ``"identical fits — not
    tested"``, ``"physics helps"``, ``"physics hurts"`` or ``"no significant
    difference"``.
    """
    a = run.ablation
    if a is None or not len(a):
        return []
    out = []
    for _, r in a.iterrows():
        model = str(r["model"])
        lam = tuned_lambda(run, model)
        identical = (float(r["rmse_diff_mgdl"]) == 0.0 and float(r["ci_low"]) == 0.0
                     and float(r["ci_high"]) == 0.0)
        if lam == 0.0:
            verdict, tested = "physics off by tuning — not tested", False
        elif identical:
            verdict, tested = "identical fits — not tested", False
        elif truthy(r["significant"]):
            verdict = "physics helps" if float(r["rmse_diff_mgdl"]) < 0 else "physics hurts"
            tested = True
        else:
            verdict, tested = "no significant difference", True
        out.append({"model": model, "lambda": lam, "tested": tested, "verdict": verdict,
                    "row": r})
    return out


#: The study's Beer–Lambert PINNs (their physics term: the residual A − εcl).
_BEER_LAMBERT_PINNS: Final = ("original-pinn", "optimized-pinn")


def term_verdicts(run: RunData) -> list[dict[str, Any]]:
    """Each PINN's physics term, measured during training: does it move the fit?

    :func:`~nirglucose.models.physics_effect.physics_verdict` of each model's row of
    ``histories.json`` (its timed fit), ablation rows left out. One dict per PINN with
    gradient probes: ``model``, ``verdict`` (``active``, ``inert``, ``off``),
    ``reason``, ``constant`` (its training physics loss changed by less than 0.1 %)
    and ``pull_sd`` (median displacement of the predictions, training SD).
    """
    out = []
    for model, hist in (run.histories or {}).items():
        if ablation_base(str(model)) is not None or hist is None or not len(hist):
            continue
        v = physics_verdict(hist)
        if v["verdict"] == "unmeasured":
            continue
        out.append({"model": str(model), "verdict": v["verdict"], "reason": v["reason"],
                    "constant": bool(v.get("physics_constant")),
                    "pull_sd": v.get("median_pull_sd")})
    return out


def _term_sentence(run: RunData, v: Mapping[str, Any]) -> str:
    """One PINN's physics term in words (no numbers: the reason carries them)."""
    m, name = v["model"], label(v["model"])
    if v["verdict"] == "off":
        return f"{name}: physics off ({v['reason']})"
    if v["verdict"] == "inert":
        what = ("the study's Beer–Lambert term" if m in _BEER_LAMBERT_PINNS
                else "its physics term")
        how = "is constant during training" if v["constant"] else "does not move the fit"
        return (f"{name}: {what} {how}, so its ablation cannot show an effect "
                f"({v['reason']})")
    return f"{name}: its physics term is active ({v['reason']})"


def term_findings(run: RunData) -> list[Finding]:
    terms = term_verdicts(run)
    if not terms:
        return []
    p = run.preset
    text = (f"The physics terms on {p}, measured during training (gradient probes of the "
            "timed fit, histories.json): " + "; ".join(_term_sentence(run, v) for v in terms)
            + ".")
    return [Finding("physics", p, text.replace("{", "{{").replace("}", "}}"), (),
                    f"ablation-{p}")]


#: The deployable forward-model estimator, and the data-driven rows it is held against
#: in the answer to "does physics help?" (deployable estimators only).
_FORWARD_DEPLOYABLE: Final = "device-inversion"
_DATA_DRIVEN: Final = ("ebl", "gp")


def _forward_evidence(run: RunData, *, n_boot: int, seed: int) -> pd.DataFrame:
    """``device-inversion`` against EBL and the GP on the run's predictions (Holm)."""
    p = run.predictions
    have = set(p["model"].astype(str)) if len(p) else set()
    pairs = [(_FORWARD_DEPLOYABLE, r) for r in _DATA_DRIVEN
             if _FORWARD_DEPLOYABLE in have and r in have]
    if not pairs or significance_withheld(int(p["subject_id"].nunique())):
        return pd.DataFrame()
    col = "scored_mgdl" if "scored_mgdl" in p.columns else "predicted_mgdl"
    keep = p[p["model"].isin({m for pair in pairs for m in pair})]
    return compare_models(keep, pairs=pairs, pred_col=col, n_boot=n_boot, seed=seed)


def physics_answer(run: RunData, *, n_boot: int = 2000, seed: int = 0) -> Finding:
    """One line: does physics help on this preset? With its evidence, deployable only.

    The evidence: each tested physics ablation (a PINN against itself without its
    physics term; a term that is inert during training, :func:`term_verdicts`, is said
    to be unable to show an effect), and the deployable forward-model estimator
    (``device-inversion``) against EBL and the GP, paired cluster bootstrap over
    subjects, Holm-adjusted. Privileged estimators are never evidence. The answer is
    ``yes`` when some evidence favours physics significantly and none goes against it,
    ``no`` when some goes against and none favours, ``mixed`` when both, and
    ``no evidence`` when no difference is significant (the CIs include 0).
    """
    p = run.preset
    terms = {v["model"]: v for v in term_verdicts(run)}
    items: list[str] = []
    vals: list[Value] = []
    pro = con = 0
    for v in physics_verdicts(run):
        base = ablation_base(v["model"]) or v["model"]
        if privilege(run, base) is not None:  # a -fm PINN reads the generator: no evidence
            continue
        if not v["tested"]:
            items.append(f"{label(v['model'])}: {v['verdict']}")
            continue
        r, m = v["row"], v["model"]
        src = f"{p}/ablation.csv:{m}"
        vals += [Value(float(r["rmse_diff_mgdl"]), 1, (f"{src}:rmse_diff_mgdl",), sign=True),
                 Value(float(r["ci_low"]), 1, (f"{src}:ci_low",), sign=True),
                 Value(float(r["ci_high"]), 1, (f"{src}:ci_high",), sign=True)]
        inert = terms.get(base, {}).get("verdict") == "inert"
        items.append(f"{label(m)} with − without its physics term {{}} mg/dL [{{}}, {{}}]"
                     + (" (the term is inert during training: this cannot show an effect)"
                        if inert else f", {v['verdict']}"))
        if not inert and v["verdict"] == "physics helps":
            pro += 1
        elif not inert and v["verdict"] == "physics hurts":
            con += 1
    fwd = _forward_evidence(run, n_boot=n_boot, seed=seed)
    for _, r in fwd.iterrows():
        src = f"{p}/predictions.parquet:paired {r['model']} vs {r['reference_model']}"
        vals += [Value(float(r["rmse_diff_mgdl"]), 1, (src,), op="paired", sign=True),
                 Value(float(r["ci_low"]), 1, (src,), op="paired", sign=True),
                 Value(float(r["ci_high"]), 1, (src,), op="paired", sign=True)]
        sig = bool(r["significant"])
        better = float(r["rmse_diff_mgdl"]) < 0
        items.append(f"{label(str(r['model']))} − {label(str(r['reference_model']))} "
                     "{} mg/dL [{}, {}]" + (", no significant difference" if not sig else
                                            ", the forward model better" if better else
                                            ", the forward model worse"))
        pro += sig and better
        con += sig and not better
    answer = ("yes" if pro and not con else "no" if con and not pro else "mixed" if pro
              else "no evidence")
    if not items:
        text = (f"Does physics help on {p}? Not asked: no tested physics ablation and no "
                "deployable forward model beside EBL or the GP in this run.")
    else:
        text = (f"Does physics help on {p}? {answer.capitalize()} — deployable estimators "
                "only (Δ RMSE, 95 % CI, paired cluster bootstrap over subjects, "
                "Holm-adjusted): " + "; ".join(items) + ".")
    anchor = (f"ablation-{p}" if run.ablation is not None and len(run.ablation)
              else _ANCHOR_HEADLINE)
    return Finding("answer", p, text, tuple(vals), anchor)
