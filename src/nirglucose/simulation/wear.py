"""Wear simulation: each subject wears one device for days, a reading every few minutes.

The snapshot simulator (:mod:`.simulator`) draws every reading independently. Here the
same per-reading engine (physiology state, measurement, contact, the optics layer, the
hardware layer, PPG; one function each, called in the snapshot simulator's order) is fed
states that evolve in time:

* glucose: the UVA/Padova model (:mod:`.uva_padova`) driven by a meal scenario and, for
  type 1, basal-bolus insulin (:mod:`.meal_scenario`); the reference column
  ``glucose_mgdl`` is the plasma glucose, the optics see the interstitial glucose
  (:mod:`.interstitial`, ``true_isf_glucose_mgdl``);
* environment: the day's temperature and humidity cycle (:mod:`.diurnal`) around a
  subject's own climate, day-to-day changes of ``environment.temperature_within_sd_c``
  and ``environment.humidity_within_sd_pct``; pressure and ambient light as in the
  snapshot simulator;
* the device: one start-up reference at the start of the wear, LED ageing that
  accumulates with the hours worn (from a device age drawn as in the snapshot
  simulator), a new contact state (pressure and coupling) at each re-seating;
* the subject: traits fixed (the same traits, and diabetes status, as the snapshot
  simulator draws for the same seed and subject id), heart rate following the day.

A subject's status and traits come from the snapshot simulator's block streams (so the
subject is the same person), every time-varying draw from the subject's own streams
(:class:`~._random.SubjectStreams`), and the glucose integration is element-wise per
subject: the output is byte-identical whatever the chunking or number of workers.
Chunks of :data:`WEAR_CHUNK_SUBJECTS` subjects bound the memory.

Assumptions (each stated where it is used): the wear starts at 00:00 of day 0 in the
fasting steady state, after a last meal at 20:00 the day before; no stress and no
exercise; readings continue through the re-seating; the prediabetes glucose model is
halfway between the normal and type 2 ones.
"""

from __future__ import annotations

import json
from collections.abc import Iterator
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from .._version import __version__
from ..config import ScenarioConfig
from ..constants import MINUTES_PER_DAY
from ..dataset import MANIFEST, META_KEY, atomic_write
from ..exceptions import ConfigError
from . import contact, diurnal, environment, physiology, therapy
from . import meal_scenario as meals
from . import uva_padova as uva
from ._random import BLOCK_SUBJECTS, RandomStreams, SubjectStreams, categorical
from .glucose import reflect_into_range
from .interstitial import ISF_LAG_MIN, interstitial_glucose_mgdl
from .partitioned import prepare_partitioned_dir
from .simulator import Readings, measure_readings, scenario_tables

__all__ = [
    "MINUTES_PER_DAY",
    "WEAR_CHUNK_SUBJECTS",
    "WearOptions",
    "readings_per_subject",
    "wear_times_min",
    "subject_profiles",
    "glucose_trajectories",
    "simulate_wear_chunk",
    "iter_wear_chunks",
    "simulate_wear_frame",
    "wear_metadata",
    "write_wear_partitioned",
]

#: Subjects per chunk: a chunk of a 14-day, 5-minute wear is 16 x 4032 rows, about
#: 70 MB in memory. [-]
WEAR_CHUNK_SUBJECTS = 16
#: Time of the last meal before the wear starts, from its 00:00 (20:00 the day before,
#: the scenario's dinner). [min]
_PREVIOUS_MEAL_MIN = -240.0


