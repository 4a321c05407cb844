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

Setup: the ``swir`` geometry (rho 3 mm, epidermis 80 um, the grid's kernel and
roulette settings), skin mus' 14.5 /cm (the box's top: the detector farthest in
transport units) and 9 /cm, fat/skin mus' ratio 0.76, epidermis 2 /cm, skin thickness
tau 0.5, 2.65 and 5.8 transport mean free paths. References are per transport length,
as in the table (one run serves every mus' node): the table's own (0.25 /cm over
14.5 /cm) and 2, 4 and 8 /cm at mus' 14.5 /cm. The kernel's reference absorption is
the same in every layer, so the subcutis is given the box's top dermal mua here (above
every reference tried); the table itself would need a reference per layer, which
changes only the subcutis term.

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
from nirglucose.optics.lut import LUT_GRIDS, LUT_MC_PHOTONS, grid_mc_settings

GRID = LUT_GRIDS["swir"]
SETTINGS = grid_mc_settings("swir")
RHO_CM, T_EPI_CM = 0.3, 0.008  # the geometry of the validation (optics_reference.py)
HALF_CM = SETTINGS["half_width_cm"]
MUSP_TOP = GRID["musp_dermis_per_cm"][1]  # the box's top skin mus' [1/cm]
MUA_D = np.array([14.0, 20.0, GRID["mua_dermis_per_cm"][1]])  # dermal mua measured [1/cm]
#: The table's reference absorption per transport length: the box's smallest mua over
#: its largest mus' (``nirglucose.optics.lut.build``), the same for every mus' node. [-]
TABLE_REF = min(GRID["mua_dermis_per_cm"][0], GRID["mua_subcutis_per_cm"][0]) / MUSP_TOP
#: References tried, per transport length: the table's, and 2, 4 and 8 /cm at the top
#: mus' (what a second set of runs for the strongly absorbing nodes could use). [-]
REFS = (TABLE_REF, 2.0 / MUSP_TOP, 4.0 / MUSP_TOP, 8.0 / MUSP_TOP)
#: Photons per run: fewer at the table's reference (each photon lives longer). [-]
PHOTONS_TABLE_REF, PHOTONS_OTHER = 2_000_000, 8_000_000
CASES = [(MUSP_TOP, 0.5), (MUSP_TOP, 2.65), (MUSP_TOP, 5.8), (9.0, 2.65)]  # (mus' /cm, tau)


def _one(musp: float, tau: float, ref: float) -> dict:
    n = PHOTONS_TABLE_REF if ref == TABLE_REF else PHOTONS_OTHER
    m = np.array([musp])
    band = ((RHO_CM - HALF_CM) * musp, (RHO_CM + HALF_CM) * musp)
    cpu0 = time.process_time()
    run = mc_white.white_mc_run(tau, 0.76, m * T_EPI_CM, band, n_photons=n, seed=11,
                                mua_ref=ref, path_split=SETTINGS["path_split"], n_threads=1)
    cpu = time.process_time() - cpu0
    t = mc_white.white_mc_tally(run, RHO_CM, HALF_CM, m, np.array([2.0]), MUA_D,
                                np.array([MUA_D[-1]]))
    rel = (t["reflectance_se_per_cm2"] / t["reflectance_per_cm2"]).ravel()
    return {"reference_per_transport_length": round(ref, 5),
            "reference_per_cm_at_this_musp": round(ref * musp, 3), "photons": n,
            "cpu_s": round(cpu, 2), "rel_se": [round(float(v), 4) for v in rel],
            "merit": [float(1.0 / (v * v * cpu)) for v in rel]}


def main() -> None:
    out = []
    for musp, tau in CASES:
        rows = [_one(musp, tau, r) for r in REFS]
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
                      "table_photons": LUT_MC_PHOTONS["swir"],
                      "best_gain_over_table_reference": best}))


if __name__ == "__main__":
    main()
