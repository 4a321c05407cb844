"""The compiled physiology state equals the NumPy reference bit for bit.

:func:`nirglucose.simulation.physiology.sample_state` runs, after its draws, one compiled
pass (:mod:`nirglucose.simulation.kernels.physiology_kernel`); ``compiled=False`` is the
NumPy form it replaces. Same draws, same bytes, for every column of a block, over
configurations that move each term (stress, pulsation, clipping, no variation).
"""

from __future__ import annotations

import numpy as np
import pytest

import nirglucose as ng
from kernel_checks import assert_same_block, block_with
from nirglucose.simulation import physiology

CASES = {
    "paper": ("paper", {}),
    "wearable": ("wearable", {}),
    "lab (no variation, no pulsation)": ("lab", {}),
    "noise x 3": ("paper", {"noise_scale": 3.0}),
    "narrow limits (clipped often)": ("paper", {
        "physiology.systolic_bp_mmhg": [115.0, 125.0], "physiology.heart_rate_bpm": [65, 75],
        "physiology.resp_rate_bpm": [13.0, 15.0], "physiology.saturation_limits": [0.7, 0.75],
        "physiology.blood_fraction_limits": [0.02, 0.03]}),
    "stress always": ("paper", {"glucose.stress_prob": 1.0}),
}


@pytest.mark.parametrize("case", list(CASES))
def test_compiled_state_equals_the_numpy_reference(case, monkeypatch):
    preset, overrides = CASES[case]
    cfg = ng.resolve_config(preset, overrides)
    assert_same_block(*(block_with(physiology, "sample_state", compiled, cfg, 5, 2, 900, 900,
                                   monkeypatch) for compiled in (False, True)))


def test_the_state_kernel_clips_as_numpy_does():
    from nirglucose.simulation.kernels.physiology_kernel import _clip

    for x, lo, hi in ((-0.0, 0.0, 1.0), (0.0, -0.0, 1.0), (2.0, 0.0, 1.0), (-1.0, 0.0, 1.0),
                      (float("nan"), 0.0, 1.0), (1.0, 0.0, 1.0), (-0.0, -1.0, 0.0)):
        want = np.clip(np.full(20, x), lo, hi)[0]
        got = _clip(x, lo, hi)
        assert np.array(got).tobytes() == np.array(want).tobytes(), (x, lo, hi)
