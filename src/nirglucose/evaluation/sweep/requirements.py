"""The "what it takes" study: per detector, the least design at published magnitudes.

:func:`requirements_study` runs the search of :mod:`~nirglucose.design.requirements`
for each detector in preset ``physical``, evaluates what each lever group is worth,
draws the averaging curve of the study's device and of the named designs, confirms the
named designs by simulation (:mod:`~nirglucose.evaluation.sweep.confirmation`) and returns a
:class:`RequirementsResult`: one answer line per detector
(:meth:`RequirementsResult.answer_lines`) and its tables, which
:meth:`RequirementsResult.to_dir` writes atomically (the figures:
:mod:`nirglucose.plots.requirements`).

Budget (measured, docs/user_guide/requirements.md): at the default size the search
takes seconds per detector; the confirmation simulations and fits take most of the
study's few minutes on two cores.
"""

from __future__ import annotations

import json
import time
import warnings
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from ..._version import __version__
from ...config import resolve_config
from ...config.parts import detector_part
from ...config.presets import DEVICE_CAPABILITIES
from ...dataset import atomic_write
from ...design.averaging import glucose_lag_rmse_mgdl
from ...design.bound import design_bound, design_terms
from ...design.levers import KNOWLEDGE, LEVERS, Design, lever_table
from ...design.requirements import (
    GENERIC_WAVELENGTHS_NM,
    RELAX_ORDER,
    REQUIREMENTS_PRESET,
    TARGET_MARD_PCT,
    TARGET_RMSE_MGDL,
    DesignEvaluator,
    averaging_rows,
    candidate_records,
    least_design,
    lever_gains,
)
from ...design.search import SEARCH_DETECTORS
from ...design.state_bound import state_bound
from ...exceptions import ConfigError, DataError, check_positive_int
from ...models.registry import available_models, privileged_knowledge
from .confirmation import CONFIRM_MODELS, confirm_design

__all__ = ["REQUIREMENTS_FILES", "RequirementsResult", "requirements_study"]

#: Files written by :meth:`RequirementsResult.to_dir`.
REQUIREMENTS_FILES = ("minimal_designs.csv", "averaging_curve.csv", "lever_gains.csv",
                      "confirmation.csv", "search_trace.csv", "levers.csv",
                      "requirements.json")
#: The reference check of the confirmation: the preset ``paper``'s five capabilities
#: (exact physiology) at published magnitudes, 12 bits and one reading (the issue's
#: table's row).
_CHECK = "check: paper's five capabilities, exact physiology"
#: Name of the study's own photodiode with its four LEDs (``detectors`` entry None).
STUDY = "study"


