"""Speed and accuracy of the slab solvers on the MCML benchmark slab.

Prints a short human-readable summary and, on its last line, one JSON object:

* ``slab_rt_ms_per_solve``: adding-doubling time per element (default quadrature),
  measured on a vector of 40 different absorptions.
* ``slab_rt_ms_per_solve_quad8``: the same with ``quad_pts=8``.
* ``mc_photons_per_s``: Monte Carlo packets per second on the benchmark slab.
* ``ad_rd_rel_err`` / ``ad_tt_rel_err`` and ``mc_rd_rel_err`` / ``mc_tt_rel_err``:
  relative errors against the published MCML values (Rd = 0.09734, Tt = 0.66096;
  Wang, Jacques & Zheng 1995, doi:10.1016/0169-2607(95)01640-F), with the Monte
  Carlo standard errors ``mc_rd_rel_se`` / ``mc_tt_rel_se``.

Run: ``python benchmarks/optics_solvers.py [n_photons]`` (default 1 000 000).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "validation"))  # nirglucose_reference
from nirglucose_reference.adding_doubling import slab_rt  # noqa: E402
from nirglucose_reference.monte_carlo import mc_slab  # noqa: E402

MCML_RD = 0.09734
MCML_TT = 0.66096
BENCH = (10.0, 90.0, 0.75, 0.02, 1.0)  # mua, mus [1/cm], g, d [cm], n


def _time_slab_rt(quad_pts: int) -> float:
    mua = np.linspace(1.0, 20.0, 40)
    slab_rt(mua[:2], 90.0, 0.75, 0.02, 1.4, quad_pts=quad_pts)  # warm-up (imports)
    t0 = time.perf_counter()
    slab_rt(mua, 90.0, 0.75, 0.02, 1.4, quad_pts=quad_pts)
    return (time.perf_counter() - t0) / mua.size * 1e3


def main(n_photons: int = 1_000_000) -> dict[str, float]:
    ms16 = _time_slab_rt(16)
    ms8 = _time_slab_rt(8)
    r_ad, t_ad = slab_rt(*BENCH)

    t0 = time.perf_counter()
    res = mc_slab(*BENCH, n_photons=n_photons, rng=20240601)
    dt = time.perf_counter() - t0

    out = {
        "slab_rt_ms_per_solve": round(ms16, 3),
        "slab_rt_ms_per_solve_quad8": round(ms8, 3),
        "mc_photons_per_s": round(n_photons / dt),
        "mc_n_photons": n_photons,
        "ad_rd": round(float(r_ad), 6),
        "ad_tt": round(float(t_ad), 6),
        "ad_rd_rel_err": round(float(r_ad) / MCML_RD - 1, 6),
        "ad_tt_rel_err": round(float(t_ad) / MCML_TT - 1, 6),
        "mc_rd": round(res.diffuse_reflectance, 6),
        "mc_tt": round(res.total_transmittance, 6),
        "mc_rd_rel_err": round(res.diffuse_reflectance / MCML_RD - 1, 6),
        "mc_tt_rel_err": round(res.total_transmittance / MCML_TT - 1, 6),
        "mc_rd_rel_se": round(res.diffuse_reflectance_se / MCML_RD, 6),
        "mc_tt_rel_se": round(res.total_transmittance_se / MCML_TT, 6),
    }
    print(f"adding-doubling: {ms16:.2f} ms/solve (quad 16), {ms8:.2f} ms/solve (quad 8)")
    print(f"  MCML slab Rd={float(r_ad):.5f} Tt={float(t_ad):.5f}")
    print(f"Monte Carlo: {n_photons / dt:,.0f} photons/s")
    print(
        f"  MCML slab Rd={res.diffuse_reflectance:.5f}+-{res.diffuse_reflectance_se:.5f} "
        f"Tt={res.total_transmittance:.5f}+-{res.total_transmittance_se:.5f}"
    )
    print(json.dumps(out))
    return out


def _cli(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("n_photons", nargs="?", type=int, default=1_000_000,
                    help="Monte Carlo photon packets (default 1 000 000)")
    args = ap.parse_args(argv)
    if args.n_photons < 1:
        ap.error(f"n_photons = {args.n_photons} is invalid; expected an integer >= 1")
    main(args.n_photons)
    return 0


if __name__ == "__main__":
    sys.exit(_cli())
