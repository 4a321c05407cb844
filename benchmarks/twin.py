"""Benchmark of a device's twin (:func:`nirglucose.fit_twin`): first file, then a second.

A 25-subject device file (one to four LEDs, a 10-bit ADC, 8 readings per person,
reference glucose, two physiological columns; simulated on the ``physical`` preset with a
hidden LED and glucose gain 11) is fitted twice in a fresh cache directory:

* ``first``: the device's posterior estimator is trained (``--simulations`` simulated
  devices, the flow, the recalibration devices), then the file is fitted;
* ``second``: another file of the same device (another seed) is fitted with the cached
  estimator: cache load, summaries, posterior sampling, posterior predictive checks, the
  device bound and the file's CV errors (``timing`` of ``twin.json``).

For each, the wall time and the CPU time of this process and its worker processes
(psutil, read every second so that workers the pool retires still count; on a shared
machine the wall time also counts other processes' turns, the CPU time does not), and
the stages' wall times (``timing.stages_s`` of ``twin.json``). The command line adds its
start (imports) and ``nirglucose report`` to the second file's time: ``--cli`` times
``nirglucose twin`` and ``nirglucose report`` of the second file as commands too. Goal
(issue 41): first <= 600 s, second <= 30 s on 2 cores.

Prints a JSON object on its last line (times in seconds).

Usage: ``python benchmarks/twin.py [--leds 1] [--simulations 6000] [--jobs 2] [--cli]``
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import tempfile
import time
import warnings
from pathlib import Path

LED_SETS = {1: (940.0,), 2: (850.0, 940.0), 3: (850.0, 940.0, 1050.0),
            4: (850.0, 940.0, 1050.0, 1150.0)}


def _write(path: Path, wavelengths, seed: int) -> Path:
    import nirglucose as ng

    leds = [{"wavelength_nm": w, "fwhm_nm": 35.0, "power_mw": 2.2,
             "responsivity_a_per_w": 0.55, "glucose_gain": 11.0} for w in wavelengths]
    f = ng.simulate("physical", n_subjects=25, per_subject=8, seed=seed,
                    overrides={"leds": leds, "hardware.adc_bits": 10}).frame
    cols = ["subject_id", "glucose_mgdl", *(f"adc_{w:g}" for w in wavelengths), "age_yr",
            "skin_temp_c"]
    f[cols].to_csv(path, index=False)
    return path


def _cpu_s() -> dict[int, float]:
    """CPU seconds (user + system) of this process and of each live descendant (the
    worker processes stay alive between calls, so their time is read, not waited for)."""
    import psutil

    me = psutil.Process()
    out = {}
    for p in (me, *me.children(recursive=True)):
        try:
            t = p.cpu_times()
        except psutil.Error:
            continue
        out[p.pid] = t.user + t.system
    return out


class _CpuWatch:
    """The CPU seconds of this process and its descendants over a block, read every
    ``every_s`` seconds so that a worker the pool retires meanwhile (loky ends idle
    workers) still counts, up to its last reading."""

    def __init__(self, every_s: float = 1.0) -> None:
        import threading

        self.every_s, self.seen, self._stop = every_s, {}, threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)

    def _run(self) -> None:
        while not self._stop.wait(self.every_s):
            self.seen.update(_cpu_s())

    def __enter__(self):
        self.start = _cpu_s()
        self._thread.start()
        return self

    def __exit__(self, *exc) -> None:
        self._stop.set()
        self._thread.join()
        self.seen.update(_cpu_s())
        self.cpu_s = sum(v - self.start.get(pid, 0.0) for pid, v in self.seen.items())


def _fit(path: Path, settings, jobs: int) -> tuple[dict, object]:
    import nirglucose as ng

    t0 = time.perf_counter()
    with _CpuWatch() as watch, warnings.catch_warnings():
        warnings.simplefilter("ignore")
        twin = ng.fit_twin(path, adc_bits=10, settings=settings, n_jobs=jobs)
    cpu = watch.cpu_s
    return {"wall_s": round(time.perf_counter() - t0, 1), "cpu_s": round(cpu, 1),
            "cached_estimator": twin.info["timing"]["cached_estimator"],
            "stages_s": twin.info["timing"].get("stages_s")}, twin


def _command(args: list[str]) -> dict:
    """Wall and CPU seconds of ``nirglucose ARGS`` in a fresh interpreter (its start and
    imports included; CPU of the process and the workers it waited for)."""
    import resource
    import subprocess
    import sys

    r0, t0 = resource.getrusage(resource.RUSAGE_CHILDREN), time.perf_counter()
    done = subprocess.run([sys.executable, "-m", "nirglucose.cli", *args],
                          capture_output=True, text=True, check=False)
    r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    if done.returncode:
        raise SystemExit(f"nirglucose {' '.join(args)} failed: {done.stderr.strip()[-300:]}")
    return {"wall_s": round(time.perf_counter() - t0, 1),
            "cpu_s": round(r1.ru_utime - r0.ru_utime + r1.ru_stime - r0.ru_stime, 1)}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--leds", type=int, default=1, choices=sorted(LED_SETS))
    ap.add_argument("--simulations", type=int, default=6000)
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--cli", action="store_true",
                    help="also time the second file as commands (twin, then report)")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        os.environ["NIRGLUCOSE_CACHE"] = str(Path(tmp) / "cache")
        from nirglucose.twin import InferenceSettings

        settings = InferenceSettings(n_simulations=args.simulations)
        wl = LED_SETS[args.leds]
        first, _ = _fit(_write(Path(tmp) / "a.csv", wl, 11), settings, args.jobs)
        second, twin = _fit(_write(Path(tmp) / "b.csv", wl, 12), settings, args.jobs)
        cli = None
        if args.cli:
            out = str(Path(tmp) / "tw")
            cli = {"twin": _command(["twin", "--data", str(Path(tmp) / "b.csv"), "--out", out,
                                     "--adc-bits", "10", "--simulations",
                                     str(args.simulations), "--jobs", str(args.jobs)]),
                   "report": _command(["report", out])}
            cli["total_wall_s"] = round(cli["twin"]["wall_s"] + cli["report"]["wall_s"], 1)
            cli["total_cpu_s"] = round(cli["twin"]["cpu_s"] + cli["report"]["cpu_s"], 1)
    print(json.dumps({
        "benchmark": "twin", "leds": args.leds, "subjects": 25, "per_subject": 8,
        "simulations": args.simulations, "jobs": args.jobs, "cpus": os.cpu_count(),
        "load_1min": round(os.getloadavg()[0], 2), "python": platform.python_version(),
        "first": first, "second": second, "second_cli": cli,
        "goal_s": {"first": 600, "second": 30},
    }))


if __name__ == "__main__":
    main()
