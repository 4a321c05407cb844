"""The simulator facade: the only place that knows the order of the layers.

glucose, environment -> physiology (traits, state) -> measured physiology -> contact
-> LED temperatures and ages -> optics -> ambient light -> hardware -> PPG. The layer
engine (:func:`measure_readings`) runs the layers from physiology on, in that order, for
the snapshot simulator here (:func:`simulate_block`) and the worn one
(:mod:`nirglucose.simulation.wear`), which differ only in how they draw glucose, the
environment and the traits over time. Work is done per block of subjects
(:data:`BLOCK_SUBJECTS`) with its own random streams, so the output is the same whatever
the chunking or the number of workers.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from dataclasses import dataclass, field, replace

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
    "Readings",
    "measure_readings",
    "ScenarioTables",
    "scenario_tables",
    "iter_blocks",
    "simulate_frame",
    "nominal_tissue",
    "detected_fraction_given_glucose",
    "true_tissue_state",
    "scenario_band_spectra",
    "water_temperature_delta_c",
]

@dataclass(frozen=True)
class ScenarioTables:
    """A scenario's precomputed optics (band spectra, geometry factor, look-up table),
    shared by every block of a run and passed to its workers."""

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


def scenario_tables(cfg: ScenarioConfig) -> ScenarioTables:
    """The scenario's precomputed optics (:class:`ScenarioTables`), once per run."""
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
    return ScenarioTables(spectra, geometry, lut)


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
    tables: ScenarioTables | None = None,
) -> tuple[dict, int]:
    """Simulate one block of subjects' snapshots; returns ``(columns, n_random_variates)``.

    Draws what happens to the block's people (glucose, environment, physiological
    traits), each from its own named streams of the block, and hands the readings to
    the layer engine (:func:`measure_readings`), which orders every later layer.
    """
    tables = scenario_tables(cfg) if tables is None else tables
    streams = RandomStreams(seed, block)
    n = n_sub * per_subject
    rep = np.repeat(np.arange(n_sub), per_subject)

    glucose = sample_glucose(cfg, n_sub, per_subject, streams)
    env = environment.apply_environment(cfg, n_sub, per_subject, streams)
    traits = physiology.sample_traits(cfg, n_sub, streams)
    readings = Readings(
        ids={
            "subject_id": (first_subject + rep).astype(np.int64, copy=False),
            "measurement_id": (first_subject * per_subject
                               + np.arange(n)).astype(np.int64, copy=False),
        },
        subject_index=rep,
        startup=np.arange(0, n, per_subject),
        # each subject's traits per reading: v[rep], as a repeat (the same values, no
        # index look-up)
        traits={k: v.repeat(per_subject) for k, v in traits.items()},
        glucose=glucose,
        env=env,
        led_ages=lambda st: hardware.led_ages_h(cfg, rep, n_sub, st),
    )
    return measure_readings(cfg, tables, streams, readings), streams.n_variates


@dataclass(frozen=True)
class Readings:
    """The readings a simulator hands the layer engine (:func:`measure_readings`), with
    what that simulator drew itself for them: who is read when (``ids``), the glucose
    and environment at each reading, and the subjects' traits.

    The snapshot simulator (:func:`simulate_block`) fills it per block of subjects; the
    worn one (:func:`nirglucose.simulation.wear.simulate_wear_chunk`) per subject's
    series, with the hooks below for what a worn device adds.

    Attributes
    ----------
    ids : dict
        Identity columns, in column order (``subject_id``, ``measurement_id``, ...).
    subject_index : numpy.ndarray
        Each reading's subject within the batch (0-based), (n,).
    startup : numpy.ndarray
        The readings at which a subject's device starts (its LED temperatures' start).
    traits : dict
        The subjects' physiological traits at each reading, (n,) each.
    glucose : dict
        The reference glucose layer at each reading (``glucose_mgdl``, ...).
    env : dict
        The environment layer at each reading.
    led_ages : callable
        ``led_ages(streams) -> {"age_h", "age_cal_h"}``: the LEDs' ages. [h]
    seen : dict, optional
        The glucose the optics see (a worn device: the interstitial one); default
        ``glucose``.
    placement : callable, optional
        ``placement(streams) -> (pressure, coupling_z)`` per reading, where the probe's
        placement persists over readings (a worn device between re-seatings).
    adjust_physiology : callable, optional
        ``adjust_physiology(phys) -> phys`` after the physiology layer (a worn
        device's diurnal heart rate).
    truth : dict
        Further ``true_*`` columns.
    """

    ids: dict
    subject_index: np.ndarray
    startup: np.ndarray
    traits: dict
    glucose: dict
    env: dict
    led_ages: Callable[[RandomStreams], dict]
    seen: dict | None = None
    placement: Callable[[RandomStreams], tuple] | None = None
    adjust_physiology: Callable[[dict], dict] | None = None
    truth: dict = field(default_factory=dict)


