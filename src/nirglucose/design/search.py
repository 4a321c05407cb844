"""Searching LED sets: every k-subset of a candidate list ranked by the bound of a design.

:func:`candidate_leds` builds the candidate list (a wavelength grid with one FWHM rule),
:func:`drive_powers_mw` sets each candidate's drive power for a detector (one power
rule), and :func:`rank_designs` ranks every subset of k = 1 ... ``k_max`` candidates
per detector by the Cramér–Rao bound of :mod:`~nirglucose.design.bound`
(``condition="device"`` by default), in a tidy DataFrame. The ``wavelengths`` sweep
study (:mod:`~nirglucose.evaluation.sweep.studies`) confirms the best designs with the
benchmark.

Rules (assumptions, stated):

FWHM
    ``fwhm_nm = wavelength_nm x r``, r the mean FWHM / centre of the study's four LEDs
    (:data:`~nirglucose.config.DEFAULT_LEDS`: 40/850, 45/940, 50/1050, 60/1150, so
    r = 0.049): an LED's emission width in energy is roughly constant (about 1.8 kT,
    E. F. Schubert, "Light-Emitting Diodes", 2nd ed., Cambridge University Press
    (2006), ch. 5), so its width in wavelength grows with the centre; the linear rule
    fits the study's four LEDs (the lambda^2 rule overshoots them). Commercial
    1,300-1,650 nm LEDs are often broader (around 100 nm), which this rule does not
    model.
Power
    Each candidate is driven so that its median noise-free reading over the pilot
    states (:func:`~nirglucose.design.bound.design_terms`) sits at
    ``target_code_fraction`` of the ADC's full scale ("a device drives its LEDs for
    mid-scale codes", docs/user_guide/design_a_device.md), but at most
    ``max_power_mw`` (default: the brightest of the study's LEDs, 10 mW): a dim
    channel (a weak detector or strong water absorption) is not rescued by an
    unbounded drive.
Detector
    A detector blind at a candidate (the config refuses the LED: its band lies beyond
    the detector's responsivity table) or seeing it with less than
    ``min_relative_responsivity`` of its peak responsivity excludes it for that
    detector.

Every subset's bound is computed in batches with the Sherman–Morrison form of the
noise covariance (diagonal plus a common term), identical to
:meth:`~nirglucose.design.bound.DesignTerms.bound` (a test checks it): about 10 µs
per subset.
"""

from __future__ import annotations

import itertools
import json
import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
import pandas as pd

from ..config import DEFAULT_LEDS, resolve_config
from ..config.detector import responsivity_curve
from ..config.parts import detector_part
from ..constants import DEFAULT_LED_WAVELENGTHS_NM
from ..exceptions import ConfigError, check_positive_int, unknown_name
from ..simulation.forward_model import ForwardModel
from .bound import CONDITIONS, DesignTerms, _pilot, _population_key, design_terms

__all__ = [
    "CANDIDATE_WAVELENGTHS_NM",
    "SEARCH_DETECTORS",
    "FWHM_PER_NM",
    "candidate_leds",
    "drive_powers_mw",
    "rank_designs",
    "subset_bounds",
]

#: Default candidate centres: 800-1,650 nm every 50 nm and the study's four LEDs
#: (850, 940, 1050, 1150 nm). [nm]
CANDIDATE_WAVELENGTHS_NM: tuple[float, ...] = tuple(
    sorted({float(w) for w in range(800, 1651, 50)} | set(DEFAULT_LED_WAVELENGTHS_NM))
)
#: Default detectors of the search: a Si (BPW34) and an InGaAs (G17190-010K) part.
SEARCH_DETECTORS: tuple[str, ...] = ("BPW34", "G17190-010K")
#: FWHM per nm of centre wavelength: the mean over the study's four LEDs. [-]
FWHM_PER_NM = float(np.mean([e.fwhm_nm / e.wavelength_nm for e in DEFAULT_LEDS]))
#: Drive power cap: the brightest of the study's LEDs. [mW]
MAX_POWER_MW = float(max(e.power_mw for e in DEFAULT_LEDS))
#: Subsets evaluated together (memory: about 20 kB per subset with 256 states). [-]
_BATCH = 2048


