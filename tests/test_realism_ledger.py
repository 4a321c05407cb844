"""The realism ledger's record (studies/records/realism_ledger.json) is the package's:
its per-band numbers recomputed here; the slow sections on request (-m slow)."""

from __future__ import annotations

import importlib.util
import json
from pathlib import Path

import numpy as np
import pytest

_ROOT = Path(__file__).resolve().parents[1]
_RECORD = json.loads((_ROOT / "studies" / "records" / "realism_ledger.json").read_text())

pytestmark = pytest.mark.filterwarnings("ignore:lipid absorption above")


def _script():
    spec = importlib.util.spec_from_file_location(
        "realism_ledger", _ROOT / "studies" / "realism_ledger.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def _same(got, want):
    assert len(got) == len(want)
    for g, w in zip(got, want, strict=True):
        assert g.keys() == w.keys()
        for k in g:
            if isinstance(w[k], str):
                assert g[k] == w[k]
            else:
                np.testing.assert_allclose(g[k], w[k], rtol=1e-9, atol=0, err_msg=k)


def test_per_band_numbers_are_the_packages():
    glucose, temps = _script().glucose_and_temperature()
    _same(glucose, _RECORD["glucose_per_100_mgdl"])
    _same(temps, _RECORD["temperature_equivalence"])


def test_the_page_quotes_the_record():
    page = (_ROOT / "docs" / "user_guide" / "realism.md").read_text()
    for r in _RECORD["temperature_equivalence"]:
        if r["band_nm"] in (1450, 1550, 1650):
            assert f"| {r['band_nm']} |" in page
            assert f"{abs(r['mgdl_per_c_light']):.0f} |" in page
    cohort = _RECORD["devices"]["cohort"]
    assert f"{cohort['oracle']['rmse_mgdl']:.1f}" in page
    assert f"MARD {cohort['per_subject_calibration_no_optics']['mard_pct']:.1f} %" in page


@pytest.mark.slow
def test_bounds_and_cohort_are_the_packages():
    mod = _script()
    want = _RECORD["devices"]["bounds"]
    got = mod.bounds()
    np.testing.assert_allclose(got["water_temperature_on"]["device"],
                               want["water_temperature_on"]["device"], rtol=1e-9)
    np.testing.assert_allclose([g["oracle"] for g in got["by_gain"]],
                               [w["oracle"] for w in want["by_gain"]], rtol=1e-9)
    _same(mod.water_temperature_in_the_bound(), _RECORD["water_temperature_in_the_bound"])
