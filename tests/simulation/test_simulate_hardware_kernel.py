"""The compiled hardware layer equals the NumPy reference bit for bit.

:mod:`nirglucose.simulation.kernels.hardware_kernel` does the hardware layer's chain
(LED power -> photocurrent -> noise -> TIA -> INL -> rounding -> saturation) in one
compiled pass; :func:`nirglucose.simulation.hardware.apply_hardware` with
``compiled=False`` is the NumPy composition it replaces. Same draws, same bytes, for
every output, over configurations that take each branch of the kernel.
"""

from __future__ import annotations

import numpy as np
import pytest

import nirglucose as ng
from kernel_checks import assert_same_block, block_with
from nirglucose.exceptions import ConfigError
from nirglucose.simulation import hardware, simulator
from nirglucose.simulation.kernels import hardware_kernel as hk

_LED = {"wavelength_nm": 940.0, "fwhm_nm": 40.0, "power_mw": 5.0,
        "responsivity_a_per_w": 0.6}

CASES = {
    "paper (monitor photodiode)": ("paper", {}),
    "no monitor": ("paper", {"device.monitor_photodiode": False}),
    "wearable": ("wearable", {}),
    "noise x 3": ("paper", {"noise_scale": 3.0}),
    "saturated codes": ("paper", {"hardware.tia_gain_ohm": 3e6}),
    "noise off": ("lab", {"noise_scale": 0.0}),
    "inl off, shot off, ambient off": ("paper", {"noise.adc_inl.enabled": False,
                                                 "noise.shot.enabled": False,
                                                 "noise.ambient_light.enabled": False}),
    "per-LED ageing, flicker, read noise": ("paper", {"leds": [
        {**_LED, "ageing_per_1000h": 0.004, "flicker_rel": 0.003, "read_noise_lsb": 0.7},
        {**_LED, "wavelength_nm": 1050.0, "read_noise_lsb": 0.0}]}),
    "14-bit, detector shunt": ("paper", {"hardware.adc_bits": 14,
                                         "detector": "G17190-010K"}),
}


@pytest.mark.parametrize("case", list(CASES))
def test_compiled_hardware_layer_equals_the_numpy_reference(case, monkeypatch):
    preset, overrides = CASES[case]
    cfg = ng.resolve_config(preset, overrides)
    assert_same_block(*(block_with(hardware, "apply_hardware", compiled, cfg, 3, 1, 700, 700,
                                   monkeypatch) for compiled in (False, True)))


def test_compiled_hardware_layer_returns_the_reference_arrays():
    cfg = ng.resolve_config("paper", {"device.monitor_photodiode": False})
    tables = simulator.scenario_tables(cfg)
    outs = []
    orig = hardware.apply_hardware
    for compiled in (False, True):
        seen = {}

        def layer(*args, _seen=seen, _c=compiled, **kwargs):
            _seen.update(orig(*args, compiled=_c))
            return _seen

        hardware.apply_hardware = layer
        try:
            simulator.simulate_block(cfg, 0, 0, 0, 50, 2, tables)
        finally:
            hardware.apply_hardware = orig
        outs.append(seen)
    want, got = outs
    assert set(got) == set(want)
    for key in want:
        assert want[key].shape == got[key].shape, key
        assert np.asarray(want[key]).tobytes() == np.asarray(got[key]).tobytes(), key


def _front_end(inl: float, bits: int = 12):
    return hk.FrontEnd(*([0.0] * len(hk.FrontEnd._fields)))._replace(
        vref=3.3, full=float(2**bits - 1), inl=inl)


@pytest.mark.parametrize("inl", [2.0, -1.5, 0.0, 1e3])
def test_kernel_conversion_equals_adc_convert_at_the_rounding_edges(inl):
    # codes built to land on and within 1e-13 .. 1e-3 LSB of half-integers (where the
    # polynomial sine must give way to the C library's), across the whole range, below 0
    # and above full scale, plus non-finite inputs kept apart (they raise)
    rng = np.random.default_rng(7)
    full = 4095.0
    target = np.concatenate([np.arange(-3, 4099) + 0.5, rng.uniform(-5, 4100, 20_000)])
    eps = rng.choice([0.0, 1e-13, -1e-13, 1e-9, -1e-9, 1e-6, -1e-3], target.size)
    ideal = target + eps
    # solve ideal + inl sin(pi ideal / FS) + offset = target + eps for the offset
    offset = target + eps - ideal - inl * np.sin(np.pi * ideal / full)
    voltage = ideal / full * 3.3
    want = hardware.adc_convert(voltage, 3.3, 12, inl, offset)
    got = np.empty(voltage.size, np.int64)
    assert hk.convert(voltage, offset, _front_end(inl), got)
    np.testing.assert_array_equal(got, want)


def test_kernel_conversion_flags_non_finite_codes():
    out = np.empty(3, np.int64)
    volts = np.array([1.0, np.nan, np.inf])
    assert not hk.convert(volts, np.zeros(3), _front_end(2.0), out)
    assert hk.convert(volts[:1], np.zeros(1), _front_end(2.0), out[:1])
    assert not hk.convert(volts[:1], np.array([np.nan]), _front_end(2.0), out[:1])


@pytest.mark.parametrize("compiled", [False, True])
def test_both_layers_refuse_a_non_finite_adc_input(compiled, monkeypatch):
    # noise 40 x drives the analog chain out of range (issue 20): a ConfigError either way
    cfg = ng.resolve_config("paper", {"noise_scale": 40.0})
    with pytest.raises(ConfigError, match="not finite"):
        block_with(hardware, "apply_hardware", compiled, cfg, 3, 1, 700, 700, monkeypatch)