@dataclass(frozen=True)
class WearOptions:
    """The wear's time-course settings (defaults and sources in the modules named).

    Parameters
    ----------
    isf_lag_min : float
        Blood-to-interstitial time constant (:data:`.interstitial.ISF_LAG_MIN`). [min]
    shower_hour : float
        Hour of the daily re-seating (:data:`.diurnal.SHOWER_HOUR`). [h]
    temperature_amplitude_c : float
        Amplitude of the air temperature's daily cycle, at most a quarter of the
        scenario's temperature range (:data:`.diurnal.TEMPERATURE_AMPLITUDE_C`). [degC]
    heart_rate_amplitude_bpm : float
        Amplitude of the heart rate's daily cycle
        (:data:`.diurnal.HEART_RATE_AMPLITUDE_BPM`). [1/min]
    """

    isf_lag_min: float = ISF_LAG_MIN
    shower_hour: float = diurnal.SHOWER_HOUR
    temperature_amplitude_c: float = diurnal.TEMPERATURE_AMPLITUDE_C
    heart_rate_amplitude_bpm: float = diurnal.HEART_RATE_AMPLITUDE_BPM

    def __post_init__(self) -> None:
        for name, value in asdict(self).items():
            if not (isinstance(value, int | float) and np.isfinite(value) and value >= 0):
                raise ConfigError(f"WearOptions.{name} must be a finite number >= 0, got "
                                  f"{value!r}")
        if self.shower_hour >= 24:
            raise ConfigError(f"WearOptions.shower_hour must be within 0-24 h, got "
                              f"{self.shower_hour!r}")


def readings_per_subject(wear_days, every_min) -> int:
    """Readings of one subject's wear, checking the arguments (one-line errors).

    Examples
    --------
    >>> readings_per_subject(14, 5)
    4032
    """
    for name, value, hint in (("wear_days", wear_days, "a whole number of days, e.g. 14"),
                              ("every_min", every_min, "minutes between readings, e.g. 5")):
        if not isinstance(value, int | np.integer) or isinstance(value, bool) or value < 1:
            raise ConfigError(f"{name} must be a positive integer ({hint}), got {value!r}")
    if MINUTES_PER_DAY % every_min:
        raise ConfigError(f"every_min must divide a day (1440 min) into whole readings, got "
                          f"{every_min}; e.g. 1, 5, 10, 15, 30 or 60")
    return int(wear_days) * MINUTES_PER_DAY // int(every_min)


def wear_times_min(wear_days: int, every_min: int) -> np.ndarray:
    """Reading times since 00:00 of the wear's first day, (readings,). [min]

    Examples
    --------
    >>> wear_times_min(1, 360)
    array([   0,  360,  720, 1080])
    """
    readings_per_subject(wear_days, every_min)
    return np.arange(0, wear_days * MINUTES_PER_DAY, every_min, dtype=np.int64)


