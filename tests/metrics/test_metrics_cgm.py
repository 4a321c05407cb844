"""Standards of a worn monitor (metrics/cgm.py), each against a worked example.

Where the source has no numeric example the expected value is computed by hand in the
test from the published definition, on a small independent dataset (said at each test).
The lower bound of an agreement rate is checked against Newcombe (1998), Table II
(continuity-corrected Wilson, method 4), which the clustered bound of Short et al. (2020)
reduces to when every subject has one reading.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from nirglucose.exceptions import DataError
from nirglucose.metrics import (
    ICGM_CRITERIA,
    TIME_IN_RANGE_TARGETS_PCT,
    agreement_rates,
    estimated_lag,
    icgm_criteria,
    mard_by_day,
    mard_by_range,
    rate_of_change,
    time_in_range_agreement,
    time_in_ranges,
    trend_agreement,
)

# --- MARD -------------------------------------------------------------------------------


def test_mard_by_range_hand_computed() -> None:
    # Hand-computed from MARD = mean |p - r| / r x 100, ranges by the reference:
    # < 70: |66-60|/60 = 10 %, |45-50|/50 = 10 %           -> 10 %
    # 70-180: |77-70|/70 = 10 %, |153-180|/180 = 15 %      -> 12.5 %  (70, 180 included)
    # > 180: |200-250|/250 = 20 %                          -> 20 %
    # overall: (10 + 10 + 10 + 15 + 20) / 5                 -> 13 %
    ref = [60, 50, 70, 180, 250]
    pred = [66, 45, 77, 153, 200]
    t = mard_by_range(ref, pred)
    assert t["range"].tolist() == ["<70", "70-180", ">180", "overall"]
    assert t["n_readings"].tolist() == [2, 2, 1, 5]
    np.testing.assert_allclose(t["mard_pct"], [10.0, 12.5, 20.0, 13.0])


def test_mard_by_range_empty_range_is_nan() -> None:
    t = mard_by_range([100.0, 120.0], [110.0, 120.0])
    assert t.loc[0, "n_readings"] == 0 and np.isnan(t.loc[0, "mard_pct"])
    assert t.loc[3, "mard_pct"] == pytest.approx(5.0)


def test_mard_by_day_hand_computed() -> None:
    # day 2: 10 %, 30 %; day 1: 5 % (unsorted input, sorted output)
    t = mard_by_day([100, 100, 200], [110, 70, 210], [2, 2, 1])
    assert t["day"].tolist() == [1, 2]
    np.testing.assert_allclose(t["mard_pct"], [5.0, 20.0])
    assert t["n_readings"].tolist() == [1, 2]


def test_mard_by_day_rejects_bad_day() -> None:
    with pytest.raises(DataError, match="day has 1 values"):
        mard_by_day([100, 100], [100, 100], [1])
    with pytest.raises(DataError, match="day contains NaN"):
        mard_by_day([100, 100], [100, 100], [1.0, np.nan])


# --- agreement rates ---------------------------------------------------------------------


def _independent(n_hit: int, n: int, ref: float = 100.0):
    """n readings at ``ref`` (70-180 range), n_hit within 15 %, each its own subject."""
    pred = np.where(np.arange(n) < n_hit, ref, 1.5 * ref)
    return np.full(n, ref), pred, np.arange(n)


@pytest.mark.parametrize(
    ("n_hit", "n", "newcombe_lower"),
    # Newcombe RG, Stat Med 17:857-872, 1998, Table II, method 4 (score with
    # continuity correction), 95 % two-sided lower limits.
    [(81, 263, 0.2535), (15, 148, 0.0598), (1, 29, 0.0018)],
)
def test_wilson_bound_reproduces_newcombe_table(n_hit, n, newcombe_lower) -> None:
    ref, pred, subj = _independent(n_hit, n)
    # A two-sided 95 % limit is a one-sided 97.5 % bound.
    t = agreement_rates(ref, pred, subj, method="wilson", confidence=0.975)
    row = t[(t["range"] == "70-180") & (t["limit"] == "15 %")].iloc[0]
    assert row["estimate_pct"] == pytest.approx(100.0 * n_hit / n)
    assert row["lower_bound_pct"] == pytest.approx(100.0 * newcombe_lower, abs=0.006)
    assert row["n_readings"] == n and row["n_subjects"] == n


def test_clustered_wilson_hand_computed() -> None:
    # Three subjects with 4 readings each at 100 mg/dL; hits 4, 2, 0 within 15 %.
    # Short et al. 2020: M = 12, p = 6/12 = 0.5, sum x^2/m = (16 + 4 + 0)/4 = 5,
    # BMS = (5 - 36/12) / 2 = 1, WMS = (6 - 5) / 9 = 1/9, n* = (144 - 48) / (2 * 12) = 4,
    # rho = (1 - 1/9) / (1 + 3/9) = 2/3, design effect xi = 1 + rho (48 - 12)/12 = 3.
    m_big, p, xi, z = 12.0, 0.5, 3.0, 1.6448536269514722
    root = np.sqrt(xi * z * z - 2 - 1 / m_big + 4 * p * (m_big * (1 - p) + 1))
    expected = (2 * m_big * p + xi * z * z - 1 - np.sqrt(xi) * z * root) / (
        2 * (m_big + xi * z * z))
    hits = [1, 1, 1, 1, 1, 1, 0, 0, 0, 0, 0, 0]
    ref = np.full(12, 100.0)
    pred = np.where(np.array(hits) == 1, 100.0, 150.0)
    subj = np.repeat(["a", "b", "c"], 4)
    t = agreement_rates(ref, pred, subj, method="wilson")
    row = t[(t["range"] == "70-180") & (t["limit"] == "15 %")].iloc[0]
    assert row["lower_bound_pct"] == pytest.approx(100.0 * expected, rel=1e-12)
    # Clustering widens the bound: the same readings as 12 independent subjects.
    alone = agreement_rates(ref, pred, np.arange(12), method="wilson")
    assert alone.loc[1, "lower_bound_pct"] > row["lower_bound_pct"] + 5.0


def test_agreement_ranges_and_limits_hand_computed() -> None:
    # Ranges by the device reading (iCGM convention); < 70 in mg/dL, others in %.
    ref = [60, 60, 100, 100, 200, 300]
    pred = [50, 40, 114, 150, 260, 150]
    subj = [1, 1, 2, 2, 3, 3]
    t = agreement_rates(ref, pred, subj, method="wilson").set_index(["range", "limit"])
    # < 70 by device: (60, 50) |d| = 10 <= 15; (60, 40) |d| = 20 > 15 but <= 20.
    assert t.loc[("<70", "15 mg/dL"), "estimate_pct"] == 50.0
    assert t.loc[("<70", "20 mg/dL"), "estimate_pct"] == 100.0
    # 70-180 by device: (100, 114) 14 %, (100, 150) 50 %, (300, 150) 50 %.
    assert t.loc[("70-180", "15 %"), "n_readings"] == 3
    assert t.loc[("70-180", "15 %"), "estimate_pct"] == pytest.approx(100.0 / 3)
    assert t.loc[("70-180", "40 %"), "estimate_pct"] == pytest.approx(100.0 / 3)
    # > 180 by device: (200, 260) 30 %.
    assert t.loc[(">180", "40 %"), "estimate_pct"] == 100.0
    # overall uses % everywhere: 10/60 = 16.7 %, 20/60 = 33 %, 14 %, 50 %, 30 %, 50 %.
    assert t.loc[("overall", "20 %"), "estimate_pct"] == pytest.approx(200.0 / 6)
    by_ref = agreement_rates(ref, pred, subj, range_by="reference", method="wilson")
    by_ref = by_ref.set_index(["range", "limit"])
    assert by_ref.loc[(">180", "15 %"), "n_readings"] == 2  # 200 and 300 by reference


def test_bootstrap_bound_is_seeded_and_below_the_estimate() -> None:
    rng = np.random.default_rng(0)
    subj = np.repeat(np.arange(20), 15)
    ref = rng.uniform(80.0, 170.0, subj.size)
    pred = ref * (1 + rng.normal(0, 0.1, 20)[subj] + rng.normal(0, 0.06, subj.size))
    a = agreement_rates(ref, pred, subj, n_boot=2000, seed=3)
    b = agreement_rates(ref, pred, subj, n_boot=2000, seed=3)
    pd.testing.assert_frame_equal(a, b)
    ok = a["n_readings"] > 0
    assert (a.loc[ok, "lower_bound_pct"] <= a.loc[ok, "estimate_pct"]).all()
    # Clustered data: the subject bootstrap is wider than treating readings as independent.
    alone = agreement_rates(ref, pred, np.arange(subj.size), n_boot=2000, seed=3)
    row = (a["range"] == "70-180") & (a["limit"] == "15 %")
    assert a.loc[row, "lower_bound_pct"].item() < alone.loc[row, "lower_bound_pct"].item()


def test_bootstrap_agrees_with_wilson_for_independent_readings() -> None:
    ref, pred, subj = _independent(170, 200)
    boot = agreement_rates(ref, pred, subj, n_boot=4000, seed=1)
    wil = agreement_rates(ref, pred, subj, method="wilson")
    assert boot.loc[1, "lower_bound_pct"] == pytest.approx(wil.loc[1, "lower_bound_pct"], abs=1.0)


def test_bootstrap_falls_back_to_wilson_when_the_rate_is_100_pct() -> None:
    # 29/29 readings of one subject: no bootstrap spread, so the continuity-corrected
    # Wilson bound of 29 independent readings (Newcombe 1998, method 4; p = 1):
    # (2n + z^2 - 1 - z sqrt(z^2 - 2 - 1/n + 4)) / (2 (n + z^2)), z = 1.96.
    n, z = 29.0, 1.959963984540054
    expected = (2 * n + z * z - 1 - z * np.sqrt(z * z - 2 - 1 / n + 4)) / (2 * (n + z * z))
    ref = np.full(29, 100.0)
    boot = agreement_rates(ref, ref, np.zeros(29), n_boot=500, confidence=0.975)
    assert boot.loc[1, "lower_bound_pct"] == pytest.approx(100.0 * expected, rel=1e-12)
    assert 80.0 < boot.loc[1, "lower_bound_pct"] < 90.0
    # The Wilson method counts each subject once at 100 % (rho = 1): wider.
    subj = np.repeat([0, 1, 2], [10, 10, 9])
    wil = agreement_rates(ref, ref, subj, method="wilson", confidence=0.975)
    assert wil.loc[1, "lower_bound_pct"] < 50.0


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"method": "exact"}, "method must be one of"),
        ({"range_by": "both"}, "range_by must be"),
        ({"n_boot": 10}, "n_boot must be"),
        ({"confidence": 1.5}, "confidence must lie"),
    ],
)
def test_agreement_rejects_bad_options(kwargs, match) -> None:
    with pytest.raises(DataError, match=match):
        agreement_rates([100, 110], [100, 110], [1, 2], **kwargs)


def test_agreement_rejects_bad_subjects() -> None:
    with pytest.raises(DataError, match="subject_id has 1 values"):
        agreement_rates([100, 110], [100, 110], [1])
    with pytest.raises(DataError, match="subject_id contains missing"):
        agreement_rates([100, 110], [100, 110], np.array(["a", None], dtype=object))


# --- iCGM criteria -------------------------------------------------------------------------


def test_icgm_thresholds_are_those_of_the_special_controls() -> None:
    got = {k: (c.range, c.limit, c.required_pct) for k, c in ICGM_CRITERIA.items()}
    assert got == {
        "A": ("<70", "15 mg/dL", 85.0), "B": ("70-180", "15 %", 70.0),
        "C": (">180", "15 %", 80.0), "D": ("<70", "40 mg/dL", 98.0),
        "E": ("70-180", "40 %", 99.0), "F": (">180", "40 %", 99.0),
        "G": ("overall", "20 %", 87.0),
    }


def test_icgm_criteria_table_and_verdicts() -> None:
    # 40 subjects x 60 readings of an accurate device across the range passes A-G;
    # one gross crossing (device 60, reference 250) fails H only.
    rng = np.random.default_rng(5)
    subj = np.repeat(np.arange(40), 60)
    ref = rng.uniform(45.0, 380.0, subj.size)
    pred = ref * (1 + rng.normal(0, 0.02, subj.size))
    t = icgm_criteria(ref, pred, subj, n_boot=1000, seed=0)
    assert t["criterion"].tolist() == list("ABCDEFGHI")
    assert list(t.columns) == ["criterion", "range", "limit", "estimate_pct",
                               "lower_bound_pct", "n_readings", "n_subjects", "required",
                               "passes"]
    assert t["passes"].all()
    assert (t["n_subjects"].iloc[:7] == 40).all()
    ref[0], pred[0] = 250.0, 60.0
    t = icgm_criteria(ref, pred, subj, n_boot=1000, seed=0).set_index("criterion")
    assert not t.loc["H", "passes"] and t.loc["H", "estimate_pct"] == 1.0
    assert t.loc["I", "passes"]


def test_icgm_fails_a_criterion_without_data_and_below_threshold() -> None:
    # Only euglycaemic readings: A, C, D, F have no data and are not met.
    ref = np.full(8, 100.0)
    pred = np.array([100, 100, 100, 100, 150, 150, 150, 150], dtype=float)
    t = icgm_criteria(ref, pred, np.arange(8), method="wilson").set_index("criterion")
    for letter in "ACDF":
        assert not t.loc[letter, "passes"] and t.loc[letter, "n_readings"] == 0
    assert t.loc["B", "estimate_pct"] == 50.0 and not t.loc["B", "passes"]


# --- rate of change and trend accuracy -------------------------------------------------------


def test_rate_of_change_per_subject_in_time_order() -> None:
    # subject 1 at t = 0, 5, 15 (given out of order); subject 2 at t = 0, 10.
    g = [90, 100, 110, 50, 80]
    s = [1, 1, 1, 2, 2]
    t = [15, 0, 5, 10, 0]
    got = rate_of_change(g, s, t)
    np.testing.assert_allclose(got, [-2.0, np.nan, 2.0, -3.0, np.nan])


def test_rate_of_change_max_gap_drops_rates_across_dropouts() -> None:
    got = rate_of_change([100, 110, 130, 140], [1, 1, 1, 1], [0, 5, 60, 65], max_gap_min=15)
    np.testing.assert_allclose(got, [np.nan, 2.0, np.nan, 2.0])
    with pytest.raises(DataError, match="max_gap_min must be"):
        rate_of_change([100, 110], [1, 1], [0, 5], max_gap_min=0)


def test_mixed_subject_id_types_are_one_clear_error() -> None:
    with pytest.raises(DataError, match="subject_id values must be of one sortable type"):
        time_in_ranges([100, 110], np.array([1, "a"], dtype=object))


def test_rate_of_change_rejects_repeated_time() -> None:
    with pytest.raises(DataError, match="time_min repeats within a subject"):
        rate_of_change([100, 110], [1, 1], [0, 0])


def test_trend_agreement_hand_computed_matrix() -> None:
    # Reference rates (mg/dL/min): +3, -0.5, -1.5; device rates: +2.5, +1.5, -1.5.
    ref = [100, 115, 112.5, 105]
    dev = [100, 112.5, 120, 112.5]
    r = trend_agreement(ref, dev, [7, 7, 7, 7], [0, 5, 10, 15])
    assert r.n_pairs == 3
    assert r.agreement_pct == pytest.approx(200.0 / 3)
    m = r.matrix
    assert m.index.tolist() == ["<-2", "-2..-1", "-1..1", "1..2", ">2"]
    assert m.loc[">2", ">2"] == 1 and m.loc["-1..1", "1..2"] == 1
    assert m.loc["-2..-1", "-2..-1"] == 1 and int(m.to_numpy().sum()) == 3


def test_trend_agreement_custom_edges_and_errors() -> None:
    r = trend_agreement([100, 110, 120], [100, 104, 120], [1, 1, 1], [0, 5, 10],
                        edges_mgdl_per_min=(0.0,))
    assert r.matrix.shape == (2, 2) and r.agreement_pct == 100.0
    with pytest.raises(DataError, match="strictly increasing"):
        trend_agreement([100, 110], [100, 110], [1, 1], [0, 5], edges_mgdl_per_min=(1.0, 1.0))
    with pytest.raises(DataError, match="no subject has two readings"):
        trend_agreement([100, 110], [100, 110], [1, 2], [0, 5])


# --- lag ----------------------------------------------------------------------------------


def test_estimated_lag_recovers_known_delays() -> None:
    t = np.arange(0.0, 600.0, 5.0)
    ref = 140 + 50 * np.sin(2 * np.pi * t / 240)
    ref2 = 120 + 30 * np.sin(2 * np.pi * t / 180 + 1.0)
    dev = 140 + 50 * np.sin(2 * np.pi * (t - 10) / 240)   # 10 min behind
    dev2 = 120 + 30 * np.sin(2 * np.pi * (t - 15) / 180 + 1.0)  # 15 min behind
    res = estimated_lag(np.r_[ref, ref2], np.r_[dev, dev2],
                        np.r_[np.zeros(t.size), np.ones(t.size)], np.r_[t, t])
    np.testing.assert_allclose(res.per_subject["lag_min"], [10.0, 15.0], atol=0.05)
    assert res.median_min == pytest.approx(12.5, abs=0.05)
    # percentiles of two values, linear interpolation: 11.25 and 13.75
    assert (res.q25_min, res.q75_min) == pytest.approx((11.25, 13.75), abs=0.05)
    # A device ahead of the reference gives a negative lag.
    ahead = estimated_lag(ref, 140 + 50 * np.sin(2 * np.pi * (t + 5) / 240),
                          np.zeros(t.size), t)
    assert ahead.median_min == pytest.approx(-5.0, abs=0.05)


def test_estimated_lag_resolves_below_the_sampling_interval() -> None:
    # An 8 min delay sampled every 5 min: the parabolic peak lands near 8, not 5 or 10.
    t = np.arange(0.0, 1440.0, 5.0)
    ref = 140 + 50 * np.sin(2 * np.pi * t / 240) + 20 * np.sin(2 * np.pi * t / 97)
    dev = 140 + 50 * np.sin(2 * np.pi * (t - 8) / 240) + 20 * np.sin(2 * np.pi * (t - 8) / 97)
    assert estimated_lag(ref, dev, np.zeros(t.size), t).median_min == pytest.approx(8.0, abs=0.5)


def test_estimated_lag_errors() -> None:
    with pytest.raises(DataError, match="not uniformly spaced"):
        estimated_lag([100, 110, 120, 130], [100, 110, 120, 130], [1] * 4, [0, 5, 10, 20])
    with pytest.raises(DataError, match="max_lag_min must be positive"):
        estimated_lag([100, 110, 120], [100, 110, 120], [1] * 3, [0, 5, 10], max_lag_min=0)


# --- time in ranges -------------------------------------------------------------------------


def test_time_in_ranges_edges_hand_computed() -> None:
    # Battelino et al. 2019: TBR < 54 and < 70; TIR 70-180 inclusive; TAR > 180, > 250.
    g = [50, 54, 69, 70, 180, 181, 250, 251, 100, 100]
    t = time_in_ranges(g, ["x"] * 10).iloc[0]
    assert t["n_readings"] == 10
    assert t["tbr_lt54_pct"] == 10.0       # 50
    assert t["tbr_lt70_pct"] == 30.0       # 50, 54, 69
    assert t["tir_70_180_pct"] == 40.0     # 70, 180, 100, 100
    assert t["tar_gt180_pct"] == 30.0      # 181, 250, 251
    assert t["tar_gt250_pct"] == 10.0      # 251


def test_time_in_range_agreement_targets() -> None:
    assert TIME_IN_RANGE_TARGETS_PCT["tir_70_180_pct"] == (">", 70.0)
    assert TIME_IN_RANGE_TARGETS_PCT["tbr_lt70_pct"] == ("<", 4.0)
    ref = [100, 120, 150, 200, 60, 100, 100, 100]
    pred = [100, 120, 150, 170, 75, 100, 100, 100]
    t = time_in_range_agreement(ref, pred, [1, 1, 1, 1, 2, 2, 2, 2])
    tir = t[t["metric"] == "tir_70_180_pct"].set_index("subject_id")
    assert tir.loc[1, "reference_pct"] == 75.0 and tir.loc[1, "predicted_pct"] == 100.0
    assert tir.loc[1, "difference_pct"] == 25.0
    assert tir.loc[1, "reference_meets"] and tir.loc[1, "predicted_meets"]
    tbr = t[t["metric"] == "tbr_lt70_pct"].set_index("subject_id")
    # subject 2: reference 25 % below 70 misses the < 4 % target, the device hides it.
    assert not tbr.loc[2, "reference_meets"] and tbr.loc[2, "predicted_meets"]
    assert len(t) == 2 * len(TIME_IN_RANGE_TARGETS_PCT)


def test_time_in_ranges_rejects_nan() -> None:
    with pytest.raises(DataError, match="glucose_mgdl contains NaN"):
        time_in_ranges([100, np.nan], [1, 1])


def test_clopper_pearson_closed_forms() -> None:
    # Exact binomial bound (Clopper & Pearson 1934), one-sided: with all n readings
    # within the limit P(X = n | p) = p^n = alpha gives p_L = alpha^(1/n); with none, 0.
    ref, pred, subj = _independent(10, 10)
    t = agreement_rates(ref, pred, subj, method="clopper-pearson")
    assert t.loc[1, "lower_bound_pct"] == pytest.approx(100.0 * 0.05 ** (1 / 10), rel=1e-12)
    ref, pred, subj = _independent(0, 10)
    t = agreement_rates(ref, pred, subj, method="clopper-pearson", confidence=0.975)
    assert t.loc[1, "lower_bound_pct"] == 0.0 and t.loc[1, "estimate_pct"] == 0.0
