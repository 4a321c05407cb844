"""design.requirements: the least design really is least; bounds behave; answers exist."""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest

from nirglucose.config import resolve_config
from nirglucose.design import design_terms
from nirglucose.design.averaging import averaging_overrides
from nirglucose.design.exposure import max_led_power_mw
from nirglucose.design.levers import KNOWLEDGE, LEVERS
from nirglucose.design.requirements import (
    RELAX_ORDER,
    DesignEvaluator,
    candidate_records,
    least_design,
    lever_gains,
)
from nirglucose.design.state_bound import state_bound
from nirglucose.evaluation.sweep.confirmation import confirm_design
from nirglucose.evaluation.sweep.requirements import REQUIREMENTS_FILES, requirements_study
from nirglucose.exceptions import ConfigError

SMALL_NM = (800.0, 900.0, 1000.0, 1100.0)
TARGET = dict(target_rmse_mgdl=20.0, target_mard_pct=15.0)


@pytest.fixture(scope="module")
def ev():
    c = candidate_records("physical", "BPW34", SMALL_NM)
    return DesignEvaluator("physical", c, n_states=48, **TARGET)


@pytest.fixture(scope="module")
def least(ev):
    d, trace = least_design(ev)
    assert d is not None, trace
    return d


def test_candidates_are_sorted_capped_and_seen_by_the_detector(ev):
    c = ev.candidates
    wl = c.wavelengths_nm
    assert wl == sorted(wl)
    assert 1150.0 not in wl  # BPW34's table ends at 1,099 nm: blind at the study's 1150
    assert [wl[i] for i in c.study] == [850.0, 940.0, 1050.0]
    assert np.all(c.caps_mw <= max_led_power_mw(wl) + 1e-9)
    assert np.all([r["power_mw"] <= cap for r, cap in zip(c.records, c.caps_mw, strict=True)])


def test_the_ceiling_keeps_every_led_within_the_exposure_limits(ev):
    leds = ev.overrides(ev.ceiling())["leds"]
    for led in leds:
        assert led["power_mw"] <= float(max_led_power_mw(led["wavelength_nm"])) + 1e-9


def test_the_least_design_reaches_the_target_and_no_weaker_neighbour_does(ev, least):
    assert ev.feasible(ev.evaluate(least))
    weaker = [least.with_level(lv.name, least.level(lv.name) - 1)
              for lv in LEVERS if least.level(lv.name) > 0]
    weaker += [dataclasses.replace(least, leds=tuple(i for i in least.leds if i != j))
               for j in least.leds if len(least.leds) > 1]
    assert weaker  # the study's basic wearable does not reach it: something was needed
    for d in weaker:
        e = ev.evaluate(d)
        assert not ev.feasible(e), (d, e)
    assert not ev.feasible(ev.evaluate(ev.study()))


def test_better_precision_never_raises_the_bound(ev):
    # from today's errors to exact, one quantity at a time, at a capable design; the
    # prior is a regression on a 600-row pilot, so a quantity that carries no
    # information may wobble by its sampling noise (< 0.5 %)
    base = ev.ceiling().with_group("knowledge", top=False).with_level("adc_bits", 1)
    for k in KNOWLEDGE:
        name = f"knowledge:{k.name}"
        b = np.array([ev.evaluate(base.with_level(name, i)).state_rmse_mgdl
                      for i in range(len(next(x for x in LEVERS if x.name == name).values))])
        assert np.all(np.diff(b) <= 0.005 * b[:-1]), (name, b)
    hydration = [ev.evaluate(base.with_level("knowledge:hydration", i)).state_rmse_mgdl
                 for i in (0, 5)]
    assert hydration[1] < 0.8 * hydration[0]  # knowing hydration exactly helps here


def test_composed_terms_equal_a_direct_design_terms(ev, least):
    # the search reuses one pilot's Jacobians with another pilot's prior: the states do
    # not depend on the measurement errors, so this is exact
    ov = ev.overrides(least)
    direct = design_terms("physical", overrides=ov, n_states=48)
    cached = ev.terms(least)
    idx = list(least.leds)
    np.testing.assert_array_equal(direct.jacobian, cached.jacobian[:, idx, :])
    np.testing.assert_allclose(direct.nuisance_cov, ev.prior(least), rtol=1e-12)
    e = ev.evaluate(least.with_level("window_s", 0))
    assert e.state_rmse_mgdl == pytest.approx(state_bound(direct), rel=1e-8)


def test_averaging_in_the_bound_matches_its_simulator_emulation(ev, least):
    # N = 16 readings: noise / 16 in the bound; bandwidth / 16, flicker / 4, +2 bits
    d = least.with_level("capability:monitor_photodiode", 1).with_level("adc_bits", 1)
    ov = ev.overrides(d)
    cfg = resolve_config("physical", ov)
    emulated = design_terms("physical", overrides={**ov, **averaging_overrides(cfg, 16)},
                            n_states=48)
    terms = ev.terms(d)
    averaged = dataclasses.replace(terms, noise_var=terms.noise_var / 16)
    idx = list(d.leds)
    np.testing.assert_allclose(emulated.noise_var, averaged.noise_var[:, idx], rtol=2e-3)


