"""How the requirements study's InGaAs answer moves with the first-overtone assumption.

Glucose's first C–H overtone band (about 1,600 nm) has a published position but no
published absorptivity the package could cite (``src/nirglucose/data/optics/SOURCES.md``):
its height is ``glucose.first_overtone_relative_peak`` times the 1,150 nm band (10 by
default, an assumption). This reruns ``nirglucose sweep --study requirements`` for the
InGaAs detector (the only one whose bands reach the overtone; the Si answer stops at
1,100 nm) at several heights, confirming each named design with the oracle and the
training mean, and prints one JSON object on its last line: per height, the least
design's answer line (``studies/records/requirements_overtone.json``).

Usage: python studies/requirements_overtone.py [--peaks 1,2.5,5,10,20] [--out DIR]
"""

from __future__ import annotations

import argparse
import json
import tempfile
from pathlib import Path

from nirglucose.cli import main


def run(peak: float, out: Path) -> str:
    """The InGaAs answer line of one overtone height."""
    code = main(["sweep", "--study", "requirements", "--vary", "detector=G17190-010K",
                 "--models", "mean,oracle", "--set",
                 f"glucose.first_overtone_relative_peak={peak:g}", "--out", str(out),
                 "--jobs", "1"])
    if code != 0:
        raise SystemExit(f"the requirements study failed at peak {peak:g} (exit {code})")
    (line,) = json.loads((out / "requirements.json").read_text())["answer"]
    return line


def cli() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--peaks", default="1,2.5,5,10,20")
    ap.add_argument("--out", type=Path, default=None)
    a = ap.parse_args()
    root = a.out or Path(tempfile.mkdtemp(prefix="req-overtone-"))
    root.mkdir(parents=True, exist_ok=True)
    peaks = [float(p) for p in a.peaks.split(",")]
    answers = {f"{p:g}": run(p, root / f"peak{p:g}") for p in peaks}
    print(json.dumps({"detector": "G17190-010K", "preset": "physical",
                      "key": "glucose.first_overtone_relative_peak", "default": 10.0,
                      "answers": answers}))


if __name__ == "__main__":
    cli()
