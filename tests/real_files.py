"""Small device files as they come from real teams (issue 43), for the CLI tests.

* :func:`one_led_mmoll_frame`: one 940 nm LED on a 10-bit ADC, glucose in mmol/L.
* :func:`two_converter_frame`: a 940 nm reading from a 10-bit analog front end and an
  18-bit IR count (1050 nm) from a digital PPG sensor, with a ``diabetic`` yes/no
  column; the people with diabetes sit higher in glucose *and* in both channels, while
  inside each group the channels carry no glucose at all: any pooled skill is the
  offset between the groups.
* :func:`ac_coupled_ppg_frame`: a PPG sensor's file whose front end is AC-coupled: every
  reading's code is the converter's bias point, mid-scale, give or take its noise.
"""

from __future__ import annotations

import numpy as np
import pandas as pd


def one_led_mmoll_frame(n_subjects: int = 30, per_subject: int = 2, seed: int = 43
                        ) -> pd.DataFrame:
    """One LED, 10-bit codes (up to 1023), reference glucose_mmoll."""
    rng = np.random.default_rng(seed)
    sid = np.repeat(np.arange(n_subjects), per_subject)
    glucose = rng.uniform(4.0, 14.0, len(sid))
    adc = 450.0 + 25.0 * glucose + rng.normal(0.0, 20.0, len(sid))
    return pd.DataFrame({"subject_id": sid, "glucose_mmoll": np.round(glucose, 1),
                         "adc_940": np.round(adc)})


def two_converter_frame(n_subjects: int = 40, per_subject: int = 3, seed: int = 43
                        ) -> pd.DataFrame:
    """Two converters (10-bit adc_940, 18-bit adc_1050) and a diabetic yes/no column."""
    rng = np.random.default_rng(seed)
    sid = np.repeat(np.arange(n_subjects), per_subject)
    diabetic = np.where(sid % 2 == 1, "yes", "no")
    d = diabetic == "yes"
    glucose = np.where(d, rng.uniform(130.0, 300.0, len(sid)), rng.uniform(75.0, 135.0,
                                                                           len(sid)))
    adc_940 = np.where(d, 700.0, 500.0) + rng.normal(0.0, 40.0, len(sid))
    adc_1050 = np.where(d, 150_000.0, 110_000.0) + rng.normal(0.0, 8_000.0, len(sid))
    return pd.DataFrame({"subject_id": sid, "diabetic": diabetic,
                         "glucose_mgdl": np.round(glucose), "adc_940": np.round(adc_940),
                         "adc_1050": np.round(adc_1050)})


def ac_coupled_ppg_frame(n_subjects: int = 30, per_subject: int = 3, seed: int = 43
                         ) -> pd.DataFrame:
    """Two 12-bit channels (880, 940 nm) at mid-scale whatever the person or glucose."""
    rng = np.random.default_rng(seed)
    sid = np.repeat(np.arange(n_subjects), per_subject)
    out = {"subject_id": sid, "glucose_mgdl": np.round(rng.uniform(70.0, 250.0, len(sid)))}
    for nm in (880, 940):
        out[f"adc_{nm}"] = np.round(2047.5 + rng.normal(0.0, 12.0, len(sid)))
    return pd.DataFrame(out)
