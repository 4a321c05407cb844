"""Peak memory of the in-memory simulation per snapshot (sets resources.SIM_BYTES_PER_SNAPSHOT).

Runs ``simulate_frame`` on the paper preset in a fresh process for two sizes and
prints the slope of peak RSS (ru_maxrss) against the number of snapshots, so the
interpreter's and the tables' fixed cost cancels. The last line is one JSON object.

Usage: python tools/cli_memory.py [--small 300] [--large 3000]
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys

_CHILD = """
import resource, sys
from nirglucose.config import resolve_config
from nirglucose.simulation.simulator import simulate_frame
n = int(sys.argv[1])
frame = simulate_frame(resolve_config("paper"), n, 3, 0)
print(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024)
"""


def peak_rss_bytes(subjects: int) -> int:
    out = subprocess.run([sys.executable, "-c", _CHILD, str(subjects)], check=True,
                         capture_output=True, text=True).stdout
    return int(out.split()[-1])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--small", type=int, default=300, help="subjects of the small run")
    ap.add_argument("--large", type=int, default=3000, help="subjects of the large run")
    a = ap.parse_args()
    small, large = peak_rss_bytes(a.small), peak_rss_bytes(a.large)
    per = (large - small) / (3 * (a.large - a.small))
    print(json.dumps({"subjects": [a.small, a.large], "per_subject": 3,
                      "peak_rss_bytes": [small, large],
                      "bytes_per_snapshot": round(per)}))


if __name__ == "__main__":
    main()
