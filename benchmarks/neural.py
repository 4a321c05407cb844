"""Speed of the five networks: training, single-sample latency, batch throughput.

Measures, on this machine:

1. training each network with its defaults on the ``paper`` preset (80 subjects x 3 =
   240 snapshots, seed 0); goal: all five in <= 60 s together;
2. training each on 100,000 snapshots (``paper`` preset, 33,334 subjects x 3) with
   large-data settings (batch 512, at most 40 epochs, patience 5, no refit: the 20 %
   validation split is 20,000 snapshots), fully, not extrapolated; goal: <= 5 min each;
3. single-sample latency of ``predict_one`` and of ``predict`` on a one-row array
   (median, 90th percentile, and the best median of ten blocks of calls, the figure
   least disturbed by other work), against the study's 3.8 / 2.1 / 15.2 / 6.1 /
   0.8 ms; goal: 10x faster;
4. batch throughput of ``predict`` on 100,000 rows.

Torch runs on ``--threads`` intra-op threads (default 1: these networks are small, and
on a shared two-core machine a second thread mostly adds contention). The one-off cost
of importing ``torch._dynamo`` (pulled in by the first ``torch.optim`` optimiser of a
process) is reported separately. The load average before and after is recorded: other
work on the machine slows every number here.

Usage::

    python benchmarks/neural.py [--threads 1] [--large-n 100000] [--skip-large]

The last line of the output is one JSON object.
"""

from __future__ import annotations

import argparse
import json
import os
import time

import numpy as np
import torch

import nirglucose as ng
from nirglucose.models import make_model
from nirglucose.models._base import MEASURED_COLUMNS

MODELS = ("original-pinn", "optimized-pinn", "rte-pinn", "selective-rte-pinn", "sdnn")
#: The study's single-sample inference times. [ms]
STUDY_LATENCY_MS = {
    "original-pinn": 3.8,
    "optimized-pinn": 2.1,
    "rte-pinn": 15.2,
    "selective-rte-pinn": 6.1,
    "sdnn": 0.8,
}
LARGE_SETTINGS = {
    "batch_size": 512,
    "max_epochs": 40,
    "patience": 5,
    "val_fraction": 0.2,
    "refit": False,
}


