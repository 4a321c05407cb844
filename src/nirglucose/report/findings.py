"""The findings section at the top of the report: sentences, headline figure, distances.

The sentences and the numbers in them are computed by
:mod:`nirglucose.evaluation.benchmark.findings`; this module only renders them. Every number is a
``<span class="v">`` carrying the unrounded value (``data-value``), the file, row and
column it was read from (``data-src``, sources joined by ``|``) and how it was derived
(``data-op``), so that a reader or a test can check it against the results files;
every sentence ends with a link to the figure or table behind it.
"""

from __future__ import annotations

import base64
import logging
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING

import numpy as np
import pandas as pd

from ..evaluation.benchmark.findings import (
    Finding,
    RunData,
    Value,
    best_and_tied,
    compute_findings,
    headline_table,
    label,
)
from ..evaluation.benchmark.subgroups import subgroup_findings
from ..formatting import format_number
from ..models.labels import knows
from .markup import esc as _esc
from .markup import physics_off_models, preset_of

if TYPE_CHECKING:
    from .figures import Results

__all__ = ["preset_of", "run_data", "computed_findings", "findings_section", "finding_html",
           "ANCHOR_NAMES"]

logger = logging.getLogger(__name__)

#: What each kind of anchor is called in the link that ends a sentence.
ANCHOR_NAMES = {
    "fig-headline": "headline figure",
    "distance-table": "distances table",
    "ablation": "physics ablation",
    "fig-wavelengths": "wavelength utilisation figure",
    "study-orderings": "study orderings",
    "reproduced-table": "main table",
    "extra-table": "further metrics",
    "presets": "presets compared",
    "run-info": "provenance",
    "subgroups": "subgroups",
}


def run_data(results: Results) -> RunData:
    """What the findings read from one loaded run (``ablation.csv`` read here)."""
    path = results.directory / "ablation.csv"
    ablation = None
    if path.is_file():
        try:
            ablation = pd.read_csv(path)
        except (OSError, ValueError, pd.errors.EmptyDataError):
            ablation = None
    return RunData(preset=preset_of(results), metrics=results.metrics, meta=results.meta,
                   predictions=results.predictions, comparisons=results.comparisons,
                   ablation=ablation, drop_one=results.drop_one, histories=results.histories)


def _value_html(v: Value) -> str:
    src = _esc("|".join(v.sources))
    return (f'<span class="v" data-value="{float(v.value)!r}" data-digits="{v.digits}" '
            f'data-scale="{float(v.scale)!r}" data-op="{_esc(v.op)}" data-src="{src}" '
            f'title="{src}">{_esc(v.text())}</span>')


def _anchor_name(anchor: str) -> str:
    for key, name in ANCHOR_NAMES.items():
        if anchor == key or anchor.startswith((key + "-", key + "_")):
            suffix = anchor[len(key) + 1:] if anchor != key else ""
            return f"{name} ({suffix})" if suffix else name
    return anchor


def finding_html(f: Finding) -> str:
    """One finding as a list item: text, numbers as tagged spans, a link to its evidence."""
    body = "".join(_value_html(p) if isinstance(p, Value) else _esc(p) for p in f.parts())
    return (f'<li class="finding" data-topic="{_esc(f.topic)}" '
            f'data-preset="{_esc(f.preset or "")}">{body} '
            f'<a class="ev" href="#{_esc(f.anchor)}">→ {_esc(_anchor_name(f.anchor))}</a></li>')


#: Heading of each topic of the findings, in reading order.
TOPIC_TITLES = {
    "best": "Best deployable model, and the references",
    "distance": "Distance from no skill and from the oracle",
    "physics": "The physics terms and their ablations", "leds": "What each LED adds",
    "claims": "The study's claims",
    "presets": "What separates the presets", "range": "Glucose range",
    "subgroups": "Subgroups", "subjects": "Sample size",
}


def _grouped(findings: Sequence[Finding]) -> str:
    """The findings as one short list per topic, topics in :data:`TOPIC_TITLES` order."""
    topics = [t for t in TOPIC_TITLES if any(f.topic == t for f in findings)]
    topics += [t for t in dict.fromkeys(f.topic for f in findings) if t not in topics]
    return "".join(
        f'<h4>{_esc(TOPIC_TITLES.get(t, t))}</h4><ul class="findings">'
        + "".join(finding_html(f) for f in findings if f.topic == t) + "</ul>"
        for t in topics)


