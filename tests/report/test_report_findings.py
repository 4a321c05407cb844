"""The findings section: every number equals the results files it names, on two presets.

Parsed with the standard library's HTML parser, so this runs where no browser is
installed; ``test_report_browser.py`` checks the same in Chromium.
"""

from __future__ import annotations

import json
import math
import re
from collections import Counter
from html.parser import HTMLParser
from pathlib import Path

import pandas as pd
import pytest


class _Findings(HTMLParser):
    """Collects ids, links, the findings' number spans and the contents list."""

    def __init__(self) -> None:
        super().__init__()
        self.ids: list[str] = []
        self.links: list[str] = []
        self.values: list[dict] = []
        self.findings: list[dict] = []
        self.nav_links: list[str] = []
        self.h2_ids: list[str] = []
        self._span: dict | None = None
        self._li: dict | None = None
        self._nav = False

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        if "id" in a:
            self.ids.append(a["id"])
        if tag == "h2" and "id" in a:
            self.h2_ids.append(a["id"])
        if tag == "nav":
            self._nav = True
        if tag == "a" and (a.get("href") or "").startswith("#"):
            self.links.append(a["href"][1:])
            if self._nav:
                self.nav_links.append(a["href"][1:])
            if self._li is not None and a.get("class") == "ev":
                self._li["anchor"] = a["href"][1:]
        if tag == "li" and a.get("class") == "finding":
            self._li = {"topic": a.get("data-topic"), "preset": a.get("data-preset"),
                        "text": "", "values": [], "anchor": None}
        if tag == "span" and a.get("class") == "v":
            self._span = {**a, "text": ""}

    def handle_endtag(self, tag):
        if tag == "span" and self._span is not None:
            self.values.append(self._span)
            if self._li is not None:
                self._li["values"].append(self._span)
            self._span = None
        elif tag == "li" and self._li is not None:
            self.findings.append(self._li)
            self._li = None
        elif tag == "nav":
            self._nav = False

    def handle_data(self, data):
        if self._span is not None:
            self._span["text"] += data
        if self._li is not None:
            self._li["text"] += data


def _parse(path: Path) -> _Findings:
    page = _Findings()
    page.feed(path.read_text(encoding="utf-8"))
    return page


def _fmt(value: float, digits: int, sign: bool) -> str:
    if digits == 0:
        return f"{value:+,.0f}" if sign else f"{value:,.0f}"
    return f"{value:+.{digits}f}" if sign else f"{value:.{digits}f}"


class _Files:
    """Reads a source (``<preset>/<file>:<keys>``) from the results directory."""

    def __init__(self, root: Path) -> None:
        self.root = root

    def metric(self, preset: str, model: str, col: str) -> float:
        doc = json.loads((self.root / preset / "metrics.json").read_text())
        row = next(r for r in doc["metrics"] if r["model"] == model)
        return float(row[col])

    def read(self, src: str) -> float | None:
        """The value a single source names, or None for a source not read from a file."""
        preset, rest = src.split("/", 1)
        file, _, key = rest.partition(":")
        if file == "metrics.json":
            model, col = key.rsplit(":", 1)
            return self.metric(preset, model, col)
        if file == "ablation.csv":
            model, col = key.rsplit(":", 1)
            a = pd.read_csv(self.root / preset / "ablation.csv").set_index("model")
            return float(a.at[model, col]) if col in a.columns else None
        if file == "drop_one.csv":
            model, wl, col = key.rsplit(":", 2)
            t = pd.read_csv(self.root / preset / "drop_one.csv")
            row = t[(t["model"] == model) & (t["dropped_wavelength_nm"] == float(wl))]
            return float(row[col].iloc[0])
        if file == "meta.json" and key != "config":
            node = json.loads((self.root / preset / "meta.json").read_text())
            for part in key.split("."):  # model names hold no dots
                node = node[part]
            return float(node)
        return None


def _expected(files: _Files, span: dict) -> float | None:
    srcs = span["data-src"].split("|")
    op = span["data-op"]
    if op == "count":  # counted from the comparisons or predictions: checked by topic
        return None
    vals = [files.read(s) for s in srcs]
    if any(v is None for v in vals):
        return None
    if op == "":
        return vals[0]
    if op == "diff":
        return vals[0] - vals[1]
    if op == "share_removed":
        return 1.0 - vals[0] / vals[1]
    if op == "skill":
        return 1.0 - (vals[0] / vals[1]) ** 2
    if op == "ratio":
        return vals[0] // vals[1]
    return None