@dataclass
class RequirementsResult:
    """The study's answer and tables (files: :data:`REQUIREMENTS_FILES`).

    Attributes
    ----------
    minimal_designs : pandas.DataFrame
        One row per detector: whether a design reaches the targets, the least one (or
        the ceiling where none does), its levers, errors and confirmation.
    averaging_curve : pandas.DataFrame
        Errors against the averaging window of the study's device and the named and
        ceiling designs.
    lever_gains : pandas.DataFrame
        What each lever group is worth, per detector (:func:`~nirglucose.design.
        requirements.lever_gains`).
    confirmation : pandas.DataFrame
        Simulated RMSE with 95 % CI per design and model, beside its bounds.
    search_trace : pandas.DataFrame
        Each step the search took, per detector.
    levers : pandas.DataFrame
        The levers, their config keys and levels.
    meta : dict
        Settings, regime, targets, candidates, timings and notes.
    """

    minimal_designs: pd.DataFrame
    averaging_curve: pd.DataFrame
    lever_gains: pd.DataFrame
    confirmation: pd.DataFrame
    search_trace: pd.DataFrame
    levers: pd.DataFrame
    meta: dict[str, Any] = field(default_factory=dict)

    def answer_lines(self) -> list[str]:
        """One line per detector: the least design reaching the targets, or how far the
        best falls short and which lever buys most."""
        return [_answer(row, self.meta, self.confirmation)
                for _, row in self.minimal_designs.iterrows()]

    @classmethod
    def from_dir(cls, path: str | Path) -> RequirementsResult:
        """Read back what :meth:`to_dir` wrote (the answer lines are recomputed from the
        tables and meta, and equal the saved ones).

        Raises
        ------
        DataError
            A file of :data:`REQUIREMENTS_FILES` is missing or unreadable.
        """
        d = Path(path)
        missing = [f for f in REQUIREMENTS_FILES if not (d / f).is_file()]
        if missing:
            raise DataError(f"{str(d)!r} is not a requirements study's output: missing "
                            f"{', '.join(missing)} (run `nirglucose sweep --study "
                            "requirements --out DIR`)")
        try:
            doc = json.loads((d / "requirements.json").read_text(encoding="utf-8"))
            frames = {f[:-4]: _read_csv(d / f) for f in REQUIREMENTS_FILES if f.endswith(".csv")}
            return cls(**frames, meta=dict(doc["meta"]))
        except (OSError, ValueError, KeyError, TypeError) as exc:
            raise DataError(f"{str(d)!r}: cannot read the requirements study's files "
                            f"({exc}); run the study again") from None

    def to_dir(self, path: str | Path) -> Path:
        """Write every table and ``requirements.json`` (answer lines and meta) atomically
        into ``path`` (created if missing)."""
        out = Path(path)
        out.mkdir(parents=True, exist_ok=True)
        for name, frame in (("minimal_designs.csv", self.minimal_designs),
                            ("averaging_curve.csv", self.averaging_curve),
                            ("lever_gains.csv", self.lever_gains),
                            ("confirmation.csv", self.confirmation),
                            ("search_trace.csv", self.search_trace),
                            ("levers.csv", self.levers)):
            atomic_write(out / name, lambda tmp, f=frame: f.to_csv(tmp, index=False))
        doc = {"answer": self.answer_lines(), "meta": self.meta}
        atomic_write(out / "requirements.json", lambda tmp: Path(tmp).write_text(
            json.dumps(doc, indent=2, sort_keys=True, default=_jsonable)))
        return out


def _read_csv(path: Path) -> pd.DataFrame:
    """A table of :meth:`RequirementsResult.to_dir`; text columns stay text (an empty
    one, e.g. no capability, is '' as written, not NaN)."""
    try:
        frame = pd.read_csv(path, keep_default_na=False, na_values=[""])
    except pd.errors.EmptyDataError:
        return pd.DataFrame()
    for col in ("capabilities", "leds_nm", "led_sources"):
        if col in frame:
            frame[col] = frame[col].fillna("").astype(str)
    return frame


def _jsonable(x: Any) -> Any:
    if isinstance(x, np.generic):
        return x.item()
    if isinstance(x, np.ndarray):
        return x.tolist()
    raise TypeError(f"not JSON-serialisable: {type(x).__name__}")


def _knowledge_text(row: pd.Series) -> str:
    parts = []
    ppg = "ppg_perfusion_spo2" in str(row["capabilities"])
    for k in KNOWLEDGE:
        frac = row[f"fraction_{k.name}"]
        sd = row[f"sd_{k.name}"]
        name = k.name.replace("_", " ")
        if k.key.startswith("device.") and not ppg:
            continue  # blood volume and SpO2 are measured by the PPG front end only
        if frac == 0:
            parts.append(f"{name} exact (no instrument)")
            continue
        tag = "today's" if frac == 1 else next(
            (txt.split(",")[0] for f, txt in k.instruments if f == frac), "no published instrument")
        parts.append(f"{name} +-{sd:.3g} {k.unit} ({tag})")
    return "; ".join(parts)


def _ci(r: pd.Series) -> str:
    return f"{r.rmse_mgdl:.1f} [{r.rmse_ci_low:.1f}, {r.rmse_ci_high:.1f}]"


