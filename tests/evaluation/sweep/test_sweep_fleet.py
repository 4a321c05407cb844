"""The fleet study: unseen units, factory reference, same-unit baseline (issue 30)."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from nirglucose.evaluation.sweep.fleet import (
    FLEET_DEFAULTS,
    FLEET_VARIANTS,
    fleet_metrics,
    fleet_table,
)
from nirglucose.evaluation.sweep.run import run_sweep, study_scenarios
from nirglucose.evaluation.sweep.studies import resolve_scenarios
from nirglucose.exceptions import ConfigError

#: A small fleet: 3 training units, 2 test units, 60 training subjects.
_FLEET = {**FLEET_DEFAULTS, "n_train_units": 3, "n_test_units": 2,
          "test_subjects_per_unit": 20}


def _rmse(scale, variant, model="ebl", seed=0, **fleet):
    spec = {"preset": "paper", "overrides": {}, "n_subjects": 60, "per_subject": 3,
            "seed": seed, "model": model, "model_params": {}, "n_boot": 20,
            "fleet": {**_FLEET, **fleet, "tolerance_scale": scale, "variant": variant}}
    return fleet_metrics(spec)["rmse_mgdl"]


def test_identical_units_make_unseen_equal_to_same_unit():
    same = np.mean([_rmse(0.0, "same-unit", seed=s) for s in (0, 1)])
    unseen = np.mean([_rmse(0.0, "no-transfer", seed=s) for s in (0, 1)])
    # same distribution of training data: only the draw of training subjects differs
    assert unseen == pytest.approx(same, rel=0.2)
    # and identical units need no transfer: the fitted map is the identity
    assert _rmse(0.0, "slope-bias") == pytest.approx(_rmse(0.0, "no-transfer"), rel=1e-6)


def test_wide_tolerance_hurts_and_the_factory_reference_recovers_most():
    same = _rmse(2.0, "same-unit")
    none = _rmse(2.0, "no-transfer")
    sb = _rmse(2.0, "slope-bias")
    assert none > 2 * same  # unseen units cost accuracy without transfer
    recovered = (none - sb) / (none - same)
    assert recovered > 0.5, (same, none, sb)
    assert _rmse(2.0, "bias") < none


def test_scenarios_and_vary():
    sc = study_scenarios("fleet")
    assert {s.labels["variant"] for s in sc} == set(FLEET_VARIANTS)
    assert all(s.kind == "fleet" for s in sc)
    sc, preset = resolve_scenarios({"tolerance_scale": [0, 1]}, "fleet", None, {})
    assert preset == "paper" and len(sc) == 2 * len(FLEET_VARIANTS)
    with pytest.raises(ConfigError, match="tolerance_scale"):
        resolve_scenarios({"noise_scale": [1]}, "fleet", None, {})
    with pytest.raises(ConfigError, match="0-2.4"):
        study_scenarios("fleet", [0, 7])


@pytest.mark.parametrize(
    ("change", "match"),
    [
        ({"variant": "pds"}, "fleet variant"),
        ({"transfer_subjects": 1}, "at least 2"),
        ({"n_test_units": 0}, "positive integer"),
        ({"n_train_units": 40}, "--subjects"),
    ],
)
def test_bad_fleet_settings_raise_one_line(change, match):
    with pytest.raises(ConfigError, match=match) as err:
        _rmse(1.0, change.pop("variant", "no-transfer"), **change)
    assert "\n" not in str(err.value)


def test_sweep_runs_resumes_and_writes_the_table(tmp_path):
    kw = {"study": "fleet", "seeds": 1, "models": ["ebl"], "n_subjects": 30,
          "n_boot": 20, "jobs": 1, "out": tmp_path / "s"}
    res = run_sweep({"tolerance_scale": [0, 1]}, **kw)
    table = res.effects
    assert list(table.columns[:3]) == ["tolerance_scale", "variant", "model"]
    assert len(table) == 2 * len(FLEET_VARIANTS)
    assert (table["variant"].tolist()[:4]) == list(FLEET_VARIANTS)
    assert (tmp_path / "s" / "effects.csv").exists()
    again = run_sweep({"tolerance_scale": [0, 1]}, **kw)
    assert again.meta["tasks_computed"] == 0
    pd.testing.assert_frame_equal(again.effects, table)


def test_fleet_table_interval_over_seeds():
    f = pd.DataFrame({"tolerance_scale": [1.0] * 4, "variant": ["same-unit"] * 2 + ["bias"] * 2,
                      "model": ["ebl"] * 4, "seed": [0, 1, 0, 1],
                      "rmse_mgdl": [10.0, 12.0, 20.0, 30.0]})
    t = fleet_table(f)
    r = t[t["variant"] == "bias"].iloc[0]
    # mean 25, SD 7.071, t(0.975, 1) = 12.706: half-width 63.53
    assert r["rmse_mgdl"] == 25.0
    assert r["rmse_ci_high"] == pytest.approx(25 + 12.7062 * 5.0, rel=1e-4)
    assert r["rmse_vs_same_unit"] == pytest.approx(25 / 11)

# Long-running (whole studies, end-to-end runs, Monte Carlo or every model): `make test-slow`,
# which CI runs beside the fast `make test` (tests/test_slow_marks.py)
pytestmark = pytest.mark.slow
