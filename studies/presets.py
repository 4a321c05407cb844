"""Raw correlation and EBL accuracy of every preset (issue 18: device capabilities).

Protocol, per preset:

* raw correlation rho: the largest over the LED channels of |Pearson r| between
  ``glucose_mgdl`` and ``log(adc_<nm>)`` on 20,000 snapshots (5,000 subjects x 4),
  for seeds 0-4; mean and SD over the seeds (README, "Presets and calibration");
* accuracy: ``simulate(preset, 80, 3, seed)`` for seeds 0-4, subject-grouped 5-fold
  CV (:class:`sklearn.model_selection.GroupKFold` on ``subject_id``, as the benchmark
  uses), RMSE of the 240 pooled out-of-fold predictions; mean and SD over the seeds, for

  - ``ebl``: ``make_model("ebl", **tuned_params("ebl", preset))`` as the benchmark
    builds it (every physiological column the device records, the PPG columns of
    ``paper`` included; the ridge penalty tuned on seeds 1000-1002, disjoint from these;
    its own inner subject-grouped CV for a preset the tuning does not cover);
  - ``no_skill``: the training folds' mean glucose.

Options: ``--presets paper,wearable`` (default: all), ``--set key=value`` (applied to
every preset, e.g. for calibration), ``--seeds 5``, ``--no-accuracy`` (rho only).
Calibration of ``paper``'s ``glucose.signal_gain``: ``--presets paper --no-accuracy
--set glucose.signal_gain=G`` over G on a grid of 0.5; the gain whose mean rho is
closest to 0.21 is chosen (rho alone, never the RMSE).

Not a timed test. Prints one JSON object on its last line.
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np

N_RHO_SUBJECTS, RHO_PER_SUBJECT = 5_000, 4  # 20,000 snapshots
N_SUBJECTS, PER_SUBJECT, N_SPLITS = 80, 3, 5



def raw_correlation(frame) -> float:
    """max over channels of |r(glucose_mgdl, log adc_<nm>)|."""
    g = frame["glucose_mgdl"].to_numpy(float)
    cols = [c for c in frame.columns if c.startswith("adc_") and not c.startswith("adc_ref_")]
    return max(abs(np.corrcoef(g, np.log(frame[c].to_numpy(float)))[0, 1]) for c in cols)


def accuracy(preset: str, seed: int, overrides: dict) -> dict:
    """Grouped-CV RMSE of ebl and the no-skill mean for one seed."""
    from sklearn.model_selection import GroupKFold

    import nirglucose as ng
    from nirglucose.models import make_model, tuned_params

    ds = ng.simulate(preset, N_SUBJECTS, PER_SUBJECT, seed=seed, overrides=overrides)
    frame = ds.frame
    y = frame["glucose_mgdl"].to_numpy(float)
    groups = frame["subject_id"].to_numpy()
    pred = {k: np.empty_like(y) for k in ("ebl", "no_skill")}
    for tr, te in GroupKFold(n_splits=N_SPLITS).split(frame, y, groups):
        train = ng.Dataset(frame.iloc[tr].reset_index(drop=True), config=ds.config)
        test = ng.Dataset(frame.iloc[te].reset_index(drop=True), config=ds.config)
        ebl = make_model("ebl", **tuned_params("ebl", preset))  # {} for an untuned preset
        pred["ebl"][te] = ebl.fit(train).predict(test)
        pred["no_skill"][te] = y[tr].mean()
    return {k: float(np.sqrt(np.mean((p - y) ** 2))) for k, p in pred.items()}


def _mean_sd(values) -> dict:
    v = np.asarray(values, float)
    return {"mean": round(float(v.mean()), 4), "sd": round(float(v.std(ddof=1)), 4)}


def main(argv=None) -> dict:
    import nirglucose as ng
    from nirglucose.config import PRESETS, device_capabilities, parse_override

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--presets", default=",".join(PRESETS))
    ap.add_argument("--set", action="append", default=[], dest="overrides")
    ap.add_argument("--seeds", type=int, default=5)
    ap.add_argument("--no-accuracy", action="store_true")
    args = ap.parse_args(argv)
    overrides = dict(parse_override(o) for o in args.overrides)
    seeds = range(args.seeds)
    t0 = time.perf_counter()
    out: dict = {"protocol": {"rho_snapshots": N_RHO_SUBJECTS * RHO_PER_SUBJECT,
                              "cv": f"{N_SUBJECTS}x{PER_SUBJECT}, GroupKFold({N_SPLITS})",
                              "seeds": list(seeds), "overrides": overrides}, "presets": {}}
    for preset in args.presets.split(","):
        cfg = ng.resolve_config(preset, overrides)
        rho = [
            raw_correlation(
                ng.simulate(preset, N_RHO_SUBJECTS, RHO_PER_SUBJECT, s, overrides=overrides).frame
            )
            for s in seeds
        ]
        row = {
            "signal_gain": cfg.glucose.signal_gain,
            "capabilities": list(device_capabilities(cfg)),
            "rho": _mean_sd(rho),
        }
        if not args.no_accuracy:
            acc = [accuracy(preset, s, overrides) for s in seeds]
            for k in acc[0]:
                row[f"rmse_{k}_mgdl"] = _mean_sd([a[k] for a in acc])
        out["presets"][preset] = row
        print(preset, json.dumps(row), flush=True)
    out["elapsed_s"] = round(time.perf_counter() - t0, 1)
    return out


if __name__ == "__main__":
    print(json.dumps(main()))
