"""Hardware layer: LEDs, photodiode, transimpedance amplifier and ADC.

Physics (DESIGN.md physics notes):

* LED: P = P0 [1 - 0.002 (T - 25) - 0.001 t/1000 h + N(0, 0.1 %)]; the peak shifts
  0.2-0.3 nm/degC with junction temperature.
* Photodiode: I_sig = R(lambda) P_opt; I_dark = I25 e^{0.1 (T - 25)};
  shot noise sqrt(2 e I BW); Johnson noise sqrt(4 k T BW / R).
* TIA: V = I R_f. ADC: round(V / Vref (2^bits - 1)) + INL + offset drift, clipped to
  the code range (saturation of a real converter).

The device takes a reference reading of each LED at start-up (the subject's session),
through a neutral attenuator of known transmission, and an offset-cancellation current
that nulls the dark current at that temperature. Drift between then and each
measurement (LED temperature, ageing, dark current) is what the reference cannot
remove. With a monitor photodiode (``device.monitor_photodiode``) the reference is
instead read at every measurement from the same LED pulse, with the monitor's own
shot, Johnson and conversion noise: LED power drift, ageing and flicker cancel in
adc / adc_ref, the thermal wavelength shift does not. Ambient light is removed by an
LED-off reading; its flicker between the two readings and its shot noise remain.

References
----------
.. [1] Hamamatsu Photonics, "Si photodiodes" technical information (dark current,
   shot and thermal noise), and S1223/S1336 datasheets.
.. [2] P. Horowitz, W. Hill, "The Art of Electronics", 3rd ed., sec. 8.1 (Johnson and
   shot noise).
.. [3] Vishay TSAL6200 / VSLY5850 IR-LED datasheets (thermal coefficients).
"""

from __future__ import annotations

import numpy as np

from .. import portable as pm
from ..constants import (
    BOLTZMANN_J_PER_K,
    DARK_CURRENT_DOUBLING_COEFF_PER_C,
    ELEMENTARY_CHARGE_C,
    LED_AGEING_PER_1000H,
    LED_REFERENCE_TEMPERATURE_C,
    LED_THERMAL_COEFF_PER_C,
    ZERO_CELSIUS_K,
)
from ..exceptions import ConfigError

__all__ = [
    "board_temperature_c",
    "led_temperatures_c",
    "led_ages_h",
    "led_power_w",
    "led_peak_shift_nm",
    "dark_current_a",
    "shot_noise_sd_a",
    "johnson_noise_sd_a",
    "adc_inl_lsb",
    "adc_convert",
    "johnson_resistance_ohm",
]


def board_temperature_c(ambient_c, skin_c, skin_weight: float) -> np.ndarray:
    """Board temperature between air and skin, (1 - w) T_ambient + w T_skin. [degC]

    The board sits between the air and the skin it is strapped to; halfway
    (``hardware.board_skin_weight`` = 0.5) is an assumption of this package.

    Examples
    --------
    >>> float(board_temperature_c(20.0, 34.0, 0.5))
    27.0
    """
    return (1.0 - skin_weight) * np.asarray(ambient_c) + skin_weight * np.asarray(skin_c)


def led_temperatures_c(cfg, ambient_c, skin_c, first_rows, streams) -> dict:
    """Junction and board temperatures of each reading and of the start-up reference.

    A pulsed LED's junction sits ``hardware.led_self_heating_c`` above ambient, with an
    SD of ``led_self_heating_sd_c`` between readings (scaled by the
    ``led_thermal_drift`` noise source); the junction's forward-voltage heating is the
    mechanism of the datasheets' thermal coefficients [3]_. The reference is read at
    each subject's first reading's ambient.

    Returns
    -------
    dict
        ``led_c`` (n, n_led), ``board_c`` (n,), ``led_cal_c`` (n_sub, n_led),
        ``board_cal_c`` (n_sub,). [degC]
    """
    hw = cfg.hardware
    n, n_sub, n_led = len(ambient_c), len(first_rows), len(cfg.leds.emitters)
    f_thermal = cfg.noise_factor("led_thermal_drift")
    # heating + f sd z, in place in the draws (+ and x commute exactly)
    heat = streams("led_thermal_drift").normal(size=(n + n_sub, n_led))
    heat *= f_thermal * hw.led_self_heating_sd_c
    heat += hw.led_self_heating_c
    board_c = board_temperature_c(ambient_c, skin_c, hw.board_skin_weight)
    return {
        "led_c": ambient_c[:, None] + heat[:n],
        "board_c": board_c,
        "led_cal_c": ambient_c[first_rows][:, None] + heat[n:],
        "board_cal_c": board_c[first_rows],
    }


