"""Issue 39: what the report's results rest on (privileged rows apart, the (n.s.) flag,
the limits box, the physics terms measured, the reader's fixes).

Fast: small synthetic predictions, no benchmark run; the page-level checks use the
session's two-preset report (``preset_report``)."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest

from nirglucose.evaluation.benchmark.finding import Value
from nirglucose.evaluation.benchmark.findings import (
    RunData,
    best_and_tied,
    compute_findings,
    headline_table,
    physics_answer,
    term_verdicts,
)
from nirglucose.metrics.resampling import compare_models
from nirglucose.models.labels import row_privilege

#: Noise SD of each synthetic model [mg/dL]: the privileged inversion is the most
#: accurate, as on the study's presets.
_SD = {"physics-inversion": 3.0, "oracle": 2.0, "ebl": 14.0, "device-inversion": 12.0,
       "gp": 30.0, "mean": 55.0}


def _preds(sd=_SD, n_subjects: int = 24, seed: int = 0) -> pd.DataFrame:
    rng = np.random.default_rng(seed)
    ref = rng.uniform(80.0, 300.0, n_subjects * 3)
    subj = np.repeat(np.arange(n_subjects), 3)
    parts = []
    for m, s in sd.items():
        pred = np.maximum(ref + rng.normal(0.0, s, ref.size), 1.0)
        parts.append(pd.DataFrame({"model": m, "subject_id": subj,
                                   "measurement_id": np.arange(ref.size), "repeat": 0,
                                   "fold": subj % 4, "reference_mgdl": ref,
                                   "predicted_mgdl": pred, "scored_mgdl": pred}))
    return pd.concat(parts, ignore_index=True)


def _run(preds: pd.DataFrame, *, with_privileged_column: bool = True,
         preset: str = "physical", histories=None) -> RunData:
    rows = []
    for m, g in preds.groupby("model", sort=False):
        rmse = float(np.sqrt(np.mean((g["scored_mgdl"] - g["reference_mgdl"]) ** 2)))
        row = {"model": m, "rmse_mgdl": rmse, "rmse_ci_low": rmse - 1, "rmse_ci_high": rmse + 1}
        if with_privileged_column:
            row["privileged"] = row_privilege(m)
        rows.append(row)
    metrics = pd.DataFrame(rows)
    # the comparisons as the benchmark wrote them before issue 39: oracle excluded only
    vb = compare_models(preds, pred_col="scored_mgdl", n_boot=200, seed=0)
    vb.insert(0, "family", "vs_best")
    return RunData(preset=preset, metrics=metrics, meta={}, predictions=preds,
                   comparisons=vb, histories=histories)


def test_ns_flag_shows_for_a_numpy_bool():
    """The distances table's (n.s.): a bool column gives numpy.bool_, never ``False``."""
    from nirglucose.report.findings import _distance_html

    v = Value(10.0, 1, ("p/metrics.json:ebl:rmse_mgdl",))
    dist = pd.DataFrame({"preset": ["p", "p"], "model": ["ebl", "gp"], "rmse": [v, v],
                         "below_no_skill": [v, v], "share_removed": [v, v],
                         "vs_oracle": [v, v], "beats_no_skill": [True, False]})
    assert dist["beats_no_skill"].dtype == bool
    html = _distance_html(dist)
    assert html.count("(n.s.)") == 2  # the legend's and GP's row
    gp_row = html[html.index("Gaussian process"):]
    assert "(n.s.)" in gp_row[:gp_row.index("</tr>")]
    ebl_row = html[html.index("Enhanced Beer"):]
    assert "(n.s.)" not in ebl_row[:ebl_row.index("</tr>")]


def test_metrics_json_says_what_each_row_knows():
    from nirglucose.evaluation.benchmark.result import METRIC_COLUMNS

    assert "privileged" in METRIC_COLUMNS
    assert row_privilege("oracle") and row_privilege("physics-inversion")
    assert row_privilege("original-pinn-fm") and row_privilege("physics-inversion+gp")
    assert row_privilege("device-inversion") is None and row_privilege("ebl") is None
    assert row_privilege("my-own-model") is None  # a user's estimator: deployable


def test_benchmark_ranks_only_deployable_rows_best():
    from nirglucose.evaluation.benchmark.aggregate import _comparisons

    preds = _preds()
    c = _comparisons(preds, list(_SD), n_boot=200, alpha=0.05, seed=0, study=False)
    assert set(c.loc[c["family"] == "vs_best", "reference_model"]) == {"device-inversion"}


