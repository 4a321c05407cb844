"""Benchmark of the design bound (:mod:`nirglucose.design.bound`) on one core.

Times, after one warm-up call (the pilot simulation and the optics' compilation, cached
per population):

* ``design_bound`` of one design (the paper preset with another LED set and a named
  detector): the median wall time of a full call (config, Jacobians, noise, bound), and
  its median CPU time (``time.process_time``: on a shared machine the wall time also
  counts the other processes' turns);
* the same for a design on the water bands with ``noise.water_temperature`` on (InGaAs
  detector, LEDs 1050/1300/1550/1650 nm: one more nuisance, the skin temperature);
* ranking every 4-subset of 10 candidate LEDs (750-1250 nm, 210 subsets): one
  ``design_terms`` call over the 10 and one ``DesignTerms.bound`` per subset, for both
  conditions; and the best subset found.

With ``--oracle`` it also measures bound / oracle RMSE on every preset (the oracle
fitted on 75 simulated subjects x 3, scored on 75 others, seed 1; the table of
docs/user_guide/design_a_device.md), under ``"vs_oracle"``.

Prints a JSON object on its last line (times in seconds, bounds in mg/dL).
Goal: milliseconds per design.

Usage: ``python benchmarks/design_bound.py [--repeats 20] [--oracle]``
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")  # one core

import argparse  # noqa: E402
import itertools  # noqa: E402
import json  # noqa: E402
import platform  # noqa: E402
import statistics  # noqa: E402
import time  # noqa: E402
import warnings  # noqa: E402

from nirglucose.design import design_bound, design_terms  # noqa: E402

CANDIDATES_NM = (750, 800, 850, 900, 950, 1000, 1050, 1100, 1150, 1250)
K = 4


def _timed(repeats, fn):
    """Median wall and CPU seconds of ``fn()`` over ``repeats`` calls, and its last value."""
    wall, cpu = [], []
    for _ in range(repeats):
        w0, c0 = time.perf_counter(), time.process_time()
        out = fn()
        wall.append(time.perf_counter() - w0)
        cpu.append(time.process_time() - c0)
    return statistics.median(wall), statistics.median(cpu), out


def _leds(wavelengths):
    # powers for mid-scale reference codes with the default photodiode's responsivity
    return [{"wavelength_nm": w, "fwhm_nm": 40.0, "power_mw": 2.0,
             "responsivity_a_per_w": 0.5} for w in wavelengths]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=20, help="timed repeats")
    parser.add_argument("--oracle", action="store_true", help="also bound / oracle per preset")
    args = parser.parse_args()

    design = {"leds": _leds((800, 900, 1000, 1100)), "overrides": None}
    start = time.perf_counter()
    design_bound("paper", **design)
    warmup_s = time.perf_counter() - start
    wall_s, cpu_s, bound = _timed(args.repeats, lambda: design_bound("paper", **design))
    swir = {"leds": [{"wavelength_nm": w, "fwhm_nm": 80.0, "power_mw": 10.0}
                     for w in (1050, 1300, 1550, 1650)], "detector": "G17190-010K",
            "overrides": {"noise.water_temperature.enabled": True}}
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message="lipid absorption above")
        design_bound("paper", **swir)  # its pilot and tables
        swir_wall_s, swir_cpu_s, swir_bound = _timed(
            args.repeats, lambda: design_bound("paper", **swir))

    start = time.perf_counter()
    terms = design_terms("wearable", leds=_leds(CANDIDATES_NM))
    terms_s = time.perf_counter() - start
    subsets = list(itertools.combinations(range(len(CANDIDATES_NM)), K))
    start = time.perf_counter()
    ranked = {cond: sorted((terms.bound(s, condition=cond).rmse_mgdl, s) for s in subsets)
              for cond in ("device", "oracle")}
    rank_s = time.perf_counter() - start
    best = {cond: {"rmse_mgdl": r[0][0], "wavelengths_nm": [CANDIDATES_NM[i] for i in r[0][1]]}
            for cond, r in ranked.items()}
    vs_oracle = _vs_oracle() if args.oracle else None
    print(json.dumps({
        "benchmark": "design_bound",
        "python": platform.python_version(),
        "warmup_s": warmup_s,
        "design_bound_median_s": wall_s,
        "design_bound_median_cpu_s": cpu_s,
        "design_bound_rmse_mgdl": bound.rmse_mgdl,
        "design_bound_swir_water_temperature_median_s": swir_wall_s,
        "design_bound_swir_water_temperature_median_cpu_s": swir_cpu_s,
        "design_bound_swir_water_temperature_rmse_mgdl": swir_bound.rmse_mgdl,
        "subsets": len(subsets),
        "design_terms_10_leds_s": terms_s,
        "rank_all_subsets_both_conditions_s": rank_s,
        "per_subset_s": rank_s / (2 * len(subsets)),
        "best_subset": best,
        "vs_oracle": vs_oracle,
    }))


def _vs_oracle() -> dict:
    import numpy as np

    import nirglucose as ng
    from nirglucose.config import PRESETS
    from nirglucose.models.oracle import Oracle

    out = {}
    for preset in PRESETS:
        ds = ng.simulate(preset, 150, 3, seed=1)
        fr = ds.frame
        train = fr["subject_id"] < 75
        model = Oracle().fit(ng.Dataset(fr[train].reset_index(drop=True), config=ds.config))
        test = fr[~train].reset_index(drop=True)
        pred = model.predict(ng.Dataset(test, config=ds.config))
        rmse = float(np.sqrt(np.mean((pred - test["glucose_mgdl"]) ** 2)))
        bound = design_bound(preset, condition="oracle").rmse_mgdl
        out[preset] = {"bound_mgdl": bound, "oracle_mgdl": rmse, "ratio": bound / rmse,
                       "device_bound_mgdl": design_bound(preset).rmse_mgdl}
    return out


if __name__ == "__main__":
    main()