def led_ages_h(cfg, subject_index, n_sub: int, streams) -> dict:
    """Device age at each subject's start-up reference and at each reading. [h]

    The age at start-up is uniform over ``hardware.led_age_h``; each reading follows it
    by a uniform ``hardware.hours_since_reference_h``.
    """
    hw = cfg.hardware
    rng = streams("led_ageing")
    age_cal_h = rng.uniform(*hw.led_age_h, size=n_sub)
    age_h = age_cal_h[subject_index] + rng.uniform(
        *hw.hours_since_reference_h, size=len(subject_index)
    )
    return {"age_h": age_h, "age_cal_h": age_cal_h}


def led_power_w(
    p0_w,
    led_temperature_c,
    age_h,
    flicker_rel,
    *,
    thermal_coeff_per_c: float = LED_THERMAL_COEFF_PER_C,
    ageing_per_1000h=LED_AGEING_PER_1000H,
) -> np.ndarray:
    """LED optical power P = P0 [1 - a (T - 25) - b t / 1000 h + n].

    Parameters
    ----------
    p0_w : array_like
        Power at 25 degC when new. [W]
    led_temperature_c : array_like
        Junction temperature. [degC]
    age_h : array_like
        Hours of operation. [h]
    flicker_rel : array_like
        Relative flicker draw n (N(0, 0.1 %) in DESIGN.md). [-]
    thermal_coeff_per_c : float
        a. [1/degC]
    ageing_per_1000h : float or array_like
        b (one per LED where the LEDs age differently). [1/(1000 h)]

    Returns
    -------
    numpy.ndarray
        Optical power. [W]

    References
    ----------
    DESIGN.md physics notes; Vishay IR-LED datasheets [3]_.

    Examples
    --------
    >>> float(led_power_w(1e-3, 35.0, 0.0, 0.0))
    0.00098
    """
    t = np.asarray(led_temperature_c, dtype=float) - LED_REFERENCE_TEMPERATURE_C
    return np.asarray(p0_w) * (
        1.0
        - thermal_coeff_per_c * t
        - ageing_per_1000h * np.asarray(age_h) / 1000.0
        + np.asarray(flicker_rel)
    )


def led_peak_shift_nm(led_temperature_c, nm_per_c: float) -> np.ndarray:
    """Shift of the LED's peak wavelength from its 25 degC value [3]_. [nm]

    Examples
    --------
    >>> float(led_peak_shift_nm(45.0, 0.25))
    5.0
    """
    return nm_per_c * (np.asarray(led_temperature_c, dtype=float) - LED_REFERENCE_TEMPERATURE_C)


def dark_current_a(
    i25_a, temperature_c, per_c: float = DARK_CURRENT_DOUBLING_COEFF_PER_C
) -> np.ndarray:
    """Photodiode dark current I25 exp(k (T - 25)), k = 0.1 /degC (Hamamatsu [1]_). [A]

    Examples
    --------
    >>> round(float(dark_current_a(1e-10, 35.0)) * 1e10, 4)
    2.7183
    """
    t = np.asarray(temperature_c, dtype=float) - 25.0
    return np.asarray(i25_a) * pm.exp(per_c * t)


def shot_noise_sd_a(current_a, bandwidth_hz: float) -> np.ndarray:
    """Shot-noise standard deviation sqrt(2 e I BW) [2]_. [A]

    Examples
    --------
    >>> round(float(shot_noise_sd_a(1e-6, 10.0)) * 1e12, 3)
    1.79
    """
    return np.sqrt(2.0 * ELEMENTARY_CHARGE_C * np.abs(np.asarray(current_a)) * bandwidth_hz)