def _confirmed_text(conf: pd.DataFrame, design: str) -> str:
    c = conf[conf["design"] == design] if "design" in conf else conf.iloc[:0]
    if c.empty:
        return "not simulated"
    out = []
    for model, bound, what in (
            ("oracle", "bound_oracle_bound_rmse_mgdl", "oracle-conditioned bound"),
            ("physics-inversion", "bound_total_rmse_mgdl", "per-state bound")):
        r = c[c["model"] == model]
        if not r.empty:
            r = r.iloc[0]
            out.append(f"{model} (privileged reference) {_ci(r)} ({what} {r[bound]:.2g})")
    dep = c[[privileged_knowledge(m) is None if m in available_models() else True
             for m in c["model"]]]
    if not dep.empty:
        r = dep.loc[dep["rmse_mgdl"].idxmin()]
        out.append(f"best deployable ({r.model}) {_ci(r)}")
    return ", ".join(out) + " mg/dL"


def _answer(row: pd.Series, meta: dict[str, Any], conf: pd.DataFrame) -> str:
    extra = "".join(f", {k}={v}" for k, v in sorted(meta.get("overrides", {}).items()))
    regime = f"[{meta['preset']}, glucose signal gain {meta['glucose_signal_gain']:g}{extra}]"
    target = f"{meta['target_rmse_mgdl']:g} mg/dL RMSE and MARD {meta['target_mard_pct']:g} %"
    caps = [c.replace("_", " ") for c in str(row["capabilities"]).split(",") if c]
    design = (f"{row['n_leds']} LEDs ({row['leds_nm']} nm), "
              f"{', '.join(caps) if caps else 'no capability'}, {row['adc_bits']}-bit ADC, "
              f"{row['window_label']} ({row['n_readings']} readings), LED power "
              f"x{row['power_factor']:g}")
    errors = (f"error {row['total_rmse_mgdl']:.1f} mg/dL (per-state bound "
              f"{row['state_rmse_mgdl']:.1f}, lag {row['lag_rmse_mgdl']:.1f}; MARD "
              f"{row['mard_pct']:.1f} %; van Trees {row['vt_device_rmse_mgdl']:.2g}, "
              f"oracle-conditioned {row['oracle_bound_rmse_mgdl']:.2g})")
    head = f"{regime} {row['detector_label']}: "
    simulated = f"; simulated: {_confirmed_text(conf, row['design'])}"
    if row["reached"]:
        return (f"{head}reaches {target} with {design}; tissue known to: "
                f"{_knowledge_text(row)}; {errors}{simulated}")
    return (f"{head}no design in reach of {target}: the best (every lever at its top: "
            f"{design}, exact tissue knowledge) has {errors}, "
            f"{row['shortfall_mgdl']:.1f} mg/dL short; the lever that buys most: "
            f"{row['lever_buys_most']} (worth {row['lever_worth_mgdl']:.1f} mg/dL at the "
            f"top){simulated}")


def _label(detector: str | None) -> tuple[str, str]:
    """(name, label) of a detector; None is the study's photodiode with its four LEDs."""
    if detector is None:
        return STUDY, "the study's photodiode and four LEDs (S1336 responsivities)"
    return detector, f"{detector_part(detector).material} ({detector})"


def _design_row(ev: DesignEvaluator, d: Design, reached: bool,
                gains: pd.DataFrame) -> dict[str, Any]:
    """One row of ``minimal_designs``."""
    e = ev.evaluate(d)
    name, label = _label(ev.candidates.detector)
    wl = ev.candidates.wavelengths_nm
    best = gains.loc[gains["worth_at_ceiling_mgdl"].idxmax()]
    row: dict[str, Any] = {
        "detector": name, "detector_label": label,
        "design": f"{name}: {'least' if reached else 'ceiling'}",
        "reached": reached, "n_leds": len(d.leds),
        "leds_nm": ",".join(f"{wl[i]:g}" for i in d.leds),
        "led_sources": ",".join(ev.candidates.sources[i] for i in d.leds),
        "capabilities": ",".join(d.capabilities()), "adc_bits": int(d.value("adc_bits")),
        "power_factor": float(d.value("power_factor")), "window_s": e.window_s,
        "window_label": next(lv for lv in LEVERS if lv.name == "window_s").label(
            d.level("window_s")),
        **{k: v for k, v in vars(e).items() if k != "window_s"},
        "shortfall_mgdl": max(0.0, e.total_rmse_mgdl - ev.target_rmse_mgdl),
        "lever_buys_most": best["lever"], "lever_worth_mgdl": best["worth_at_ceiling_mgdl"],
    }
    for k, frac in zip(KNOWLEDGE, d.knowledge_fractions(), strict=True):
        row[f"fraction_{k.name}"] = frac
        row[f"sd_{k.name}"] = frac * _get(ev.base, k.key)
    ov = ev.overrides(d)
    row["overrides_json"] = json.dumps(ov, sort_keys=True, separators=(",", ":"))
    return row


