"""``make run``'s budget: wall and CPU seconds of each stage of the job, as the Makefile runs it.

The commands are the Makefile's own (``make -n run``, with ``BIN`` set to this Python's
directory, the install step left out and ``OUT`` a scratch directory), so a change to
the Makefile's presets, models or protocol is what gets timed. Each command runs in a
subprocess; its CPU time is the user + system time of the process and every worker it
waited for (``RUSAGE_CHILDREN``), so it holds on a machine shared with others, where the
wall time does not. Per preset, the benchmark's own wall time and the summed CPU of its
tasks (``meta.json``: ``wall_time_s``, ``tasks_cpu_s``) split the benchmark stage.

Budget (issue 43): ``make run`` installed in at most 180 s of wall time on 2 idle cores,
which needs the CPU total at most about 300 s (the two benchmark workers are not busy
all the time, and the report draws on one core).

Environment: ``NIRGLUCOSE_BENCH_MAKE_VARS`` (extra ``make`` variables, e.g.
``"PRESET=paper MODELS=ebl,pls,mean,gp,gbr"`` for a scaled run; default none: the full
job), ``NIRGLUCOSE_BENCH_DIR`` (the output directory, created if needed and kept, its
``results/`` removed first so the run is cold; default a temporary one, deleted
afterwards).

Prints one JSON object on its last line.
"""

from __future__ import annotations

import json
import os
import resource
import shlex
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
#: issue 43: ``make run`` installed within 3 minutes on 2 cores.
WALL_BUDGET_S = 180.0
#: The CPU total that fits the wall budget on 2 cores (see the module docstring).
CPU_BUDGET_S = 300.0


def _commands(out: Path, extra: list[str]) -> list[str]:
    """The shell commands of ``make run`` (continuation lines joined, echoes left out)."""
    bin_dir = Path(sys.executable).parent
    text = subprocess.run(
        ["make", "-s", "-n", "-C", str(ROOT), "run", f"BIN={bin_dir}", "STAMP=",
         f"OUT={out}", *extra], capture_output=True, text=True, check=True).stdout
    lines = text.replace("\\\n", " ").splitlines()
    return [ln.strip() for ln in lines if ln.strip() and not ln.strip().startswith("echo")]


def _stage_name(command: str) -> str:
    words = shlex.split(command)
    return words[1] if len(words) > 1 else words[0]


def _run(command: str, log: Path) -> dict:
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    with log.open("w") as f:
        proc = subprocess.run(command, shell=True, cwd=ROOT, stdout=f, stderr=subprocess.STDOUT)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if proc.returncode:
        tail = log.read_text()[-2000:]
        raise SystemExit(f"{command!r} exited {proc.returncode}:\n{tail}")
    user, system = after.ru_utime - before.ru_utime, after.ru_stime - before.ru_stime
    return {"stage": _stage_name(command), "command": command, "wall_s": round(wall, 2),
            "cpu_s": round(user + system, 2), "user_s": round(user, 2),
            "sys_s": round(system, 2)}


def _presets(out: Path) -> list[dict]:
    """Each preset's benchmark: its own wall time, its tasks' CPU, its models and protocol."""
    rows = []
    dirs = [d for d in sorted(out.iterdir()) if (d / "meta.json").is_file()]
    for d in dirs or ([out] if (out / "meta.json").is_file() else []):
        meta = json.loads((d / "meta.json").read_text())
        rows.append({"preset": meta.get("preset"), "wall_s": round(meta["wall_time_s"], 2),
                     "task_cpu_s": round(float(meta.get("tasks_cpu_s", float("nan"))), 2),
                     "tasks": meta.get("tasks_total"),
                     "folds": meta.get("n_splits"), "repeats": meta.get("repeats"),
                     "models": list(meta.get("models", []))})
    return rows


def main() -> dict:
    extra = shlex.split(os.environ.get("NIRGLUCOSE_BENCH_MAKE_VARS", ""))
    scratch = os.environ.get("NIRGLUCOSE_BENCH_DIR")
    base = Path(scratch) if scratch else Path(tempfile.mkdtemp(prefix="make-run-"))
    base.mkdir(parents=True, exist_ok=True)
    out = base / "results"
    if out.exists():  # a cold run: no task of a previous one is reused
        shutil.rmtree(out)
    try:
        commands = _commands(out, extra)
        load0 = os.getloadavg()[0]
        stages = [_run(c, base / f"stage{i}.log") for i, c in enumerate(commands)]
        presets = _presets(out)
        load1 = os.getloadavg()[0]
    finally:
        if not scratch:
            shutil.rmtree(base, ignore_errors=True)
    wall = sum(s["wall_s"] for s in stages)
    cpu = sum(s["cpu_s"] for s in stages)
    return {
        "benchmark": "make_run",
        "make_vars": extra,
        "stages": stages,
        "presets": presets,
        "total_wall_s": round(wall, 2),
        "total_cpu_s": round(cpu, 2),
        "wall_budget_s": WALL_BUDGET_S,
        "cpu_budget_s": CPU_BUDGET_S,
        "within_cpu_budget": cpu <= CPU_BUDGET_S,
        "within_wall_budget": wall <= WALL_BUDGET_S,
        "cores": os.cpu_count(),
        # a loaded machine stretches the wall time, not the CPU time
        "load_average_1min": [round(load0, 2), round(load1, 2)],
    }


if __name__ == "__main__":
    print(json.dumps(main()))