def johnson_noise_sd_a(temperature_c, bandwidth_hz: float, resistance_ohm: float) -> np.ndarray:
    """Johnson (thermal) noise current of a resistor, sqrt(4 k T BW / R) [2]_. [A]

    Examples
    --------
    >>> round(float(johnson_noise_sd_a(25.0, 10.0, 1e5)) * 1e12, 3)
    1.283
    """
    t_k = np.asarray(temperature_c, dtype=float) + ZERO_CELSIUS_K
    return np.sqrt(4.0 * BOLTZMANN_J_PER_K * t_k * bandwidth_hz / resistance_ohm)


def adc_inl_lsb(code, full_scale: int, inl_peak_lsb: float) -> np.ndarray:
    """Integral non-linearity as a bow, INL_peak sin(pi code / full scale). [LSB]

    A single bow with zero error at both ends is the classic INL shape of SAR
    converters after end-point calibration (Analog Devices MT-010).

    Examples
    --------
    >>> float(adc_inl_lsb(2047.5, 4095, 2.0))
    2.0
    """
    return inl_peak_lsb * pm.sin(np.pi * np.asarray(code, dtype=float) / full_scale)


_NOT_FINITE = ("the simulated ADC input is not finite: the noise settings drive the "
               "simulation outside its physical range; lower noise_scale or noise.*.scale")


def adc_convert(voltage_v, vref_v: float, bits: int, inl_peak_lsb: float, offset_lsb) -> np.ndarray:
    """Convert voltages to integer codes: round(V / Vref FS + INL + offset), clipped.

    Parameters
    ----------
    voltage_v : array_like
        Input voltage. [V]
    vref_v : float
        Full-scale voltage. [V]
    bits : int
        Resolution. [bit]
    inl_peak_lsb : float
        Peak INL. [LSB]
    offset_lsb : array_like
        Offset (drift). [LSB]

    Returns
    -------
    numpy.ndarray of int64
        Codes in [0, 2^bits - 1] (saturated outside, as a converter does).

    Examples
    --------
    >>> adc_convert(np.array([0.0, 1.65, 5.0]), 3.3, 12, 0.0, 0.0)
    array([   0, 2048, 4095])
    """
    full = 2**bits - 1
    ideal = np.asarray(voltage_v, dtype=float) / vref_v * full
    code = ideal + adc_inl_lsb(ideal, full, inl_peak_lsb) + np.asarray(offset_lsb)
    if not np.all(np.isfinite(code)):  # NaN would cast to -2^63 (issue 20)
        raise ConfigError(_NOT_FINITE)
    return np.clip(np.rint(code), 0, full).astype(np.int64)


