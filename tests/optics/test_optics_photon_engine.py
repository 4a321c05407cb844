"""Tests of nirglucose_reference.photon_engine (one engine, pluggable tallies)."""

from __future__ import annotations

import numpy as np
import pytest

from nirglucose.exceptions import ConfigError
from nirglucose_reference.mc_paths import mc_detected_paths
from nirglucose_reference.monte_carlo import mc_layers
from nirglucose_reference.photon_engine import Stack, run_photons

LAYERS = dict(mua_per_cm=[1.0, 0.3], mus_per_cm=[100.0, 60.0], g=[0.9, 0.8],
              thickness_cm=[0.02, np.inf], n_layers=[1.4, 1.4])


class _Totals:
    """A tally of one's own: the engine needs only the two hooks."""

    def __init__(self):
        self.absorbed_w, self.top_w, self.bottom_w, self.calls = 0.0, 0.0, 0.0, 0

    def absorbed(self, layer, weight):
        self.absorbed_w += float(weight.sum())

    def escaped(self, packets, idx, weight, top):
        self.calls += 1
        assert idx.size == weight.size == top.size and np.all(weight >= 0)
        self.top_w += float(weight[top].sum())
        self.bottom_w += float(weight[~top].sum())


def _stack(**over):
    kw = {**LAYERS, **over}
    return Stack.from_layers(kw["mua_per_cm"], kw["mus_per_cm"], kw["g"], kw["thickness_cm"],
                             kw["n_layers"], 1.0)


def _run(tally, absorption="discrete", n=3000, seed=4, stack=None):
    run_photons(stack or _stack(), tally, n, np.random.default_rng(seed),
                absorption=absorption, weight_threshold=1e-4, roulette_chance=0.1,
                max_steps=1_000_000)


def test_a_custom_tally_sees_what_the_mcml_front_end_reports():
    # same engine, same random numbers: the front end's totals are this tally's, exactly
    t = _Totals()
    _run(t)
    res = mc_layers(**LAYERS, n_photons=3000, rng=4)
    assert t.calls > 0
    assert t.top_w / 3000 == pytest.approx(res.diffuse_reflectance, rel=1e-12)
    assert t.absorbed_w / 3000 == pytest.approx(res.absorbed_per_layer.sum(), rel=1e-12)
    assert t.bottom_w == 0.0  # semi-infinite: nothing leaves through the bottom


def test_weight_is_conserved_up_to_roulette_noise():
    # launched 1 - R_sp = absorbed + escaped, on average (roulette is unbiased)
    stack = _stack(thickness_cm=[0.02, 0.05])
    t = _Totals()
    _run(t, n=20_000, stack=stack)
    total = (t.absorbed_w + t.top_w + t.bottom_w) / 20_000
    assert total == pytest.approx(1.0 - stack.specular, abs=0.01)
    assert t.bottom_w > 0.0


def test_continuous_absorption_never_calls_absorbed_and_matches_the_ring_front_end():
    t = _Totals()
    t.absorbed = lambda layer, weight: pytest.fail("continuous runs absorb along the path")
    _run(t, absorption="continuous")
    res = mc_detected_paths(LAYERS["mua_per_cm"], LAYERS["mus_per_cm"], LAYERS["g"],
                            [0.02], (0.0, 10.0), n_photons=3000, rng=4)
    assert t.top_w / 3000 == pytest.approx(res.diffuse_reflectance, rel=1e-12)


def test_unknown_absorption_model_is_one_config_error():
    with pytest.raises(ConfigError, match="absorption = 'analog' is unknown"):
        _run(_Totals(), absorption="analog")


@pytest.mark.parametrize(
    ("kw", "match"),
    [
        ({"roulette_chance": 1.5}, r"roulette_chance = 1\.5 is out of range"),
        ({"roulette_chance": 0.0}, r"roulette_chance = 0\.0 is out of range"),
        ({"weight_threshold": 1.0}, r"weight_threshold = 1\.0 is out of range"),
        ({"weight_threshold": "abc"}, r"weight_threshold = 'abc' is not a number"),
        ({"n_photons": 0}, r"n_photons = 0 is invalid"),
        ({"n_photons": 2.0}, r"n_photons = 2\.0 is invalid"),
    ],
)
def test_the_engine_checks_its_run_settings(kw, match):
    # the checks live in the engine, so every front end (and a caller's own tally) has them
    args = dict(n_photons=10, absorption="discrete", weight_threshold=1e-4,
                roulette_chance=0.1, max_steps=1000) | kw
    with pytest.raises(ConfigError, match=match):
        run_photons(_stack(), _Totals(), args.pop("n_photons"), np.random.default_rng(0), **args)


@pytest.mark.parametrize("n", [0.0, -1.4, np.nan, np.inf])
def test_the_engine_refuses_a_stack_with_a_bad_refractive_index(n):
    stack = Stack.from_layers([1.0], [10.0], [0.5], [0.1], [1.4], 1.0)
    bad = Stack(**{**stack.__dict__, "n_ext": np.array([1.0, n, 1.0])})
    with pytest.raises(ConfigError, match="refractive index = .* is out of range"):
        run_photons(bad, _Totals(), 10, np.random.default_rng(0), absorption="discrete",
                    weight_threshold=1e-4, roulette_chance=0.1, max_steps=1000)
