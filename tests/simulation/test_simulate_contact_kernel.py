"""The compiled contact layer equals the NumPy reference bit for bit.

:func:`nirglucose.simulation.contact.apply_contact` runs, after its draws, one compiled
pass (:mod:`nirglucose.simulation.kernels.contact_kernel`); ``compiled=False`` is the
NumPy form it replaces. Same draws, same bytes, with and without humidity compensation,
a constant-force probe, scaled noise and a worn device's placements.
"""

from __future__ import annotations

import numpy as np
import pytest

import nirglucose as ng
from nirglucose.simulation._random import RandomStreams
from nirglucose.simulation.contact import apply_contact

CASES = {
    "paper": ("paper", {}),
    "wearable": ("wearable", {}),
    "lab": ("lab", {}),
    "compensated": ("paper", {"device.humidity_compensation": True}),
    "uncompensated": ("paper", {"device.humidity_compensation": False}),
    "constant force": ("paper", {"device.constant_force_probe": True}),
    "scaled noise": ("paper", {"noise_scale": 3.0}),
}


def _inputs(n, seed=2):
    rng = np.random.default_rng(seed)
    phys = {"true_blood_fraction": rng.uniform(0.005, 0.08, n),
            "true_skin_thickness_mm": rng.uniform(0.8, 3.0, n)}
    env = {"true_humidity_pct": rng.uniform(10.0, 95.0, n)}
    measured = {"humidity_pct": env["true_humidity_pct"] + rng.normal(0, 3.0, n)}
    return phys, env, measured


@pytest.mark.parametrize("case", list(CASES))
@pytest.mark.parametrize("placed", [False, True])
def test_compiled_contact_equals_the_numpy_reference(case, placed):
    preset, overrides = CASES[case]
    try:
        cfg = ng.resolve_config(preset, overrides)
    except Exception as exc:  # an override a preset does not take
        pytest.skip(str(exc))
    n = 5000
    phys, env, measured = _inputs(n)
    placement = None
    if placed:
        rng = np.random.default_rng(3)
        placement = (rng.beta(2.0, 3.0, n), rng.normal(size=n))
    want_s, got_s = RandomStreams(4, 9), RandomStreams(4, 9)
    want = apply_contact(cfg, phys, env, measured, want_s, placement, compiled=False)
    got = apply_contact(cfg, phys, env, measured, got_s, placement)
    assert got_s.n_variates == want_s.n_variates
    assert list(got) == list(want)
    for col in want:
        a, b = np.asarray(want[col]), np.asarray(got[col])
        assert a.dtype == b.dtype and a.tobytes() == b.tobytes(), col