def _get(cfg, key: str) -> float:
    node: Any = cfg
    for part in key.split("."):
        node = getattr(node, part)
    return float(node)


def _detector_part(ev: DesignEvaluator, relax_order) -> dict[str, Any]:
    """Search one detector: its row, gains, averaging rows, trace and the named design."""
    detector, _ = _label(ev.candidates.detector)
    d, trace = least_design(ev, relax_order)
    reached = d is not None
    named = d if reached else ev.ceiling()
    gains = lever_gains(ev).assign(detector=detector)
    row = _design_row(ev, named, reached, gains)
    curve = averaging_rows(ev, named, row["design"])
    if reached:
        curve += averaging_rows(ev, ev.ceiling(), f"{detector}: ceiling")
    steps = pd.DataFrame(trace, columns=["lever", "level", "total_rmse_mgdl"]).assign(
        detector=detector, step=lambda f: np.arange(len(f)))
    return {"row": row, "gains": gains, "curve": curve, "trace": steps, "design": named}


def _check_overrides(ev: DesignEvaluator) -> dict[str, Any]:
    return {**ev.base_overrides, **{key: on for key, on, _ in DEVICE_CAPABILITIES.values()}}


def _check_row(ev: DesignEvaluator) -> dict[str, Any]:
    """Errors of the reference check (:data:`_CHECK`), as :class:`Evaluation` fields."""
    ov = _check_overrides(ev)
    terms = design_terms(ev.preset, overrides=ov, n_states=ev.n_states)
    state = state_bound(terms)
    return {"state_rmse_mgdl": state, "lag_rmse_mgdl": 0.0, "total_rmse_mgdl": state,
            "mard_pct": ev.mard_pct(state),
            "vt_device_rmse_mgdl": design_bound(ev.preset, overrides=ov,
                                                n_states=ev.n_states).rmse_mgdl,
            "oracle_bound_rmse_mgdl": terms.bound(condition="oracle").rmse_mgdl,
            "n_readings": 1, "window_s": 0.0}


def _bounds(ev: DesignEvaluator, d: Design) -> dict[str, Any]:
    """A named design's errors (:class:`~nirglucose.design.requirements.Evaluation`)."""
    return dict(vars(ev.evaluate(d)))


def _confirmations(preset: str, named: list[tuple[str, dict, dict]], opts: dict
                   ) -> pd.DataFrame:
    """Simulated RMSE per named design and model, beside the design's bounds (columns
    ``bound_<field>``)."""
    frames = []
    for design, overrides, bounds in named:
        conf = confirm_design(preset, overrides, int(bounds["n_readings"]), **opts)
        frames.append(conf.assign(design=design, **{f"bound_{k}": v for k, v in bounds.items()
                                                    if k not in ("n_readings", "window_s")},
                                  window_s=bounds["window_s"]))
    return pd.concat(frames, ignore_index=True) if frames else pd.DataFrame()