def candidate_leds(wavelengths_nm: Sequence[float] | None = None) -> list[dict[str, float]]:
    """LED records of the candidate centres, FWHM by the module's rule, 1 mW each.

    Parameters
    ----------
    wavelengths_nm : sequence of float, optional
        Candidate centres (default :data:`CANDIDATE_WAVELENGTHS_NM`). [nm]

    Returns
    -------
    list of dict
        ``{"wavelength_nm", "fwhm_nm", "power_mw"}`` per candidate, sorted by centre.

    Raises
    ------
    ConfigError
        An empty list, a repeated or non-finite centre.

    Examples
    --------
    >>> [round(c["fwhm_nm"], 1) for c in candidate_leds([850, 1650])]
    [41.4, 80.3]
    """
    wl = list(CANDIDATE_WAVELENGTHS_NM if wavelengths_nm is None else wavelengths_nm)
    if not wl:
        raise ConfigError("give at least one candidate wavelength (nm)")
    try:
        vals = [float(w) for w in wl]
    except (TypeError, ValueError):
        raise ConfigError(f"candidate wavelengths must be numbers in nm, got {wl!r}") from None
    if not all(math.isfinite(v) for v in vals) or len(set(vals)) != len(vals):
        raise ConfigError(f"candidate wavelengths must be distinct finite numbers, got {wl!r}")
    return [{"wavelength_nm": v, "fwhm_nm": v * FWHM_PER_NM, "power_mw": 1.0}
            for v in sorted(vals)]


def _usable(preset: str, leds: list[dict[str, float]], detector: str,
            min_relative: float, overrides: dict[str, Any]) -> list[dict[str, float]]:
    """The candidates ``detector`` sees (not blind, above ``min_relative`` of its peak)."""
    peak = float(np.max(responsivity_curve(detector_part(detector))[1]))
    out = []
    for led in leds:
        try:
            cfg = resolve_config(preset, {**overrides, "leds": [led], "detector": detector})
        except ConfigError:
            continue  # blind: the band lies beyond the detector's table
        if cfg.leds.responsivity_a_per_w[0] >= min_relative * peak:
            out.append(led)
    return out


def drive_powers_mw(
    preset: str,
    leds: Sequence[dict[str, float]],
    detector: str | None,
    *,
    target_code_fraction: float = 0.5,
    max_power_mw: float | None = None,
    overrides: dict[str, Any] | None = None,
) -> list[float]:
    """Drive power of each LED by the module's power rule.

    The noise-free code is proportional to the LED power (code = R P T / T_ref x gain),
    so one evaluation at the records' powers scales to the target.

    Parameters
    ----------
    preset : str
        Scenario preset (population, ADC, TIA gain).
    leds : sequence of dict
        LED records (``power_mw`` the probe power).
    detector : str or None
        Catalogue photodiode (None: the preset's responsivities).
    target_code_fraction : float
        Median reading as a fraction of the ADC's full scale, in (0, 1]. [-]
    max_power_mw : float, optional
        Cap (default: the brightest of the study's LEDs, 10 mW). [mW]
    overrides : dict, optional
        Further dotted overrides.

    Returns
    -------
    list of float
        Power per LED. [mW]
    """
    if not 0 < target_code_fraction <= 1:
        raise ConfigError(f"target_code_fraction must be in (0, 1], got {target_code_fraction}")
    cap = MAX_POWER_MW if max_power_mw is None else float(max_power_mw)
    if not cap > 0:
        raise ConfigError(f"max_power_mw must be > 0 mW, got {max_power_mw}")
    extra = {**(overrides or {}), "leds": list(leds)}
    if detector is not None:
        extra["detector"] = detector
    cfg = resolve_config(preset, extra)
    pilot = _pilot(_population_key(cfg))
    m = ForwardModel(cfg, cfg.optics.model).log_ratio(pilot.glucose_mgdl, pilot.theta)
    hw = cfg.hardware
    full = 2**hw.adc_bits - 1
    probe = np.asarray(cfg.leds.power_mw, float)
    i_ref = np.asarray(cfg.leds.responsivity_a_per_w, float) * probe * 1e-3 * (
        hw.reference_transmission)
    code = np.median(i_ref[None, :] * np.exp(m), axis=0) * hw.tia_gain_ohm / hw.adc_vref_v * full
    with np.errstate(divide="ignore"):
        power = np.where(code > 0, probe * target_code_fraction * full / code, np.inf)
    return [float(p) for p in np.minimum(power, cap)]


