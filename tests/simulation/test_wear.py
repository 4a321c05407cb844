"""Wear simulation: determinism across chunks and workers, the time columns, persisting
device and subject states, the interstitial lag, and one-line errors."""

from __future__ import annotations

import numpy as np
import pytest

import nirglucose as ng
from nirglucose.cli import main
from nirglucose.dataset import COLUMN_UNITS, WEAR_COLUMNS
from nirglucose.exceptions import ConfigError
from nirglucose.simulation import wear
from nirglucose.simulation.interstitial import interstitial_glucose_mgdl

#: The basic wearable: hand-placed contact (pressure and coupling vary between seatings)
#: and no monitor photodiode (LED drift reaches the readings).
CFG = ng.resolve_config("wearable")


@pytest.fixture(scope="module")
def frame():
    """Three subjects, two days, a reading every 30 min (288 rows)."""
    return wear.simulate_wear_frame(CFG, 3, 2, 30, seed=3)


def test_bytes_do_not_depend_on_chunks_or_workers(tmp_path):
    ref = ng.Dataset(wear.simulate_wear_frame(CFG, 3, 1, 120, seed=3)).content_hash()
    one = wear.simulate_wear_frame(CFG, 3, 1, 120, seed=3, chunk_subjects=1)
    two = wear.simulate_wear_frame(CFG, 3, 1, 120, seed=3, chunk_subjects=2, n_jobs=2)
    assert ng.Dataset(one).content_hash() == ref == ng.Dataset(two).content_hash()
    a, b = tmp_path / "a", tmp_path / "b"
    assert wear.write_wear_partitioned(CFG, a, 3, 1, 120, 3, chunk_subjects=1) == 36
    wear.write_wear_partitioned(CFG, b, 3, 1, 120, 3, n_jobs=2, chunk_subjects=1)
    for part in sorted(a.glob("part-*.parquet")):
        assert part.read_bytes() == (b / part.name).read_bytes()
    loaded = ng.load_dataset(a)
    assert loaded.content_hash() == ref and loaded.metadata["wear"]["every_min"] == 120
    assert ng.Dataset(wear.simulate_wear_frame(CFG, 3, 1, 120, seed=4)).content_hash() != ref


