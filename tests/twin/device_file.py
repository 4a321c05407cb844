"""A realistic device file for the twin's tests: one 940 nm LED, a 10-bit ADC, reference
glucose in mmol/L, 25 people, in the user guide's format (docs/user_data.md, example 1).

The file is simulated with a device that differs from the twin's base (its own LED width,
power and responsivity) and a hidden glucose gain; the ``true_*`` columns, the simulator's
metadata and every column the device does not record are dropped, the glucose is written
in mmol/L: what a prototype team would bring.
"""

from __future__ import annotations

from pathlib import Path

import nirglucose as ng
from nirglucose.constants import MGDL_PER_MMOLL_GLUCOSE

#: The hidden device: a 35 nm wide 940 nm LED at 2.2 mW on a 0.55 A/W photodiode.
HIDDEN_LED = {"wavelength_nm": 940.0, "fwhm_nm": 35.0, "power_mw": 2.2,
              "responsivity_a_per_w": 0.55}


def write_device_file(path: Path, *, gain: float, n_subjects: int = 25, per_subject: int = 8,
                      seed: int = 11, preset: str = "physical") -> Path:
    """Write the device file (CSV) simulated with glucose gain ``gain``; its path."""
    ds = ng.simulate(preset, n_subjects=n_subjects, per_subject=per_subject, seed=seed,
                     overrides={"leds": [{**HIDDEN_LED, "glucose_gain": gain}],
                                "hardware.adc_bits": 10})
    f = ds.frame
    out = f[["subject_id", "measurement_id"]].copy()
    out["glucose_mmoll"] = (f["glucose_mgdl"] / MGDL_PER_MMOLL_GLUCOSE).round(1)
    out["adc_940"] = f["adc_940"]
    out["age_yr"] = f["age_yr"].astype(int)
    out["skin_temp_c"] = f["skin_temp_c"].round(1)
    out.to_csv(path, index=False)
    return path