def subset_bounds(terms: DesignTerms, subsets: np.ndarray, *, condition: str = "device",
                  prior: bool = True) -> np.ndarray:
    """The bound of many LED subsets at once.

    Parameters
    ----------
    terms : DesignTerms
        Jacobians and noise of the candidate set (:func:`~nirglucose.design.design_terms`).
    subsets : numpy.ndarray
        (n_subsets, k) indices into the candidate set, each row one design.
    condition : {'device', 'oracle'}
        What the bound knows (:data:`~nirglucose.design.bound.CONDITIONS`).
    prior : bool
        Include the Gaussian glucose prior.

    Returns
    -------
    numpy.ndarray
        (n_subsets,) bound on glucose RMSE, as
        ``terms.bound(row, condition=condition).rmse_mgdl``. [mg/dL]

    Notes
    -----
    With S = D + c 1 1^T (independent variances D, common variance c) the per-state
    Fisher information J^T S^-1 J is, by the Sherman–Morrison identity (G. H. Golub,
    C. F. Van Loan, "Matrix Computations", 4th ed. (2013), 2.1.4),
    sum_k w_k J_k J_k^T - c u u^T / (1 + c sum_k w_k), w = 1 / D, u = sum_k w_k J_k;
    saturated channels keep their variance in S with a zero Jacobian row, as in
    :meth:`~nirglucose.design.bound.DesignTerms.bound`.
    """
    if condition not in CONDITIONS:
        raise ConfigError(unknown_name("condition", condition, CONDITIONS))
    subsets = np.atleast_2d(np.asarray(subsets, dtype=int))
    n_led = terms.jacobian.shape[1]
    if subsets.size == 0 or subsets.min() < 0 or subsets.max() >= n_led:
        raise ConfigError(f"subsets must index the {n_led} LEDs of the set")
    jac = np.where(terms.saturated[:, :, None], 0.0, terms.jacobian)  # (n, L, p)
    with np.errstate(divide="ignore"):
        w = np.where(np.isfinite(terms.noise_var), 1.0 / terms.noise_var, 0.0)  # (n, L)
    if condition == "oracle":
        jac = jac[:, :, :1]  # the oracle knows the nuisances: glucose's information only
    n, _, p = jac.shape
    wj = w[:, :, None] * jac
    c = terms.common_var
    lam = 1.0 / terms.glucose_var if prior else 0.0
    out = np.empty(len(subsets))
    if condition == "oracle":
        for start in range(0, len(subsets), _BATCH):
            idx = subsets[start:start + _BATCH]
            f_gg = (wj[:, idx, 0] * jac[:, idx, 0]).sum(axis=2)  # (n, B)
            if c > 0:
                f_gg = f_gg - c * wj[:, idx, 0].sum(axis=2) ** 2 / (1.0 + c * w[:, idx].sum(axis=2))
            with np.errstate(divide="ignore"):
                out[start:start + len(idx)] = np.sqrt(np.mean(1.0 / (f_gg + lam), axis=0))
        return out
    # per-LED state-mean of w J J^T: the additive part
    a_led = np.einsum("nlp,nlq->lpq", wj, jac) / n
    prior_info = np.zeros((p, p))
    prior_info[0, 0] = lam
    prior_info[1:, 1:] = np.linalg.inv(terms.nuisance_cov)
    for start in range(0, len(subsets), _BATCH):
        idx = subsets[start:start + _BATCH]
        info = a_led[idx].sum(axis=1) + prior_info
        if c > 0:
            u = wj[:, idx, :].sum(axis=2)  # (n, B, p)
            s = w[:, idx].sum(axis=2)  # (n, B)
            info -= np.einsum("nb,nbp,nbq->bpq", c / (1.0 + c * s), u, u) / n
        e0 = np.zeros((len(idx), p, 1))
        e0[:, 0, 0] = 1.0
        try:
            out[start:start + len(idx)] = np.sqrt(np.linalg.solve(info, e0)[:, 0, 0])
        except np.linalg.LinAlgError:
            out[start:start + len(idx)] = [terms.bound(row).rmse_mgdl for row in idx]
    return out


