"""The simulator facade: the only place that knows the order of the layers.

environment -> glucose -> physiology (traits, state) -> contact -> optics -> hardware
-> measurement. Work is done per block of subjects (:data:`BLOCK_SUBJECTS`) with its
own random streams, so the output is the same whatever the chunking or the number of
workers.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass, replace

import numpy as np
import pandas as pd

from .. import portable as pm
from ..config import ReferenceTissue, ScenarioConfig
from ..constants import MGDL_PER_MMOLL_GLUCOSE
from ..optics import absorption, forward, tissue
from . import _random, contact, environment, hardware, measurement, physiology
from ._random import RandomStreams
from .glucose import sample_glucose

__all__ = [
    "block_ranges",
    "simulate_block",
    "iter_blocks",
    "simulate_frame",
    "nominal_tissue",
    "detected_fraction_given_glucose",
    "true_tissue_state",
    "scenario_band_spectra",
    "water_temperature_delta_c",
]

@dataclass(frozen=True)
class _Tables:
    spectra: tissue.BandSpectra
    geometry: np.ndarray
    lut: object = None  # the rte-lut model's table, specialised to the band nodes


def scenario_band_spectra(cfg: ScenarioConfig) -> tissue.BandSpectra:
    """The chromophore tables over the scenario's LED bands."""
    return tissue.band_spectra(
        cfg.leds.wavelengths_nm,
        cfg.leds.fwhm_nm,
        cfg.leds.band_points,
        cfg.optics.water_source,
        cfg.glucose.absorptivity_per_cm_per_mm,
        glucose_first_overtone_relative_peak=cfg.glucose.first_overtone_relative_peak,
        water_temperature_scale=cfg.noise_factor("water_temperature"),
    )


def water_temperature_delta_c(cfg: ScenarioConfig, skin_temp_c) -> np.ndarray | None:
    """The tissue water's temperature minus its table's, per reading, or None when off.

    The ``water_temperature`` switch takes the tissue water at the skin temperature
    (``true_skin_temp_c``, an assumption: the dermis the light samples is taken to be at
    the skin's temperature) and water's absorption at that temperature,
    mua + s d(mua)/dT (T_skin - T_table) (Röttgers et al., Opt. Express 22, 25093 (2014);
    :func:`nirglucose.optics.absorption.water_mua_at_temperature_per_cm`), s the switch's
    factor (in the spectra's ``water_dt`` table) and T_table the water table's
    temperature (:data:`~nirglucose.optics.absorption.WATER_TABLE_TEMPERATURE_C`).

    Parameters
    ----------
    cfg : ScenarioConfig
        Scenario (its ``noise.water_temperature`` switch and ``optics.water_source``).
    skin_temp_c : array_like
        Skin temperature per reading. [degC]

    Returns
    -------
    numpy.ndarray or None
        T_skin - T_table per reading [degC]; None when the switch is off (factor 0).
    """
    if cfg.noise_factor("water_temperature") == 0.0:
        return None
    t_table = absorption.WATER_TABLE_TEMPERATURE_C[cfg.optics.water_source]
    return np.asarray(skin_temp_c, dtype=float) - t_table


def _tables(cfg: ScenarioConfig) -> _Tables:
    spectra = scenario_band_spectra(cfg)
    ref = cfg.optics.reference_tissue
    # the reference skin at the thermoneutral skin temperature (physiology.skin_temp_c_neutral)
    nominal = replace(nominal_tissue(1, ref), water_temperature_delta_c=water_temperature_delta_c(
        cfg, np.full(1, cfg.physiology.skin_temp_c_neutral)))
    optics = tissue.tissue_optics(
        spectra,
        nominal,
        water_displacement_per_mm=0.0,
        scattering_rel_per_mm=0.0,
    )
    sep_cm = cfg.optics.source_detector_mm / 10.0
    mua, musp, _ = forward.mixed_optics(optics, np.array([ref.skin_thickness_mm / 10.0]), sep_cm)
    geometry = forward.geometry_factor(
        mua[0],
        musp[0],
        sep_cm,
        cfg.optics.detector_area_mm2 / 100.0,
        cfg.optics.tissue_refractive_index,
    )
    lut = None
    if cfg.optics.model == "rte-lut":
        lut = _node_tables(cfg, spectra, optics["musp_subcutis"][0] / optics["musp_dermis"][0])
    return _Tables(spectra, geometry, lut)