def requirements_study(
    preset: str = REQUIREMENTS_PRESET,
    detectors: Sequence[str | None] = (None, *SEARCH_DETECTORS),
    *,
    target_rmse_mgdl: float = TARGET_RMSE_MGDL,
    target_mard_pct: float = TARGET_MARD_PCT,
    wavelengths_nm: Sequence[float] = GENERIC_WAVELENGTHS_NM,
    n_states: int = 256,
    relax_order: Sequence[str] = RELAX_ORDER,
    confirm: bool = True,
    confirm_subjects: int = 60,
    confirm_per_subject: int = 3,
    confirm_models: Sequence[str] = CONFIRM_MODELS,
    confirm_folds: int = 5,
    confirm_resamples: int = 500,
    overrides: dict[str, Any] | None = None,
    seed: int = 0,
    jobs: int = 1,
) -> RequirementsResult:
    """What would a device need to read glucose on real skin? (module docstring).

    Parameters
    ----------
    preset : str
        The regime (default ``physical``: glucose's optical effect at its published
        magnitude).
    detectors : sequence of str or None
        One answer line each: None, the study's own photodiode with its four LEDs (its
        LED set can only shrink), and catalogue photodiodes with every candidate LED
        they see (default: those three, a Si and an InGaAs part).
    target_rmse_mgdl, target_mard_pct : float
        What the least design must reach. [mg/dL], [%]
    wavelengths_nm : sequence of float
        Generic candidate LED centres besides the study's LEDs and the SWIR parts. [nm]
    n_states : int
        Pilot states the bounds average. [-]
    relax_order : sequence of str
        Order in which the search gives levers up
        (:data:`~nirglucose.design.requirements.RELAX_ORDER`).
    confirm : bool
        Simulate the named designs and score ``confirm_models`` on them.
    confirm_subjects, confirm_per_subject : int
        Size of each confirming simulation. [-]
    confirm_models : sequence of str
        Models scored on each confirmed design.
    confirm_folds, confirm_resamples : int
        Folds of the confirmation's subject-grouped cross-validation, and its
        cluster-bootstrap resamples per 95 % interval. [-]
    overrides : dict, optional
        Dotted overrides on the preset that every design keeps, e.g.
        ``{"noise.water_temperature.enabled": True}`` (water absorbing at the skin
        temperature, a published confounder the preset leaves off); recorded in
        ``meta["overrides"]`` and in each answer line's regime.
    seed : int
        Seed of the confirming simulations and benchmarks.
    jobs : int
        Worker processes of the confirming benchmarks (results identical for any value).

    Returns
    -------
    RequirementsResult
    """
    t0 = time.perf_counter()
    detectors = list(dict.fromkeys([detectors] if isinstance(detectors, str) else detectors))
    if not detectors:
        raise ConfigError("give at least one detector (nirglucose parts lists them)")
    for det in detectors:
        if det is not None:
            detector_part(det)
    for name, v in (("confirm_subjects", confirm_subjects),
                    ("confirm_per_subject", confirm_per_subject),
                    ("confirm_folds", confirm_folds), ("confirm_resamples", confirm_resamples)):
        check_positive_int(name, v)
    overrides = dict(overrides or {})
    try:
        base = resolve_config(preset, overrides)
    except ConfigError as exc:
        raise ConfigError(f"the study's overrides: {exc}") from None
    with warnings.catch_warnings():
        # the lipid table ends at 1,598 nm: recorded once in meta["notes"]
        warnings.filterwarnings("ignore", message="lipid absorption above")
        result, timings = _run(preset, detectors, base, dict(
            target_rmse_mgdl=target_rmse_mgdl, target_mard_pct=target_mard_pct,
            n_states=n_states, overrides=overrides), wavelengths_nm, relax_order, confirm, dict(
            n_subjects=confirm_subjects, per_subject=confirm_per_subject, seed=seed,
            models=tuple(confirm_models), n_splits=confirm_folds, n_boot=confirm_resamples,
            jobs=jobs))
    timings["total_s"] = time.perf_counter() - t0
    result.meta.update(_meta(preset, base, detectors, target_rmse_mgdl, target_mard_pct,
                             relax_order, n_states, confirm, confirm_subjects,
                             confirm_per_subject, confirm_models, seed, timings))
    result.meta.update(confirm_folds=int(confirm_folds),
                       confirm_resamples=int(confirm_resamples), overrides=overrides)
    return result