def apply_hardware(cfg, detected_fraction_led, temps: dict, subject_index, streams, *,
                   compiled: bool = True) -> dict:
    """Hardware layer entry: ADC codes of each measurement and of the start-up reference.

    Parameters
    ----------
    cfg : ScenarioConfig
        Scenario.
    detected_fraction_led : numpy.ndarray
        Per-LED band-averaged detected fraction of the LED power at 25 degC, with the
        band already weighted by the (temperature-shifted) emission, (n, n_led). [-]
    temps : dict
        ``led_c`` (n, n_led), ``board_c`` (n,), ``age_h`` (n,), and per subject
        ``led_cal_c`` (n_sub, n_led), ``board_cal_c`` (n_sub,), ``age_cal_h`` (n_sub,);
        ``ambient_a`` (n,), ``ambient_flicker`` (n,): temperatures [degC], ages [h],
        ambient photocurrent [A] and its relative flicker [-].
    subject_index : numpy.ndarray
        Row -> subject within the block, (n,).
    streams : RandomStreams
        Random generators of the block.
    compiled : bool
        True (the default): the same operations in one compiled pass
        (:mod:`nirglucose.simulation.kernels.hardware_kernel`), the same draws, the same
        bits; False: the NumPy composition below, the reference.

    Returns
    -------
    dict
        ``adc`` and ``adc_ref`` (n, n_led) int64 codes (``adc_ref`` the start-up
        reference, or with ``device.monitor_photodiode`` the monitor reading of each
        measurement), ``signal_v`` (n, n_led) the
        noise-free analog voltage, ``detected_power_w`` (n, n_led).
    """
    if compiled:
        return _apply_hardware_compiled(cfg, detected_fraction_led, temps, subject_index,
                                        streams)
    hw = cfg.hardware
    n_sub = int(subject_index.max()) + 1 if len(subject_index) else 0
    p0 = np.asarray(cfg.leds.power_mw)[None, :] * 1e-3
    resp = np.asarray(cfg.leds.responsivity_a_per_w)[None, :]
    p_led, p_cal = _led_powers(cfg, p0, temps, n_sub, streams)
    inl = cfg.noise_factor("adc_inl") * hw.adc_inl_lsb

    # Measurement: LED power, optics, photocurrent, front end, conversion.
    detected_power_w = p_led * detected_fraction_led
    dark_now, i_dark_residual = _dark_currents_a(cfg, temps, subject_index)
    voltage = _measurement_voltage_v(
        cfg, resp * detected_power_w, dark_now, i_dark_residual, temps, streams
    )
    offset = _offset_lsb(cfg, temps["board_c"])
    adc = adc_convert(voltage, hw.adc_vref_v, hw.adc_bits, inl,
                      offset + _read_noise_lsb(cfg, voltage.shape, streams))

    adc_ref = _reference_codes(cfg, resp * p_cal, temps, inl, streams)[subject_index]
    if cfg.device.monitor_photodiode:
        adc_ref = _monitor_codes(
            cfg, resp * p_led, (dark_now, i_dark_residual), offset, inl, temps, streams
        )
    signal_v = resp * (p0 * detected_fraction_led) * hw.tia_gain_ohm
    return {
        "adc": adc,
        "adc_ref": adc_ref,
        "signal_v": signal_v,
        "voltage_v": voltage,
        "detected_power_w": detected_power_w,
    }


def _apply_hardware_compiled(cfg, fraction, temps: dict, subject_index, streams) -> dict:
    """:func:`apply_hardware` through the compiled kernels: the reference's draws, in its
    order, then one pass over the readings and one over the start-up references."""
    from .kernels import hardware_kernel as hk

    n, n_led = np.shape(fraction)
    n_sub = int(subject_index.max()) + 1 if len(subject_index) else 0
    monitor = bool(cfg.device.monitor_photodiode)
    read_sd = np.asarray([e.read_noise_lsb for e in cfg.leds.emitters])
    read = bool(np.any(read_sd > 0))

    def normal(name, rows):
        return streams(name).normal(size=(rows, n_led))

    z_flicker, z_flicker_cal = normal("led_flicker", n), normal("led_flicker.cal", n_sub)
    z = [normal(name, n) for name in ("ambient_light", "shot", "johnson")]
    z_read = normal("read_noise", n) if read else z[1]
    z_cal = [normal(name, n_sub) for name in ("shot.cal", "johnson.cal")]
    z_mon = [normal(name, n) for name in ("monitor.shot", "monitor.johnson")] if monitor else z[1:]
    k, led = _front_end_constants(cfg, n_led, read, monitor)
    f64 = np.float64
    signal_v, voltage_v, power_w, offset, monitor_v = (
        np.empty((n, n_led) if m else (0, n_led)) for m in (1, 1, 1, 1, monitor))
    hk.reading_voltages(
        np.asarray(fraction, f64), temps["led_c"], np.asarray(temps["age_h"], f64),
        np.asarray(temps["board_c"], f64), np.asarray(temps["board_cal_c"], f64),
        subject_index, np.asarray(temps["ambient_a"], f64),
        np.asarray(temps["ambient_flicker"], f64), (z_flicker, *z, z_read, *z_mon), led, k,
        signal_v, voltage_v, power_w, offset, monitor_v)
    v_ref, offset_ref = np.empty((n_sub, n_led)), np.empty((n_sub, n_led))
    hk.reference_voltages(np.asarray(temps["led_cal_c"], f64), np.asarray(temps["age_cal_h"], f64),
                          np.asarray(temps["board_cal_c"], f64), z_flicker_cal, *z_cal, led, k,
                          v_ref, offset_ref)
    adc, ref = np.empty((n, n_led), np.int64), np.empty((n_sub, n_led), np.int64)
    ok = hk.convert(voltage_v.ravel(), offset.ravel(), k, adc.ravel())
    ok &= hk.convert(v_ref.ravel(), offset_ref.ravel(), k, ref.ravel())
    if monitor:  # the monitor's offset: the row's, without the read noise
        adc_monitor = np.empty((n, n_led), np.int64)
        offset_mon = np.repeat(k.offset_per_c * (np.asarray(temps["board_c"], f64)
                                                  - LED_REFERENCE_TEMPERATURE_C), n_led)
        ok &= hk.convert(monitor_v.ravel(), offset_mon, k, adc_monitor.ravel())
    if not ok:
        raise ConfigError(_NOT_FINITE)
    return {
        "adc": adc,
        "adc_ref": adc_monitor if monitor else ref[subject_index],
        "signal_v": signal_v,
        "voltage_v": voltage_v,
        "detected_power_w": power_w,
    }


