"""The rte-lut forward model: LUT build time, accuracy, interpolation speed, simulator cost.

* build: the default table built from scratch by white Monte Carlo in a temporary cache
  directory (wall and CPU seconds, number of nodes solved; about 2 hours of CPU), or
  reused from NIRGLUCOSE_BENCH_LUT_CACHE;
* accuracy: table / direct solve - 1 at 120 random off-grid points uniform in each axis'
  coordinate over the table's box, in 12 groups sharing (musp_ratio, thickness) (one
  Monte Carlo run each); "direct solve" is
  nirglucose_reference.lut_checks.direct_solve, a run at
  the point with the table's settings and common random numbers (at the default
  table's 3.2 million photons per run about 90 CPU-minutes: 45 measured at 1.6 million);
  with the direct solve's own standard error;
* monte_carlo_vs_diffusion: the MC table / the layered diffusion model
  (nirglucose.optics.layers) over the box and over the paper preset's cohort;
* throughput: points per CPU second of the generic interpolation and of the simulator's
  node-specialised path (node evaluations: the compiled kernel, and its numpy
  reference), in the simulator's slices, and the kernel's first call (a cache load);
* simulator: rng_floor_ratio (benchmarks/simulate.py's method) of the paper preset with
  the default model and with optics.model = "rte-lut", on NIRGLUCOSE_BENCH_SNAPSHOTS
  snapshots (default here 200 000, fewer than benchmarks/simulate.py's 1 000 000);
* accuracy_independent (only with NIRGLUCOSE_BENCH_REFERENCE=1, about 17 CPU-minutes):
  the table against independent direct solves (4 000 000 photons, other random
  numbers) at 36 points in 3 groups (one solve per point: too noisy to judge 1 % at a
  point; studies/optics_reference.py averages seeds for that);
* Monte Carlo (only with NIRGLUCOSE_BENCH_MC=1, about 2 min of CPU): the three-layer
  model against nirglucose_reference.mc_paths at a few skin states.

Prints one JSON object on its last line.
"""

from __future__ import annotations

import json
import os
import sys
import tempfile
import time

# one BLAS thread, set before numpy loads its BLAS (set later, it is ignored and the
# simulator's matrix products spin on idle threads, which counts as CPU time)
os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", os.environ["OMP_NUM_THREADS"])

import numpy as np  # noqa: E402

os.environ.setdefault("NIRGLUCOSE_BENCH_SNAPSHOTS", "200000")
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
_ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(_ROOT, "validation"))  # nirglucose_reference (not installed)

import simulate as sim_bench  # noqa: E402  (benchmarks/simulate.py)

from nirglucose.optics import layers, tissue  # noqa: E402
from nirglucose.optics import lut as L  # noqa: E402
from nirglucose.optics.lut import interpolate as LI  # noqa: E402
from nirglucose_reference import lut_checks as LV  # noqa: E402

RHO_CM, T_EPI_CM, N_TISSUE = 0.3, 0.008, 1.4


def _cohort(seed: int = 0) -> tuple[dict, np.ndarray, np.ndarray]:
    """Layer optics of the paper preset's cohort at every LED band node.

    Returns the solver keyword arguments as (rows, n_led, n_pts) arrays (thickness
    (rows,)), and the nominal subcutis/dermis scattering ratio of each node.
    """
    import nirglucose as ng
    from nirglucose.simulation.simulator import scenario_band_spectra, true_tissue_state

    cfg = ng.resolve_config("paper", {})
    frame = ng.simulate("paper", n_subjects=700, per_subject=3, seed=seed).frame
    wl = [f"{w:g}" for w in cfg.leds.wavelengths_nm]
    state = true_tissue_state(cfg, frame, frame["glucose_mgdl"].to_numpy(float))
    spectra = scenario_band_spectra(cfg)
    optics = tissue.tissue_optics(
        spectra, state,
        water_displacement_per_mm=cfg.glucose.water_displacement_per_mm,
        scattering_rel_per_mm=cfg.glucose.scattering_rel_per_mm,
        shift_nm=frame[[f"true_led_shift_nm_{w}" for w in wl]].to_numpy(float),
    )
    lay = layers.layers_from_tissue_optics(optics, frame["true_melanin_fraction"].to_numpy(float))
    args = {
        "mua_epidermis_per_cm": np.ascontiguousarray(lay["mua_epidermis"]),
        "mua_dermis_per_cm": lay["mua_dermis"],
        "musp_dermis_per_cm": lay["musp_dermis"],
        "mua_subcutis_per_cm": lay["mua_subcutis"],
        "musp_subcutis_per_cm": lay["musp_subcutis"],
    }
    ratio = spectra.spectra["musp_fat"] / spectra.spectra["musp_skin"]
    return args, frame["true_skin_thickness_probe_mm"].to_numpy(float) / 10.0, ratio