def _node_tables(cfg: ScenarioConfig, spectra, ratio: np.ndarray):
    """The ``rte-lut`` model's node table: one for all LEDs where one grid covers their
    bands, else a tuple with one per LED (``optics.lut_grid = "auto"``: bands on both
    sides of 1320 nm; :func:`~nirglucose.optics.lut.lut_grids_for_bands`)."""
    from ..optics import lut as lut_mod

    named: str | None = cfg.optics.lut_grid
    if named == "auto":
        named = lut_mod.lut_grid_named_in_env()
    grids = (named,) * len(ratio) if named else lut_mod.lut_grids_for_bands(spectra.nodes_nm)

    def table(name: str, q: np.ndarray):
        return lut_mod.node_lut(lut_mod.get_lut(
            cfg.optics.source_detector_mm / 10.0, cfg.optics.epidermis_thickness_mm / 10.0,
            cfg.optics.tissue_refractive_index, grid=name, solver=cfg.optics.lut_solver), q)

    if len(set(grids)) == 1:
        return table(grids[0], ratio)
    return tuple(table(name, ratio[i:i + 1]) for i, name in enumerate(grids))


#: Rows per optics slice: the (rows, n_led, n_points) temporaries then fit in the
#: CPU cache, which makes the memory-bound array arithmetic several times faster.
_OPTICS_SLICE_ROWS = 4096


def _band_detected_fraction(cfg, tables, state, melanin, thickness_mm, shift_nm) -> np.ndarray:
    """Detected fraction per LED, integrated over each emission band, (n, n_led).

    By ``optics.model``: the compiled Beer–Lambert pass (the default), the compiled
    layer optics with the RTE table, or any other forward model slice by slice.
    """
    n = len(melanin)
    n_led = len(cfg.leds.wavelengths_nm)
    shift = np.broadcast_to(np.asarray(shift_nm, dtype=float), (n, n_led))
    if cfg.optics.model == "beer-lambert":
        return _band_beer_lambert(cfg, tables, state, melanin, thickness_mm, shift)
    if cfg.optics.model == "rte-lut":
        return _band_rte_lut(cfg, tables, state, melanin, thickness_mm, shift)
    return _band_forward_model(cfg, tables, state, melanin, thickness_mm, shift)


def _band_beer_lambert(cfg, tables, state, melanin, thickness_mm, shift) -> np.ndarray:
    """The default optics in one compiled pass over rows, LEDs and band points."""
    from ..optics.kernels.band_kernel import band_detected_fraction

    return band_detected_fraction(
        tables.spectra,
        state,
        shift_nm=shift,
        melanin_fraction=melanin,
        skin_thickness_cm=thickness_mm / 10.0,
        epidermis_thickness_cm=cfg.optics.epidermis_thickness_mm / 10.0,
        separation_cm=cfg.optics.source_detector_mm / 10.0,
        geometry_factor=tables.geometry,
        water_displacement_per_mm=cfg.glucose.water_displacement_per_mm,
        scattering_rel_per_mm=cfg.glucose.scattering_rel_per_mm,
    )


def _band_rte_lut(cfg, tables, state, melanin, thickness_mm, shift) -> np.ndarray:
    """Layer optics compiled, then the RTE table kernel."""
    from ..optics.kernels.band_kernel import band_detected_fraction_lut

    return band_detected_fraction_lut(
        tables.spectra,
        state,
        shift_nm=shift,
        melanin_fraction=melanin,
        skin_thickness_cm=thickness_mm / 10.0,
        node_lut=tables.lut,
        detector_area_cm2=cfg.optics.detector_area_mm2 / 100.0,
        water_displacement_per_mm=cfg.glucose.water_displacement_per_mm,
        scattering_rel_per_mm=cfg.glucose.scattering_rel_per_mm,
    )


_STATE_FIELDS = ("blood_fraction", "saturation", "water_fraction", "subcutis_fat_fraction",
                 "glucose_mm", "water_temperature_delta_c")


