"""The wavelengths sweep study: top designs by the bound, confirmed, tabled and drawn."""

from __future__ import annotations

import json

import pandas as pd
import pytest

from nirglucose.cli import main
from nirglucose.design import rank_designs
from nirglucose.evaluation.sweep.run import run_sweep
from nirglucose.evaluation.sweep.studies import STUDY_MODELS, resolve_scenarios
from nirglucose.exceptions import ConfigError
from nirglucose.report.sweep import sweep_figures, sweep_section

OPTIONS = {"detector": ["BPW34"], "n_leds": [1, 2]}
TINY = {"seeds": 1, "n_subjects": 16, "per_subject": 2, "n_splits": 2, "repeats": 1,
        "n_boot": 50, "jobs": 1}


def test_scenarios_are_the_best_designs_of_the_ranking():
    sc, preset = resolve_scenarios({**OPTIONS, "top_n": [2]}, "wavelengths", None, {})
    assert preset == "wearable"
    ranked = rank_designs("wearable", detectors=["BPW34"], k_max=2, top=2)
    assert [s.labels["wavelengths_nm"] for s in sc] == ranked["wavelengths_nm"].tolist()
    for s, (_, r) in zip(sc, ranked.iterrows(), strict=True):
        assert s.overrides == {"leds": json.loads(r["leds"]), "detector": "BPW34"}
        assert s.labels["bound_rmse_mgdl"] == pytest.approx(r["bound_rmse_mgdl"])
        assert s.preset == "wearable"
    assert STUDY_MODELS["wavelengths"] == ("oracle", "ebl", "gp")


@pytest.mark.slow  # make test-slow (CI runs it)
def test_study_runs_end_to_end_resumes_and_reports(tmp_path):
    out = tmp_path / "sweep"
    res = run_sweep(dict(OPTIONS), study="wavelengths", out=out, **TINY)
    e = pd.read_csv(out / "effects.csv")
    assert set(e["model"]) == {"oracle", "ebl", "gp"}
    assert sorted(e["n_leds"].unique()) == [1, 2]
    assert {"bound_rmse_mgdl", "oracle_bound_rmse_mgdl", "rmse_mgdl", "rmse_ci_low",
            "rmse_ci_high", "study_leds_kept"} <= set(e.columns)
    assert (e["rmse_ci_low"] <= e["rmse_mgdl"]).all()
    assert (e["rmse_mgdl"] <= e["rmse_ci_high"]).all()
    # the table's RMSE is the task's RMSE
    f = res.frame
    for _, r in e.iterrows():
        hit = f[(f["scenario"] == r["scenario"]) & (f["model"] == r["model"])]["rmse_mgdl"]
        assert r["rmse_mgdl"] == pytest.approx(float(hit.iloc[0]))
    again = run_sweep(dict(OPTIONS), study="wavelengths", out=out, **TINY)
    assert again.meta["tasks_computed"] == 0 and again.meta["tasks_cached"] == 6
    html = sweep_section(out)
    assert 'id="sweep-designs"' in html and 'id="fig-sweep_designs"' in html
    assert [f.name for f in sweep_figures(out)] == ["sweep_designs"]


@pytest.mark.parametrize("vary, base, match", [
    ({"noise_scale": [1]}, {}, "does not apply"),
    ({"top_n": [1, 2]}, {}, "one value"),
    ({"n_leds": [0]}, {}, "integers >= 1"),
    ({"detector": ["NOPE"]}, {}, "unknown detector"),
    ({}, {"leds": [{"wavelength_nm": 900}]}, "chooses leds itself"),
])
def test_bad_study_options(vary, base, match):
    with pytest.raises(ConfigError, match=match):
        resolve_scenarios(vary, "wavelengths", None, base)


def test_cli_bad_option_is_one_line(tmp_path, capsys):
    rc = main(["sweep", "--study", "wavelengths", "--vary", "detector=NOPE", "--seeds", "1",
               "--out", str(tmp_path / "s")])
    err = capsys.readouterr().err.strip()
    assert rc == 2 and len(err.splitlines()) == 1 and "unknown detector" in err


def _frame(rmse_by_seed):
    rows = []
    for seed, (oracle, ebl) in enumerate(rmse_by_seed):
        for model, v in (("oracle", oracle), ("ebl", ebl)):
            rows.append({"scenario": "BPW34:k=1:#1:900", "detector": "BPW34", "n_leds": 1,
                         "rank": 1, "wavelengths_nm": "900", "study_leds_kept": "none",
                         "bound_rmse_mgdl": 20.0, "oracle_bound_rmse_mgdl": 9.0,
                         "seed": seed, "model": model, "rmse_mgdl": v,
                         "rmse_ci_low": v - 1, "rmse_ci_high": v + 2})
    return pd.DataFrame(rows)


def test_design_table_interval_over_seeds_and_for_one_seed():
    from nirglucose.evaluation.sweep.wavelengths import wavelength_designs

    two = wavelength_designs(_frame([(10.0, 30.0), (12.0, 34.0)]))
    o = two[two["model"] == "oracle"].iloc[0]
    # mean 11, SD sqrt(2), n 2: half-width t(0.975, 1) x SD / sqrt(2) = 12.7062
    assert o["rmse_mgdl"] == pytest.approx(11.0)
    assert o["rmse_ci_high"] - 11.0 == pytest.approx(12.7062, abs=1e-4)
    assert o["ci"] == "t over seeds" and o["n_seeds"] == 2
    one = wavelength_designs(_frame([(10.0, 30.0)]))
    e = one[one["model"] == "ebl"].iloc[0]
    assert (e["rmse_ci_low"], e["rmse_mgdl"], e["rmse_ci_high"]) == (29.0, 30.0, 32.0)
    assert e["ci"] == "subject bootstrap"

