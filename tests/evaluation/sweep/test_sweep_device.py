"""The ``device`` sweep study: each capability off alone in paper, on alone in wearable."""

from __future__ import annotations

import pytest

from nirglucose.config import (
    DEVICE_CAPABILITIES,
    PRESET_CAPABILITIES,
    device_capabilities,
    resolve_config,
)
from nirglucose.evaluation.sweep.run import STUDIES, study_scenarios
from nirglucose.exceptions import ConfigError


def test_device_study_switches_one_capability_at_a_time():
    assert "device" in STUDIES
    scenarios = study_scenarios("device")
    names = [s.name for s in scenarios]
    assert len(names) == len(set(names)) == 2 + 2 * len(DEVICE_CAPABILITIES)
    for s in scenarios:
        # the same scenario whatever the sweep's base preset
        on = {
            base: set(device_capabilities(resolve_config(base, s.overrides)))
            for base in ("paper", "wearable")
        }
        assert on["paper"] == on["wearable"]
        expected = set(PRESET_CAPABILITIES[s.labels["base"]])
        if s.labels["switch"] == "off":
            expected -= {s.labels["capability"]}
        elif s.labels["switch"] == "on":
            expected |= {s.labels["capability"]}
        assert on["paper"] == expected, s.name
        gain = resolve_config("wearable", s.overrides).glucose.signal_gain
        assert gain == resolve_config(s.labels["base"]).glucose.signal_gain


def test_device_study_takes_no_values():
    with pytest.raises(ConfigError, match="takes no values"):
        study_scenarios("device", [1, 2])
