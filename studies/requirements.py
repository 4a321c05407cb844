"""Benchmark of the "what it takes" study (:mod:`nirglucose.evaluation.sweep.requirements`).

Runs the study at its default size (preset ``physical``, the study's photodiode with its
four LEDs, the Si BPW34 and InGaAs G17190-010K detectors, targets 15 mg/dL RMSE and
MARD 10 %, 256 pilot states, the named designs confirmed on 60 subjects x 3 with the
oracle, physics-inversion, device-inversion, EBL and PLS) and times, besides the whole
study (budget: 10 minutes on 2 cores):

* one design's error with the evaluator's pieces cached (the search's unit; budget
  10 ms): the median of ``--repeats`` calls of ``DesignEvaluator.evaluate`` on the
  InGaAs least design;
* one design's error after a change of tissue knowledge (a new nuisance prior: one
  pilot simulation), the median over the knowledge levels of one quantity.

Prints a JSON object on its last line: times [s], the answer lines, and a few bounds
[mg/dL]. With ``--out DIR`` it also writes the study's tables and figures there, and
with ``--record PATH`` the JSON object (indented) to PATH.

Usage: ``python studies/requirements.py [--repeats 20] [--jobs 1] [--out DIR]
[--record studies/records/requirements.json] [--no-confirm]``
"""

from __future__ import annotations

import argparse
import json
import platform
import statistics
import time
import warnings
from pathlib import Path

from nirglucose.design.levers import KNOWLEDGE_FRACTIONS
from nirglucose.design.requirements import DesignEvaluator, candidate_records, least_design
from nirglucose.evaluation.sweep.requirements import requirements_study


def _design_times(repeats: int) -> dict:
    # the lipid table ends at 1,598 nm (the study records it in meta["notes"])
    warnings.filterwarnings("ignore", message="lipid absorption above")
    c = candidate_records("physical", "G17190-010K")
    ev = DesignEvaluator("physical", c)
    d, _ = least_design(ev)
    d = d if d is not None else ev.ceiling()
    cached = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        ev.evaluate(d)
        cached.append(time.perf_counter() - t0)
    # a fresh evaluator, warmed on the design: each other hydration level is a new prior
    ev = DesignEvaluator("physical", c)
    d = d.with_level("knowledge:hydration", 0)
    ev.evaluate(d)
    fresh = []
    for level in range(1, len(KNOWLEDGE_FRACTIONS)):
        t0 = time.perf_counter()
        ev.evaluate(d.with_level("knowledge:hydration", level))
        fresh.append(time.perf_counter() - t0)
    return {"design_error_cached_median_s": statistics.median(cached),
            "design_error_new_knowledge_median_s": statistics.median(fresh)}


def _figures(result, out: Path) -> list[str]:
    from nirglucose.plots.requirements import plot_averaging_curve, plot_minimal_designs
    from nirglucose.plots.style import save_figure

    paths = []
    ax = plot_averaging_curve(result.averaging_curve,
                              target_rmse_mgdl=result.meta["target_rmse_mgdl"],
                              title="physical (glucose gain 1): error vs averaging window")
    paths += save_figure(ax.figure, out / "requirements_averaging", ("png",))
    ax = plot_minimal_designs(result.minimal_designs, title="least designs, physical")
    paths += save_figure(ax.figure, out / "requirements_designs", ("png",))
    return [str(p) for p in paths]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=20, help="timed repeats per design")
    parser.add_argument("--jobs", type=int, default=1, help="benchmark worker processes")
    parser.add_argument("--out", type=Path, help="write the study's files and figures here")
    parser.add_argument("--record", type=Path, help="write the JSON object here")
    parser.add_argument("--no-confirm", action="store_true", help="skip the simulations")
    args = parser.parse_args()

    t0 = time.perf_counter()
    result = requirements_study(confirm=not args.no_confirm, jobs=args.jobs)
    study_s = time.perf_counter() - t0
    figures = []
    if args.out:
        result.to_dir(args.out)
        figures = _figures(result, args.out)
    md = result.minimal_designs
    conf = result.confirmation
    doc = {
        "benchmark": "requirements",
        "python": platform.python_version(),
        "preset": result.meta["preset"],
        "glucose_signal_gain": result.meta["glucose_signal_gain"],
        "study_s": study_s,
        "timings_s": result.meta["timings_s"],
        **_design_times(args.repeats),
        "answer": result.answer_lines(),
        "designs": md[["design", "reached", "n_leds", "leds_nm", "capabilities", "adc_bits",
                       "window_s", "n_readings", "state_rmse_mgdl", "lag_rmse_mgdl",
                       "total_rmse_mgdl", "mard_pct", "vt_device_rmse_mgdl",
                       "oracle_bound_rmse_mgdl"]].to_dict(orient="records"),
        "study_device": result.meta["study_device"],
        "confirmation": conf[["design", "model", "rmse_mgdl", "rmse_ci_low", "rmse_ci_high",
                              "bound_total_rmse_mgdl", "bound_oracle_bound_rmse_mgdl",
                              "bound_state_rmse_mgdl"]].to_dict(
            orient="records") if len(conf) else [],
        "figures": figures,
    }
    text = json.dumps(doc, default=float)
    if args.record:
        args.record.write_text(json.dumps(doc, indent=2, default=float) + "\n")
    print(text)


if __name__ == "__main__":
    main()