#: :func:`_front_end_constants` of the scenarios seen last, by identity (each entry holds
#: its scenario, a frozen model, so the identity stays its own while cached).
_CONSTANTS: dict = {}


def _front_end_constants(cfg, n_led: int, read: bool, monitor: bool):
    """The kernels' scalars (:class:`~nirglucose.simulation.kernels.hardware_kernel.
    FrontEnd`) and per-LED rows (P0, responsivity, ageing, flicker x factor, read-noise SD
    x scale), each computed as the NumPy reference computes it; once per scenario."""
    key = (id(cfg), n_led, read, monitor)
    hit = _CONSTANTS.get(key)
    if hit is not None and hit[0] is cfg:
        return hit[1]
    if len(_CONSTANTS) >= 64:
        _CONSTANTS.clear()
    _CONSTANTS[key] = (cfg, _compute_front_end_constants(cfg, n_led, read, monitor))
    return _CONSTANTS[key][1]


def _compute_front_end_constants(cfg, n_led: int, read: bool, monitor: bool):
    """:func:`_front_end_constants`, computed."""
    from .kernels.hardware_kernel import FrontEnd

    hw = cfg.hardware
    ageing = hw.led_ageing_per_1000h * cfg.noise_factor("led_ageing")
    if any(e.ageing_per_1000h is not None for e in cfg.leds.emitters):
        ageing = (np.asarray(cfg.leds.ageings(hw.led_ageing_per_1000h))[None, :]
                  * cfg.noise_factor("led_ageing"))
    rel = hw.led_flicker_rel
    if any(e.flicker_rel is not None for e in cfg.leds.emitters):
        rel = np.asarray(cfg.leds.flicker_rels(hw.led_flicker_rel))[None, :]
    rows = (np.asarray(cfg.leds.power_mw)[None, :] * 1e-3,
            np.asarray(cfg.leds.responsivity_a_per_w)[None, :], ageing,
            rel * cfg.noise_factor("led_flicker"),
            cfg.noise_scale * np.asarray([e.read_noise_lsb for e in cfg.leds.emitters])[None, :])
    led = np.ascontiguousarray(np.vstack([np.broadcast_to(np.asarray(r, dtype=np.float64),
                                                          (1, n_led)) for r in rows]))
    k = FrontEnd(
        hw.led_thermal_coeff_per_c * cfg.noise_factor("led_thermal_drift"),
        hw.dark_current_25c_na * 1e-9, float(hw.dark_current_per_c),
        cfg.noise_factor("dark_current"), cfg.noise_factor("ambient_light"),
        1.0 - hw.ambient_rejection, cfg.noise_factor("shot"), 2.0 * ELEMENTARY_CHARGE_C,
        float(hw.bandwidth_hz), cfg.noise_factor("johnson"), 4.0 * BOLTZMANN_J_PER_K,
        float(johnson_resistance_ohm(cfg)), float(hw.tia_gain_ohm),
        cfg.noise_factor("adc_offset_drift") * cfg.hardware.adc_offset_drift_lsb_per_c,
        float(hw.adc_vref_v), float(2**hw.adc_bits - 1),
        cfg.noise_factor("adc_inl") * hw.adc_inl_lsb, float(hw.reference_transmission),
        float(read), float(monitor),
    )
    return FrontEnd(*(float(x) for x in k)), led