def test_every_number_equals_the_file_it_names(preset_report, preset_results):
    page = _parse(preset_report)
    files = _Files(preset_results)
    assert page.findings, "no findings section"
    checked = Counter()
    for span in page.values:
        value = float(span["data-value"])
        shown = _fmt(value * float(span["data-scale"]), int(span["data-digits"]),
                     span["text"].startswith(("+", "-")) and not _fmt(
                         value * float(span["data-scale"]), int(span["data-digits"]), False
                     ).startswith("-"))
        assert span["text"] == shown, span
        want = _expected(files, span)
        if want is not None:
            assert math.isclose(value, want, rel_tol=1e-9, abs_tol=1e-12), span
            checked[span["data-src"].split("/", 1)[1].split(":", 1)[0]] += 1
    # the numbers of metrics.json, ablation.csv and meta.json were all re-derived
    assert checked["metrics.json"] >= 20 and checked["ablation.csv"] >= 4
    assert checked["drop_one.csv"] >= 4  # each named LED's Δ RMSE, its CI and the RMSE
    assert checked["meta.json"] >= 3


def test_best_model_and_ties_follow_the_comparisons(preset_report, preset_results):
    page = _parse(preset_report)
    for preset in ("paper", "wearable"):
        c = pd.read_csv(preset_results / preset / "comparisons.csv")
        vb = c[c["family"] == "vs_best"]
        best = vb["reference_model"].iloc[0]
        comp = vb[~vb["model"].isin(["oracle", "mean", "physics-inversion"])
                  & ~vb["model"].str.contains("/")]
        n_tied = int((~comp["significant"]).sum())
        f = next(x for x in page.findings if x["topic"] == "best" and x["preset"] == preset)
        src = {v["data-src"]: v for v in f["values"]}
        assert f"{preset}/metrics.json:{best}:rmse_mgdl" in src
        counts = [v for v in f["values"] if v["data-op"] == "count"]
        if n_tied:
            assert int(float(counts[0]["data-value"])) == n_tied
            assert "not distinguishable" in f["text"]
        else:
            assert "significantly worse" in f["text"]


def test_physics_off_by_tuning_gives_no_verdict(preset_report):
    text = preset_report.read_text(encoding="utf-8")
    page = _parse(preset_report)
    paper = [f for f in page.findings if f["topic"] == "physics" and f["preset"] == "paper"]
    assert any("physics off by tuning — not tested" in f["text"] for f in paper)
    assert not any("no significant difference" in f["text"] for f in paper)
    # nowhere on the page a Δ of an identical pair, nor a verdict for it
    assert "+0.00 [+0.00, +0.00]" not in text
    table = text[text.index('id="ablation-paper"'):]
    table = table[:table.index("</table>")]
    assert "not tested" in table and "no significant difference" not in table
    # the tested preset keeps its Δ, CI and verdict
    wear = [f for f in page.findings if f["topic"] == "physics" and f["preset"] == "wearable"]
    assert any("Δ RMSE" in f["text"] and "Holm-adjusted p" in f["text"] for f in wear)


def test_links_ids_and_contents(preset_report):
    page = _parse(preset_report)
    dup = [k for k, n in Counter(page.ids).items() if n > 1]
    assert dup == []
    assert set(page.links) <= set(page.ids)
    assert all(f["anchor"] in page.ids for f in page.findings), "a finding without evidence"
    assert set(page.h2_ids) <= set(page.nav_links)  # every section in the contents
    for key in ("findings", "fig-headline", "distance-table", "subgroups", "presets"):
        assert key in page.nav_links
    assert page.ids.index("findings") < page.ids.index("table")  # findings come first


def test_headline_figure_and_alt_text(preset_report, preset_results):
    text = preset_report.read_text(encoding="utf-8")
    m = re.search(r'<figure id="fig-headline"><div class="zoom"><img '
                  r'src="data:image/png;base64,[^"]+" alt="([^"]+)"', text)
    assert m
    alt = m.group(1)
    for preset in ("paper", "wearable"):
        doc = json.loads((preset_results / preset / "metrics.json").read_text())
        ns = next(r for r in doc["metrics"] if r["model"] == "mean")["rmse_mgdl"]
        assert f"{preset}: best" in alt and f"no skill {ns:.1f}" in alt
    # every figure's alt text says what it shows, not only its title
    figs = re.findall(r'<figure id="fig-[^"]+"><div class="zoom"><img [^>]*alt="([^"]*)"'
                      r'.*?<figcaption><b>[^<]*?\. ([^<]+?)\.</b>', text)
    assert len(figs) >= 15
    for alt, title in figs:
        assert title in alt and len(alt) > len(title) + 40, alt


