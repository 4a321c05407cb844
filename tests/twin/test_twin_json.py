"""twin.json: round trip, the scenario it makes, and one clear error for a bad file."""

from __future__ import annotations

import json

import numpy as np
import pytest

import nirglucose as ng
from nirglucose.twin import Twin, load_twin
from nirglucose.twin.device import TwinDevice
from nirglucose.twin.parameters import fitted_parameters, held_parameters
from nirglucose.twin.twin import parameter_entry

DEVICE = TwinDevice((940.0,), 10, False, False, ("age_yr", "skin_temp_c"), False, 25, 8)


@pytest.fixture(scope="module")
def twin() -> Twin:
    """A twin built by hand: prior draws as its 'posterior' (no training)."""
    params = fitted_parameters(DEVICE)
    rng = np.random.default_rng(0)
    z = np.column_stack([rng.uniform(*p.fit_bounds, size=200) for p in params])
    values = np.column_stack([p.from_fit(z[:, i]) for i, p in enumerate(params)])
    entries = [parameter_entry(p, z[:, i]) for i, p in enumerate(params)]
    entries += [parameter_entry(p, None) for p in held_parameters(DEVICE)]
    return Twin(DEVICE, entries, values, values[0], {"warnings": []})


def test_round_trip(tmp_path, twin):
    twin.save(tmp_path / "tw")
    back = load_twin(tmp_path / "tw")
    assert back.device == twin.device
    np.testing.assert_array_equal(back.draws, twin.draws)
    assert back.parameters == json.loads(json.dumps(twin.parameters))
    assert back.overrides("map") == twin.overrides("map")


def test_entries_carry_the_issue_fields(twin):
    for e in twin.parameters:
        assert {"key", "median", "lower", "upper", "identified"} <= set(e)
        assert e["lower"] <= e["median"] <= e["upper"]
    held = [e for e in twin.parameters if not e["fitted"]]
    # a column the file lacks and drift without times: prior, not identified, a reason
    assert {e["key"] for e in held} >= {"measurement.bmi_kgm2",
                                         "leds.emitters.0.ageing_per_1000h"}
    assert all(not e["identified"] and e["reason"] for e in held)
    # prior draws fill the prior: nothing identified
    assert not any(e["identified"] for e in twin.parameters)


def test_scenario_is_the_device_with_the_values(twin):
    cfg = twin.scenario("map")
    assert cfg.leds.wavelengths_nm == (940.0,)
    assert cfg.hardware.adc_bits == 10
    assert cfg.glucose.signal_gain == 1.0  # the physical base: the gain is per LED
    gain = twin.map_values[twin.fitted_keys.index("leds.emitters.0.glucose_gain")]
    assert cfg.leds.emitters[0].glucose_gain == pytest.approx(gain)
    draws = {twin.scenario("posterior", seed=s).leds.emitters[0].power_mw for s in range(5)}
    assert len(draws) > 1  # posterior mode: a draw per seed


def test_simulate_takes_a_twin(tmp_path, twin):
    twin.save(tmp_path)
    a = ng.simulate(ng.twin_scenario(tmp_path / "twin.json"), n_subjects=3, per_subject=2, seed=1)
    b = ng.simulate(ng.twin_scenario(twin), n_subjects=3, per_subject=2, seed=1)
    assert list(a.frame.columns[:5]) == ["subject_id", "measurement_id", "glucose_mgdl",
                                         "diabetes_status", "adc_940"]
    assert a.frame.equals(b.frame)
    assert a.frame["adc_940"].max() <= 1023


def _write(tmp_path, twin, edit) -> str:
    doc = twin.to_json()
    edit(doc)
    path = tmp_path / "twin.json"
    path.write_text(json.dumps(doc))
    return str(path)


@pytest.mark.parametrize("edit, words", [
    (lambda d: d.update(format="other"), "not a twin file"),
    (lambda d: d.update(format_version=9), "format_version"),
    (lambda d: d["parameters"][0].update(median=1e9), "lower"),
    (lambda d: d["parameters"][0].update(lower="x"), "finite numbers"),
    (lambda d: d["parameters"][1].update(identified="yes"), "true or false"),
    (lambda d: d["parameters"][0].pop("key"), "no 'key'"),
    (lambda d: d.update(draws=[[1.0]]), "columns"),
    (lambda d: d["map"].clear(), "'map'"),
    (lambda d: d["device"].pop("adc_bits"), "'device'"),
    (lambda d: d.update(parameters=[]), "no 'parameters'"),
])
def test_malformed_twin_json_is_one_clear_error(tmp_path, twin, edit, words):
    path = _write(tmp_path, twin, edit)
    with pytest.raises(ng.DataError, match=words) as info:
        load_twin(path)
    assert "\n" not in str(info.value)


def test_missing_and_unreadable_twin(tmp_path):
    with pytest.raises(ng.DataError, match="no twin file"):
        load_twin(tmp_path / "nothing.json")
    bad = tmp_path / "twin.json"
    bad.write_text("{not json")
    with pytest.raises(ng.DataError, match="cannot read"):
        load_twin(bad)


def test_unknown_mode(twin):
    with pytest.raises(ng.ConfigError, match="map, posterior"):
        twin.overrides("mode")
