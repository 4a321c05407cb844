"""Unit-to-unit tolerance: the ``fleet`` study's table and which tolerance costs most.

1. Runs the built-in sweep study ``fleet`` (:func:`nirglucose.evaluation.run_sweep`,
   ``study="fleet"``) on the ``paper`` preset: tolerance scales 0, 0.25, 0.5, 1, 2 (1 =
   :class:`nirglucose.design.fleet.FleetTolerances`: LED peak +-10 nm, LED power
   between the datasheet's min and typ, responsivity +-5 %, ADC offset +-4 LSB) x the
   variants same-unit / no-transfer / bias / slope-bias x EBL, GP and the oracle, with
   4 training units (80 training subjects in all) and 3 unseen test units (20 subjects
   each), 3 seeds, 2 local workers. Prints the table (mean RMSE over seeds, 95 %
   t-interval over seeds).
2. Attribution at scale 1: each tolerance alone (the others zero), EBL and the oracle,
   same-unit, no-transfer and slope-bias, mean RMSE over the same seeds.

One JSON object on the last line: wall times and both tables' numbers.

Usage: python studies/fleet.py [--seeds 3] [--jobs 2] [--models ebl,gp,oracle]
    [--scales 0,0.25,0.5,1,2] [--out DIR] [--no-attribution]
"""

from __future__ import annotations

import argparse
import json
import time


def _attribution(seeds: int) -> dict:
    from dataclasses import asdict

    from nirglucose.design.fleet import FleetTolerances
    from nirglucose.evaluation.sweep.fleet import FLEET_DEFAULTS, fleet_metrics

    full = asdict(FleetTolerances())
    none = {"wavelength_half_width_nm": 0.0, "power_min_ratio": 1.0, "responsivity_rel": 0.0,
            "adc_offset_lsb": 0}
    out = {}
    for name in full:
        tol = {**none, name: full[name]}
        for model in ("ebl", "oracle"):
            for variant in ("same-unit", "no-transfer", "slope-bias"):
                rmse = []
                for seed in range(seeds):
                    spec = {"preset": "paper", "overrides": {}, "n_subjects": 80,
                            "per_subject": 3, "seed": seed, "model": model, "model_params": {},
                            "n_boot": 20, "fleet": {**FLEET_DEFAULTS, "tolerance_scale": 1.0,
                                                    "variant": variant, "tolerances": tol}}
                    rmse.append(fleet_metrics(spec)["rmse_mgdl"])
                out[f"{name} {model} {variant}"] = round(sum(rmse) / len(rmse), 2)
    return out


def main() -> None:
    from nirglucose.evaluation.sweep.fleet import format_fleet_table
    from nirglucose.evaluation.sweep.run import run_sweep

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=3)
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--models", default="ebl,gp,oracle")
    ap.add_argument("--scales", default="0,0.25,0.5,1,2")
    ap.add_argument("--out", default=None)
    ap.add_argument("--no-attribution", action="store_true")
    a = ap.parse_args()
    scales = [float(v) for v in a.scales.split(",")]
    t0 = time.perf_counter()
    res = run_sweep({"tolerance_scale": scales}, study="fleet", seeds=a.seeds,
                    models=a.models.split(","), n_subjects=80, per_subject=3, n_boot=500,
                    jobs=a.jobs, out=a.out)
    wall = time.perf_counter() - t0
    table = res.effects
    print(format_fleet_table(table))
    out = {
        "protocol": f"paper, fleet of 4 training units (80 subjects x 3) and 3 test units "
                    f"(20 subjects x 3 each), 4 transfer subjects, seeds 0-{a.seeds - 1}, "
                    f"{a.jobs} workers",
        "sweep_wall_s": round(wall, 1),
        "tasks": res.meta["tasks_total"],
        "table": [
            {"scale": r.tolerance_scale, "variant": r.variant, "model": r.model,
             "rmse_mgdl": round(r.rmse_mgdl, 2),
             "ci": [round(r.rmse_ci_low, 2), round(r.rmse_ci_high, 2)],
             "vs_same_unit": round(r.rmse_vs_same_unit, 2)}
            for r in table.itertuples()
        ],
    }
    if not a.no_attribution:
        t1 = time.perf_counter()
        out["attribution_scale1"] = _attribution(a.seeds)
        out["attribution_wall_s"] = round(time.perf_counter() - t1, 1)
        for k, v in out["attribution_scale1"].items():
            print(f"{k}: {v}")
    print(json.dumps(out))


if __name__ == "__main__":
    main()