def _run(preset, detectors, base, ev_opts, wavelengths_nm, relax_order, confirm, conf_opts):
    """The study's computation (see :func:`requirements_study`)."""
    timings: dict[str, float] = {}
    t = time.perf_counter()
    ov = ev_opts["overrides"]
    study_ev = DesignEvaluator(preset, candidate_records(preset, None, overrides=ov), **ev_opts)
    study_design = study_ev.study()
    curve = averaging_rows(study_ev, study_design, "study's device")
    parts, candidates = [], {}
    for det in detectors:
        ev = DesignEvaluator(preset, candidate_records(preset, det, wavelengths_nm, ov),
                             **ev_opts)
        parts.append((ev, _detector_part(ev, relax_order)))
        candidates[_label(det)[0]] = [{**r, "source": s} for r, s in
                           zip(ev.candidates.records, ev.candidates.sources, strict=True)]
    timings["search_s"] = time.perf_counter() - t
    rows = [p["row"] for _, p in parts]
    e_study = study_ev.evaluate(study_design)
    named = [("study's device", study_ev.overrides(study_design), _bounds(study_ev, study_design))]
    named += [(p["row"]["design"], ev.overrides(p["design"]), _bounds(ev, p["design"]))
              for ev, p in parts]
    named.append((_CHECK, _check_overrides(study_ev), _check_row(study_ev)))
    t = time.perf_counter()
    conf = _confirmations(preset, named, conf_opts) if confirm else pd.DataFrame(
        columns=["design", "model", "rmse_mgdl", "rmse_ci_low", "rmse_ci_high", "mard_pct"])
    timings["confirm_s"] = time.perf_counter() - t
    result = RequirementsResult(
        minimal_designs=pd.DataFrame(rows),
        averaging_curve=pd.DataFrame(curve + [r for _, p in parts for r in p["curve"]]),
        lever_gains=pd.concat([p["gains"] for _, p in parts], ignore_index=True),
        confirmation=conf,
        search_trace=pd.concat([p["trace"] for _, p in parts], ignore_index=True),
        levers=pd.DataFrame(lever_table()),
        meta={"candidates": candidates, "study_device": vars(e_study),
              "mean_inverse_glucose_per_mgdl": study_ev.mean_inverse_glucose},
    )
    return result, timings


def _meta(preset, base, detectors, target_rmse, target_mard, relax_order, n_states, confirm,
          confirm_subjects, confirm_per_subject, confirm_models, seed, timings) -> dict:
    rate = float(glucose_lag_rmse_mgdl([60.0], base)[0])
    return {
        "package_version": __version__, "preset": preset,
        "glucose_signal_gain": float(base.glucose.signal_gain),
        "detectors": [_label(d)[0] for d in detectors], "target_rmse_mgdl": float(target_rmse),
        "target_mard_pct": float(target_mard), "relax_order": list(relax_order),
        "n_states": int(n_states), "confirm": bool(confirm),
        "confirm_subjects": int(confirm_subjects), "confirm_per_subject": int(confirm_per_subject),
        "confirm_models": list(confirm_models), "seed": int(seed), "timings_s": timings,
        "lag_rmse_60s_mgdl": rate,
        "notes": [
            "criterion: the per-state bound (design/state_bound.py) with the averaging lag; "
            "the van Trees device bound is reported beside it but credits designs with "
            "information their states do not have",
            "the bounds assume the device's forward model is exact: no model error",
            "the oracle and physics-inversion add the quantisation of the data's ADC bits "
            "(LSB^2/12; the averaging emulation raises the bits) to their noise covariance "
            "(evaluation/sweep/confirmation.py); they are privileged references, not "
            "device estimators",
            "the confirmation emulates N readings averaged with floor(log4 N) more ADC bits, "
            "so a simulated design's quantisation falls by at most N: it is noisier than the "
            "design the bound describes (docs/user_guide/requirements.md, Limits)",
            "lipid absorption is held at its 1,598 nm value above it (optics tables): candidates "
            "above 1,600 nm underestimate the 1,720 nm fat band",
        ],
    }
