"""Speed of the Enhanced Beer–Lambert model: fit, batch and single-sample prediction, C.

* ``fit_100k_s``: ``EnhancedBeerLambert().fit(ds)`` on 100,000 simulated snapshots
  (20,000 subjects x 5, paper preset; 25 ridge penalties, 5 grouped inner folds), wall
  time, best of 3 (goal < 2 s).
* ``batch_samples_per_s``: ``model.predict(X)`` on 1,000,000 rows of raw measured values
  (an (n, 20) float64 array), best of 5; for a column-major array (what
  ``DataFrame.to_numpy()`` gives) and a row-major one (goal >= 5e6).
* ``single_us``: ``model.predict_one(adc, adc_ref, pmf)`` from one row of raw values
  given as Python lists, mean per call, best of 7 repeats of 20,000 calls (goal <= 5 us;
  the study reports 0.01 ms). ``single_numpy_us``: ``model.predict(X[i:i+1])`` for
  comparison.
* ``c_ns_per_prediction``: the exported C (gcc -O2, separate translation unit, so no
  inlining into the loop) called 2,000,000 times over 1,024 different samples with a
  volatile sink, best of 3 runs (goal <= 100 ns); ``c_object_bytes``: text + data + bss
  of ``nirglucose_model.o`` (-O2) as reported by ``size`` (``c_object_file_bytes``: the
  .o file itself, with symbols).

The machine is shared: its load average is recorded with the numbers.
Prints one JSON object on its last line.
"""

from __future__ import annotations

import json
import os
import platform
import shutil
import subprocess
import tempfile
import time
import timeit
from pathlib import Path

import numpy as np

N_FIT = 100_000
N_BATCH = 1_000_000

TIMING_DRIVER = r"""
#define _POSIX_C_SOURCE 199309L
#include <stdio.h>
#include <stdlib.h>
#include <time.h>
#include "nirglucose_model.h"
#define N 1024
static float x[N][20];
int main(int argc, char **argv)
{
    FILE *f;
    long i, iters;
    struct timespec t0, t1;
    volatile float sink = 0.0f;
    if (argc != 3 || !(f = fopen(argv[1], "rb"))) return 1;
    if (fread(x, sizeof(float), N * 20, f) != N * 20) return 1;
    fclose(f);
    iters = atol(argv[2]);
    for (i = 0; i < 100000; ++i) {
        const float *r = x[i & (N - 1)];
        sink = nirglucose_predict(r, r + 4, r + 8);
    }
    clock_gettime(CLOCK_MONOTONIC, &t0);
    for (i = 0; i < iters; ++i) {
        const float *r = x[i & (N - 1)];
        sink = nirglucose_predict(r, r + 4, r + 8);
    }
    clock_gettime(CLOCK_MONOTONIC, &t1);
    printf("%.4f\n", ((t1.tv_sec - t0.tv_sec) * 1e9 + (t1.tv_nsec - t0.tv_nsec)) / iters);
    (void)sink;
    return 0;
}
"""


def _best(fn, repeats: int) -> float:
    best = float("inf")
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t0)
    return best


