"""The sweep section of the report: an HTML fragment with tables and embedded figures."""

from __future__ import annotations

import pandas as pd
import pytest

from nirglucose.config import NOISE_SOURCES
from nirglucose.evaluation.sweep.run import SweepResult, ablation_effects, summarize_sweep
from nirglucose.exceptions import DataError
from nirglucose.report.sweep import save_sweep_figures, sweep_figures, sweep_section

SOURCES = NOISE_SOURCES[:4]  # a few sources keep the figure quick to render


def _meta(study, varied, labels, scenarios):
    return {"study": study, "varied": varied, "label_columns": labels, "scenarios": scenarios,
            "seeds": [0, 1], "models": ["ebl", "pls"], "preset": "paper", "n_subjects": 80,
            "per_subject": 3, "protocol": "grouped-cv", "n_splits": 5, "repeats": 3,
            "version": "test", "base_overrides": {"hardware.adc_bits": 14}}


@pytest.fixture
def grid_dir(tmp_path):
    rows = [{"study": "noise-scale", "scenario": f"noise_scale={x:g}", "noise_scale": x,
             "seed": s, "model": m, "rmse_mgdl": b * x + s, "mard_pct": b * x / 2 + s,
             "clarke_a_pct": 90.0, "within15_pct": 80.0, "bias_mgdl": 0.0,
             "rmse_vs_oracle": float("nan")}
            for x in (0.5, 1.0, 2.0) for s in (0, 1) for m, b in (("ebl", 10.0), ("pls", 20.0))]
    f = pd.DataFrame(rows)
    meta = _meta("noise-scale", ["noise_scale"], ["noise_scale"], list(f["scenario"].unique()))
    SweepResult(f, summarize_sweep(f, ["noise_scale"]), None, meta).save(tmp_path / "grid")
    return tmp_path / "grid"


@pytest.fixture
def ablation_dir(tmp_path):
    rows = []
    for s in (0, 1):
        for m in ("ebl", "pls"):
            rmse = {"all-on": 30.0 + s, "all-off": 10.0 + s}
            for k, src in enumerate(SOURCES):
                rmse[f"off:{src}"] = 30.0 + s - k
                rmse[f"only:{src}"] = 10.0 + s + k
            rows += [{"scenario": sc, "ablation": sc.split(":")[0], "seed": s, "model": m,
                      "rmse_mgdl": v, "mard_pct": v / 2, "clarke_a_pct": 90.0}
                     for sc, v in rmse.items()]
    f = pd.DataFrame(rows)
    meta = _meta("ablation", [], ["ablation"], list(f["scenario"].unique()))
    SweepResult(f, summarize_sweep(f, ["ablation"]), ablation_effects(f), meta).save(
        tmp_path / "abl")
    return tmp_path / "abl"


def test_grid_section(grid_dir):
    html = sweep_section(grid_dir)
    assert html.startswith('<section id="sweep">') and html.rstrip().endswith("</section>")
    assert html.count("data:image/png;base64,") == 2
    assert 'id="sweep-crossing"' in html and 'id="sweep-summary"' in html
    assert "hardware.adc_bits=14" in html
    assert "<script" not in html


def test_ablation_section_and_files(ablation_dir):
    html = sweep_section(ablation_dir)
    assert 'id="sweep-ablation"' in html and html.count("data:image/png") == 1
    table = html[html.index('id="sweep-ablation"'):]
    assert table.index(SOURCES[-1]) < table.index(SOURCES[0])  # costliest first
    assert [f.name for f in sweep_figures(ablation_dir)] == ["sweep_ablation"]
    paths = save_sweep_figures(ablation_dir, formats=("png",))
    assert [p.name for p in paths] == ["sweep_ablation.png"] and paths[0].stat().st_size > 0


def test_not_a_sweep_dir(tmp_path):
    with pytest.raises(DataError, match="not a sweep directory"):
        sweep_section(tmp_path)


def test_build_report_includes_sweep_sections(synthetic_results, grid_dir, tmp_path):
    from nirglucose.report import build_report

    out = build_report(synthetic_results, tmp_path / "r.html", sweep_dirs=[grid_dir])
    page = out.read_text()
    assert page.count('<section id="sweep">') == 1
    # after the provenance and its figures (each figure sits beside its text, issue 39)
    assert page.index('id="figs-data"') < page.index('<section id="sweep">')


def test_cli_report_rejects_a_missing_sweep_dir(synthetic_results, tmp_path, capsys):
    from nirglucose.cli import main

    code = main(["report", str(synthetic_results), "--out", str(tmp_path / "r.html"),
                 "--sweep", str(tmp_path / "nope")])
    assert code == 2 and "holds no sweep.csv" in capsys.readouterr().err


def test_mismatch_section_states_regime_seeds_and_privileged_rows(tmp_path):
    from nirglucose.evaluation.sweep.analysis import mismatch_table

    rows = []
    for s in (0, 1, 2):
        for made in ("beer-lambert", "diffusion"):
            for assumed in ("beer-lambert", "diffusion"):
                sc = f"data={made}:assumed={assumed}"
                for m, v in (("physics-inversion", 3.0 if made == assumed else 30.0),
                             ("device-inversion", 8.0 if made == assumed else 35.0),
                             ("ebl", 40.0 + s), ("mean", 57.0), ("oracle", 1.0)):
                    rows.append({"study": "mismatch", "scenario": sc, "data_model": made,
                                 "assumed_model": assumed, "mismatched": made != assumed,
                                 "seed": s, "model": m, "rmse_mgdl": v + s,
                                 "rmse_ci_low": v + s - 5, "rmse_ci_high": v + s + 5,
                                 "mard_pct": v / 2, "clarke_a_pct": 90.0})
    f = pd.DataFrame(rows)
    labels = ["data_model", "assumed_model", "mismatched"]
    meta = {**_meta("mismatch", [], labels, list(f["scenario"].unique())), "seeds": [0, 1, 2],
            "tuning": {"ebl": "re-tuned per dataset: ridge penalty by inner CV"}}
    e = mismatch_table(f, ["physics-inversion", "device-inversion"])
    SweepResult(f, summarize_sweep(f, labels), e, meta).save(tmp_path / "mm")
    html = sweep_section(tmp_path / "mm")
    start = html.index('id="sweep-mismatch"')
    table = html[start:html.index("</table>", start)]
    assert "amplified ×11" in html and "3 simulated datasets (seeds)" in html
    assert "re-tuned per dataset" in html
    # the privileged rows are marked as references, the deployable one is not
    assert table.count("(privileged reference)") == 2 * 2 + 2  # the inversion's, the oracle's
    assert "Device inversion (published tables) assuming <code>diffusion</code></td>" in table
    assert "best re-tuned deployable reference" in html and "best model" not in html.lower()

# Long-running (whole studies, end-to-end runs, Monte Carlo or every model): `make test-slow`,
# which CI runs beside the fast `make test` (tests/test_slow_marks.py)
pytestmark = pytest.mark.slow