def test_hypoglycaemia_caveat_and_subject_floor(preset_report, preset_results):
    page = _parse(preset_report)
    for preset in ("paper", "wearable"):
        p = pd.read_parquet(preset_results / preset / "predictions.parquet")
        below = int((p.drop_duplicates("measurement_id")["reference_mgdl"] < 70).sum())
        f = next(x for x in page.findings if x["topic"] == "range" and x["preset"] == preset)
        assert ("says nothing about hypoglycaemia" in f["text"]) == (below == 0)
    floor = next(x for x in page.findings if x["topic"] == "subjects")
    n = min(pd.read_parquet(preset_results / p / "predictions.parquet")["subject_id"].nunique()
            for p in ("paper", "wearable"))
    assert int(float(floor["values"][0]["data-value"])) == n


@pytest.mark.parametrize("by", ["diabetes_status", "fitzpatrick_type"])
def test_subgroup_tables(preset_report, by):
    text = preset_report.read_text(encoding="utf-8")
    for preset in ("paper", "wearable"):
        i = text.index(f'id="subgroups-{preset}-{by}"')
        table = text[i:text.index("</table>", i)]
        assert re.search(r"<td>\d+\.\d \[\d+\.\d, \d+\.\d\]</td>", table)


def test_bland_altman_limits_are_the_tables(preset_results):
    """One definition: the figure's bias and limits are per repeat, averaged (as metrics)."""
    from nirglucose.metrics import summary
    from nirglucose.report.figures import bland_altman_inputs

    p = pd.read_parquet(preset_results / "wearable" / "predictions.parquet")
    ba = bland_altman_inputs(p, ["ebl", "sdnn"])
    for m in ("ebl", "sdnn"):
        per = [summary(g["reference_mgdl"], g["scored_mgdl"])
               for _, g in p[p["model"] == m].groupby("repeat")]
        for key, col in (("bias", "bias_mgdl"), ("loa_low", "loa_low_mgdl"),
                         ("loa_high", "loa_high_mgdl")):
            assert math.isclose(ba[m][key], sum(s[col] for s in per) / len(per),
                                rel_tol=1e-12), (m, key)


def test_latency_inside_timing_noise_ranks_nothing():
    from nirglucose.report.figures import efficiency_table, radar_scores
    from nirglucose.report.figures.inputs import latency_resolution

    a = pd.DataFrame({"model": ["ebl", "pls", "sdnn"], "rmse_mgdl": [14.0, 20.0, 15.0],
                      "n_parameters": [67, 19, 3809],
                      "latency_single_ms": [0.12, 0.055, 0.07]})
    b = a.assign(latency_single_ms=[0.044, 0.050, 0.066])  # the same models, another run
    res = latency_resolution(a, [b])
    assert not res["resolved"] and math.isclose(res["noise"], 0.12 / 0.044)
    assert "latency" not in radar_scores(a, list(a["model"])).columns  # never an axis
    eff = efficiency_table(a, list(a["model"]), latency=False)
    assert eff["front_latency"].tolist() == [True, False, False]  # only the most accurate
    # a spread far beyond the noise is resolved
    c = a.assign(latency_single_ms=[0.1, 10.0, 0.1])
    assert latency_resolution(c, [c])["resolved"]


def test_every_preset_gets_its_training_and_pipeline_figures(preset_report):
    text = preset_report.read_text(encoding="utf-8")
    for key in ("fig-training", "fig-training_wearable", "fig-pipeline",
                "fig-pipeline_wearable"):
        assert f'<figure id="{key}"><div class="zoom"><img' in text, key
    i = text.index('<figure id="fig-training_wearable">')
    cap = text[i:text.index("</figure>", i)]
    assert "validation (dashed)" in cap and "no validation split" not in cap


def test_ablation_rows_never_compete_and_are_named():
    """``<pinn>/lambda=<v>`` and ``<pinn>/no-physics`` rows are ablations, not models."""
    from nirglucose.evaluation.benchmark.findings import _is_competitor, label

    assert not _is_competitor("rte-pinn/lambda=0.1")
    assert not _is_competitor("rte-pinn/no-physics")
    assert _is_competitor("rte-pinn")
    assert label("rte-pinn/lambda=0.1").endswith("(λ = 0.1)")
    assert label("rte-pinn/no-physics").endswith("(no physics)")


def test_no_sentence_keeps_an_unfilled_placeholder(preset_report):
    """Every ``{}`` of a finding's template is filled by one of its values (a stray one
    shifts every later number onto the wrong words)."""
    page = Path(preset_report).read_text()
    assert "{}" not in page and "{{" not in page