def _c_timing(model, X: np.ndarray) -> dict:
    gcc, size = shutil.which("gcc"), shutil.which("size")
    if gcc is None:
        return {"c_ns_per_prediction": None, "c_note": "gcc not found"}
    from nirglucose.export import export_c

    with tempfile.TemporaryDirectory() as tmp:
        d = Path(tmp)
        export_c(model, d)
        (d / "driver.c").write_text(TIMING_DRIVER)
        obj = d / "nirglucose_model.o"
        flags = ["-std=c99", "-Wall", "-Wextra", "-Werror", "-O2"]
        subprocess.run(
            [gcc, *flags, "-c", str(d / "nirglucose_model.c"), "-o", str(obj)], check=True
        )
        subprocess.run(
            [
                gcc,
                "-std=c99",
                "-O2",
                "-I",
                str(d),
                str(d / "driver.c"),
                str(obj),
                "-o",
                str(d / "timing"),
                "-lm",
            ],
            check=True,
        )
        X[:1024].astype(np.float32).tofile(d / "x.f32")
        runs = [
            float(
                subprocess.run(
                    [str(d / "timing"), str(d / "x.f32"), "2000000"],
                    capture_output=True,
                    text=True,
                    check=True,
                ).stdout
            )
            for _ in range(3)
        ]
        out = {
            "c_ns_per_prediction": round(min(runs), 2),
            "c_ns_per_prediction_runs": [round(r, 2) for r in runs],
            "c_object_file_bytes": obj.stat().st_size,
        }
        if size:
            text = (
                subprocess.run([size, str(obj)], capture_output=True, text=True, check=True)
                .stdout.splitlines()[-1]
                .split()
            )
            out.update(
                {
                    "c_object_bytes": int(text[3]),
                    "c_object_text_bytes": int(text[0]),
                    "c_object_data_bytes": int(text[1]) + int(text[2]),
                }
            )
        out["c_compiler"] = subprocess.run(
            [gcc, "--version"], capture_output=True, text=True
        ).stdout.splitlines()[0]
    return out


def main() -> dict:
    import nirglucose as ng
    from nirglucose.dataset import measured_columns
    from nirglucose.models import EnhancedBeerLambert

    load_before = os.getloadavg()
    ds = ng.simulate("paper", N_FIT // 5, 5, seed=0)
    assert len(ds) == N_FIT
    fit_times = []
    model = None
    for _ in range(3):
        t0 = time.perf_counter()
        model = EnhancedBeerLambert().fit(ds)
        fit_times.append(time.perf_counter() - t0)

    frame = ds.frame
    X_f = frame[measured_columns()].to_numpy(dtype=float)  # column-major, as pandas gives
    reps = -(-N_BATCH // len(X_f))
    X_col = np.asfortranarray(np.tile(X_f, (reps, 1))[:N_BATCH])
    X_row = np.ascontiguousarray(X_col)
    model.predict(X_col[:10_000])
    t_col = _best(lambda: model.predict(X_col), 5)
    t_row = _best(lambda: model.predict(X_row), 5)

    row = X_row[123]
    adc, ref, pmf = row[:4].tolist(), row[4:8].tolist(), row[8:].tolist()
    assert abs(model.predict_one(adc, ref, pmf) - model.predict(X_row[123:124])[0]) < 1e-9
    n_calls = 20_000
    single = (
        min(timeit.repeat(lambda: model.predict_one(adc, ref, pmf), number=n_calls, repeat=7))
        / n_calls
    )
    one = X_row[123:124]
    single_np = min(timeit.repeat(lambda: model.predict(one), number=2000, repeat=5)) / 2000

    result = {
        "benchmark": "linear",
        "model": "ebl",
        "n_parameters": model.n_parameters,
        "fit_100k_s": round(min(fit_times), 3),
        "fit_100k_s_runs": [round(t, 3) for t in fit_times],
        "batch_samples_per_s": round(N_BATCH / t_col),
        "batch_samples_per_s_row_major": round(N_BATCH / t_row),
        "single_us": round(single * 1e6, 3),
        "single_numpy_us": round(single_np * 1e6, 2),
        **_c_timing(model, X_row),
        "goals": {
            "fit_100k_s": "< 2",
            "batch_samples_per_s": ">= 5e6",
            "single_us": "<= 5",
            "c_ns_per_prediction": "<= 100",
        },
        "machine": {
            "cpu": platform.processor() or platform.machine(),
            "cores": os.cpu_count(),
            "load_avg_1min_before": round(load_before[0], 2),
            "load_avg_1min_after": round(os.getloadavg()[0], 2),
            "python": platform.python_version(),
            "numpy": np.__version__,
        },
    }
    return result


if __name__ == "__main__":
    print(json.dumps(main()))