def _study_kept(wavelengths: Sequence[float]) -> str:
    kept = [w for w in DEFAULT_LED_WAVELENGTHS_NM if float(w) in {float(x) for x in wavelengths}]
    return ",".join(f"{w:g}" for w in kept) if kept else "none"


_COLUMNS = ["preset", "detector", "n_leds", "rank", "wavelengths_nm", "bound_rmse_mgdl",
            "condition", "oracle_bound_rmse_mgdl", "study_leds_kept", "n_study_leds_kept",
            "leds"]


def _rank_k(terms: DesignTerms, usable: list[dict[str, float]], k: int, condition: str,
            top: int | None) -> pd.DataFrame:
    """Every k-subset of ``usable`` ranked (bound, then wavelengths: deterministic)."""
    subsets = np.array(list(itertools.combinations(range(len(usable)), k)), dtype=int)
    rmse = subset_bounds(terms, subsets, condition=condition)
    oracle = subset_bounds(terms, subsets, condition="oracle")
    wl = [[usable[i]["wavelength_nm"] for i in s] for s in subsets]
    order = sorted(range(len(subsets)), key=lambda i: (round(float(rmse[i]), 9), wl[i]))[:top]
    study = {float(w) for w in DEFAULT_LED_WAVELENGTHS_NM}
    return pd.DataFrame({
        "n_leds": k,
        "rank": np.arange(1, len(order) + 1),
        "wavelengths_nm": [",".join(f"{w:g}" for w in wl[i]) for i in order],
        "bound_rmse_mgdl": rmse[order],
        "condition": condition,
        "oracle_bound_rmse_mgdl": oracle[order],
        "study_leds_kept": [_study_kept(wl[i]) for i in order],
        "n_study_leds_kept": [len(study & set(wl[i])) for i in order],
        "leds": [json.dumps([usable[j] for j in subsets[i]], separators=(",", ":"))
                 for i in order],
    })


