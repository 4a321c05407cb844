"""Agreement rates and iCGM bounds against the published worked example.

Stephan et al. (2022), the method our ``metrics/cgm.py`` follows, publish a worked
example with their code: 24 CGM sensors x 150 paired readings (``Test_Data.csv``) and
their results (``CI_Results.csv``): per range the agreement rates AR15/AR20/AR40 and
their one-sided 95 % lower bounds by Clopper-Pearson (CP), clustered continuity-corrected
Wilson (WCC, with the intraclass correlation) and BCa bootstrap (10,000 resamples of the
sensors, numpy's legacy generator seeded with 1). Both files are stored byte for byte
under ``tests/metrics/data/`` (SOURCES.md: repository, commit, MIT notice).

Tolerances:

* rates, CP, WCC and ICC: 1e-9 (percentage points, or the ICC itself). The formulas
  are the same closed forms; the two implementations differ only in the order of
  floating-point sums, a few units in the last place (1e-13 here).
* BCa, replayed: fed the authors' very resamples (the stream of
  ``numpy.random.RandomState(1).choice`` over the sorted sensor ids), our BCa bound is
  theirs to 1e-9: same cluster bootstrap, same jackknife acceleration, same quantile
  rule. What is left between the two is the random stream alone.
* BCa, our generator: our default stream (``numpy.random.default_rng(seed)``) gives other
  resamples, so the bound differs by Monte Carlo error. The test measures that error
  itself, as the spread of the bound over 10 seeds of 10,000 resamples each (0.005 to
  0.09 percentage points depending on the row, largest for the 374 readings < 70 mg/dL),
  and asks the published bound to lie within 4 standard deviations of the mean over
  those seeds (of the difference of one published run and a 10-run mean).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from scipy import stats

from nirglucose.metrics import (
    ICGM_CRITERIA,
    agreement_rates,
    icgm_criteria,
    rate_categories,
    trend_agreement,
)
from nirglucose.metrics.cgm import _prepare_agreement, _rate_table

DATA = Path(__file__).parent / "data"
TEST_DATA = DATA / "ifdt_ulm_ci_test_data.csv"
RESULTS = DATA / "ifdt_ulm_ci_results.csv"
#: The authors' row names -> ours.
RANGES = {"<70": "<70", "70-180": "70-180", ">180": ">180", "Total": "overall"}
ABS = 1e-9


@pytest.fixture(scope="module")
def readings() -> pd.DataFrame:
    return pd.read_csv(TEST_DATA)


@pytest.fixture(scope="module")
def published() -> pd.DataFrame:
    """The authors' results, one row per (range, limit), in our labels."""
    wide = pd.read_csv(RESULTS)
    rows = []
    for _, r in wide.iterrows():
        for limit in (15, 20, 40):
            label = RANGES[r["Range"]]
            rows.append({
                "range": label, "limit": f"{limit} {'mg/dL' if label == '<70' else '%'}",
                "ar": r[f"AR{limit}"], "cp": r[f"CP_CI{limit}"], "wcc": r[f"WCC_CI{limit}"],
                "icc": r[f"WCC_ICC{limit}"], "bca": r[f"BCa_CI{limit}"],
            })
    return pd.DataFrame(rows).set_index(["range", "limit"])


def _ours(readings: pd.DataFrame, **kwargs) -> pd.DataFrame:
    t = agreement_rates(readings["Comp"], readings["CGM"], readings["SensorID"], **kwargs)
    return t.set_index(["range", "limit"])


def test_the_stored_example_is_complete(readings) -> None:
    # SOURCES.md: 98,701 bytes, 3,600 rows; 24 sensors x 150 readings, no gaps.
    assert TEST_DATA.stat().st_size == 98_701
    assert RESULTS.stat().st_size == 1_230
    assert readings.shape == (3600, 3)
    assert readings.notna().all().all()
    assert (readings.groupby("SensorID").size() == 150).all()
    assert readings["SensorID"].nunique() == 24


def test_rates_wilson_bounds_and_icc_reproduce_the_authors(readings, published) -> None:
    ours = _ours(readings, method="wilson").loc[published.index]
    np.testing.assert_allclose(ours["estimate_pct"], published["ar"], rtol=0, atol=ABS)
    np.testing.assert_allclose(ours["lower_bound_pct"], published["wcc"], rtol=0, atol=ABS)
    np.testing.assert_allclose(ours["icc"], published["icc"], rtol=0, atol=ABS)
    # Readings per range follow from the rates' denominators: < 70 by the CGM reading.
    assert ours["n_readings"].xs("15 %", level="limit").to_dict() == {
        "70-180": 1593, ">180": 1633, "overall": 3600}
    assert ours.loc[("<70", "15 mg/dL"), "n_readings"] == 374
    assert (readings["CGM"] < 70).sum() == 374


def test_clopper_pearson_reproduces_the_authors(readings, published) -> None:
    ours = _ours(readings, method="clopper-pearson").loc[published.index]
    np.testing.assert_allclose(ours["lower_bound_pct"], published["cp"], rtol=0, atol=ABS)
    # The exact binomial bound, checked on one row from its definition: the one-sided
    # 95 % bound p_L solves P(X >= x | n, p_L) = 0.05.
    row = ours.loc[("70-180", "15 %")]
    x = round(row["estimate_pct"] * row["n_readings"] / 100.0)
    p_low = row["lower_bound_pct"] / 100.0
    assert stats.binom.sf(x - 1, row["n_readings"], p_low) == pytest.approx(0.05, rel=1e-9)
    # Readings taken as independent: narrower than the clustered bounds here.
    wil = _ours(readings, method="wilson").loc[published.index]
    assert (ours["lower_bound_pct"] > wil["lower_bound_pct"]).all()


