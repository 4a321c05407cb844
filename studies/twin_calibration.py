"""Simulation-based calibration of the device twin (issue 41).

The device of the user guide's example 1 at a study's size: one 940 nm LED, a 10-bit
ADC, age and skin temperature recorded, 25 people x 8 readings. The posterior estimator
is trained as ``nirglucose twin`` trains it (default settings; from the cache when
present), then ``--devices`` synthetic devices with parameters drawn from the prior are
simulated (seeds apart from the training's) and each one's posterior is sampled: per
parameter the coverage of the central 90 % interval (85-95 % required for the identified
ones) and the rank of the truth among the draws (uniform when calibrated; the ranks are
kept for the docs' histograms, ``nirglucose.plots.twin.rank_histograms``).

Writes studies/records/twin_calibration.json; one JSON object on the last line.

Usage: python studies/twin_calibration.py [--devices 100] [--draws 500]
    [--simulations 8000] [--jobs 2] [--seed 0] [--record PATH]
"""

from __future__ import annotations

import argparse
import json
import time
from dataclasses import asdict
from pathlib import Path

RECORD = Path(__file__).resolve().parent / "records" / "twin_calibration.json"


def main() -> None:
    from nirglucose.twin.calibration import COVERAGE_BAND, calibrate
    from nirglucose.twin.device import TwinDevice
    from nirglucose.twin.inference import InferenceSettings, load_or_train
    from nirglucose.twin.parameters import fitted_parameters

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--devices", type=int, default=100)
    ap.add_argument("--draws", type=int, default=500)
    ap.add_argument("--simulations", type=int, default=InferenceSettings().n_simulations)
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--record", default=str(RECORD))
    a = ap.parse_args()
    if a.devices < 10 or a.draws < 50:
        ap.error("--devices must be >= 10 and --draws >= 50")
    t0 = time.time()
    device = TwinDevice((940.0,), 10, False, False, ("age_yr", "skin_temp_c"), False, 25, 8)
    params = fitted_parameters(device)
    settings = InferenceSettings(n_simulations=a.simulations, seed=a.seed)
    est, cached = load_or_train(device, params, settings, n_jobs=a.jobs)
    t_train = time.time() - t0
    res = calibrate(device, params, est, n_devices=a.devices, n_draws=a.draws,
                    seed=a.seed, n_jobs=a.jobs)
    ident = {k: v for k, v in res["parameters"].items() if v["identified"]}
    out = {
        "device": device.to_json(), "settings": asdict(settings),
        "estimator": {k: est.meta[k] for k in ("n_train", "epochs", "simulate_s", "train_s")},
        "from_cache": cached, "coverage_band": list(COVERAGE_BAND), **res,
        "identified_met": all(v["meets_band"] for v in ident.values()),
        "seconds": {"train_or_load": round(t_train, 1),
                    "calibration": round(time.time() - t0 - t_train, 1)},
    }
    Path(a.record).write_text(json.dumps(out, indent=1) + "\n")
    short = {k: {"coverage": v["coverage"], "identified": v["identified"]}
             for k, v in res["parameters"].items()}
    print(json.dumps({"n_devices": res["n_devices"], "coverage": short,
                      "identified_met": out["identified_met"], "seconds": out["seconds"]}))


if __name__ == "__main__":
    main()