def rank_designs(
    preset: str = "wearable",
    candidates: Sequence[float] | None = None,
    detectors: Sequence[str] = SEARCH_DETECTORS,
    k_max: int = 6,
    *,
    condition: str = "device",
    top: int | None = None,
    target_code_fraction: float = 0.5,
    max_power_mw: float | None = None,
    min_relative_responsivity: float = 0.1,
    overrides: dict[str, Any] | None = None,
    led_fields: Mapping[str, Any] | None = None,
) -> pd.DataFrame:
    """Every subset of 1 ... ``k_max`` candidate LEDs per detector, ranked by the bound.

    Parameters
    ----------
    preset : str
        Scenario preset: population, noise budget, ADC, what the device measures.
    candidates : sequence of float, optional
        Candidate centres (default :data:`CANDIDATE_WAVELENGTHS_NM`); FWHM and power
        by the module's rules. [nm]
    detectors : sequence of str
        Catalogue photodiodes (``nirglucose parts``), default :data:`SEARCH_DETECTORS`.
    k_max : int
        Largest number of LEDs per design. [-]
    condition : {'device', 'oracle'}
        The bound (:data:`~nirglucose.design.bound.CONDITIONS`); ``"device"`` ranks
        what a device that must also infer the nuisances could reach.
    top : int, optional
        Keep the best ``top`` designs per detector and k (default: all).
    target_code_fraction, max_power_mw : float
        Power rule (:func:`drive_powers_mw`).
    min_relative_responsivity : float
        A candidate seen with less than this share of the detector's peak
        responsivity is excluded. [-]
    overrides : dict, optional
        Further dotted overrides of the preset (not ``leds`` or ``detector``).
    led_fields : mapping, optional
        :class:`~nirglucose.config.LED` fields every candidate takes (e.g. a device
        twin's ``glucose_gain`` and ``read_noise_lsb``); not ``wavelength_nm``,
        ``fwhm_nm`` or ``power_mw``, which the search sets.

    Returns
    -------
    pandas.DataFrame
        One row per design, sorted by detector (given order), k, rank: ``preset``,
        ``detector``, ``n_leds``, ``rank`` (1 = best bound for that detector and k),
        ``wavelengths_nm`` (comma-separated), ``bound_rmse_mgdl`` [mg/dL],
        ``condition``, ``oracle_bound_rmse_mgdl`` (the bound of what the oracle
        knows, to compare with the oracle's RMSE) [mg/dL], ``study_leds_kept``
        (which of the study's 850/940/1050/1150 nm LEDs the design keeps,
        ``"none"``), ``n_study_leds_kept``, ``leds`` (the
        design's LED records as JSON, for ``leds=`` overrides).
        ``attrs["candidates"]``: detector -> the usable candidates with their powers.

    Raises
    ------
    ConfigError
        Unknown preset, detector or condition; ``k_max`` < 1; no usable candidate.

    Examples
    --------
    >>> r = rank_designs("wearable", [850, 940, 1050], ["BPW34"], k_max=2)
    >>> bool(r.groupby("n_leds")["bound_rmse_mgdl"].min().is_monotonic_decreasing)
    True
    """
    k_max = check_positive_int("k_max", k_max)
    if condition not in CONDITIONS:
        raise ConfigError(unknown_name("condition", condition, CONDITIONS))
    if top is not None:
        top = check_positive_int("top", top)
    extra = dict(overrides or {})
    for key in ("leds", "detector"):
        if key in extra:
            raise ConfigError(f"rank_designs sets {key!r} itself; drop it from the overrides")
    detectors = list(dict.fromkeys([detectors] if isinstance(detectors, str) else detectors))
    if not detectors:
        raise ConfigError("give at least one detector (nirglucose parts lists them)")
    for det in detectors:
        detector_part(det)  # unknown part: ConfigError listing the valid ones
    resolve_config(preset, extra)  # unknown preset / bad overrides
    fields = dict(led_fields or {})
    for key in ("wavelength_nm", "fwhm_nm", "power_mw"):
        if key in fields:
            raise ConfigError(f"rank_designs sets each candidate's {key} itself; drop it from "
                              "led_fields")
    leds = [{**c, **fields} for c in candidate_leds(candidates)]
    frames, used = [], {}
    for det in detectors:
        usable = _usable(preset, leds, det, min_relative_responsivity, extra)
        if not usable:
            raise ConfigError(
                f"detector {det} sees none of the candidates "
                f"{[c['wavelength_nm'] for c in leds]} nm; choose candidates in its range"
            )
        powers = drive_powers_mw(preset, usable, det, target_code_fraction=target_code_fraction,
                                 max_power_mw=max_power_mw, overrides=extra)
        usable = [{**c, "power_mw": p} for c, p in zip(usable, powers, strict=True)]
        used[det] = usable
        terms = design_terms(preset, leds=usable, detector=det, overrides=extra or None)
        for k in range(1, min(k_max, len(usable)) + 1):
            frames.append(_rank_k(terms, usable, k, condition, top).assign(
                preset=preset, detector=det))
    out = pd.concat(frames, ignore_index=True)[_COLUMNS]
    out.attrs["candidates"] = used
    return out