def measure_readings(cfg: ScenarioConfig, tables: ScenarioTables, streams: RandomStreams,
                     readings: Readings) -> dict:
    """The layer engine: the one order of the simulator's layers after glucose and the
    environment, for snapshots and worn series alike; returns the dataset's columns.

    physiology -> measured physiology -> probe contact -> LED temperatures and ages ->
    optics -> ambient light -> hardware -> PPG; each layer draws from its own named
    streams of ``streams``.
    """
    r = readings
    n = len(r.subject_index)
    phys = physiology.apply_physiology(cfg, r.traits, r.env, r.glucose, n, streams)
    if r.adjust_physiology is not None:
        phys = r.adjust_physiology(phys)
    pmf = measurement.measure_physiology(cfg, {**phys, **r.env}, streams)
    placement = None if r.placement is None else r.placement(streams)
    probe = contact.apply_contact(cfg, phys, r.env, pmf, streams, placement=placement)
    temps = hardware.led_temperatures_c(
        cfg, r.env["true_ambient_temperature_c"], phys["true_skin_temp_c"], r.startup, streams
    )
    temps.update(r.led_ages(streams))
    ids = r.ids
    if cfg.device.reading_times and "time_min" not in ids:  # a worn series has its own
        since_h = temps["age_h"] - temps["age_cal_h"][r.subject_index]
        ids = {**ids, "time_min": np.round(since_h * 60.0, 1)}
    seen = r.glucose if r.seen is None else r.seen
    shift_nm, fraction = _optics_layer(cfg, tables, seen, phys, probe, temps)
    temps["ambient_a"], temps["ambient_flicker"] = environment.ambient_at_probe(cfg, r.env)
    hwout = hardware.apply_hardware(cfg, fraction, temps, r.subject_index, streams)
    if cfg.device.ppg_perfusion_spo2:
        pmf.update(
            measurement.measure_ppg(
                cfg, probe["true_blood_fraction_detected"], phys["true_saturation"], streams
            )
        )
    truth = {**phys, **r.env, **probe, **_hidden(r.glucose, temps), **r.truth}
    return _columns(cfg, ids, r.glucose, hwout, pmf, r.env, truth, fraction, shift_nm)


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


def row_mean(x: np.ndarray) -> np.ndarray:
    """``x.mean(axis=1)`` of a 2-D float array, bit for bit, as a sum of its columns.

    For fewer than 8 columns NumPy sums each row in order from +0.0, (((0 + x0) + x1) +
    ...), then divides by the count (a test holds the two equal); summed column by
    column that is about five times faster than NumPy's reduction over short rows. Other
    widths go to ``mean``.

    Examples
    --------
    >>> row_mean(np.array([[1.0, 2.0, 4.0], [-0.0, -0.0, -0.0]]))
    array([2.33333333, 0.        ])
    """
    k = x.shape[1]
    if not 0 < k < 8 or x.dtype != np.float64:
        return x.mean(axis=1)
    out = np.add(x[:, 0], 0.0)
    for j in range(1, k):
        out += x[:, j]
    out /= k
    return out


def _hidden(glucose: dict, temps: dict) -> dict:
    """The scalar ``true_*`` columns of the glucose and hardware layers."""
    return {
        "true_led_temperature_c": row_mean(temps["led_c"]),
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
    tables = scenario_tables(cfg)
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

        tables = scenario_tables(cfg)
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
    tables: ScenarioTables | None = None,
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
        The scenario's precomputed tables (:func:`scenario_tables`), for callers that call
        this repeatedly with one scenario; computed when omitted.

    Returns
    -------
    numpy.ndarray
        (n, n_led) fraction of LED power detected. [-]
    """
    tables = scenario_tables(cfg) if tables is None else tables
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