def test_bca_replayed_on_the_authors_resamples_is_theirs(readings, published) -> None:
    ref, pred, subj, n_subjects, codes = _prepare_agreement(
        readings["Comp"], readings["CGM"], readings["SensorID"], "device", "bootstrap",
        10_000, 0.95)
    sensors = np.unique(readings["SensorID"].to_numpy())  # sorted as the authors sort
    drawn = np.random.RandomState(1).choice(sensors, size=(10_000, sensors.size))
    draws = np.searchsorted(sensors, drawn)
    t = _rate_table(ref, pred, subj, n_subjects, codes, method="bootstrap", n_boot=10_000,
                    seed=None, confidence=0.95, draws=draws)
    t = t.set_index(["range", "limit"]).loc[published.index]
    np.testing.assert_allclose(t["lower_bound_pct"], published["bca"], rtol=0, atol=ABS)


def test_bca_with_our_generator_is_theirs_within_monte_carlo_error(readings,
                                                                   published) -> None:
    n_seeds = 10
    bounds = np.stack([
        _ours(readings, n_boot=10_000, seed=s).loc[published.index, "lower_bound_pct"]
        for s in range(n_seeds)])
    mean, sd = bounds.mean(axis=0), bounds.std(axis=0, ddof=1)
    assert (sd > 0).all() and (sd < 0.2).all()  # Monte Carlo error, not a bug
    tolerance = 4.0 * sd * np.sqrt(1.0 + 1.0 / n_seeds)
    assert (np.abs(published["bca"].to_numpy() - mean) <= tolerance).all()


def test_icgm_verdicts_follow_the_published_bounds(readings, published) -> None:
    t = icgm_criteria(readings["Comp"], readings["CGM"], readings["SensorID"],
                      method="wilson").set_index("criterion")
    for letter, crit in ICGM_CRITERIA.items():
        wcc = published.loc[(crit.range, crit.limit), "wcc"]
        assert t.loc[letter, "lower_bound_pct"] == pytest.approx(wcc, abs=ABS)
        assert t.loc[letter, "passes"] == (wcc > crit.required_pct), letter
    # H, I: CGM < 70 with comparator > 180 and the reverse, counted on the raw data.
    low_high = ((readings["CGM"] < 70) & (readings["Comp"] > 180)).sum()
    high_low = ((readings["CGM"] > 180) & (readings["Comp"] < 70)).sum()
    assert t.loc["H", "estimate_pct"] == low_high and t.loc["I", "estimate_pct"] == high_low
    assert t.loc["H", "passes"] == (low_high == 0) and t.loc["I", "passes"] == (high_low == 0)


# --- trend categories: the clinical trend concurrence analysis (CTCA) example ------------
#
# Eichenlaub, Pleus & Freckmann (2024) publish with their CTCA code a test file of
# comparator rates of change (``Comp_ROC``, mg/dL/min) and the category the authors gave
# each (``Comp_ROC_Cat``, -3..3: '<-3', '-3 to <-2', '-2 to <-1', '-1 to +1', '>+1 to +2',
# '>+2 to +3', '>+3'). Its first 465 rows are stored (SOURCES.md). They hold rates exactly
# on every edge, so they pin down the convention: an edge belongs to the band nearer zero.

CTCA = DATA / "ifdt_ulm_ctca_test_data_head.csv"
CTCA_EDGES = (-3.0, -2.0, -1.0, 1.0, 2.0, 3.0)


@pytest.fixture(scope="module")
def ctca() -> pd.DataFrame:
    return pd.read_csv(CTCA)


def test_the_stored_ctca_rows_are_complete(ctca) -> None:
    assert CTCA.stat().st_size == 15_971
    assert ctca.columns.tolist() == ["BG", "CGM", "Comp_ROC", "Comp_ROC_Cat", "CGM_ROC_Cat"]
    assert ctca.shape[0] == 465 and ctca.notna().all().all()
    for edge in CTCA_EDGES:  # each edge occurs: the convention is exercised both ways
        assert (ctca["Comp_ROC"] == edge).any(), edge


def test_rate_categories_reproduce_the_ctca_comparator_categories(ctca) -> None:
    got = rate_categories(ctca["Comp_ROC"], edges_mgdl_per_min=CTCA_EDGES) - 3
    np.testing.assert_array_equal(got, ctca["Comp_ROC_Cat"].to_numpy(dtype=int))


def test_trend_agreement_counts_the_ctca_categories(ctca) -> None:
    # One subject per row, two readings 5 min apart whose rate is the comparator rate
    # (exact on the edges: 5 x an integer rate is an integer).
    n = ctca.shape[0]
    start = np.full(n, 200.0)
    glucose = np.column_stack([start, start + 5.0 * ctca["Comp_ROC"].to_numpy()]).ravel()
    subject = np.repeat(np.arange(n), 2)
    time_min = np.tile([0.0, 5.0], n)
    r = trend_agreement(glucose, glucose, subject, time_min, edges_mgdl_per_min=CTCA_EDGES)
    assert r.n_pairs == n and r.agreement_pct == 100.0
    expected = ctca["Comp_ROC_Cat"].value_counts().reindex(range(-3, 4), fill_value=0)
    np.testing.assert_array_equal(np.diag(r.matrix.to_numpy()), expected.to_numpy())
    assert r.matrix.index.tolist() == ["<-3", "-3..-2", "-2..-1", "-1..1", "1..2", "2..3", ">3"]