def test_time_columns_and_their_units(frame):
    assert list(frame.columns[2:5]) == list(WEAR_COLUMNS)
    assert all(c in COLUMN_UNITS for c in WEAR_COLUMNS)
    one = frame[frame.subject_id == 1]
    np.testing.assert_array_equal(one.time_min, np.arange(0, 2880, 30))
    np.testing.assert_array_equal(one.wear_day, np.arange(0, 2880, 30) // 1440)
    # re-seated at the 07:30 shower: 0 before it on day 0, 1 until day 1's, then 2
    np.testing.assert_array_equal(one.seating_id, [0] * 15 + [1] * 48 + [2] * 33)
    assert frame.measurement_id.is_unique


def test_a_subject_is_the_snapshot_subject_of_the_same_seed(frame):
    snap = ng.simulate(CFG, n_subjects=3, per_subject=1, seed=3).frame
    np.testing.assert_array_equal(frame.groupby("subject_id").diabetes_status.first(),
                                  snap.diabetes_status)
    for col in ("true_bmi_kgm2", "true_age_yr", "true_melanin_fraction"):
        per_subject = frame.groupby("subject_id")[col]
        assert (per_subject.nunique() == 1).all()  # traits persist
        np.testing.assert_array_equal(per_subject.first(), snap[col])


def test_device_states_persist_and_drift(frame):
    by_seat = frame.groupby(["subject_id", "seating_id"])
    assert (by_seat.true_contact_pressure.nunique() == 1).all()  # one contact per seating
    assert (frame.groupby("subject_id").true_contact_pressure.nunique() == 3).all()
    # one start-up reference for the whole wear (no monitor photodiode in this preset)
    assert not CFG.device.monitor_photodiode
    assert (frame.groupby("subject_id").adc_ref_850.nunique() == 1).all()
    # the day's cycles: warmer air and faster heart in the afternoon than at night
    hour = frame.true_hour_of_day
    day, night = frame[(hour >= 13) & (hour <= 17)], frame[(hour >= 1) & (hour <= 5)]
    assert day.true_ambient_temperature_c.mean() > night.true_ambient_temperature_c.mean()
    assert day.true_heart_rate_bpm.mean() > night.true_heart_rate_bpm.mean() + 5
    assert day.true_humidity_pct.mean() < night.true_humidity_pct.mean()


def test_glucose_follows_the_meals_and_the_optics_see_it_late(frame):
    g = frame.glucose_mgdl.to_numpy()
    isf = frame.true_isf_glucose_mgdl.to_numpy()
    assert g.min() > 40 and g.max() < 450
    after_meal = frame.true_hours_since_meal.between(0.5, 1.5)
    fasting = frame.true_hours_since_meal > 5
    assert g[after_meal].mean() > g[fasting].mean() + 15
    rising = np.r_[False, np.diff(g) > 0] & (frame.subject_id.diff() == 0).to_numpy()
    assert (isf[rising] < g[rising]).mean() > 0.9  # the interstitial lags a rise


def test_lag_step_response_has_the_time_constant():
    tau = 7.0
    blood = np.r_[100.0, np.full(60, 200.0)]
    g = interstitial_glucose_mgdl(blood, 1.0, tau)
    frac = (g[1:] - 100.0) / 100.0  # response to the step at minute 0, sampled each minute
    t = np.arange(len(frac))
    slope = np.polyfit(t[1:40], np.log(1.0 - frac[1:40]), 1)[0]
    assert -1.0 / slope == pytest.approx(tau, rel=1e-6)
    assert np.interp(1 - np.exp(-1), frac, t) == pytest.approx(tau, abs=0.05)
    np.testing.assert_array_equal(interstitial_glucose_mgdl(blood, 1.0, 0.0), blood)


@pytest.mark.parametrize("days, every, match", [
    (-1, 5, "wear_days must be a positive integer"),
    (1.5, 5, "wear_days must be a positive integer"),
    (2, 7, "every_min must divide a day"),
    (2, 0, "every_min must be a positive integer"),
])
def test_bad_arguments_give_one_line(days, every, match):
    with pytest.raises(ConfigError, match=match) as err:
        ng.simulate_wear("paper", 2, days, every)
    assert "\n" not in str(err.value)


@pytest.mark.parametrize("kwargs, match", [
    ({"n_jobs": 0}, "n_jobs must be a positive integer or -1"),
    ({"n_jobs": "a"}, "n_jobs must be a positive integer or -1"),
    ({"seed": -1}, "seed must be a non-negative integer"),
    ({"seed": 1.0}, "seed must be a non-negative integer"),
])
@pytest.mark.parametrize("wear", [False, True])
def test_bad_seed_and_workers_give_one_line(kwargs, match, wear):
    extra = {"wear_days": 1, "every_min": 240} if wear else {}
    with pytest.raises(ConfigError, match=match):
        ng.simulate("paper", 2, **extra, **kwargs)


def test_a_numpy_integer_seed_is_a_seed():
    assert ng.simulate("paper", 2, 2, seed=np.int64(3)).content_hash() == \
        ng.simulate("paper", 2, 2, seed=3).content_hash()


def test_simulate_with_wear_days_is_simulate_wear():
    a = ng.simulate("paper", 2, seed=5, wear_days=1, every_min=240)
    b = ng.simulate_wear("paper", 2, 1, 240, seed=5)
    assert len(a) == 12 and a.content_hash() == b.content_hash()
    assert a.metadata["wear"] == b.metadata["wear"]
    with pytest.raises(ConfigError, match="per_subject does not apply"):
        ng.simulate("paper", 2, 4, wear_days=1)
    with pytest.raises(ConfigError, match="give wear_days too"):
        ng.simulate("paper", 2, every_min=5)


def test_too_many_rows_without_an_output_path_is_refused_up_front():
    with pytest.raises(ConfigError, match="write a directory"):
        ng.simulate_wear("paper", 10**8, 14, 1)


def test_cli_wear_errors_and_a_small_run(tmp_path, capsys):
    assert main(["simulate", "--out", str(tmp_path / "w.parquet"), "--wear-days", "2",
                 "--every-min", "7"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "--every-min must divide a day" in err
    assert main(["simulate", "--out", str(tmp_path / "w.parquet"), "--every-min", "5"]) == 2
    out = tmp_path / "w"
    assert main(["simulate", "--out", str(out), "--subjects", "2", "--wear-days", "1",
                 "--every-min", "120"]) == 0
    ds = ng.load_dataset(out)
    assert len(ds) == 24 and ds.metadata["wear"]["wear_days"] == 1
