"""Figure: rank histograms of the device twin's simulation-based calibration.

Reads studies/records/twin_calibration.json (studies/twin_calibration.py) and draws
one histogram per parameter (nirglucose.plots.twin.figure_rank_histograms).

Usage: python docs/make_twin_figure.py [out.png]
(default docs/figures/twin_rank_histograms.png)
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

from nirglucose.plots.style import figure_bytes
from nirglucose.plots.twin import figure_rank_histograms

ROOT = Path(__file__).resolve().parents[1]


def main() -> None:
    out = Path(sys.argv[1]) if len(sys.argv) > 1 else ROOT / "docs/figures/twin_rank_histograms.png"
    record = json.loads((ROOT / "studies/records/twin_calibration.json").read_text())
    out.write_bytes(figure_bytes(figure_rank_histograms(record), "png", close=True))
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
