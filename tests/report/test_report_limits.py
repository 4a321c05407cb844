"""Issue 39: what the report's results rest on (privileged rows apart, the (n.s.) flag,
the limits box, the physics terms measured, the reader's fixes).

Fast: small synthetic predictions, no benchmark run; the page-level checks use the
session's two-preset report (``preset_report``)."""

from __future__ import annotations

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
