"""Benchmark of the clinical metrics on 1,000,000 (reference, prediction) pairs.

Runs every public metric a few times on one core and prints a JSON object on its last
line: the median wall time of :func:`nirglucose.metrics.summary` (goal: < 0.5 s) and of
each metric separately, in seconds. For comparison it also times one point-in-polygon
test with ``matplotlib.path.Path.contains_points`` (one Parkes zone polygon), the
approach the np.interp boundary curves replace.

Usage: ``python benchmarks/metrics.py [--n 1000000] [--repeats 5]``
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")  # one core, as the goal is stated

import argparse  # noqa: E402
import json  # noqa: E402
import platform  # noqa: E402
import statistics  # noqa: E402
import time  # noqa: E402
from collections.abc import Callable  # noqa: E402

import numpy as np  # noqa: E402

from nirglucose import metrics  # noqa: E402

GOAL_SUMMARY_S = 0.5


def _median_time(func: Callable[[], object], repeats: int) -> float:
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        func()
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def _matplotlib_path_time(ref: np.ndarray, pred: np.ndarray, repeats: int) -> float | None:
    try:
        from matplotlib.path import Path
    except ImportError:  # pragma: no cover - matplotlib is a dependency, but optional here
        return None
    # Type 1 zone A as one closed polygon (A/B upper, then A/B lower reversed).
    upper = list(metrics.PARKES_TYPE1_LINES["A/B upper"])
    lower = list(metrics.PARKES_TYPE1_LINES["A/B lower"])
    polygon = Path([(0, 0), *upper, (550, 550), *lower[::-1], (0, 0)])
    points = np.column_stack([ref, pred])
    return _median_time(lambda: polygon.contains_points(points), repeats)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=1_000_000, help="number of pairs")
    parser.add_argument("--repeats", type=int, default=5, help="timed repeats per metric")
    args = parser.parse_args()

    rng = np.random.default_rng(20240601)
    ref = rng.uniform(40.0, 400.0, args.n)
    # mostly accurate, with a heavy tail so that every zone is populated
    pred = np.abs(ref * rng.normal(1.0, 0.12, args.n) + rng.standard_t(2.0, args.n) * 15.0)
    zones = metrics.clarke_zones(ref, pred)

    cases: dict[str, Callable[[], object]] = {
        "summary": lambda: metrics.summary(ref, pred),
        "summary_type2": lambda: metrics.summary(ref, pred, diabetes_type=2),
        "rmse": lambda: metrics.rmse(ref, pred),
        "mard": lambda: metrics.mard(ref, pred),
        "mean_bias": lambda: metrics.mean_bias(ref, pred),
        "within_percent": lambda: metrics.within_percent(ref, pred, 20),
        "bland_altman": lambda: metrics.bland_altman(ref, pred),
        "iso15197_2013": lambda: metrics.iso15197_2013(ref, pred),
        "iso15197_2013_zone_ab": lambda: metrics.iso15197_2013_zone_ab(ref, pred),
        "clarke_zones": lambda: metrics.clarke_zones(ref, pred),
        "parkes_zones_type1": lambda: metrics.parkes_zones(ref, pred, diabetes_type=1),
        "parkes_zones_type2": lambda: metrics.parkes_zones(ref, pred, diabetes_type=2),
        "zone_percentages": lambda: metrics.zone_percentages(zones),
    }
    # warm-up (first-call imports and page faults)
    metrics.summary(ref[:1000], pred[:1000])

    times = {name: _median_time(func, args.repeats) for name, func in cases.items()}
    summary_runs = [_median_time(cases["summary"], 1) for _ in range(args.repeats)]
    mpl = _matplotlib_path_time(ref, pred, max(1, args.repeats // 2))

    for name, seconds in times.items():
        print(f"{name:24s} {seconds * 1e3:9.1f} ms")
    result = {
        "benchmark": "metrics",
        "n_pairs": args.n,
        "repeats": args.repeats,
        "summary_median_s": round(statistics.median(summary_runs), 4),
        "summary_min_s": round(min(summary_runs), 4),
        "summary_max_s": round(max(summary_runs), 4),
        "goal_summary_s": GOAL_SUMMARY_S,
        "meets_goal": statistics.median(summary_runs) < GOAL_SUMMARY_S,
        "per_function_median_s": {k: round(v, 4) for k, v in times.items()},
        "matplotlib_path_one_polygon_s": None if mpl is None else round(mpl, 4),
        "numpy": np.__version__,
        "python": platform.python_version(),
    }
    print(json.dumps(result))


if __name__ == "__main__":
    main()