@pytest.mark.parametrize("column", [True, False])
def test_findings_never_call_a_privileged_row_best(column):
    run = _run(_preds(), with_privileged_column=column)
    assert run.comparisons["reference_model"].iloc[0] == "physics-inversion"  # old ranking
    best, tied, worse, _ = best_and_tied(run)
    assert best == "device-inversion"
    assert "physics-inversion" not in tied + worse
    findings, dist = compute_findings([run], n_boot=200)
    best_f = [f for f in findings if f.topic == "best"]
    assert "best deployable estimator" in best_f[0].text()
    assert "Device inversion" in best_f[0].text()
    for f in findings:
        t = f.text()
        if "Physics inversion" in t or "Oracle" in t:
            assert "reference" in t.lower() or "bound" in t, t
            assert "best" not in t.split("Physics inversion")[0][-40:], t
    ref = next(f for f in best_f if f.text().startswith("References"))
    assert "knows the generating scenario" in ref.text()
    table, _ = headline_table([run])
    assert table.set_index("model").at["physics-inversion", "status"] == "reference"
    assert "best" not in set(table.loc[table["model"] == "physics-inversion", "status"])
    assert dist.set_index("model").at["physics-inversion", "privileged"]


def test_answer_names_deployable_evidence_only():
    run = _run(_preds())
    f = physics_answer(run, n_boot=200)
    text = f.text()
    assert text.startswith("Does physics help on physical?")
    assert "Device inversion (published tables) − Enhanced Beer–Lambert" in text
    assert "Physics inversion" not in text and "Oracle" not in text


def test_answer_says_no_evidence_when_the_cis_overlap():
    sd = {"ebl": 20.0, "device-inversion": 20.0, "gp": 20.0, "mean": 55.0}
    run = _run(_preds(sd, seed=3))
    text = physics_answer(run, n_boot=200).text()
    assert "No evidence" in text and "no significant difference" in text


def _history(pull: float, phys: tuple[float, float], lam_grad: float = 0.05):
    return [{"epoch": e, "train_physics": p, "grad_norm_data": 1.0,
             "grad_norm_physics": lam_grad, "grad_norm_physics_unit": 0.05,
             "grad_ratio": 0.05, "pull_sd": pull, "indirect_ratio": 0.0}
            for e, p in ((1, phys[0]), (2, phys[1]))]


def test_inert_beer_lambert_term_is_said_to_be_unable_to_show_an_effect():
    hist = {"optimized-pinn": _history(4e-4, (0.11197, 0.11199)),
            "rte-pinn": _history(0.3, (0.5, 0.2)),
            "original-pinn": _history(4e-4, (0.1, 0.1), lam_grad=0.0)}
    run = _run(_preds({"ebl": 14.0, "optimized-pinn": 15.0, "rte-pinn": 16.0,
                       "original-pinn": 16.0, "mean": 55.0}), histories=hist)
    got = {v["model"]: v["verdict"] for v in term_verdicts(run)}
    assert got == {"optimized-pinn": "inert", "rte-pinn": "active", "original-pinn": "off"}
    findings, _ = compute_findings([run], n_boot=200)
    text = " ".join(f.text() for f in findings if f.topic == "physics")
    assert ("the study's Beer–Lambert term is constant during training, so its ablation "
            "cannot show an effect") in text
    assert "RTE-inspired PINN: its physics term is active" in text
    assert "Original PINN: physics off" in text


def test_physics_depth_puts_a_physics_off_pinn_on_no_physics():
    from nirglucose.report.figures.inputs import physics_depth_table

    metrics = pd.DataFrame({"model": ["original-pinn", "rte-pinn", "physics-inversion", "ebl"],
                            "rmse_mgdl": [20.0, 22.0, 3.0, 14.0],
                            "n_parameters": [1e5, 2e5, 30, 60]})
    t, _ = physics_depth_table(metrics, list(metrics["model"]),
                               lambdas={"original-pinn": 0.0, "rte-pinn": 0.1})
    t = t.set_index("model")
    assert t.at["original-pinn", "physics_depth"] == 0.0
    assert "physics off" in t.at["original-pinn", "label"]
    assert t.at["rte-pinn", "physics_depth"] > 0 and "off" not in t.at["rte-pinn", "label"]
    assert "physics-inversion" not in t.index  # privileged: a reference line, not a bubble


def test_labels_sit_nearest_their_own_markers():
    from matplotlib.figure import Figure
    from matplotlib.text import Annotation

    from nirglucose.plots.labels import label_points, place_labels

    fig = Figure(figsize=(4, 3))
    ax = fig.add_subplot()
    x = np.array([1.0, 1.05, 1.1, 2.0, 2.02, 3.0])
    y = np.array([10.0, 10.4, 9.8, 20.0, 20.3, 15.0])
    ax.scatter(x, y)
    ax.set_xlim(0.5, 3.5)
    ax.set_ylim(5, 25)
    label_points(ax, x, y, [f"model {k}" for k in range(len(x))])
    place_labels(fig)
    renderer = fig.canvas.get_renderer()
    pts = ax.transData.transform(np.c_[x, y])
    for ann in (t for t in ax.texts if isinstance(t, Annotation)):
        k = int(ann.get_text().split()[-1])
        bb = ann.get_window_extent(renderer)
        if ann.arrow_patch is not None:  # a leader line says whose it is
            continue
        gaps = [np.hypot(max(bb.x0 - px, 0, px - bb.x1), max(bb.y0 - py, 0, py - bb.y1))
                for px, py in pts]
        assert int(np.argmin(gaps)) == k or gaps[k] == min(gaps), ann.get_text()