def _headline_html(runs: Sequence[RunData]) -> str:
    from ..plots.forest import figure_headline
    from ..plots.style import figure_bytes

    table, refs = headline_table(runs)
    if not len(table):
        return ""
    fig = figure_headline(table, refs)
    data = base64.b64encode(figure_bytes(fig, "png")).decode("ascii")
    presets = list(dict.fromkeys(table["preset"]))
    alt = "; ".join(_alt_of(table, refs, p) for p in presets)
    return (f'<figure id="fig-headline"><div class="zoom"><img '
            f'src="data:image/png;base64,{data}" alt="{_esc(alt)}"></div>'
            '<p class="zoom-hint">Full size: scroll the figure sideways.</p>'
            "<figcaption><b>Headline figure.</b> Each deployable competitor's RMSE "
            "with its 95 % cluster-bootstrap CI on every preset (rows sorted by the first "
            "preset's RMSE, one colour and marker per model as in every figure). Filled: "
            "the best deployable model (its CI shaded) and those not distinguishable from "
            "it (paired cluster bootstrap over subjects, Holm-adjusted); open: "
            "significantly worse. Below the grey rule, black hollow markers with dotted CIs: "
            "privileged references (they read the generating scenario), drawn apart like "
            "the oracle and never ranked. Dashed: no skill (the training mean); dotted: "
            "the oracle, which inverts the forward model with the true nuisances (a bound, "
            "not a competitor)."
            "</figcaption></figure>")


def _alt_of(table: pd.DataFrame, refs: dict, preset: str) -> str:
    """Content-bearing alt text of one panel: best, tied count and the references."""
    part = table[table["preset"] == preset].sort_values("rmse_mgdl")
    part = part[part["status"] != "reference"]  # privileged: never best nor worst
    if not len(part):
        return f"{preset}: no deployable competitor"
    best = part[part["status"] == "best"]
    head = part.iloc[0] if not len(best) else best.iloc[0]

    txt = (f"{preset}: best {label(str(head['model']))} {format_number(head['rmse_mgdl'])} "
           f"mg/dL, {int((part['status'] == 'tied').sum())} tied with it, worst "
           f"{label(str(part.iloc[-1]['model']))} {format_number(part.iloc[-1]['rmse_mgdl'])}")
    r = refs.get(preset, {})
    if "mean" in r:
        txt += f", no skill {format_number(r['mean'])}"
    if "oracle" in r:
        txt += f", oracle {format_number(r['oracle'])}"
    return txt


def _not_better(beats: object) -> bool:
    """Whether a ``beats_no_skill`` cell says "tested, not significantly better": False
    as a Python or NumPy bool (a bool column gives ``numpy.bool_``, never ``False``
    itself); None or NaN (not tested) is not."""
    if beats is None or (not isinstance(beats, (bool, np.bool_)) and pd.isna(beats)):
        return False
    return not bool(beats)


