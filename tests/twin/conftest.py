"""The twin's fixtures: the example device file and one trained estimator per session.

Training is the expensive step (simulations and a flow): the session trains it once, in
a cache directory of its own, and every test that fits a file of the same device (the
gain-11 file, the gain-1 file, the CLI) reuses it from that cache.
"""

from __future__ import annotations

import pytest

from nirglucose.twin import InferenceSettings

from .device_file import write_device_file

#: A small training budget for the tests (the default is larger: docs, benchmark); the
#: CLI's defaults besides --simulations, so `twin --simulations 2000` finds it cached.
TEST_SIMULATIONS = 2000
TEST_SETTINGS = InferenceSettings(n_simulations=TEST_SIMULATIONS)


@pytest.fixture(scope="session")
def twin_cache(tmp_path_factory):
    """A cache directory for the session's trained estimators."""
    return tmp_path_factory.mktemp("twin_cache")


@pytest.fixture
def use_twin_cache(twin_cache, monkeypatch):
    monkeypatch.setenv("NIRGLUCOSE_CACHE", str(twin_cache))
    return twin_cache


@pytest.fixture(scope="session")
def gain11_file(tmp_path_factory):
    return write_device_file(tmp_path_factory.mktemp("dev") / "one_led.csv", gain=11.0)


@pytest.fixture(scope="session")
def gain1_file(tmp_path_factory):
    return write_device_file(tmp_path_factory.mktemp("dev1") / "one_led.csv", gain=1.0,
                             seed=12)


@pytest.fixture(scope="session")
def twin11(gain11_file, twin_cache):
    """The twin of the gain-11 file (trains the session's estimator)."""
    import warnings

    import nirglucose as ng

    mp = pytest.MonkeyPatch()
    mp.setenv("NIRGLUCOSE_CACHE", str(twin_cache))
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            twin = ng.fit_twin(gain11_file, adc_bits=10, settings=TEST_SETTINGS, n_jobs=1,
                               ppc_devices=40)
    finally:
        mp.undo()
    twin.info["caught"] = [str(w.message) for w in caught]
    return twin