def test_an_unreachable_target_names_the_shortfall_and_the_lever():
    c = candidate_records("physical", "BPW34", (800.0,))
    ev = DesignEvaluator("physical", c, n_states=32, target_rmse_mgdl=1e-4, target_mard_pct=1e-5)
    d, trace = least_design(ev)
    assert d is None and trace[0][0] == "ceiling"
    gains = lever_gains(ev)
    assert set(gains["lever"]) >= {"tissue knowledge", "averaging time", "LED power",
                                   "wavelengths", "ADC bits"}
    assert np.all(np.isfinite(gains["worth_at_ceiling_mgdl"]))


def test_relax_order_must_name_every_lever(ev):
    with pytest.raises(ConfigError, match="relax_order"):
        least_design(ev, RELAX_ORDER[:-1])
    with pytest.raises(ConfigError, match="target_rmse_mgdl"):
        DesignEvaluator("physical", ev.candidates, target_rmse_mgdl=-1)


def test_study_answers_one_line_per_detector_and_writes_its_files(tmp_path):
    res = requirements_study(detectors=("BPW34",), wavelengths_nm=(800.0, 1000.0), n_states=32,
                             confirm=False, **TARGET)
    lines = res.answer_lines()
    assert len(lines) == 1
    assert lines[0].startswith("[physical, glucose signal gain 1] Si (BPW34): ")
    assert ("reaches 20 mg/dL" in lines[0]) or ("no design in reach" in lines[0])
    row = res.minimal_designs.iloc[0]
    assert row["total_rmse_mgdl"] <= 20.0 if row["reached"] else row["shortfall_mgdl"] > 0
    assert set(res.averaging_curve["design"]) >= {"study's device", "BPW34: least"}
    res.to_dir(tmp_path / "req")
    assert sorted(p.name for p in (tmp_path / "req").iterdir()) == sorted(REQUIREMENTS_FILES)
    doc = json.loads((tmp_path / "req" / "requirements.json").read_text())
    assert doc["answer"] == lines and doc["meta"]["glucose_signal_gain"] == 1.0
    again = requirements_study(detectors=("BPW34",), wavelengths_nm=(800.0, 1000.0),
                               n_states=32, confirm=False, **TARGET)
    assert again.answer_lines() == lines  # deterministic


def test_confirm_design_simulates_the_averaged_design_and_scores_models():
    out = confirm_design("physical", {"device.monitor_photodiode": True}, 16, n_subjects=10,
                         per_subject=2, models=("mean", "ebl"), n_boot=50)
    assert sorted(out["model"]) == ["ebl", "mean"]
    assert (out["n_readings_emulated"] == 16).all() and (out["n_rows"] == 20).all()
    assert np.all(out["rmse_ci_low"] <= out["rmse_mgdl"])
    assert np.all(out["rmse_mgdl"] <= out["rmse_ci_high"])


def test_the_studys_own_device_line_names_the_tissue_knowledge_it_needs():
    res = requirements_study(detectors=(None,), n_states=32, confirm=False)
    (line,) = res.answer_lines()
    assert "the study's photodiode and four LEDs" in line
    row = res.minimal_designs.iloc[0]
    assert row["detector"] == "study" and row["n_leds"] <= 4
    if row["reached"]:  # four LEDs cannot infer eight nuisances: it must be told some
        assert "exact (no instrument)" in line or "no published instrument" in line


def test_the_studys_overrides_reach_every_design_the_bound_and_the_answer(ev):
    # water absorbing at the skin temperature (off in `physical`): one more nuisance in
    # every design's bound, and the regime named in the answer line
    on = {"noise.water_temperature.enabled": True}
    c = candidate_records("physical", "BPW34", SMALL_NM, overrides=on)
    ev_on = DesignEvaluator("physical", c, n_states=48, overrides=on, **TARGET)
    d = ev_on.study()
    assert ev_on.overrides(d)["noise.water_temperature.enabled"] is True
    assert ev_on.terms(d).jacobian.shape[-1] == ev.terms(d).jacobian.shape[-1] + 1
    res = requirements_study(detectors=("BPW34",), wavelengths_nm=(800.0, 1000.0), n_states=32,
                             confirm=False, overrides=on, **TARGET)
    (line,) = res.answer_lines()
    assert line.startswith("[physical, glucose signal gain 1, "
                           "noise.water_temperature.enabled=True] Si (BPW34): ")
    assert res.meta["overrides"] == on
    with pytest.raises(ConfigError, match="overrides"):
        requirements_study(detectors=("BPW34",), confirm=False, overrides={"noise.nope": 1})


def test_run_sweep_names_the_requirements_studys_own_entry_point():
    from nirglucose.evaluation.sweep.run import study_scenarios

    with pytest.raises(ConfigError, match="requirements_study"):
        study_scenarios("requirements")

# Long-running (whole studies, end-to-end runs, Monte Carlo or every model): `make test-slow`,
# which CI runs beside the fast `make test` (tests/test_slow_marks.py)
pytestmark = pytest.mark.slow