def _band_forward_model(cfg, tables, state, melanin, thickness_mm, shift) -> np.ndarray:
    """Any forward model of :mod:`~nirglucose.optics.forward`, :data:`_OPTICS_SLICE_ROWS`
    rows at a time, the band integral as an ordered weighted sum per slice."""
    n, n_led = shift.shape
    out = np.empty((n, n_led))
    # band integral: sum over each LED's band nodes, in node order (no BLAS: the same
    # bits on every CPU, see nirglucose.portable)
    w = tables.spectra.weights
    for lo in range(0, n, _OPTICS_SLICE_ROWS):
        sl = slice(lo, min(lo + _OPTICS_SLICE_ROWS, n))
        part = tissue.TissueState(*(None if getattr(state, f) is None
                                    else np.asarray(getattr(state, f))[sl]
                                    for f in _STATE_FIELDS))
        optics = tissue.tissue_optics(
            tables.spectra,
            part,
            water_displacement_per_mm=cfg.glucose.water_displacement_per_mm,
            scattering_rel_per_mm=cfg.glucose.scattering_rel_per_mm,
            shift_nm=shift[sl],
        )
        nodes = forward.detected_fraction(
            cfg.optics.model,
            optics,
            melanin_fraction=melanin[sl],
            skin_thickness_cm=thickness_mm[sl] / 10.0,
            epidermis_thickness_cm=cfg.optics.epidermis_thickness_mm / 10.0,
            separation_cm=cfg.optics.source_detector_mm / 10.0,
            detector_area_cm2=cfg.optics.detector_area_mm2 / 100.0,
            n_tissue=cfg.optics.tissue_refractive_index,
            geometry_factor=tables.geometry,
            lut=tables.lut,
        )
        out[sl] = pm.dot_last(nodes.reshape(nodes.shape[0], n_led, -1), w)
    return out


def nominal_tissue(n: int, ref: ReferenceTissue) -> tissue.TissueState:
    """The reference tissue composition (``optics.reference_tissue``) repeated ``n`` times."""
    return tissue.TissueState(
        *(
            np.full(n, v)
            for v in (
                ref.blood_fraction,
                ref.saturation,
                ref.water_fraction,
                ref.subcutis_fat_fraction,
                ref.glucose_mm,
            )
        )
    )


def block_ranges(n_subjects: int, block_subjects: int | None = None):
    """``(block, first_subject, n_subjects_in_block)`` for every block."""
    block_subjects = block_subjects or _random.BLOCK_SUBJECTS
    return [
        (b, start, min(block_subjects, n_subjects - start))
        for b, start in enumerate(range(0, n_subjects, block_subjects))
    ]


def simulate_block(
    cfg: ScenarioConfig,
    seed: int,
    block: int,
    first_subject: int,
    n_sub: int,
    per_subject: int,
    tables: _Tables | None = None,
) -> tuple[dict, int]:
    """Simulate one block of subjects; returns ``(columns, n_random_variates)``.

    Orders the layers (each draws from its own named streams of the block):
    glucose, environment, physiology, measurement, contact, LED temperatures and ages,
    optics, ambient light, hardware, PPG.
    """
    tables = _tables(cfg) if tables is None else tables
    streams = RandomStreams(seed, block)
    n = n_sub * per_subject
    rep = np.repeat(np.arange(n_sub), per_subject)
    first = np.arange(0, n, per_subject)

    glucose = sample_glucose(cfg, n_sub, per_subject, streams)
    env = environment.apply_environment(cfg, n_sub, per_subject, streams)
    traits = physiology.sample_traits(cfg, n_sub, streams)
    traits_rows = {k: v[rep] for k, v in traits.items()}
    phys = physiology.apply_physiology(cfg, traits_rows, env, glucose, n, streams)
    pmf = measurement.measure_physiology(cfg, {**phys, **env}, streams)
    probe = contact.apply_contact(cfg, phys, env, pmf, streams)

    temps = hardware.led_temperatures_c(
        cfg, env["true_ambient_temperature_c"], phys["true_skin_temp_c"], first, streams
    )
    temps.update(hardware.led_ages_h(cfg, rep, n_sub, streams))
    shift_nm, fraction = _optics_layer(cfg, tables, glucose, phys, probe, temps)
    temps["ambient_a"], temps["ambient_flicker"] = environment.ambient_at_probe(cfg, env)
    hwout = hardware.apply_hardware(cfg, fraction, temps, rep, streams)
    if cfg.device.ppg_perfusion_spo2:
        pmf.update(
            measurement.measure_ppg(
                cfg, probe["true_blood_fraction_detected"], phys["true_saturation"], streams
            )
        )
    ids = {
        "subject_id": (first_subject + rep).astype(np.int64),
        "measurement_id": (first_subject * per_subject + np.arange(n)).astype(np.int64),
    }
    truth = {**phys, **env, **probe, **_hidden(glucose, temps)}
    cols = _columns(cfg, ids, glucose, hwout, pmf, env, truth, fraction, shift_nm)
    return cols, streams.n_variates