def _cohort_points(cohort, n_points: int, seed: int = 0) -> dict:
    args, thick, _ = cohort
    full = args["mua_dermis_per_cm"].shape
    idx = np.random.default_rng(seed).choice(int(np.prod(full)), n_points, replace=False)
    out = {k: v.ravel()[idx] for k, v in args.items()}
    out["skin_thickness_cm"] = np.broadcast_to(thick[:, None, None], full).ravel()[idx]
    return out


def _errors(lut, points, **kw) -> dict:
    err = LV.lut_errors(lut, points, **kw)
    r = np.abs(err["reflectance"])
    p = np.abs(err["pathlength"])
    return {
        "n_points": int(r.size),
        "direct_median_rel_se": round(float(np.median(err["reflectance_se"])), 5),
        "reflectance_max_rel_error": round(float(r.max()), 5),
        "reflectance_median_rel_error": round(float(np.median(r)), 5),
        "reflectance_p99_rel_error": round(float(np.percentile(r, 99)), 5),
        "share_above_1pct": round(float(np.mean(r > 0.01)), 5),
        "path_median_rel_error": dict(zip(layers.LAYER_NAMES,
                                          np.round(np.median(p, axis=0), 5).tolist(),
                                          strict=True)),
    }


def _vs_diffusion(lut, points) -> dict:
    r_mc, _ = L.interpolate_lut(lut, **points)
    r_d, _ = layers.three_layer_reflectance(RHO_CM, epidermis_thickness_cm=T_EPI_CM,
                                            n_tissue=N_TISSUE, **points)
    ratio = r_mc / r_d
    return {k: round(float(f(ratio)), 4) for k, f in (
        ("median_ratio", np.median), ("min_ratio", np.min), ("max_ratio", np.max),
        ("p5_ratio", lambda x: np.percentile(x, 5)),
        ("p95_ratio", lambda x: np.percentile(x, 95)))}


def _throughput(lut, cohort) -> dict:
    from nirglucose.simulation.simulator import _OPTICS_SLICE_ROWS

    pts = LV.random_lut_points(lut, 200_000, rng=3)
    start = time.process_time()
    L.interpolate_lut(lut, **pts)
    generic = 200_000 / (time.process_time() - start)
    args, thick, ratio = cohort  # the simulator's layout: (rows, n_led, n_pts)
    nlut = L.node_lut(lut, ratio)
    start = time.perf_counter()  # the compiled kernel's first call: load (or compile)
    L.interpolate_node_lut(nlut, skin_thickness_cm=thick[:1], **{k: v[:1] for k, v in args.items()})
    first_call = time.perf_counter() - start

    def node_rate(fn, repeats: int) -> float:
        """Node evaluations per CPU second, best of ``repeats`` passes over the cohort."""
        best = 0.0
        for _ in range(repeats):
            n_done, start = 0, time.process_time()
            for lo in range(0, thick.size, _OPTICS_SLICE_ROWS):  # the simulator's slices
                sl = slice(lo, lo + _OPTICS_SLICE_ROWS)
                n_done += fn(nlut, skin_thickness_cm=thick[sl],
                             **{k: v[sl] for k, v in args.items()}).size
            best = max(best, n_done / (time.process_time() - start))
        return best

    return {
        "generic_points_per_s": round(generic),
        "node_points_per_s": round(node_rate(L.interpolate_node_lut, 5)),
        "node_numpy_points_per_s": round(node_rate(LI._interpolate_node_lut_numpy, 2)),
        "node_kernel_first_call_s": round(first_call, 3),
    }


def _simulator() -> dict:
    out = {"n_snapshots": sim_bench.N_SNAPSHOTS}
    for label, over in (("paper", None), ("paper_rte_lut", {"optics.model": "rte-lut"})):
        sim_bench._simulate("paper", over)  # warm (tables, imports, the LUT from cache)
        elapsed, n_rows, sizes = sim_bench._simulate("paper", over)
        floor = sim_bench._rng_floor(sizes)
        out[label] = {
            "seconds": round(elapsed, 3),
            "snapshots_per_s": round(n_rows / elapsed),
            "rng_floor_ratio": round(elapsed / floor, 2),
        }
    return out


