"""Summaries: pure functions of a device file, the same for the file and the simulator."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

import nirglucose as ng
from nirglucose.twin.device import TwinDevice, device_of
from nirglucose.twin.summaries import summaries, summary_names

DEV = TwinDevice((940.0, 1150.0), 16, False, False, ("age_yr", "fitzpatrick_type"), False,
                 20, 5)


@pytest.fixture(scope="module")
def frame():
    return ng.simulate("physical", n_subjects=20, per_subject=5, seed=2, overrides={
        "leds": [{"wavelength_nm": w, "fwhm_nm": 40.0, "power_mw": 3.0,
                  "responsivity_a_per_w": 0.5} for w in (940.0, 1150.0)],
        "hardware.adc_bits": 16}).frame


def test_names_match_values(frame):
    x = summaries(frame, DEV)
    assert len(x) == len(summary_names(DEV)) and np.isfinite(x).all()
    assert "corr_940_1150" in summary_names(DEV) and "within_fitzpatrick_type" in \
        summary_names(DEV)


def test_scaling_the_codes_moves_only_the_level(frame):
    names = summary_names(DEV)
    a = dict(zip(names, summaries(frame, DEV), strict=True))
    doubled = frame.copy()
    doubled[["adc_940", "adc_1150"]] *= 2
    b = dict(zip(names, summaries(doubled, DEV), strict=True))
    for n in names:
        if n.startswith("level_"):
            assert b[n] - a[n] == pytest.approx(np.log10(2.0))
        else:
            assert b[n] == pytest.approx(a[n], abs=1e-9), n


def test_slope_sign_follows_glucose(frame):
    f = frame.copy()
    names = summary_names(DEV)
    f["adc_940"] = (5000 + 10 * f["glucose_mgdl"]).round()
    up = dict(zip(names, summaries(f, DEV), strict=True))["slope_940"]
    f["adc_940"] = (9000 - 10 * f["glucose_mgdl"]).round()
    down = dict(zip(names, summaries(f, DEV), strict=True))["slope_940"]
    assert up > 0 > down


def test_fitzpatrick_share_off_the_mode():
    dev = TwinDevice((940.0,), 10, False, False, ("fitzpatrick_type",), False, 2, 4)
    f = pd.DataFrame({"subject_id": [0] * 4 + [1] * 4,
                      "glucose_mgdl": [90, 100, 110, 120] * 2,
                      "adc_940": [500, 501, 502, 503, 600, 601, 602, 604],
                      "fitzpatrick_type": [2, 2, 3, 2, 5, 5, 5, 5]})
    x = dict(zip(summary_names(dev), summaries(f, dev), strict=True))
    assert x["within_fitzpatrick_type"] == pytest.approx(1 / 8)


def test_device_of_reads_what_the_file_declares(frame):
    cols = ["subject_id", "measurement_id", "glucose_mgdl", "adc_940", "adc_1150",
            "adc_ref_940", "adc_ref_1150", "age_yr"]
    dev = device_of(ng.Dataset(frame[cols].copy()), adc_bits=16)
    assert dev.wavelengths_nm == (940.0, 1150.0) and dev.reference and not dev.monitor
    assert dev.physiology == ("age_yr",) and (dev.n_subjects, dev.per_subject) == (20, 5)
    monitor = frame[cols].copy()
    monitor["adc_ref_940"] += np.arange(len(monitor)) % 3
    assert device_of(ng.Dataset(monitor), adc_bits=16).monitor


@pytest.mark.parametrize("drop, words", [("subject_id", "no 'subject_id'"),
                                         ("glucose_mgdl", "no 'glucose_mgdl'")])
def test_device_of_refuses_a_file_without_people_or_glucose(frame, drop, words):
    with pytest.raises(ng.DataError, match=words):
        device_of(ng.Dataset(frame.drop(columns=[drop])), adc_bits=16)


def test_device_of_refuses_too_few_people(frame):
    few = frame[frame["subject_id"] < 3]
    with pytest.raises(ng.DataError, match="at least 5 people"):
        device_of(ng.Dataset(few.copy()), adc_bits=16)


def test_cli_default_simulations_is_the_library_default():
    """The CLI's --simulations default keys the same cached estimator as ng.fit_twin."""
    from nirglucose.cli.twin_command import DEFAULT_SIMULATIONS
    from nirglucose.twin import InferenceSettings

    assert DEFAULT_SIMULATIONS == InferenceSettings().n_simulations