def _dark_currents_a(cfg, temps: dict, subject_index):
    """Dark current of each reading, and its residual after the start-up cancellation.

    The offset-cancellation current nulls the dark current at the subject's start-up
    board temperature; what remains is the change since then (Hamamatsu [1]_). [A]
    """
    hw = cfg.hardware
    i25 = hw.dark_current_25c_na * 1e-9
    dark_now = dark_current_a(i25, temps["board_c"], hw.dark_current_per_c)[:, None]
    dark_cal = dark_current_a(i25, temps["board_cal_c"][subject_index], hw.dark_current_per_c)[
        :, None
    ]
    return dark_now, cfg.noise_factor("dark_current") * (dark_now - dark_cal)


def _measurement_voltage_v(cfg, i_sig, dark_now, i_dark_residual, temps: dict, streams):
    """TIA output of each reading: signal, dark residual, ambient residual and noise. [V]

    The LED-off reading removes the ambient photocurrent except its flicker between the
    two readings; the ambient current still adds shot noise (Horowitz & Hill [2]_).
    """
    hw = cfg.hardware
    i_amb = cfg.noise_factor("ambient_light") * temps["ambient_a"][:, None]
    amb_residual = (
        i_amb
        * (1.0 - hw.ambient_rejection)
        * temps["ambient_flicker"][:, None]
        * streams("ambient_light").normal(size=i_sig.shape)
    )
    shot, johnson = _front_end_noise_a(
        cfg, i_sig + dark_now + i_amb, temps["board_c"], ("shot", "johnson"), streams
    )
    return (i_sig + i_dark_residual + amb_residual + shot + johnson) * hw.tia_gain_ohm


def _reference_codes(cfg, i_ref_signal_a, temps: dict, inl: float, streams) -> np.ndarray:
    """ADC codes of each subject's start-up reference, (n_sub, n_led).

    The same LED through a neutral attenuator of known transmission, no tissue; the
    ``*_cal_*`` temperatures are per subject. Its own shot and Johnson noise
    (Horowitz & Hill [2]_) and conversion at the start-up board temperature.
    """
    hw = cfg.hardware
    i_ref = i_ref_signal_a * hw.reference_transmission
    i25 = hw.dark_current_25c_na * 1e-9
    dark_cal_sub = dark_current_a(i25, temps["board_cal_c"], hw.dark_current_per_c)[:, None]
    shot_ref, johnson_ref = _front_end_noise_a(
        cfg, i_ref + dark_cal_sub, temps["board_cal_c"], ("shot.cal", "johnson.cal"), streams
    )
    v_ref = (i_ref + shot_ref + johnson_ref) * hw.tia_gain_ohm
    offset_ref = _offset_lsb(cfg, temps["board_cal_c"])
    return adc_convert(v_ref, hw.adc_vref_v, hw.adc_bits, inl, offset_ref)


def _monitor_codes(cfg, i_led_signal_a, dark, offset, inl: float, temps: dict, streams):
    """ADC codes of a monitor photodiode at each reading, (n, n_led).

    It reads the same LED pulse through the reference path's attenuation: the LED power
    of this reading (drift, ageing, flicker included), with the monitor's own
    dark-current residual, shot and Johnson noise (Horowitz & Hill [2]_) and its own
    conversion (quantisation, INL, offset at this board temperature). ``dark`` is
    (dark current now, its residual) of :func:`_dark_currents_a`, in A.
    """
    hw = cfg.hardware
    dark_now, i_dark_residual = dark
    i_mon = i_led_signal_a * hw.reference_transmission
    shot_mon, johnson_mon = _front_end_noise_a(
        cfg, i_mon + dark_now, temps["board_c"], ("monitor.shot", "monitor.johnson"), streams
    )
    v_mon = (i_mon + i_dark_residual + shot_mon + johnson_mon) * hw.tia_gain_ohm
    return adc_convert(v_mon, hw.adc_vref_v, hw.adc_bits, inl, offset)


