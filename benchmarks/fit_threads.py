"""Fit time of a network against torch's thread count, by training-set size.

Measures, on this machine, the wall time of one ``fit`` of ``--model`` (default SDNN,
its default 300 full-batch epochs, ``random_state=0``) on the first ``n`` rows of a
``wearable`` dataset, for each ``n`` in ``--sizes`` and each thread count in
``--threads`` (``0`` stands for torch's default, the machine's cores). The library's
own rule (one thread below :data:`nirglucose.models._training.SMALL_FIT_ROWS` rows) is
switched off while measuring, so each thread count is what it says; the last rows
(``library``) time the rule itself at torch's default thread count, i.e. what a user
gets. Each time is the median of ``--repeats`` fits after one warm-up fit per process
(the first torch optimiser imports ``torch._dynamo``).

It also records whether each thread count gives the same predictions, bit for bit, as
one thread: the thread count is part of a fit's arithmetic once torch splits work.

The load average before and after is recorded: on a shared machine, other work slows
the multi-threaded fits most (their threads wait for each other).

Usage::

    python benchmarks/fit_threads.py [--sizes 25,250,1000,4000,16000] [--threads 1,0]

The last line of the output is one JSON object.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import statistics
import time

import numpy as np
import torch

import nirglucose as ng
from nirglucose.models import _training, make_model


def _ints(text: str) -> list[int]:
    return [int(v) for v in text.split(",") if v.strip()]


def _fit(model: str, ds, epochs: int | None):
    params = {"random_state": 0} if epochs is None else {"random_state": 0, "max_epochs": epochs}
    t0 = time.perf_counter()
    est = make_model(model, **params).fit(ds)
    return time.perf_counter() - t0, est


def _timed(model: str, ds, threads: int, repeats: int, epochs: int | None):
    """``(median seconds, predictions on ds)`` of ``repeats`` fits on ``threads``."""
    default = torch.get_num_threads()
    torch.set_num_threads(threads or default)
    try:
        runs = [_fit(model, ds, epochs) for _ in range(repeats)]
    finally:
        torch.set_num_threads(default)
    pred = np.asarray(runs[-1][1].predict(ds.frame), dtype=float)
    return statistics.median(t for t, _ in runs), pred


def _size_row(args, ds, n: int) -> dict:
    """Median fit time per thread count on ``n`` rows, without and with the library rule."""
    rows = ds.rows(np.arange(n))
    saved = _training.SMALL_FIT_ROWS
    _training.SMALL_FIT_ROWS = 0  # measure each thread count as it is
    try:
        timed = {t: _timed(args.model, rows, t, args.repeats, args.epochs) for t in args.threads}
    finally:
        _training.SMALL_FIT_ROWS = saved
    library_s, _ = _timed(args.model, rows, 0, args.repeats, args.epochs)
    one = timed.get(1, (None, None))[1]
    return {
        "rows": n,
        "fit_s": {("default" if t == 0 else str(t)): round(s, 4) for t, (s, _) in timed.items()},
        "library_rule_fit_s": round(library_s, 4),
        "same_predictions_as_1_thread": {
            ("default" if t == 0 else str(t)): bool(np.array_equal(p, one))
            for t, (_, p) in timed.items()
            if one is not None and t != 1
        },
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--model", default="sdnn")
    ap.add_argument("--sizes", type=_ints, default=[25, 250, 1000, 4000, 16000])
    ap.add_argument("--threads", type=_ints, default=[1, 0], help="0: torch's default")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--epochs", type=int, default=None, help="default: the model's")
    args = ap.parse_args()
    if min(args.sizes) < 2 or args.repeats < 1 or min(args.threads) < 0:
        ap.error("--sizes must be >= 2 rows, --repeats >= 1, --threads >= 0")
    out = {
        "benchmark": "fit_threads",
        "model": args.model,
        "torch": torch.__version__,
        "cpu_count": os.cpu_count(),
        "torch_default_threads": torch.get_num_threads(),
        "small_fit_rows": _training.SMALL_FIT_ROWS,
        "repeats": args.repeats,
        "load_avg_start": os.getloadavg()[0],
    }
    per_subject = 5
    ds = ng.simulate("wearable", math.ceil(max(args.sizes) / per_subject), per_subject, seed=0)
    _fit(args.model, ds.rows(np.arange(min(args.sizes))), 2)  # warm-up: imports, dispatch
    out["sizes"] = [_size_row(args, ds, n) for n in args.sizes]
    out["load_avg_end"] = os.getloadavg()[0]
    print(json.dumps(out))


if __name__ == "__main__":
    main()