def _distance_html(dist: pd.DataFrame, off: Mapping[str, set[str]] | None = None) -> str:
    """Competitors × presets: RMSE, mg/dL below no skill, % of its error removed, × oracle;
    a PINN whose tuned physics weight is 0 on a preset (``off``: preset -> models) says
    "physics off" there."""
    if not len(dist):
        return ""
    presets = list(dict.fromkeys(dist["preset"]))
    models = list(dict.fromkeys(dist.sort_values("rmse", key=lambda s: s.map(
        lambda v: v.value)).loc[lambda d: d["preset"] == presets[0], "model"]))
    models += [m for m in dict.fromkeys(dist["model"]) if m not in models]
    knows_of = ({str(m): k for m, k in zip(dist["model"], dist["privileged"], strict=True)
                 if isinstance(k, str)} if "privileged" in dist.columns else {})
    refs = [m for m in models if m in knows_of]
    models = [m for m in models if m not in knows_of]
    cols = (("rmse", "RMSE [mg/dL]"), ("below_no_skill", "below no skill [mg/dL]"),
            ("share_removed", "no-skill error removed [%]"), ("vs_oracle", "× oracle [-]"))
    head1 = "<th rowspan=2>Model</th>" + "".join(
        f"<th colspan={len(cols)}>{_esc(p)}</th>" for p in presets)
    head2 = "".join(f"<th>{_esc(h)}</th>" for _ in presets for _, h in cols)

    rows = []
    for m in [*models, *refs]:
        if refs and m == refs[0]:
            rows.append(f'<tr class="ref-head"><td colspan={1 + len(cols) * len(presets)}>'
                        "References, not competitors (privileged: they read what no device "
                        "measures)</td></tr>")
        name = label(m) + (f" — reference ({knows(knows_of[m])})" if m in knows_of else "")
        where = [p for p in presets if m in (off or {}).get(p, ())]
        if where:
            name += " (physics off" + ("" if len(where) == len(presets)
                                        else f" on {', '.join(where)}") + ")"
        cells = [f"<td>{_esc(name)}</td>"]
        for p in presets:
            r = dist[(dist["preset"] == p) & (dist["model"] == m)]
            for c, _ in cols:
                v = r[c].iloc[0] if len(r) else None
                txt = _value_html(v) if isinstance(v, Value) else "–"
                if c == "share_removed" and len(r) and _not_better(r["beats_no_skill"].iloc[0]):
                    txt += " (n.s.)"
                cells.append(f"<td>{txt}</td>")
        rows.append(('<tr class="ref">' if m in knows_of else "<tr>") + "".join(cells)
                    + "</tr>")
    return ("<h3>Distance from no skill and from the oracle</h3>"
            "<p>Share of the no-skill error removed = 1 − RMSE / no-skill RMSE; "
            "(n.s.): not significantly better than no skill (paired cluster bootstrap over "
            "subjects, Holm-adjusted); × oracle = RMSE / oracle RMSE.</p>"
            f'<div class="scroll"><table id="distance-table"><thead><tr>{head1}</tr>'
            f"<tr>{head2}</tr></thead><tbody>{''.join(rows)}</tbody></table></div>")


def computed_findings(runs: Sequence[Results], *, n_boot: int = 2000
                      ) -> tuple[list[RunData], list[Finding], pd.DataFrame]:
    """Each run's :class:`RunData`, every finding and the distances, computed once
    (the limits box and the findings section both read them)."""
    data = [run_data(r) for r in runs]
    findings, dist = compute_findings(data, n_boot=n_boot)
    return data, findings, dist


def findings_section(runs: Sequence[Results], *, n_boot: int = 2000,
                     subgroups: Mapping[str, pd.DataFrame] | None = None,
                     computed: tuple[list[RunData], list[Finding], pd.DataFrame] | None = None
                     ) -> str:
    """The findings section: sentences, the headline figure, the distances table.

    Parameters
    ----------
    runs : sequence of Results
        One loaded run per preset, the primary first.
    n_boot : int
        Resamples of the paired comparisons with no skill. [-]
    subgroups : mapping of str to pandas.DataFrame, optional
        Each preset's subgroup errors (:func:`nirglucose.report.subgroups.subgroup_tables`):
        a finding per grouping on the best model.
    computed : tuple, optional
        :func:`computed_findings` of ``runs`` when the caller has it.

    Returns
    -------
    str
        HTML (``<section id="findings">``), empty when nothing can be said. The
        one-line answers (topic ``answer``) are the limits box's
        (:mod:`nirglucose.report.limits`), not repeated here.
    """
    data, findings, dist = computed if computed is not None else computed_findings(
        runs, n_boot=n_boot)
    findings = [f for f in findings if f.topic != "answer"]
    for run in data:
        table = (subgroups or {}).get(run.preset)
        if table is not None:
            findings[-1:-1] = subgroup_findings(run.preset, best_and_tied(run)[0], table)
    if not findings:
        return ""
    items = _grouped(findings)
    off = {preset_of(r): physics_off_models(r.meta) for r in runs}
    return ('<section id="findings"><h2>Findings</h2><p class="sub">Computed from this '
            "run's results files: every number links (hover) to the file, row and column "
            "it was read from, and every sentence to the figure or table behind it.</p>"
            f"{items}{_headline_html(data)}{_distance_html(dist, off)}"
            "</section>")