def _monte_carlo() -> list[dict]:
    from nirglucose_reference.mc_paths import mc_detected_paths, reweight_detected

    start = time.process_time()
    run = mc_detected_paths([0.2, 0.1, 0.03], [200.0, 200.0, 140.0], 0.9, [0.008, 0.15],
                            ring_cm=(0.25, 0.35), n_photons=30_000, rng=2)
    cpu = time.process_time() - start
    x, w = np.polynomial.legendre.leggauss(6)
    rho = 0.3 + 0.05 * x
    weight = w * 0.05 * 2 * np.pi * rho / run.ring_area_cm2
    rows = []
    for mua in ([0.25, 0.2, 0.03], [0.25, 0.3, 0.1], [5.0, 0.3, 0.1], [15.0, 0.3, 0.1],
                [35.0, 0.3, 0.1], [0.25, 1.0, 1.0], [20.0, 1.0, 0.5]):
        r_mc, se, p_mc = reweight_detected(run, mua)
        r_m, p_m = 0.0, 0.0
        for r_i, w_i in zip(rho, weight, strict=True):
            r, p = layers.three_layer_reflectance(
                r_i, mua_epidermis_per_cm=mua[0], mua_dermis_per_cm=mua[1],
                musp_dermis_per_cm=20.0, mua_subcutis_per_cm=mua[2], musp_subcutis_per_cm=14.0,
                epidermis_thickness_cm=T_EPI_CM, skin_thickness_cm=0.158)
            r_m, p_m = r_m + w_i * r, p_m + w_i * r * p
        rows.append({
            "mua_per_cm": mua,
            "model_over_mc": round(float(r_m / r_mc), 4),
            "mc_rel_se": round(float(se / r_mc), 4),
            "paths_model_cm": np.round(p_m / r_m, 4).tolist(),
            "paths_mc_cm": np.round(p_mc, 4).tolist(),
        })
    return [{"photons": run.n_photons, "cpu_s": round(cpu, 1)}, *rows]


def main() -> dict:
    result: dict = {}
    # NIRGLUCOSE_BENCH_LUT_CACHE=<dir>: reuse a table built there before (no build is
    # measured then: lut_build_s is null)
    reuse = os.environ.get("NIRGLUCOSE_BENCH_LUT_CACHE")
    with tempfile.TemporaryDirectory() as tmp:
        cache = reuse or tmp
        os.environ["NIRGLUCOSE_CACHE"] = cache  # else a cold cache: measure a real build
        wall, cpu = time.perf_counter(), time.process_time()
        lut = L.load_or_build_lut(RHO_CM, T_EPI_CM, N_TISSUE)
        result["build"] = {
            "wall_s": round(time.perf_counter() - wall, 2),
            "cpu_s": round(time.process_time() - cpu, 2),
            "n_solves": lut.n_solves,
            "table_nodes": int(np.prod(lut.shape)),
            "cache_file_mb": round(os.path.getsize(
                os.path.join(cache, f"lut-{lut.key}.npz")) / 2**20, 1),
        }
        if reuse:
            result["build"] = {"from_cache": True, **{k: result["build"][k] for k in (
                "n_solves", "table_nodes", "cache_file_mb")}}
        result["accuracy_uniform"] = _errors(
            lut, LV.random_lut_points(lut, 120, rng=7, groups=12))
        if os.environ.get("NIRGLUCOSE_BENCH_REFERENCE") == "1":  # about 17 CPU-minutes
            # independent reference: 10x the photons, other random numbers
            result["accuracy_independent"] = _errors(
                lut, LV.random_lut_points(lut, 36, rng=21, groups=3),
                n_photons=4_000_000, seed=12345)
        cohort = _cohort()
        result["monte_carlo_vs_diffusion"] = {
            "uniform_box": _vs_diffusion(lut, LV.random_lut_points(lut, 2000, rng=5)),
            "paper_cohort": _vs_diffusion(lut, _cohort_points(cohort, 2000)),
        }
        result["throughput"] = _throughput(lut, cohort)
        result["simulator"] = _simulator()
        if os.environ.get("NIRGLUCOSE_BENCH_MC") == "1":
            result["monte_carlo"] = _monte_carlo()
    result["lut_build_s"] = result["build"].get("wall_s")
    result["lut_max_rel_error"] = result["accuracy_uniform"]["reflectance_max_rel_error"]
    result["lut_median_rel_error"] = result["accuracy_uniform"]["reflectance_median_rel_error"]
    result["rng_floor_ratio_rte_lut"] = result["simulator"]["paper_rte_lut"]["rng_floor_ratio"]
    return result


if __name__ == "__main__":
    import argparse

    # no options: the environment variables of the module docstring steer it
    argparse.ArgumentParser(description=__doc__.splitlines()[0]).parse_args()
    print(json.dumps(main()))
