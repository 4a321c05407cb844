"""What it takes: the least device design that reads glucose at published magnitudes.

For each detector, :func:`requirements_study` searches the levers of
:mod:`~nirglucose.design.levers` (LED set, ADC bits, readings averaged, LED power within
the exposure limits, the four device capabilities and how precisely each tissue
quantity is known) for the least design whose error reaches a target (15 mg/dL RMSE
and MARD 10 % by default) in preset ``physical`` (glucose's optical effect at its
published magnitude, ``glucose.signal_gain`` 1), states how far the best design falls
short where none does, which lever buys most, and confirms the named designs by
simulation (:mod:`~nirglucose.evaluation.sweep.confirmation`).

Criterion
    A design's error is the per-state bound of :mod:`~nirglucose.design.state_bound`
    (glucose's posterior SD of the design linearised at each simulated state, with the
    nuisances unknown but for their priors given what the device measures), combined
    in quadrature with the lag of a window-averaged estimate
    (:func:`~nirglucose.design.averaging.glucose_lag_rmse_mgdl`). The van Trees bound of
    :func:`~nirglucose.design.design_bound` (``"device"``) and the oracle-conditioned
    bound are reported beside it; the van Trees bound is not the criterion, because at
    published magnitudes it credits a design with information its states do not have
    (:mod:`~nirglucose.design.state_bound`).
MARD
    The error is taken as Gaussian with SD equal to the total RMSE and independent of
    glucose, so MARD = RMSE x sqrt(2 / pi) x mean(1 / g) over the population's
    simulated glucose (E|e| = sigma sqrt(2 / pi) for Gaussian e).
Evaluation
    One set of Jacobians and noise per (capabilities, ADC bits, power) for all of a
    detector's candidate LEDs (:func:`~nirglucose.design.design_terms`), one nuisance
    prior per (capabilities, knowledge levels) from the same pilot simulation with
    those measurement errors; averaging divides the per-reading noise variance by the
    readings in the window. A design then costs a few milliseconds.
Search (the least design)
    Start from the ceiling (every lever at its top, every usable candidate LED); where
    it misses the target, no design in reach does. Else relax: first every knowledge
    lever together, level by level, while the target holds; then, pass after pass until
    nothing moves, each lever of ``relax_order`` as far down as the target allows
    (the LED set by dropping, one at a time, the LED whose loss costs least). The
    default order gives up first what a team can least buy (tissue knowledge: no
    instrument delivers exact physiology), then the capabilities, LED power, ADC bits,
    LEDs, and the averaging time last (firmware, and a window up to a CGM's 5 minutes
    costs little lag). The result is minimal: no single lever can be
    relaxed one level, nor any LED dropped, without missing the target (a test checks
    it); it is not guaranteed to be the cheapest of all minimal designs.
Which lever buys most
    For each lever group, what it is worth at the ceiling (the error with the group at
    its lowest level, everything else at the top) and from the study's design (the
    group alone at its top); the answer names the group worth most at the ceiling.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
import pandas as pd

from ..api import simulate
from ..config import DEFAULT_LEDS, resolve_config
from ..config.detector import responsivity_curve
from ..config.parts import LED_PARTS, detector_part
from ..exceptions import ConfigError, check_positive_int
from .averaging import glucose_lag_rmse_mgdl, readings_in
from .bound import PILOT_PER_SUBJECT, PILOT_SEED, PILOT_SUBJECTS, DesignTerms, design_terms
from .exposure import max_led_power_mw
from .levers import KNOWLEDGE, LEVERS, SWIR_LED_RECORDS, Design
from .search import FWHM_PER_NM, MAX_POWER_MW, drive_powers_mw, subset_bounds
from .state_bound import state_bounds

__all__ = [
    "CURVE_WINDOWS_S",
    "GAIN_GROUPS",
    "GENERIC_WAVELENGTHS_NM",
    "MIN_RELATIVE_RESPONSIVITY",
    "RELAX_ORDER",
    "REQUIREMENTS_PRESET",
    "TARGET_MARD_PCT",
    "TARGET_RMSE_MGDL",
    "Candidates",
    "DesignEvaluator",
    "Evaluation",
    "candidate_records",
    "averaging_rows",
    "least_design",
    "lever_gains",
]

#: The regime of the study: glucose's optical effect at its published magnitude.
REQUIREMENTS_PRESET = "physical"
#: Targets: RMSE and MARD (a CGM-class accuracy). [mg/dL], [%]
TARGET_RMSE_MGDL, TARGET_MARD_PCT = 15.0, 10.0
#: Generic candidate centres: 800-1,700 nm every 50 nm. [nm]
GENERIC_WAVELENGTHS_NM: tuple[float, ...] = tuple(float(w) for w in range(800, 1701, 50))
#: Order in which the search gives levers up (module docstring); "leds" is the LED set.
RELAX_ORDER: tuple[str, ...] = (
    *(f"knowledge:{k.name}" for k in KNOWLEDGE),
    "capability:ppg_perfusion_spo2", "capability:humidity_compensation",
    "capability:constant_force_probe", "capability:monitor_photodiode",
    "power_factor", "adc_bits", "leds", "window_s",
)
#: Averaging windows of the averaging curve. [s]
CURVE_WINDOWS_S: tuple[float, ...] = (0.0, 0.5, 1.0, 2.0, 5.0, 10.0, 20.0, 60.0, 120.0,
                                      300.0, 600.0, 1200.0, 1800.0)
#: A candidate seen with less than this share of the detector's peak responsivity is
#: not usable (as :func:`~nirglucose.design.search.rank_designs`). [-]
MIN_RELATIVE_RESPONSIVITY = 0.1


@dataclass(frozen=True)
class Candidates:
    """A detector's candidate LEDs (see :func:`candidate_records`).

    Attributes
    ----------
    detector : str or None
        Catalogue photodiode; None: the study's photodiode (its four LEDs as given).
    records : list of dict
        LED records at their drive-rule power (``wavelength_nm``, ``fwhm_nm``,
        ``power_mw``, and ``responsivity_a_per_w`` for the study's photodiode).
    sources : list of str
        ``"study"``, a part name (catalogue or SWIR) or ``"generic"`` per record.
    caps_mw : numpy.ndarray
        Power cap of the power lever per record: the exposure limit, and a catalogue
        part's datasheet power. [mW]
    study : tuple of int
        Indices of the study's LEDs among the records.
    """

    detector: str | None
    records: list[dict[str, Any]]
    sources: list[str]
    caps_mw: np.ndarray
    study: tuple[int, ...]

    @property
    def wavelengths_nm(self) -> list[float]:
        """Centre of each record. [nm]"""
        return [float(r["wavelength_nm"]) for r in self.records]


def _pool(wavelengths_nm: Sequence[float]) -> tuple[list[dict[str, float]], list[str], list]:
    """Study LEDs, catalogue parts, SWIR parts, generic grid; a centre already taken keeps
    its first record."""
    recs, srcs, caps = [], [], []
    for e in DEFAULT_LEDS:
        recs.append({"wavelength_nm": e.wavelength_nm, "fwhm_nm": e.fwhm_nm, "power_mw": 1.0})
        srcs.append("study")
        caps.append(MAX_POWER_MW)
    for part in LED_PARTS.values():
        if not part.uncertain:  # rows data/parts/SOURCES.md asks to verify are left out
            recs.append({"wavelength_nm": part.wavelength_nm, "fwhm_nm": part.fwhm_nm,
                         "power_mw": 1.0})
            srcs.append(part.part)
            caps.append(part.power_mw)
    for part, wl, fwhm, p_mw in SWIR_LED_RECORDS:
        recs.append({"wavelength_nm": wl, "fwhm_nm": fwhm, "power_mw": 1.0})
        srcs.append(part)
        caps.append(p_mw)
    for wl in wavelengths_nm:
        recs.append({"wavelength_nm": float(wl), "fwhm_nm": float(wl) * FWHM_PER_NM,
                     "power_mw": 1.0})
        srcs.append("generic")
        caps.append(MAX_POWER_MW)
    keep, seen = [], set()
    for i, r in enumerate(recs):
        if r["wavelength_nm"] not in seen:
            seen.add(r["wavelength_nm"])
            keep.append(i)
    return [recs[i] for i in keep], [srcs[i] for i in keep], [caps[i] for i in keep]


def candidate_records(preset: str = REQUIREMENTS_PRESET, detector: str | None = None,
                      wavelengths_nm: Sequence[float] = GENERIC_WAVELENGTHS_NM,
                      overrides: dict[str, Any] | None = None) -> Candidates:
    """The LEDs a detector's designs choose from, at their drive power.

    Parameters
    ----------
    preset : str
        Scenario preset (population, ADC, TIA gain).
    detector : str or None
        Catalogue photodiode; None: the study's photodiode with its four LEDs as given.
    wavelengths_nm : sequence of float
        Generic candidate centres besides the study's LEDs and :data:`SWIR_LED_RECORDS`.
        [nm]
    overrides : dict, optional
        Dotted overrides on the preset (the regime the study runs in).

    Returns
    -------
    Candidates
        The usable records (the detector sees them with at least
        :data:`MIN_RELATIVE_RESPONSIVITY` of its peak), sorted by centre, each driven
        for a mid-scale median code (:func:`~nirglucose.design.search.drive_powers_mw`)
        but at most 10 mW (a generic record or the study's LED) or its datasheet power
        (a part: the catalogue's certain NIR LEDs, ``nirglucose parts``, and
        :data:`~nirglucose.design.levers.SWIR_LED_RECORDS`). A centre taken twice keeps
        the first record of: the study's, the catalogue's, the SWIR parts', the grid's.
    """
    if detector is None:
        recs = [e.model_dump(exclude={"part"}) for e in DEFAULT_LEDS]
        caps = max_led_power_mw([r["wavelength_nm"] for r in recs])
        return Candidates(None, recs, ["study"] * len(recs),
                          np.maximum(caps, [r["power_mw"] for r in recs]), tuple(range(len(recs))))
    base_ov = dict(overrides or {})
    peak = float(np.max(responsivity_curve(detector_part(detector))[1]))
    recs, srcs, caps = [], [], []
    for r, s, c in zip(*_pool(wavelengths_nm), strict=True):
        try:
            cfg = resolve_config(preset, {**base_ov, "leds": [r], "detector": detector})
        except ConfigError:
            continue  # blind: the band lies beyond the detector's table
        if cfg.leds.responsivity_a_per_w[0] >= MIN_RELATIVE_RESPONSIVITY * peak:
            recs.append(r)
            srcs.append(s)
            caps.append(c)
    if not recs:
        raise ConfigError(f"detector {detector} sees none of the candidate LEDs")
    order = np.argsort([r["wavelength_nm"] for r in recs], kind="stable")
    recs, srcs, caps = ([x[i] for i in order] for x in (recs, srcs, caps))
    rule = drive_powers_mw(preset, recs, detector, max_power_mw=float(max(caps)),
                           overrides=base_ov or None)
    powers = np.minimum(rule, caps)
    recs = [{**r, "power_mw": float(p)} for r, p in zip(recs, powers, strict=True)]
    limit = max_led_power_mw([r["wavelength_nm"] for r in recs])
    lever_caps = np.where([s == "study" or s == "generic" for s in srcs], limit,
                          np.minimum(limit, caps))
    return Candidates(detector, recs, srcs, np.maximum(lever_caps, powers),
                      tuple(i for i, s in enumerate(srcs) if s == "study"))


@dataclass(frozen=True)
class Evaluation:
    """The error of one design (every RMSE in mg/dL).

    ``state_rmse_mgdl`` the per-state bound (the criterion), ``lag_rmse_mgdl`` the
    averaging lag, ``total_rmse_mgdl`` their quadrature sum, ``mard_pct`` its MARD,
    ``vt_device_rmse_mgdl`` the van Trees device bound and ``oracle_bound_rmse_mgdl``
    the oracle-conditioned bound (both without the lag), ``n_readings`` and
    ``window_s`` the averaging. [mg/dL], [%], [-], [s]
    """

    state_rmse_mgdl: float
    lag_rmse_mgdl: float
    total_rmse_mgdl: float
    mard_pct: float
    vt_device_rmse_mgdl: float
    oracle_bound_rmse_mgdl: float
    n_readings: int
    window_s: float


class DesignEvaluator:
    """The errors of a detector's designs, with Jacobians, noise and priors cached.

    Parameters
    ----------
    preset : str
        Scenario preset.
    candidates : Candidates
        The detector's candidate LEDs (:func:`candidate_records`).
    n_states : int
        Pilot states averaged by the bounds. [-]
    target_rmse_mgdl, target_mard_pct : float
        What a feasible design reaches. [mg/dL], [%]
    overrides : dict, optional
        Dotted overrides on the preset that every design keeps (the regime, e.g.
        ``{"noise.water_temperature.enabled": True}``); a design's levers override them.
    """

    def __init__(self, preset: str, candidates: Candidates, *, n_states: int = 256,
                 target_rmse_mgdl: float = TARGET_RMSE_MGDL,
                 target_mard_pct: float = TARGET_MARD_PCT,
                 overrides: dict[str, Any] | None = None):
        for name, v in (("target_rmse_mgdl", target_rmse_mgdl),
                        ("target_mard_pct", target_mard_pct)):
            if not (isinstance(v, int | float) and math.isfinite(v) and v > 0):
                raise ConfigError(f"{name} must be a positive number, got {v!r}")
        self.preset = preset
        self.base_overrides: dict[str, Any] = dict(overrides or {})
        self.base = resolve_config(preset, self.base_overrides)
        self.candidates = candidates
        self.n_states = check_positive_int("n_states", n_states)
        self.target_rmse_mgdl = float(target_rmse_mgdl)
        self.target_mard_pct = float(target_mard_pct)
        g = simulate(preset, PILOT_SUBJECTS, PILOT_PER_SUBJECT, PILOT_SEED,
                     overrides=self.base_overrides).frame["glucose_mgdl"]
        #: mean(1 / g) of the pilot population, for MARD. [dL/mg]
        self.mean_inverse_glucose = float(np.mean(1.0 / g.to_numpy(float)))
        self._terms: dict[tuple, DesignTerms] = {}
        self._priors: dict[tuple, np.ndarray] = {}
        self._lags: dict[float, float] = {}

    # -- cached pieces ------------------------------------------------------------------
    def _all_leds(self, design: Design) -> Design:
        return replace(design, leds=tuple(range(len(self.candidates.records))))

    def overrides(self, design: Design) -> dict[str, Any]:
        """The design's dotted overrides of the preset (one reading), the evaluator's own
        overrides included."""
        out = {**self.base_overrides,
               **design.overrides(self.base, self.candidates.records, self.candidates.caps_mw)}
        if self.candidates.detector is not None:
            out["detector"] = self.candidates.detector
        return out

    def terms(self, design: Design) -> DesignTerms:
        """Jacobians and one-reading noise of every candidate at the design's hardware."""
        key = (design.capabilities(), design.value("adc_bits"), design.value("power_factor"))
        if key not in self._terms:
            base = self._all_leds(design).with_group("knowledge", top=False)
            self._terms[key] = design_terms(self.preset, overrides=self.overrides(base),
                                            n_states=self.n_states)
        return self._terms[key]

    def prior(self, design: Design) -> np.ndarray:
        """The nuisance prior covariance given what the design measures, and how well."""
        key = (design.capabilities(), design.knowledge_fractions())
        if key not in self._priors:
            ov = self.overrides(replace(design, leds=(0,)))
            for k in ("hardware.adc_bits", "hardware.tia_gain_ohm"):
                ov.pop(k)  # the pilot's population does not depend on them
            self._priors[key] = design_terms(self.preset, overrides=ov, n_states=1).nuisance_cov
        return self._priors[key]

    def lag_rmse_mgdl(self, window_s: float) -> float:
        """The averaging lag of a window. [mg/dL]"""
        if window_s not in self._lags:
            self._lags[window_s] = (float(glucose_lag_rmse_mgdl(window_s, self.base)[0])
                                    if window_s > 0 else 0.0)
        return self._lags[window_s]

    # -- evaluation ---------------------------------------------------------------------
    def _averaged(self, design: Design, n_leds: int,
                  window_s: float | None = None) -> tuple[DesignTerms, int, float]:
        """The design's LEDs' terms (only those), with its prior and averaged noise."""
        window = float(design.value("window_s") if window_s is None else window_s)
        n = readings_in(window, n_leds, self.base.hardware.bandwidth_hz)
        t = self.terms(design)
        idx = list(design.leds)
        return replace(t, jacobian=t.jacobian[:, idx], noise_var=t.noise_var[:, idx] / n,
                       saturated=t.saturated[:, idx], nuisance_cov=self.prior(design)), n, window

    def _evaluation(self, state: float, terms: DesignTerms, n: int,
                    window: float) -> Evaluation:
        row = np.arange(terms.jacobian.shape[1])[None, :]
        lag = self.lag_rmse_mgdl(window)
        total = math.hypot(state, lag)
        return Evaluation(
            state_rmse_mgdl=float(state),
            lag_rmse_mgdl=lag,
            total_rmse_mgdl=total,
            mard_pct=self.mard_pct(total),
            vt_device_rmse_mgdl=float(subset_bounds(terms, row, condition="device")[0]),
            oracle_bound_rmse_mgdl=float(subset_bounds(terms, row, condition="oracle")[0]),
            n_readings=n,
            window_s=window,
        )

    def mard_pct(self, rmse_mgdl: float) -> float:
        """MARD of a Gaussian error of SD ``rmse_mgdl`` (module docstring). [%]"""
        return 100.0 * rmse_mgdl * math.sqrt(2.0 / math.pi) * self.mean_inverse_glucose

    def evaluate(self, design: Design, window_s: float | None = None) -> Evaluation:
        """The error of one design (at another averaging window than its level's when
        ``window_s`` is given [s])."""
        terms, n, window = self._averaged(design, len(design.leds), window_s)
        state = state_bounds(terms, [range(len(design.leds))])[0]
        return self._evaluation(state, terms, n, window)

    def feasible(self, e: Evaluation) -> bool:
        """Whether an evaluation reaches both targets."""
        return e.total_rmse_mgdl <= self.target_rmse_mgdl and e.mard_pct <= self.target_mard_pct

    def without_each_led(self, design: Design) -> list[tuple[Design, float]]:
        """Each design with one LED fewer and its total RMSE (one batched evaluation)."""
        if len(design.leds) < 2:
            return []
        k = len(design.leds)
        terms, _, window = self._averaged(design, k - 1)  # the window holds k - 1 LEDs
        states = state_bounds(terms, [[i for i in range(k) if i != j] for j in range(k)])
        lag = self.lag_rmse_mgdl(window)
        return [(replace(design, leds=tuple(i for i in design.leds if i != drop)),
                 math.hypot(st, lag)) for drop, st in zip(design.leds, states, strict=True)]

    # -- reference designs --------------------------------------------------------------
    def ceiling(self) -> Design:
        """Every lever at its top, every candidate LED."""
        return Design(tuple(range(len(self.candidates.records))),
                      tuple(len(lv.values) - 1 for lv in LEVERS))

    def study(self) -> Design:
        """The study's LEDs that the detector sees, every lever at today's level."""
        leds = self.candidates.study or (0,)
        return Design(leds)


def _relax_lever(ev: DesignEvaluator, d: Design, name: str, trace: list) -> tuple[Design, bool]:
    moved = False
    if name == "leds":
        while True:
            options = ev.without_each_led(d)
            if not options:
                break
            best, total = min(options, key=lambda o: (o[1], o[0].leds))
            e = ev.evaluate(best)
            if not ev.feasible(e):
                break
            d, moved = best, True
            trace.append(("leds", f"{len(d.leds)} LEDs", e.total_rmse_mgdl))
        return d, moved
    while d.level(name) > 0:
        cand = d.with_level(name, d.level(name) - 1)
        e = ev.evaluate(cand)
        if not ev.feasible(e):
            break
        d, moved = cand, True
        trace.append((name, str(cand.value(name)), e.total_rmse_mgdl))
    return d, moved


def least_design(ev: DesignEvaluator, relax_order: Sequence[str] = RELAX_ORDER,
                 max_passes: int = 6) -> tuple[Design | None, list[tuple[str, str, float]]]:
    """The least design reaching the evaluator's targets (module docstring, *Search*).

    Parameters
    ----------
    ev : DesignEvaluator
        The detector's evaluator.
    relax_order : sequence of str
        Lever names (:data:`~nirglucose.design.levers.LEVERS`) and ``"leds"``, in the
        order they are given up; every lever must appear once.
    max_passes : int
        Passes over ``relax_order`` at most (the search stops earlier when a pass moves
        nothing). [-]

    Returns
    -------
    design : Design or None
        None when the ceiling misses the target.
    trace : list of (str, str, float)
        Each accepted step: lever, its new level, the total RMSE then. [mg/dL]
    """
    names = {lv.name for lv in LEVERS} | {"leds"}
    if sorted(relax_order) != sorted(names):
        missing, extra = names - set(relax_order), set(relax_order) - names
        raise ConfigError(f"relax_order must name every lever once; missing {sorted(missing)}, "
                          f"unknown or repeated {sorted(extra) or 'none'}")
    d = ev.ceiling()
    trace: list[tuple[str, str, float]] = [("ceiling", "top", ev.evaluate(d).total_rmse_mgdl)]
    if not ev.feasible(ev.evaluate(d)):
        return None, trace
    knowledge = [f"knowledge:{k.name}" for k in KNOWLEDGE]
    while d.level(knowledge[0]) > 0:
        cand = d
        for name in knowledge:
            cand = cand.with_level(name, d.level(name) - 1)
        e = ev.evaluate(cand)
        if not ev.feasible(e):
            break
        d = cand
        trace.append(("knowledge (all)", str(d.value(knowledge[0])), e.total_rmse_mgdl))
    for _ in range(max_passes):
        moved = False
        for name in relax_order:
            d, m = _relax_lever(ev, d, name, trace)
            moved |= m
        if not moved:
            break
    return d, trace


#: Lever groups of :func:`lever_gains`: group -> the levers it holds (``"leds"``: set).
GAIN_GROUPS: dict[str, tuple[str, ...]] = {
    "tissue knowledge": tuple(f"knowledge:{k.name}" for k in KNOWLEDGE),
    "monitor photodiode": ("capability:monitor_photodiode",),
    "constant-force probe": ("capability:constant_force_probe",),
    "PPG perfusion/SpO2": ("capability:ppg_perfusion_spo2",),
    "humidity compensation": ("capability:humidity_compensation",),
    "LED power": ("power_factor",),
    "averaging time": ("window_s",),
    "wavelengths": ("leds",),
    "ADC bits": ("adc_bits",),
}


def _set_group(ev: DesignEvaluator, d: Design, levers: tuple[str, ...], top: bool) -> Design:
    for name in levers:
        if name == "leds":
            d = replace(d, leds=ev.ceiling().leds if top else ev.study().leds)
        else:
            lv = next(x for x in LEVERS if x.name == name)
            d = d.with_level(name, len(lv.values) - 1 if top else 0)
    return d


def lever_gains(ev: DesignEvaluator) -> pd.DataFrame:
    """What each lever group is worth at the ceiling and from the study's design.

    Returns
    -------
    pandas.DataFrame
        One row per group of :data:`GAIN_GROUPS`: ``lever``, ``ceiling_rmse_mgdl``,
        ``ceiling_without_rmse_mgdl`` (the group at its lowest level),
        ``worth_at_ceiling_mgdl`` (their difference), ``study_rmse_mgdl``,
        ``study_with_rmse_mgdl`` (the group alone at its top), ``gain_from_study_mgdl``.
        Total RMSE (bound and lag). [mg/dL]
    """
    top, study = ev.ceiling(), ev.study()
    e_top, e_study = ev.evaluate(top).total_rmse_mgdl, ev.evaluate(study).total_rmse_mgdl
    rows = []
    for group, levers in GAIN_GROUPS.items():
        without = ev.evaluate(_set_group(ev, top, levers, top=False)).total_rmse_mgdl
        with_ = ev.evaluate(_set_group(ev, study, levers, top=True)).total_rmse_mgdl
        rows.append({"lever": group, "ceiling_rmse_mgdl": e_top,
                     "ceiling_without_rmse_mgdl": without,
                     "worth_at_ceiling_mgdl": without - e_top,
                     "study_rmse_mgdl": e_study, "study_with_rmse_mgdl": with_,
                     "gain_from_study_mgdl": e_study - with_})
    return pd.DataFrame(rows)


def averaging_rows(ev: DesignEvaluator, design: Design, name: str,
                   windows_s: Sequence[float] = CURVE_WINDOWS_S) -> list[dict[str, Any]]:
    """The design's errors against its averaging window (the other levers held).

    Returns
    -------
    list of dict
        One row per window: ``design`` (``name``), ``detector``, and the fields of
        :class:`Evaluation`.
    """
    det = ev.candidates.detector or "study photodiode"
    return [{"design": name, "detector": det, **vars(ev.evaluate(design, window_s=float(w)))}
            for w in windows_s]
