"""Would a higher reference absorption make the ``swir`` table precise above 14 /cm?

The ``swir`` table's error above a dermal absorption of 14 /cm (the 1450 nm water
peak: RMS 4.7 % against independent references, ``optics_reference.py --grid swir``) is
its own Monte Carlo noise: few photons reach the detector with a path short enough to
count. Its runs simulate the box's smallest absorption analogously (each photon's path
budget, :mod:`nirglucose.optics.kernels.mc_white`) and re-weight to every node. A second
set of runs for the strongly absorbing nodes, with a reference absorption near theirs,
would end each photon sooner (cheaper photons) but kill some of the short-path photons
that count (noisier ones). This measures the trade: the figure of merit
``1 / (relative SE^2 x CPU seconds)`` of R at the detector, per dermal absorption, for
runs with the table's reference absorption and with higher ones.

Setup: the ``swir`` geometry (rho 3 mm, epidermis 80 um, kernel rho +- 0.35 mm),
skin mus' 14.5 /cm (the box's top: the detector farthest in transport units) and
9 /cm, fat/skin mus' ratio 0.76, epidermis 2 /cm, skin thickness tau 0.5, 2.65 and
5.8 transport mean free paths. The kernel's reference absorption is the same in every
layer, so the subcutis is given 26 /cm here (at or above every reference tried); the
table itself would need a reference per layer, which changes only the subcutis term.

Prints one JSON object on its last line: per case and reference, CPU seconds, the
relative SE of R at dermal 14, 20 and 26 /cm, the figure of merit and its gain over the
table's reference; and the photons a table run would need for a relative SE of 0.4 %
(a table within 1 % everywhere) and 1 % at the table's reference.
"""

from __future__ import annotations

import json
import time

import numpy as np

from nirglucose.optics.kernels import mc_white

RHO_CM, T_EPI_CM, HALF_CM = 0.3, 0.008, 0.035
MUA_D = np.array([14.0, 20.0, 26.0])  # dermal absorption of the nodes measured [1/cm]
TABLE_REF_CM = 0.25  # the swir box's smallest absorption (subcutis) [1/cm]
REFS_CM = (TABLE_REF_CM, 2.0, 4.0, 8.0)  # reference absorptions tried [1/cm]
PHOTONS = {TABLE_REF_CM: 2_000_000}  # the table's reference; others get 8 000 000
CASES = [(14.5, 0.5), (14.5, 2.65), (14.5, 5.8), (9.0, 2.65)]  # (mus' /cm, tau)


def _one(musp: float, tau: float, ref_cm: float) -> dict:
    n = PHOTONS.get(ref_cm, 8_000_000)
    m = np.array([musp])
    band = ((RHO_CM - HALF_CM) * musp, (RHO_CM + HALF_CM) * musp)
    cpu0 = time.process_time()
    run = mc_white.white_mc_run(tau, 0.76, m * T_EPI_CM, band, n_photons=n, seed=11,
                                mua_ref=ref_cm / musp, path_split=300.0, n_threads=1)
    cpu = time.process_time() - cpu0
    t = mc_white.white_mc_tally(run, RHO_CM, HALF_CM, m, np.array([2.0]), MUA_D,
                                np.array([26.0]))
    rel = (t["reflectance_se_per_cm2"] / t["reflectance_per_cm2"]).ravel()
    return {"reference_per_cm": ref_cm, "photons": n, "cpu_s": round(cpu, 2),
            "rel_se": [round(float(v), 4) for v in rel],
            "merit": [float(1.0 / (v * v * cpu)) for v in rel]}


def main() -> None:
    out = []
    for musp, tau in CASES:
        rows = [_one(musp, tau, r) for r in REFS_CM]
        base = rows[0]
        for r in rows:
            r["gain"] = [round(a / b, 2) for a, b in zip(r["merit"], base["merit"], strict=True)]
            r["merit"] = [round(v, 1) for v in r["merit"]]
        # photons a table run needs at its reference for a relative SE of 0.4 % and 1 %
        need = {f"{target:g}": [int(base["photons"] * (se / target) ** 2)
                                for se in base["rel_se"]] for target in (0.004, 0.01)}
        out.append({"musp_per_cm": musp, "skin_transport_thickness": tau, "runs": rows,
                    "table_photons_needed": need})
        print(json.dumps(out[-1]), flush=True)
    best = max(g for c in out for r in c["runs"][1:] for g in r["gain"])
    print(json.dumps({"mua_dermis_per_cm": MUA_D.tolist(), "cases": out,
                      "best_gain_over_table_reference": best}))


if __name__ == "__main__":
    main()