# --------------------------------------------------------------------------- the page


def _page(report) -> str:
    return report.read_text(encoding="utf-8")


def test_first_screen_is_title_limits_answer_then_contents(preset_report, preset_results):
    page = _page(preset_report)
    i_title, i_limits = page.index("<h1>"), page.index('<section id="limits">')
    i_answer, i_nav = page.index('id="answer"'), page.index("<nav>")
    assert i_title < i_limits < i_answer < i_nav < page.index('<section id="findings">')
    box = page[i_limits:i_nav]
    assert "paper: the study&#x27;s what-if (×11)" in box
    assert "wearable: a basic wearable (×12.5)" in box
    assert "exact — the models see the true physiology" in box  # paper
    assert "measured — with the instruments" in box  # wearable
    assert "Physics inversion (forward model) (knows the generating scenario" in box
    for preset in ("paper", "wearable"):
        preds = pd.read_parquet(preset_results / preset / "predictions.parquet")
        part = box[box.index(f'id="limits-{preset}"'):]
        part = part[:part.index("</div>")]
        assert f"{preds['subject_id'].nunique()} (" in part  # subjects behind the claims
        if preds["reference_mgdl"].min() >= 70:
            assert "no hypoglycaemia" in part
        assert "best deployable" in part and "oracle" in part and "no skill" in part
        assert "best deployable Physics inversion" not in part
        assert f"Does physics help on {preset}?" in box
    assert "Does physics help?" in box


def test_no_privileged_row_is_called_best_on_the_page(preset_report):
    page = _page(preset_report)
    for bad in ("best deployable estimator (it reads only the measured columns) is Physics",
                "best model is Physics", "lowest RMSE is Physics",
                "best deployable Physics inversion"):
        assert bad not in page
    dist = page[page.index('id="distance-table"'):]
    dist = dist[:dist.index("</table>")]
    assert "References, not competitors" in dist
    assert "Physics inversion (forward model) — reference (knows" in dist


def test_figures_sit_beside_their_text_once_each(preset_report):
    import re

    page = _page(preset_report)
    imgs = re.findall(r'<img src="data:image/png;base64,([^"]+)"', page)
    assert len(imgs) == len(set(imgs)), "a figure is on the page twice"
    pos = {k: page.index(f'id="fig-{k}"') for k in (
        "forest", "wavelengths", "training", "data", "architecture_wearable",
        "forest_wearable")}
    assert pos["wavelengths"] < page.index('id="table"')  # beside the LED findings
    assert page.index('id="table"') < pos["forest"] < page.index('id="significance"')
    assert page.index('id="significance"') < pos["training"] < page.index('id="run"')
    assert page.index('id="run"') < pos["data"]
    assert "Run information" not in page
    assert "details.json, pre { display: none" in page  # no JSON in print


def test_headline_marks_physics_off_and_privileged_apart(preset_results):
    from nirglucose.report.figures import load_results
    from nirglucose.report.findings import run_data

    runs = [run_data(load_results(preset_results / p)) for p in ("paper", "wearable")]
    table, _ = headline_table(runs)
    lab = dict(zip(table["model"], table["label"], strict=False))
    assert lab["original-pinn"] == "Original PINN (physics off on paper)"
    assert set(table.loc[table["model"] == "physics-inversion", "status"]) == {"reference"}


def test_every_figure_of_a_preset_marks_its_physics_off_pinn(preset_results):
    from nirglucose.report.figures import load_results
    from nirglucose.report.figures.page import Page

    paper = Page(results=load_results(preset_results / "paper"), out_dir=None, formats=(),
                 wanted=set(), compare=None)
    wear = Page(results=load_results(preset_results / "wearable"), out_dir=None, formats=(),
                wanted=set(), compare=None)
    assert paper.label_overrides["original-pinn"] == "Original PINN (physics off)"
    assert "original-pinn" not in wear.label_overrides  # λ = 0.01 there
    assert paper.label_overrides["physics-inversion"].endswith("(reference)")


