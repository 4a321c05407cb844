"""Issue 43: the error grids warn, in one line, about values impossible in their unit."""

from __future__ import annotations

import warnings

import pytest

from nirglucose.metrics import clarke_zones, parkes_zones


@pytest.mark.parametrize("zones", [clarke_zones, parkes_zones])
def test_mgdl_values_declared_mmoll_warn_once(zones):
    with pytest.warns(UserWarning, match="looks like mg/dL") as caught:
        zones([100.0, 120.0], [100.0, 110.0], units="mmol/L")
    assert len(caught) == 1 and "\n" not in str(caught[0].message)
    assert "33.3 mmol/L" in str(caught[0].message)


@pytest.mark.parametrize("zones", [clarke_zones, parkes_zones])
def test_plausible_mmoll_values_say_nothing(zones):
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert list(zones([5.5, 12.0, 30.0], [5.0, 11.0, 29.0], units="mmol/L")) == [
            "A", "A", "A"]
