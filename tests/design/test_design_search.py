"""design.search: every LED subset ranked by the bound (batched = per-subset, monotone)."""

from __future__ import annotations

import itertools
import json

import numpy as np
import pytest

import nirglucose as ng
from nirglucose.design import design_terms
from nirglucose.design.search import (
    candidate_leds,
    drive_powers_mw,
    rank_designs,
    subset_bounds,
)
from nirglucose.exceptions import ConfigError

SMALL_NM = (850, 900, 940, 1000, 1050, 1100)


@pytest.fixture(scope="module")
def ranking():
    return rank_designs("wearable", SMALL_NM, ["BPW34"], k_max=4)


@pytest.mark.parametrize("detector, wl", [("BPW34", (850, 940, 1050)),
                                          ("G17190-010K", (940, 1150, 1300, 1550))])
def test_batched_bound_equals_the_per_subset_bound(detector, wl):
    leds = [{**c, "power_mw": 3.0} for c in candidate_leds(wl)]
    terms = design_terms("wearable", leds=leds, detector=detector)
    for k in (1, 2, len(wl)):
        subsets = np.array(list(itertools.combinations(range(len(wl)), k)))
        for cond in ("device", "oracle"):
            want = [terms.bound(s, condition=cond).rmse_mgdl for s in subsets]
            np.testing.assert_allclose(subset_bounds(terms, subsets, condition=cond), want,
                                       rtol=1e-9)


def test_a_superset_is_never_worse(ranking):
    bound = {tuple(r.split(",")): b for r, b in
             zip(ranking["wavelengths_nm"], ranking["bound_rmse_mgdl"], strict=True)}
    for design, b in bound.items():
        for sub in itertools.combinations(design, len(design) - 1):
            if sub:
                assert b <= bound[sub] * (1 + 1e-9), (design, sub)
    best = ranking.groupby("n_leds")["bound_rmse_mgdl"].min().to_numpy()
    assert np.all(np.diff(best) <= 1e-9)
    assert best[-1] < best[0]  # more LEDs help somewhere


def test_ranking_is_complete_sorted_and_deterministic(ranking):
    n = len(SMALL_NM)
    counts = ranking.groupby("n_leds").size()
    assert [counts[k] for k in (1, 2, 3, 4)] == [n, n * (n - 1) // 2,
                                                 n * (n - 1) * (n - 2) // 6, 15]
    for _, g in ranking.groupby("n_leds"):
        assert g["rank"].tolist() == list(range(1, len(g) + 1))
        assert g["bound_rmse_mgdl"].is_monotonic_increasing
    again = rank_designs("wearable", SMALL_NM, ["BPW34"], k_max=2, top=3)
    first = ranking[ranking["n_leds"] <= 2].groupby("n_leds").head(3).reset_index(drop=True)
    assert again["wavelengths_nm"].tolist() == first["wavelengths_nm"].tolist()
    # the oracle knows more than the device: its bound is never larger
    assert (ranking["oracle_bound_rmse_mgdl"] <= ranking["bound_rmse_mgdl"] + 1e-9).all()


def test_which_study_leds_a_design_keeps(ranking):
    for wl, kept, n in zip(ranking["wavelengths_nm"], ranking["study_leds_kept"],
                           ranking["n_study_leds_kept"], strict=True):
        mine = {float(w) for w in wl.split(",")}
        want = [w for w in (850.0, 940.0, 1050.0, 1150.0) if w in mine]
        assert n == len(want)
        assert kept == (",".join(f"{w:g}" for w in want) or "none")


def test_blind_candidates_are_excluded():
    r = rank_designs("wearable", [900, 1300, 1550], ["BPW34", "G17190-010K"], k_max=3)
    used = {d: [c["wavelength_nm"] for c in cs] for d, cs in r.attrs["candidates"].items()}
    assert used == {"BPW34": [900.0], "G17190-010K": [900.0, 1300.0, 1550.0]}
    assert set(r[r["detector"] == "BPW34"]["wavelengths_nm"]) == {"900"}
    with pytest.raises(ConfigError, match="sees none of the candidates"):
        rank_designs("wearable", [1300, 1550], ["BPW34"])


def test_the_power_rule_puts_the_median_reading_at_mid_scale():
    leds = candidate_leds([850, 1000])
    power = drive_powers_mw("wearable", leds, "BPW34")
    assert all(0 < p < 10 for p in power)  # below the cap here
    half = drive_powers_mw("wearable", leds, "BPW34", target_code_fraction=0.25)
    np.testing.assert_allclose(half, np.array(power) / 2, rtol=1e-12)
    assert drive_powers_mw("wearable", leds, "BPW34", max_power_mw=0.5) == [0.5, 0.5]
    # an independent check: a simulated data set's median code with those powers
    ds = ng.simulate("wearable", n_subjects=60, per_subject=3, seed=5,
                     leds=[{**c, "power_mw": p} for c, p in zip(leds, power, strict=True)],
                     detector="BPW34")
    full = 2**ds.config.hardware.adc_bits - 1
    for w in (850, 1000):
        med = float(np.median(ds.frame[f"adc_{w}"]))
        assert med == pytest.approx(full / 2, rel=0.1)


@pytest.mark.parametrize("kwargs, match", [
    ({"k_max": 0}, "k_max"),
    ({"detectors": ["NOPE"]}, "unknown detector"),
    ({"detectors": []}, "at least one detector"),
    ({"condition": "maybe"}, "condition"),
    ({"candidates": []}, "at least one candidate"),
    ({"candidates": [900, 900]}, "distinct"),
    ({"candidates": ["x"]}, "numbers in nm"),
    ({"overrides": {"detector": "BPW34"}}, "sets 'detector' itself"),
    ({"preset": "nope"}, "unknown preset"),
])
def test_bad_inputs_raise_one_clear_error(kwargs, match):
    with pytest.raises(ConfigError, match=match):
        rank_designs(**{"candidates": SMALL_NM[:2], "detectors": ["BPW34"], **kwargs})


def test_leds_column_is_a_usable_override(ranking):
    leds = json.loads(ranking.iloc[0]["leds"])
    cfg = ng.resolve_config("wearable", {"leds": leds, "detector": "BPW34"})
    assert list(cfg.leds.wavelengths_nm) == [float(w) for w in
                                             ranking.iloc[0]["wavelengths_nm"].split(",")]