def test_three_presets_physical_with_fewer_models(tmp_path, preset_results):
    """The physical preset (×1, published magnitudes) with a smaller model set: its box
    says so and names the models that ran, its best deployable, oracle and no skill."""
    import shutil

    from report_fixtures import write_synthetic_results

    import nirglucose as ng
    from nirglucose.report.figures import load_results
    from nirglucose.report.findings import computed_findings
    from nirglucose.report.limits import limits_section

    root = tmp_path / "res"
    shutil.copytree(preset_results / "paper", root / "paper")
    d = write_synthetic_results(root / "physical", models=("ebl", "oracle", "mean",
                                                           "device-inversion"),
                                n_subjects=12, repeats=1, seed=2, with_optional=False)
    meta = json.loads((d / "metrics.json").read_text())["meta"]
    meta.update(preset="physical",
                config=json.loads(ng.simulate("physical", 2, 1, 0).config.to_json()))
    (d / "meta.json").write_text(json.dumps(meta))
    runs = [load_results(root / p) for p in ("paper", "physical")]
    data, findings, _ = computed_findings(runs, n_boot=200)
    html = limits_section(runs, data, findings)
    box = html[html.index('id="limits-physical"'):]
    box = box[:box.index("</div>")]
    assert "physical: published magnitudes" in box
    assert "×1 the published magnitudes (the published ones)" in box
    assert "Models that ran</b> (4)" in box and "Device inversion" in box
    assert "best deployable" in box and "oracle" in box and "no skill" in box
    assert "Physics inversion" not in box  # it did not run there
    assert "Does physics help on physical?" in html


def test_an_identical_figure_is_drawn_once(preset_results):
    """Two presets with the same environment draw the same picture: it is shown once,
    its caption says so, and the numbering does not skip."""
    from matplotlib.figure import Figure

    from nirglucose.report.figures import load_results
    from nirglucose.report.figures.page import Page, draw_pending

    def same():
        fig = Figure(figsize=(2, 2))
        fig.add_subplot().plot([0, 1], [0, 1])
        return fig

    page = Page(results=load_results(preset_results / "paper"), out_dir=None, formats=(),
                wanted=None, compare=None)
    page.add("environment", "Environment on paper", "Ambient conditions.", same)
    page.add("environment_wearable", "Environment on wearable", "Ambient conditions.", same)
    page.add("physiology", "Physiology", "Physiology.", lambda: Figure(figsize=(3, 2)))
    draw_pending(page)  # figures are drawn after every section numbered them
    assert [f.key for f in page.rendered] == ["environment", "physiology"]
    assert [f.number for f in page.rendered] == ["1", "2"]
    assert "The same figure for wearable" in page.rendered[0].caption


def test_every_table_row_of_a_pinn_at_lambda_zero_says_physics_off(preset_report):
    """Issue 39: a PINN tuned to λ = 0 is a plain network: the reproduced table and the
    further metrics of that preset, and the distances table (only where it is off), say
    so; the preset where it runs with physics does not."""
    import html
    import re

    text = html.unescape(preset_report.read_text())
    cells = re.findall(r"<td>([^<]*)</td>", text)
    off_rows = [c for c in cells if c.endswith("(physics off)")]
    assert off_rows, "no row says physics off"
    assert any(c.endswith("(physics off on paper)") for c in cells)  # the distances table
    wearable = text[text.index('id="extra-table-wearable"'):]
    wearable = wearable[:wearable.index("</table>")]
    assert "physics off" not in wearable


def test_each_preset_is_separated_from_the_primary(tmp_path):
    """Three presets: the findings say what separates the primary from each of the two
    others (before, only from the second)."""
    from report_fixtures import write_preset_results

    from nirglucose.report.figures import load_results
    from nirglucose.report.findings import computed_findings

    for k, (name, lam) in enumerate((("paper", 0.0), ("wearable", 0.01), ("physical", 0.01))):
        write_preset_results(tmp_path / name, name, lambda_phys=lam, seed=k)
    runs = [load_results(tmp_path / n) for n in ("paper", "wearable", "physical")]
    _, findings, _ = computed_findings(runs, n_boot=200)
    separated = [f.text() for f in findings if f.topic == "presets"]
    assert len(separated) == 2
    assert separated[0].startswith("What separates paper from wearable")
    assert separated[1].startswith("What separates paper from physical")


@pytest.mark.parametrize(("best", "says"), [(56.7, True), (42.5, False)])
def test_the_box_says_when_no_deployable_estimator_beats_the_mean(best, says):
    """Published magnitudes: the best deployable (56.7) is no better than the training
    mean (56.5), and the box says so in words; an amplified regime's (42.5) does not."""
    from nirglucose.report.limits import _box

    facts = {"preset": "physical", "gain": 1.0, "regime": "published magnitudes",
             "physiology": "measured", "privileged": {}, "subjects": 80, "snapshots": 240,
             "glucose": None, "models": ["Device inversion"], "best": "device-inversion",
             "best_rmse": best, "oracle_rmse": 52.9, "no_skill_rmse": 56.5}
    assert ("no deployable estimator beats the training mean" in _box(facts)) is says
