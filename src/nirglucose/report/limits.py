"""The limits first: what each preset's results rest on, above the report's contents.

One short box per preset: how large glucose's optical signal is against the published
magnitudes (``glucose.signal_gain``: ×11 on ``paper``, the study's what-if; ×12.5 on
``wearable``, a basic wearable; ×1 on ``physical``, the published magnitudes), whether
the models see the exact physiology or a measured one, which rows are privileged
references, the subjects behind the claims, the glucose range covered, the models that
ran, and the best deployable estimator beside the oracle and no skill. Then one line
per preset answering the study's question, "does physics help?", with its evidence
(:func:`nirglucose.evaluation.benchmark.findings.physics_answer`).

Every number is read from the run's files (``metrics.json``, ``predictions.parquet``,
``meta.json``); the regimes' names are this module's (:data:`REGIMES`).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any, Final

from ..config.presets import PAPER_SIGNAL_GAIN, WEARABLE_SIGNAL_GAIN
from ..dataset.columns import PMF_COLUMNS
from ..evaluation.benchmark.findings import (
    HYPO_MGDL,
    NO_SKILL,
    Finding,
    RunData,
    best_and_tied,
    glucose_range,
    privilege,
)
from ..formatting import format_number
from ..models.labels import ablation_base, knows, label
from .findings import finding_html
from .markup import esc as _esc

if TYPE_CHECKING:
    from .figures import Results

__all__ = ["REGIMES", "regime", "limits_facts", "limits_section"]

#: Preset -> (its glucose-signal gain, how the report names the regime)
#: (:mod:`nirglucose.config.presets`: the gains and how each was calibrated).
REGIMES: Final[dict[str, tuple[float, str]]] = {
    "paper": (PAPER_SIGNAL_GAIN, "the study's what-if (×11)"),
    "wearable": (WEARABLE_SIGNAL_GAIN, "a basic wearable (×12.5)"),
    "physical": (1.0, "published magnitudes"),
}


def regime(gain: float | None, preset: str | None = None) -> str:
    """The regime a preset's glucose-signal gain stands for, in the report's words.

    A named preset at its own gain takes its regime's name (:data:`REGIMES`); a gain of
    1 is the published magnitudes whatever the preset; any other gain is said as a
    factor.

    Examples
    --------
    >>> regime(11.0, "paper"), regime(1.0, "lab")
    ("the study's what-if (×11)", 'published magnitudes')
    >>> regime(12.5, "lab")
    '×12.5 the published glucose signal'
    """
    if gain is None:
        return "glucose signal gain not recorded"
    if preset in REGIMES and float(gain) == REGIMES[preset][0]:
        return REGIMES[preset][1]
    if float(gain) == 1.0:
        return "published magnitudes"
    return f"×{format_number(gain, style='general')} the published glucose signal"


def _config_value(res: Results, key: str) -> Any:
    """A dotted key of the run's resolved configuration (None when not recorded)."""
    cfg = res.config
    node: Any = cfg.model_dump(mode="json") if cfg is not None else None
    for part in key.split("."):
        if not isinstance(node, dict) or part not in node:
            return None
        node = node[part]
    return node


def limits_facts(res: Results, run: RunData) -> dict[str, Any]:
    """What one preset's results rest on, as plain values (the box renders them).

    Returns
    -------
    dict
        ``preset``, ``gain`` (``glucose.signal_gain``, None when not recorded),
        ``regime``, ``physiology`` (``"exact"``, ``"measured"`` or None), ``privileged``
        (label -> what it knows), ``subjects``, ``snapshots``, ``glucose`` (the
        :func:`~nirglucose.evaluation.benchmark.findings.glucose_range` of the
        predictions), ``models`` (labels of the rows that ran, ablations left out),
        ``best`` (the best deployable model or None), and the RMSE of ``best``, the
        ``oracle`` and ``no_skill`` where present. [mg/dL]
    """
    gain = _config_value(res, "glucose.signal_gain")
    m = run.m
    p = run.predictions
    rows = [str(x) for x in m.index if ablation_base(str(x)) is None]
    best = best_and_tied(run)[0]
    if best is None:  # no comparisons: the lowest RMSE among the deployable rows
        dep = [x for x in rows if x != NO_SKILL and privilege(run, x) is None]
        best = min(dep, key=lambda x: float(m.at[x, "rmse_mgdl"])) if dep else None

    def rmse(model: str | None) -> float | None:
        return float(m.at[model, "rmse_mgdl"]) if model is not None and model in m.index \
            else None

    ds = getattr(res, "dataset", None)
    meta = getattr(ds, "metadata", None) or {}
    return {
        "preset": run.preset,
        "user_data": bool(res.user_data),
        "withheld": res.meta.get("significance_withheld"),
        "file_warnings": [str(w) for w in meta.get("file_warnings", ())],
        "file_physiology": ([c for c in PMF_COLUMNS if c in ds.frame.columns]
                            if ds is not None else []),
        "gain": None if gain is None else float(gain),
        "regime": ("measured by your device" if res.user_data else
                   regime(None if gain is None else float(gain), run.preset)),
        "physiology": _config_value(res, "device.physiology"),
        "privileged": {label(x): knows(k) for x in rows
                       if x != NO_SKILL and (k := privilege(run, x)) is not None},
        "subjects": int(p["subject_id"].nunique()) if "subject_id" in p.columns else None,
        "snapshots": (int(p["measurement_id"].nunique()) if "measurement_id" in p.columns
                      else None),
        "glucose": glucose_range(run) if len(p) else None,
        "models": [label(x) for x in rows],
        "best": best,
        "best_rmse": rmse(best),
        "oracle_rmse": rmse("oracle"),
        "no_skill_rmse": rmse(NO_SKILL),
    }