def _read_noise_lsb(cfg, shape: tuple[int, ...], streams):
    """Each channel's extra temporal noise (``leds.emitters.<i>.read_noise_lsb``, EMVA 1288
    temporal dark noise), drawn per reading and scaled by ``noise_scale``; 0.0 (no draw,
    no stream) where every LED leaves it at 0. [LSB]"""
    sd = np.asarray([e.read_noise_lsb for e in cfg.leds.emitters])
    if not np.any(sd > 0):
        return 0.0
    return cfg.noise_scale * sd[None, :] * streams("read_noise").normal(size=shape)


def _led_powers(cfg, p0, temps: dict, n_sub: int, streams):
    """LED power of each reading and of each subject's start-up reference. [W]"""
    hw = cfg.hardware
    n_led = p0.shape[1]
    f_flicker = cfg.noise_factor("led_flicker")
    thermal = hw.led_thermal_coeff_per_c * cfg.noise_factor("led_thermal_drift")
    ageing = hw.led_ageing_per_1000h * cfg.noise_factor("led_ageing")
    if any(e.ageing_per_1000h is not None for e in cfg.leds.emitters):  # presets: scalar
        ageing = (np.asarray(cfg.leds.ageings(hw.led_ageing_per_1000h))[None, :]
                  * cfg.noise_factor("led_ageing"))
    n = len(temps["age_h"])
    rel = hw.led_flicker_rel
    if any(e.flicker_rel is not None for e in cfg.leds.emitters):  # presets: scalar, same bits
        rel = np.asarray(cfg.leds.flicker_rels(hw.led_flicker_rel))[None, :]
    flicker = rel * f_flicker * streams("led_flicker").normal(size=(n, n_led))
    flicker_cal = rel * f_flicker * streams("led_flicker.cal").normal(size=(n_sub, n_led))
    powers = (
        led_power_w(
            p0,
            temps[f"led{cal}_c"],
            temps[f"age{cal}_h"][:, None],
            draws,
            thermal_coeff_per_c=thermal,
            ageing_per_1000h=ageing,
        )
        for cal, draws in (("", flicker), ("_cal", flicker_cal))
    )
    return tuple(powers)


def _front_end_noise_a(cfg, shot_current_a, board_c, stream_names, streams):
    """Shot noise of a photocurrent and the TIA resistor's Johnson noise, drawn. [A]"""
    hw = cfg.hardware
    size = np.shape(shot_current_a)
    shot = cfg.noise_factor("shot") * shot_noise_sd_a(shot_current_a, hw.bandwidth_hz)
    shot = shot * streams(stream_names[0]).normal(size=size)
    johnson = (
        cfg.noise_factor("johnson")
        * johnson_noise_sd_a(board_c[:, None], hw.bandwidth_hz, johnson_resistance_ohm(cfg))
        * streams(stream_names[1]).normal(size=size)
    )
    return shot, johnson


def johnson_resistance_ohm(cfg) -> float:
    """Resistance whose Johnson noise the front end adds: the feedback resistor R_f, in
    parallel with the detector's shunt resistance R_sh where ``cfg.detector`` states one,
    R_f R_sh / (R_f + R_sh) (the noise currents of the two add in power, Hamamatsu
    "Si photodiodes" technical note [1]_; Horowitz & Hill [2]_). [Ohm]

    Examples
    --------
    >>> from nirglucose.config import resolve_config
    >>> johnson_resistance_ohm(resolve_config("paper"))
    100000.0
    >>> round(johnson_resistance_ohm(resolve_config("paper", {"detector": "G17190-010K"})))
    99920
    """
    r_f = cfg.hardware.tia_gain_ohm
    det = cfg.detector
    if det is None or det.shunt_resistance_mohm is None:
        return r_f
    r_sh = det.shunt_resistance_mohm * 1e6
    return r_f * r_sh / (r_f + r_sh)


def _offset_lsb(cfg, board_c) -> np.ndarray:
    """ADC offset drift from its 25 degC calibration at a board temperature. [LSB]"""
    return (
        cfg.noise_factor("adc_offset_drift")
        * cfg.hardware.adc_offset_drift_lsb_per_c
        * (board_c[:, None] - LED_REFERENCE_TEMPERATURE_C)
    )