def _optics_layer(cfg, tables, glucose: dict, phys: dict, probe: dict, temps: dict):
    """The optics layer: LED peak shifts [nm] and the coupled detected fraction [-].

    The LED peaks shift with junction temperature (``led_c``); the tissue under the
    probe (its detected blood, the subject's saturation, water and fat, the glucose
    scaled by ``glucose.signal_gain``, the water at the skin temperature where
    ``noise.water_temperature`` is on: :func:`water_temperature_delta_c`) is seen
    through each shifted band, and the probe's coupling scales the result, (n, n_led).
    """
    shift_nm = cfg.noise_factor("led_wavelength_shift") * hardware.led_peak_shift_nm(
        temps["led_c"], cfg.hardware.led_wavelength_shift_nm_per_c
    )
    water_dt = water_temperature_delta_c(cfg, phys["true_skin_temp_c"])

    def state(gain: float) -> tissue.TissueState:
        return tissue.TissueState(
            probe["true_blood_fraction_detected"],
            phys["true_saturation"],
            phys["true_water_fraction"],
            phys["true_subcutis_fat_fraction"],
            gain * glucose["glucose_mgdl"] / MGDL_PER_MMOLL_GLUCOSE,
            water_dt,
        )

    fraction = (
        _fraction_per_gain(
            cfg,
            tables,
            state,
            phys["true_melanin_fraction"],
            probe["true_skin_thickness_probe_mm"],
            shift_nm,
        )
        * probe["true_coupling"][:, None]
    )
    return shift_nm, fraction


def _fraction_per_gain(cfg, tables, state, melanin, thickness_mm, shift_nm) -> np.ndarray:
    """Detected fraction per LED with each LED's glucose gain, (n, n_led). [-]

    ``state(gain)`` is the tissue with glucose scaled by ``gain``. One optics pass at
    ``glucose.signal_gain`` where no LED sets its own ``glucose_gain`` (the presets:
    unchanged bytes), else one pass per distinct gain, each LED's column taken from the
    pass at its gain.
    """
    signal_gain = cfg.glucose.signal_gain
    if all(e.glucose_gain is None for e in cfg.leds.emitters):
        return _band_detected_fraction(cfg, tables, state(signal_gain), melanin, thickness_mm,
                                       shift_nm)
    gains = np.asarray(cfg.leds.glucose_gains(signal_gain))
    out = None
    for gain in sorted(set(gains.tolist())):
        part = _band_detected_fraction(cfg, tables, state(gain), melanin, thickness_mm, shift_nm)
        out = part if out is None else np.where(gains[None, :] == gain, part, out)
    return out


def _hidden(glucose: dict, temps: dict) -> dict:
    """The scalar ``true_*`` columns of the glucose and hardware layers."""
    return {
        "true_led_temperature_c": temps["led_c"].mean(axis=1),
        "true_board_temperature_c": temps["board_c"],
        "true_hours_since_meal": glucose["true_hours_since_meal"],
        "true_stress": glucose["true_stress"],
        "true_hour_of_day": glucose["true_hour_of_day"],
    }


def _columns(
    cfg, ids: dict, glucose: dict, hwout: dict, pmf: dict, env: dict, truth: dict,
    fraction: np.ndarray, shift_nm: np.ndarray,
):
    """The dataset's columns in their fixed order: ids, target, codes, PMF, truths (sorted).

    ``fraction`` and ``shift_nm`` (the optics layer's detected fraction and LED peak
    shifts, (n, n_led)) become per-LED ``true_*`` columns beside ``hwout``'s voltages.
    """
    wl = [f"{w:g}" for w in cfg.leds.wavelengths_nm]
    cols: dict[str, np.ndarray] = {
        **ids,
        "glucose_mgdl": glucose["glucose_mgdl"],
        "diabetes_status": glucose["diabetes_status"],
    }
    for i, w in enumerate(wl):
        cols[f"adc_{w}"] = hwout["adc"][:, i]
    for i, w in enumerate(wl):
        cols[f"adc_ref_{w}"] = hwout["adc_ref"][:, i]
    cols.update(pmf)
    cols["ambient_lux"] = env["true_ambient_lux"]
    shift = np.broadcast_to(shift_nm, fraction.shape)
    for i, w in enumerate(wl):
        truth[f"true_detected_fraction_{w}"] = fraction[:, i]
        truth[f"true_led_shift_nm_{w}"] = shift[:, i]
        truth[f"true_signal_v_{w}"] = hwout["signal_v"][:, i]
        truth[f"true_voltage_v_{w}"] = hwout["voltage_v"][:, i]
    cols.update(dict(sorted(truth.items())))
    return cols