def _n(v: float | None, digits: int = 1) -> str:
    return format_number(v, digits, thousands=True)


def _device_items(f: dict[str, Any]) -> list[str]:
    """The first lines of a device's file's box: what was measured, not simulated, and
    the warnings its reading raised."""
    items = ["<li><b>Glucose signal</b>: measured, not simulated — its size "
             "is whatever the optics and the skin give; no oracle bound (no scenario)</li>",
             "<li><b>Physiology</b>: " + (
                 f"the file's own columns, as measured ({_esc(', '.join(phys))})" if
                 (phys := f["file_physiology"]) else "none in the file") + "</li>"]
    for w in f["file_warnings"]:
        items.append(f"<li><b>Reading the file</b>: {_esc(w)}</li>")
    return items


def _box(f: dict[str, Any]) -> str:
    if f.get("user_data"):
        return _box_items(f, _device_items(f))
    items = []
    gain = f["gain"]
    items.append(
        f"<li><b>Glucose signal</b>: ×{_esc(format_number(gain, style='general'))} the "
        "published magnitudes" + (" (the published ones)" if gain == 1.0 else "")
        + "</li>" if gain is not None else
        "<li><b>Glucose signal</b>: its size against the published one is not recorded"
        "</li>")
    phys = f["physiology"]
    items.append("<li><b>Physiology</b>: " + (
        "exact — the models see the true physiology, no instrument error" if phys == "exact"
        else "measured — with the instruments' errors" if phys == "measured"
        else "not recorded") + "</li>")
    return _box_items(f, items)


def _box_items(f: dict[str, Any], items: list[str]) -> str:
    """The box's lines after the regime's: privileged rows, subjects, glucose range,
    RMSE beside the references, the models that ran."""
    items = list(items)
    priv = f["privileged"]
    items.append("<li><b>Privileged rows</b> (references, never ranked): " + (
        "; ".join(f"{_esc(k)} ({_esc(v)})" for k, v in priv.items()) if priv else "none")
        + "</li>")
    if f["subjects"] is not None:
        items.append(f"<li><b>Subjects</b> behind every claim: {f['subjects']}"
                     + (f" ({_n(f['snapshots'], 0)} snapshots)" if f["snapshots"] else "")
                     + "</li>")
    g = f["glucose"]
    if g is not None:
        hypo = ("no hypoglycaemia (no reading below "
                f"{format_number(HYPO_MGDL, 0)} mg/dL)" if g["min"] >= HYPO_MGDL else
                f"{g['n_hypo']} of {g['n']} readings below {format_number(HYPO_MGDL, 0)} "
                "mg/dL")
        items.append(f"<li><b>Glucose range</b>: {_n(g['min'], 0)}–{_n(g['max'], 0)} mg/dL; "
                     f"{hypo}</li>")
    res = []
    if f["best"] is not None and f.get("withheld"):
        res.append(f"lowest deployable {_esc(label(f['best']))} {_n(f['best_rmse'])}")
    elif f["best"] is not None:
        res.append(f"best deployable {_esc(label(f['best']))} {_n(f['best_rmse'])}")
    if f["oracle_rmse"] is not None:
        res.append(f"oracle {_n(f['oracle_rmse'])}")
    if f["no_skill_rmse"] is not None:
        res.append(f"no skill {_n(f['no_skill_rmse'])}")
    if res:
        worse = (f["best_rmse"] is not None and f["no_skill_rmse"] is not None
                 and f["best_rmse"] >= f["no_skill_rmse"])
        items.append(f"<li><b>RMSE</b> [mg/dL]: {'; '.join(res)}"
                     + (": no deployable estimator beats the training mean here" if worse
                        else "") + "</li>")
    if f.get("withheld"):
        items.append(f"<li><b>Significance</b>: {_esc(f['withheld'])}</li>")
    items.append(f"<li><b>Models that ran</b> ({len(f['models'])}): "
                 f"{_esc(', '.join(f['models']))}</li>")
    return (f'<div class="limit" id="limits-{_esc(f["preset"])}"><h3>{_esc(f["preset"])}: '
            f"{_esc(f['regime'])}</h3><ul>{''.join(items)}</ul></div>")


def limits_section(runs: Sequence[Results], data: Sequence[RunData],
                   findings: Sequence[Finding]) -> str:
    """The limits box of every preset and the one-line answers, as HTML.

    Parameters
    ----------
    runs : sequence of Results
        One loaded run per preset, the primary first.
    data : sequence of RunData
        Their :class:`~nirglucose.evaluation.benchmark.findings.RunData`, in the same order.
    findings : sequence of Finding
        The run's findings; those of topic ``answer`` are shown here.

    Returns
    -------
    str
        ``<section id="limits">``; empty when there is no run.
    """
    if not runs:
        return ""
    boxes = "".join(_box(limits_facts(r, d)) for r, d in zip(runs, data, strict=True))
    answers = [f for f in findings if f.topic == "answer"]
    answer = ('<h3 id="answer">Does physics help?</h3><ul class="findings answer">'
              + "".join(finding_html(f) for f in answers) + "</ul>") if answers else ""
    intro = ("Read this first. These results are your file's: every model was fitted on "
             "some of its people and scored on the others; what the file "
             "does not say (the skin's optics, the true nuisances) no model here knew."
             if all(r.user_data for r in runs) else
             "Read this first. Each preset simulates glucose at a stated size against the "
             "published magnitudes; privileged rows read the generating scenario or the true "
             "nuisances, which no device measures, so they are references and never the best "
             "model.")
    return ('<section id="limits"><h2>What these results rest on</h2>'
            f'<p class="sub">{intro}</p>'
            f'<div class="limits">{boxes}</div>{answer}</section>')