def subject_profiles(cfg: ScenarioConfig, seed: int, first: int, n: int, n_subjects: int):
    """Diabetes status codes and traits of subjects ``first`` .. ``first + n - 1`` of
    ``n_subjects``.

    Drawn as the snapshot simulator draws them (its block streams ``glucose``, first
    draw, and ``physiology.traits``, over the same blocks of ``n_subjects``), so a wear
    subject is the snapshot subject of the same seed, id and number of subjects.

    Returns
    -------
    tuple
        Status codes into ``list(cfg.glucose.status_probs)`` (n,), traits {name: (n,)}.
    """
    names = list(cfg.glucose.status_probs)
    probs = np.array([cfg.glucose.status_probs[k] for k in names])
    codes, traits = [], []
    last = first + n
    for block in range(first // BLOCK_SUBJECTS, (last - 1) // BLOCK_SUBJECTS + 1):
        start = block * BLOCK_SUBJECTS
        size = min(BLOCK_SUBJECTS, n_subjects - start)
        streams = RandomStreams(seed, block)
        code = categorical(streams("glucose"), probs, size)
        tr = physiology.sample_traits(cfg, size, streams)
        lo, hi = max(first, start) - start, min(last, start + size) - start
        codes.append(code[lo:hi])
        traits.append({k: v[lo:hi] for k, v in tr.items()})
    return (np.concatenate(codes),
            {k: np.concatenate([t[k] for t in traits]) for k in traits[0]})


def glucose_trajectories(cfg: ScenarioConfig, seed: int, subject_ids, status_codes,
                         wear_days: int,
                         therapy_errors=therapy.THERAPY_ERRORS) -> dict:
    """Plasma glucose every minute of the wear and the meals behind it.

    Each subject's meals (stream ``wear.meals``) and, for type 1, virtual patient
    (stream ``wear.patient``, uniform over the adults) and the therapy's departures from
    the ideal (:mod:`.therapy`: carb-count errors, stream ``wear.carb_count``; missed
    boluses, ``wear.missed_bolus``; the day's insulin sensitivity,
    ``wear.insulin_sensitivity``) come from its own streams;
    subjects of one model kind are integrated together, element-wise
    (:func:`.uva_padova.integrate`). ``therapy_errors`` names the departures drawn
    (default all of :data:`.therapy.THERAPY_ERRORS`; leave one out to ablate it: its
    stream is then not read, and the others' draws do not move).

    Returns
    -------
    dict
        ``blood_mgdl`` (n, wear_days * 1440) [mg/dL]; ``meal_min`` list of (meals,)
        int arrays [min]; ``patient`` (n,) type 1 patient name or "";
        ``bolus_missed`` list of (meals,) bool arrays (all False but for type 1);
        ``sensitivity`` (n, wear_days) the day's insulin-sensitivity factor (1 but for
        type 1). [-]
    """
    names = list(cfg.glucose.status_probs)
    errors = therapy.check_therapy_errors(therapy_errors)
    n, n_min = len(subject_ids), wear_days * MINUTES_PER_DAY
    patient_names, pcols = uva.type1_patients()
    meal_grid, meal_min, patient = np.zeros((n, n_min)), [], np.full(n, "", dtype=object)
    bolus, missed, si_day = np.zeros((n, n_min)), [], np.ones((n, wear_days))
    for i, sid in enumerate(subject_ids):
        streams = SubjectStreams(seed, int(sid))
        minute, carbs = meals.draw_meals(streams("wear.meals"), wear_days)
        meal_min.append(minute)
        meal_grid[i] = meals.meal_grid_mg(minute, 1000.0 * carbs, n_min)
        k = int(streams("wear.patient").integers(len(patient_names)))
        missed.append(np.zeros(minute.size, dtype=bool))
        if names[status_codes[i]] == "type1":
            patient[i] = patient_names[k]
            units, missed[i], si_day[i] = _type1_therapy(
                streams, carbs, float(pcols["carb_ratio_g_per_u"][k]), wear_days, errors)
            bolus[i] = meals.meal_grid_mg(
                minute, units * meals.INSULIN_PMOL_PER_UNIT / pcols["BW"][k], n_min)
    blood = np.empty((n, n_min))
    is_t1 = np.array([names[c] == "type1" for c in status_codes], dtype=bool)
    if is_t1.any():
        rows = [patient_names.index(p) for p in patient[is_t1]]
        p = {k: v[rows] for k, v in pcols.items()}
        si = np.stack([therapy.sensitivity_per_minute(f, n_min) for f in si_day[is_t1]])
        blood[is_t1] = uva.integrate("type1", p, uva.basal_type1(p), meal_grid[is_t1],
                                     bolus[is_t1], sensitivity=si)
    if (~is_t1).any():
        sets = [uva.parameters_2007(names[c]) for c in status_codes[~is_t1]]
        p, x0 = uva.basal_2007({k: np.array([s[k] for s in sets]) for k in sets[0]})
        blood[~is_t1] = uva.integrate("meal_2007", p, x0, meal_grid[~is_t1])
    return {"blood_mgdl": blood, "meal_min": meal_min, "patient": patient,
            "bolus_missed": missed, "sensitivity": si_day}


def _type1_therapy(streams, carbs_g, carb_ratio_g_per_u: float, wear_days: int,
                   errors) -> tuple:
    """One type 1 subject's meal boluses [U], which were missed, and each day's insulin
    sensitivity factor, with the therapy errors named in ``errors`` (:mod:`.therapy`)."""
    counted = (meals.estimated_carbs_g(streams("wear.carb_count"), carbs_g)
               if "carb_count" in errors else carbs_g)
    missed = (therapy.draw_missed_boluses(streams("wear.missed_bolus"), wear_days)
              if "missed_bolus" in errors else np.zeros(len(carbs_g), dtype=bool))
    si_day = (therapy.draw_daily_sensitivity(streams("wear.insulin_sensitivity"), wear_days)
              if "sensitivity" in errors else np.ones(wear_days))
    units = np.where(missed, 0.0, meals.bolus_units(counted, carb_ratio_g_per_u))
    return units, missed, si_day


def _wear_environment(cfg: ScenarioConfig, streams, times_min, options: WearOptions) -> dict:
    """Ambient conditions of each reading: the day's cycles (:mod:`.diurnal`) around the
    subject's climate; pressure, light and its source as the snapshot simulator draws
    them (``environment`` stream), temperature and humidity from ``wear.environment``."""
    e = cfg.environment
    n = len(times_min)
    env = environment.apply_environment(cfg, 1, n, streams)
    rng = streams("wear.environment")
    day = (times_min // MINUTES_PER_DAY).astype(np.int64)
    n_days = int(day[-1]) + 1
    hour = (times_min % MINUTES_PER_DAY) / 60.0
    lo, hi = e.temperature_c
    amp = min(options.temperature_amplitude_c, 0.25 * (hi - lo))
    day_mean_c = rng.uniform(lo + amp, hi - amp) + e.temperature_within_sd_c * rng.normal(
        size=n_days)
    temp_c = reflect_into_range(
        day_mean_c[day] + diurnal.diurnal_cosine(hour, amp, diurnal.TEMPERATURE_PEAK_HOUR),
        lo, hi)
    h_lo, h_hi = e.humidity_pct
    rh_day = reflect_into_range(
        rng.uniform(h_lo, h_hi) + e.humidity_within_sd_pct * rng.normal(size=n_days),
        h_lo, h_hi)
    vapour_hpa = rh_day / 100.0 * diurnal.saturation_vapour_pressure_hpa(day_mean_c)
    env["true_ambient_temperature_c"] = temp_c
    env["true_humidity_pct"] = reflect_into_range(
        diurnal.relative_humidity_pct(vapour_hpa[day], temp_c), h_lo, h_hi)
    return env


def _wear_glucose(cfg, status_code: int, blood, isf, meal_min, times_min) -> tuple:
    """The glucose dicts of one subject's readings: the reference (plasma) and the one
    the optics see (interstitial), with the snapshot simulator's hidden columns."""
    names = list(cfg.glucose.status_probs)
    n = len(times_min)
    eaten = np.concatenate([[_PREVIOUS_MEAL_MIN], meal_min.astype(float)])
    last = eaten[np.searchsorted(eaten, times_min, side="right") - 1]
    ref = {
        "glucose_mgdl": blood,
        "diabetes_status": pd.Categorical.from_codes(np.full(n, status_code), categories=names),
        "true_hours_since_meal": (times_min - last) / 60.0,
        "true_stress": np.zeros(n, dtype=np.int64),
        "true_hour_of_day": (times_min % MINUTES_PER_DAY) / 60.0,
    }
    return ref, {**ref, "glucose_mgdl": isf}


def _wear_subject(cfg, seed: int, sid: int, status_code: int, traits: dict, glucose: tuple,
                  times_min, options: WearOptions, tables) -> pd.DataFrame:
    """One subject's readings through the simulator's layer engine
    (:func:`~nirglucose.simulation.simulator.measure_readings`).

    ``glucose`` is (plasma, interstitial, meal minutes) at the reading times; ``traits``
    the subject's, scalars. What a worn device adds to a snapshot: the glucose over
    time (the optics see the interstitial one), the day's environment and heart rate,
    the probe's placement kept between re-seatings, and the LEDs ageing with the wear.
    """
    streams = SubjectStreams(seed, sid)
    n = len(times_min)
    ref, seen = _wear_glucose(cfg, status_code, *glucose, times_min)
    env = _wear_environment(cfg, streams, times_min, options)
    seating = diurnal.seating_index(times_min, options.shower_hour)

    def heart_rate(phys: dict) -> dict:
        phys["true_heart_rate_bpm"] = np.clip(
            phys["true_heart_rate_bpm"] + diurnal.diurnal_cosine(
                ref["true_hour_of_day"], options.heart_rate_amplitude_bpm,
                diurnal.HEART_RATE_PEAK_HOUR),
            *cfg.physiology.heart_rate_bpm)
        return phys

    def placement(st) -> tuple:
        pressure, coupling_z = contact.sample_contact(cfg, int(seating[-1]) + 1, st)
        return pressure[seating], coupling_z[seating]

    def led_ages(st) -> dict:
        age_cal_h = st("led_ageing").uniform(*cfg.hardware.led_age_h, size=1)
        return {"age_cal_h": age_cal_h, "age_h": age_cal_h[0] + times_min / 60.0}

    readings = Readings(
        ids={
            "subject_id": np.full(n, sid, dtype=np.int64),
            "measurement_id": sid * n + np.arange(n, dtype=np.int64),
            "time_min": times_min.astype(np.int64),
            "wear_day": (times_min // MINUTES_PER_DAY).astype(np.int64),
            "seating_id": seating,
        },
        subject_index=np.zeros(n, dtype=np.int64),
        startup=np.zeros(1, np.int64),
        traits={k: np.repeat(v, n) for k, v in traits.items()},
        glucose=ref,
        env=env,
        led_ages=led_ages,
        seen=seen,
        placement=placement,
        adjust_physiology=heart_rate,
        truth={"true_isf_glucose_mgdl": seen["glucose_mgdl"]},
    )
    return pd.DataFrame(measure_readings(cfg, tables, streams, readings))


def simulate_wear_chunk(cfg: ScenarioConfig, seed: int, first: int, n: int, n_subjects: int,
                        wear_days: int, every_min: int, options: WearOptions | None = None,
                        tables=None) -> pd.DataFrame:
    """The readings of subjects ``first`` .. ``first + n - 1`` of ``n_subjects``, subject
    by subject."""
    options = options or WearOptions()
    tables = scenario_tables(cfg) if tables is None else tables
    times = wear_times_min(wear_days, every_min)
    codes, traits = subject_profiles(cfg, seed, first, n, n_subjects)
    sids = np.arange(first, first + n)
    traj = glucose_trajectories(cfg, seed, sids, codes, wear_days)
    isf = interstitial_glucose_mgdl(traj["blood_mgdl"], 1.0, options.isf_lag_min)
    frames = [
        _wear_subject(cfg, seed, int(sid), int(codes[i]), {k: v[i] for k, v in traits.items()},
                      (traj["blood_mgdl"][i, times], isf[i, times], traj["meal_min"][i]),
                      times, options, tables)
        for i, sid in enumerate(sids)
    ]
    return pd.concat(frames, ignore_index=True)


def _chunks(n_subjects: int, chunk_subjects: int | None):
    size = chunk_subjects or WEAR_CHUNK_SUBJECTS
    return [(c, s, min(size, n_subjects - s)) for c, s in enumerate(range(0, n_subjects, size))]


def iter_wear_chunks(cfg: ScenarioConfig, n_subjects: int, wear_days: int, every_min: int,
                     seed: int, options: WearOptions | None = None,
                     chunk_subjects: int | None = None) -> Iterator[pd.DataFrame]:
    """Yield the wear dataset chunk by chunk (bounded memory)."""
    readings_per_subject(wear_days, every_min)
    tables = scenario_tables(cfg)
    for _, start, k in _chunks(n_subjects, chunk_subjects):
        yield simulate_wear_chunk(cfg, seed, start, k, n_subjects, wear_days, every_min,
                                  options, tables)


def simulate_wear_frame(cfg: ScenarioConfig, n_subjects: int, wear_days: int, every_min: int,
                        seed: int, n_jobs: int = 1, options: WearOptions | None = None,
                        chunk_subjects: int | None = None) -> pd.DataFrame:
    """The whole wear dataset as one DataFrame; ``n_jobs`` > 1 simulates chunks in
    parallel (the bytes do not depend on it nor on ``chunk_subjects``)."""
    readings_per_subject(wear_days, every_min)
    chunks = _chunks(n_subjects, chunk_subjects)
    if n_jobs == 1 or len(chunks) == 1:
        frames = list(iter_wear_chunks(cfg, n_subjects, wear_days, every_min, seed, options,
                                       chunk_subjects))
    else:
        from joblib import Parallel, delayed

        tables = scenario_tables(cfg)
        frames = Parallel(n_jobs=n_jobs)(
            delayed(simulate_wear_chunk)(cfg, seed, s, k, n_subjects, wear_days, every_min,
                                         options, tables)
            for _, s, k in chunks)
    return pd.concat(frames, ignore_index=True) if len(frames) > 1 else frames[0]


def wear_metadata(wear_days: int, every_min: int, options: WearOptions | None) -> dict:
    """The wear's settings as recorded in a dataset's metadata (``metadata["wear"]``)."""
    return {"wear_days": int(wear_days), "every_min": int(every_min),
            **asdict(options or WearOptions())}


def _write_chunk(cfg, seed, chunk, start, k, n_subjects, wear_days, every_min, options, tables,
                 out: Path, meta: bytes) -> tuple[int, int]:
    import pyarrow as pa
    import pyarrow.parquet as pq


    frame = simulate_wear_chunk(cfg, seed, start, k, n_subjects, wear_days, every_min, options,
                                tables)
    table = pa.Table.from_pandas(frame, preserve_index=False)
    del frame
    table = table.replace_schema_metadata({**(table.schema.metadata or {}), META_KEY: meta})
    atomic_write(out / f"part-{chunk:06d}.parquet", lambda tmp: pq.write_table(table, tmp))
    return chunk, table.num_rows


def write_wear_partitioned(cfg: ScenarioConfig, out: str | Path, n_subjects: int,
                           wear_days: int, every_min: int, seed: int, n_jobs: int = 1,
                           options: WearOptions | None = None,
                           chunk_subjects: int | None = None) -> int:
    """Write the wear dataset as ``part-NNNNNN.parquet`` files, one per chunk of subjects,
    and ``manifest.json`` last (as :func:`.partitioned.write_partitioned`); returns the
    rows written. Memory: ``n_jobs`` chunks at a time, whatever ``n_subjects``."""
    n_t = readings_per_subject(wear_days, every_min)
    out = prepare_partitioned_dir(out)
    meta_doc = {"nirglucose_version": __version__, "seed": seed,
                "config": json.loads(cfg.to_json()),
                "wear": wear_metadata(wear_days, every_min, options)}
    meta = json.dumps(meta_doc, sort_keys=True).encode()
    tables = scenario_tables(cfg)
    chunks = _chunks(n_subjects, chunk_subjects)
    args = [(cfg, seed, c, s, k, n_subjects, wear_days, every_min, options, tables, out, meta)
            for c, s, k in chunks]
    if n_jobs == 1 or len(chunks) == 1:
        counts = dict(_write_chunk(*a) for a in args)
    else:
        from joblib import Parallel, delayed

        counts = dict(Parallel(n_jobs=min(n_jobs, len(chunks)),
                               return_as="generator_unordered")(
            delayed(_write_chunk)(*a) for a in args))
    parts = [{"file": f"part-{c:06d}.parquet", "rows": int(counts[c]), "first_subject": int(s),
              "subjects": int(k)} for c, s, k in chunks]
    manifest = {"format": 1, **meta_doc, "n_subjects": int(n_subjects), "per_subject": n_t,
                "n_rows": int(sum(counts.values())), "parts": parts}
    text = json.dumps(manifest, indent=1, sort_keys=True) + "\n"
    atomic_write(out / MANIFEST, lambda tmp: Path(tmp).write_text(text, encoding="utf-8"))
    return manifest["n_rows"]