def _latency_us(fns: dict, calls: int, warmup: int = 200, blocks: int = 10) -> dict:
    """Median, 90th percentile and best block median of one-call times per function. [us]

    The calls run in ``blocks`` blocks, the functions' blocks interleaved so that each
    sees the same machine load; the best block's median is the latency with the least
    interference from other work on a shared machine (the ``timeit`` habit of taking
    the best repeat), the overall median what a caller saw.
    """
    per_block = max(1, calls // blocks)
    times: dict = {name: [] for name in fns}
    for fn in fns.values():
        for i in range(warmup):
            fn(i)
    for b in range(blocks):
        for name, fn in fns.items():
            t = np.empty(per_block)
            for j in range(per_block):
                i = b * per_block + j
                t0 = time.perf_counter_ns()
                fn(i)
                t[j] = time.perf_counter_ns() - t0
            times[name].append(t / 1e3)
    return {
        name: {
            "median": float(np.median(np.concatenate(ts))),
            "p90": float(np.percentile(np.concatenate(ts), 90)),
            "best_block_median": float(min(np.median(t) for t in ts)),
        }
        for name, ts in times.items()
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--large-n", type=int, default=100_000)
    ap.add_argument("--skip-large", action="store_true")
    ap.add_argument("--calls", type=int, default=3000)
    args = ap.parse_args()
    torch.set_num_threads(args.threads)
    out: dict = {
        "benchmark": "neural",
        "torch_version": torch.__version__,
        "torch_threads": args.threads,
        "cpu_count": os.cpu_count(),
        "load_avg_start": os.getloadavg()[0],
    }

    t0 = time.perf_counter()
    torch.optim.Adam([torch.zeros(1, requires_grad=True)])
    out["one_off_first_optimizer_import_s"] = round(time.perf_counter() - t0, 2)

    # 1. paper preset, 240 snapshots, defaults
    ds = ng.simulate("paper", n_subjects=80, per_subject=3, seed=0)
    fitted, paper = {}, {}
    for name in MODELS:
        m = make_model(name, random_state=0)
        t0 = time.perf_counter()
        m.fit(ds)
        dt = time.perf_counter() - t0
        fitted[name] = m
        paper[name] = {
            "fit_s": round(dt, 2),
            "epochs": m.n_epochs_,
            "refit_epochs": m.refit_epochs_,
            "n_parameters": m.n_parameters,
        }
        print(f"paper-240 {name}: {dt:.1f} s, {m.n_epochs_} + {m.refit_epochs_} epochs", flush=True)
    total = sum(v["fit_s"] for v in paper.values())
    out["paper_240"] = {
        "models": paper,
        "total_fit_s": round(total, 2),
        "goal_s": 60,
        "meets_goal": total <= 60,
    }

    # 3./4. latency and throughput (fitted on the paper preset)
    X = ds.frame[list(MEASURED_COLUMNS)].to_numpy(float)
    big = np.tile(X, (int(np.ceil(100_000 / len(X))), 1))[:100_000]
    latency, throughput = {}, {}
    k = len(X)
    for name, m in fitted.items():
        lat = _latency_us(
            {
                "one": lambda i, m=m: m.predict_one(X[i % k, :4], X[i % k, 4:8], X[i % k, 8:]),
                "row": lambda i, m=m: m.predict(X[i % k : i % k + 1]),
            },
            args.calls,
        )
        one, row = lat["one"], lat["row"]
        study_us = STUDY_LATENCY_MS[name] * 1e3
        latency[name] = {
            "study_ms": STUDY_LATENCY_MS[name],
            **{f"predict_one_{key}_us": round(v, 1) for key, v in one.items()},
            **{f"predict_1row_{key}_us": round(v, 1) for key, v in row.items()},
            "speedup_predict_one_median": round(study_us / one["median"], 1),
            "speedup_predict_1row_median": round(study_us / row["median"], 1),
            "speedup_predict_one_best_block": round(study_us / one["best_block_median"], 1),
            "speedup_predict_1row_best_block": round(study_us / row["best_block_median"], 1),
            "goal_10x_met_median": bool(study_us / max(one["median"], row["median"]) >= 10),
            "goal_10x_met_best_block": bool(
                study_us / max(one["best_block_median"], row["best_block_median"]) >= 10
            ),
        }
        m.predict(big[:1000])
        best = min(_time(lambda m=m: m.predict(big)) for _ in range(3))
        throughput[name] = round(len(big) / best)
        print(f"latency {name}: {latency[name]}, {throughput[name]:,} samples/s", flush=True)
    out["latency"] = latency
    out["throughput_samples_per_s"] = throughput

    # 2. 100,000 snapshots
    if not args.skip_large:
        per = 3
        t0 = time.perf_counter()
        big_ds = ng.simulate("paper", n_subjects=-(-args.large_n // per), per_subject=per, seed=0)
        large = {
            "n_snapshots": len(big_ds),
            "simulate_s": round(time.perf_counter() - t0, 2),
            "settings": LARGE_SETTINGS,
            "goal_s_each": 300,
            "models": {},
        }
        for name in MODELS:
            m = make_model(name, random_state=0, **LARGE_SETTINGS)
            t0 = time.perf_counter()
            m.fit(big_ds)
            dt = time.perf_counter() - t0
            best = m.history_[m.best_epoch_ - 1]
            large["models"][name] = {
                "fit_s": round(dt, 1),
                "epochs": m.n_epochs_,
                "best_epoch": m.best_epoch_,
                "s_per_epoch": round(dt / m.n_epochs_, 2),
                "val_rmse_mgdl": round(best["val_rmse_mgdl"], 2),
                "meets_goal": dt <= 300,
            }
            print(f"large {name}: {large['models'][name]}", flush=True)
        out["large"] = large
    out["load_avg_end"] = os.getloadavg()[0]
    print(json.dumps(out))


def _time(fn) -> float:
    t0 = time.perf_counter()
    fn()
    return time.perf_counter() - t0


if __name__ == "__main__":
    main()