def iter_blocks(
    cfg: ScenarioConfig, n_subjects: int, per_subject: int, seed: int
) -> Iterator[pd.DataFrame]:
    """Yield the dataset block by block (bounded memory)."""
    tables = _tables(cfg)
    for block, start, n_sub in block_ranges(n_subjects):
        cols, _ = simulate_block(cfg, seed, block, start, n_sub, per_subject, tables)
        yield pd.DataFrame(cols)


def simulate_frame(
    cfg: ScenarioConfig, n_subjects: int, per_subject: int, seed: int, n_jobs: int = 1
) -> pd.DataFrame:
    """The whole dataset as one DataFrame; ``n_jobs`` > 1 simulates blocks in parallel."""
    blocks = block_ranges(n_subjects)
    if n_jobs == 1 or len(blocks) == 1:
        frames = list(iter_blocks(cfg, n_subjects, per_subject, seed))
    else:
        from joblib import Parallel, delayed

        tables = _tables(cfg)
        results = Parallel(n_jobs=n_jobs)(
            delayed(simulate_block)(cfg, seed, b, s, k, per_subject, tables) for b, s, k in blocks
        )
        frames = [pd.DataFrame(cols) for cols, _ in results]
    return pd.concat(frames, ignore_index=True) if len(frames) > 1 else frames[0]


def true_tissue_state(cfg: ScenarioConfig, frame: pd.DataFrame,
                      glucose_mgdl: np.ndarray, gain: float | None = None) -> tissue.TissueState:
    """The tissue composition of each row (its ``true_*`` columns), with ``glucose_mgdl``
    in place of the row's glucose, scaled as the simulator scales it
    (``gain``, by default ``glucose.signal_gain``), and the water at the row's
    ``true_skin_temp_c`` where ``noise.water_temperature`` is on, for
    :func:`nirglucose.optics.tissue.tissue_optics`."""
    gain = cfg.glucose.signal_gain if gain is None else gain
    dt = None
    if cfg.noise_factor("water_temperature") != 0.0:
        dt = water_temperature_delta_c(cfg, frame["true_skin_temp_c"].to_numpy(float))
    return tissue.TissueState(
        frame["true_blood_fraction_detected"].to_numpy(float),
        frame["true_saturation"].to_numpy(float),
        frame["true_water_fraction"].to_numpy(float),
        frame["true_subcutis_fat_fraction"].to_numpy(float),
        gain * np.asarray(glucose_mgdl, float) / MGDL_PER_MMOLL_GLUCOSE,
        dt,
    )


def detected_fraction_given_glucose(
    cfg: ScenarioConfig,
    frame: pd.DataFrame,
    glucose_mgdl: np.ndarray,
    tables: _Tables | None = None,
) -> np.ndarray:
    """Noise-free detected fraction for each row's true nuisance state and any glucose.

    Re-runs the optical forward model with the row's ``true_*`` tissue composition,
    probe thickness, LED shift and coupling, but with ``glucose_mgdl`` in place of the
    row's glucose. Used by the oracle estimator; it reads ``true_*`` columns.

    Parameters
    ----------
    cfg : ScenarioConfig
        The scenario that generated ``frame``.
    frame : pandas.DataFrame
        Rows with the ``true_*`` columns of a simulated dataset.
    glucose_mgdl : numpy.ndarray
        Glucose per row, (n,). [mg/dL]
    tables : optional
        The scenario's precomputed tables (``_tables(cfg)``), for callers that call
        this repeatedly with one scenario; computed when omitted.

    Returns
    -------
    numpy.ndarray
        (n, n_led) fraction of LED power detected. [-]
    """
    tables = _tables(cfg) if tables is None else tables
    wl = [f"{w:g}" for w in cfg.leds.wavelengths_nm]
    shift = frame[[f"true_led_shift_nm_{w}" for w in wl]].to_numpy(float)
    fraction = _fraction_per_gain(
        cfg,
        tables,
        lambda gain: true_tissue_state(cfg, frame, glucose_mgdl, gain),
        frame["true_melanin_fraction"].to_numpy(float),
        frame["true_skin_thickness_probe_mm"].to_numpy(float),
        shift,
    )
    return fraction * frame["true_coupling"].to_numpy(float)[:, None]
