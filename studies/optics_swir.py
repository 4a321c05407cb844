"""Optics from 1300 to 1700 nm: the transport regime and the lipid hold (issue 30).

The numbers quoted in ``src/nirglucose/data/optics/SOURCES.md`` ("Above 1300 nm") and
``docs/user_guide/optics.md`` (700-1,700 nm section), at the nominal skin of
:func:`nirglucose.optics.layers.skin_layer_optics` (melanosome fraction 0.02), g = 0.9,
n = 1.4, 3 mm separation:

* ``regime``: per wavelength, dermal mua and mus' [1/cm]; adding-doubling / Monte Carlo
  total reflectance of a 3 mm dermis slab (80 000 photons) and the Monte Carlo standard
  error; Monte Carlo / Farrell diffusion R(3 mm) on a semi-infinite dermis (40 000
  photons, detector annulus 2.5-3.5 mm) and the Monte Carlo mean path of the detected
  light / the diffusion DPF x rho;
* ``lipid_hold``: R(3 mm) of the three-layer diffusion model with the subcutis' fat mua
  10 x the held value (fat fraction 0.8), over R with the held value, by skin thickness;
* ``lut_limits``: the wavelengths where nominal dermis reaches the default table's
  mua_dermis bound (2 /cm) and where the fat/skin mus' ratio reaches 0.85.

About 45 s of one CPU. Prints one JSON object on its last line.
"""

from __future__ import annotations

import json
import sys
import time
import warnings
from pathlib import Path

import numpy as np

from nirglucose.optics import absorption, scattering
from nirglucose.optics.diffusion import differential_pathlength_factor, farrell_reflectance
from nirglucose.optics.layers import skin_layer_optics, three_layer_reflectance

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "validation"))  # nirglucose_reference
from nirglucose_reference.adding_doubling import slab_rt  # noqa: E402
from nirglucose_reference.monte_carlo import mc_slab  # noqa: E402

G, N_TISSUE, RHO_CM = 0.9, 1.4, 0.3


def _regime(wavelengths_nm):
    o = skin_layer_optics(list(wavelengths_nm), melanin_fraction=0.02)
    out = {}
    for wl, mua, musp in zip(wavelengths_nm, np.ravel(o["mua_dermis"]),
                             np.ravel(o["musp_dermis"]), strict=True):
        mus = musp / (1.0 - G)
        slab = mc_slab(mua, mus, G, 0.3, N_TISSUE, n_photons=80_000, rng=6)
        r_ad, _ = slab_rt(mua, mus, G, 0.3, N_TISSUE)
        semi = mc_slab(mua, mus, G, np.inf, N_TISSUE, n_photons=40_000, rng=5,
                       rho_edges_cm=np.array([0.25, 0.35]))
        r_fd = float(farrell_reflectance(RHO_CM, mua, musp, N_TISSUE))
        path_fd = RHO_CM * float(differential_pathlength_factor(RHO_CM, mua, musp))
        out[f"{wl:g}"] = {
            "mua_dermis_per_cm": round(float(mua), 3),
            "musp_dermis_per_cm": round(float(musp), 3),
            "ad_over_mc_slab": round(float(r_ad) / slab.total_reflectance, 4),
            "mc_slab_rel_se": round(slab.total_reflectance_se / slab.total_reflectance, 4),
            "mc_over_farrell_3mm": round(semi.reflectance_per_cm2[0] / r_fd, 3),
            "mc_over_farrell_rel_se": round(
                semi.reflectance_per_cm2_se[0] / semi.reflectance_per_cm2[0], 3),
            "mc_path_over_dpf_path": round(float(semi.pathlength_at_rho_cm[0]) / path_fd, 3),
        }
    return out


def _lipid_hold():
    held = float(absorption.lipid_mua_per_cm(absorption.LIPID_TABLE_END_NM))
    out = {}
    for wl in (1650.0, 1700.0):
        o = {k: float(np.ravel(v)[0]) for k, v in
             skin_layer_optics([wl], melanin_fraction=0.02).items()}
        for t_cm in (0.08, 0.158, 0.25):
            kw = dict(mua_epidermis_per_cm=o["mua_epidermis"],
                      mua_dermis_per_cm=o["mua_dermis"], musp_dermis_per_cm=o["musp_dermis"],
                      musp_subcutis_per_cm=o["musp_subcutis"], epidermis_thickness_cm=0.008,
                      skin_thickness_cm=t_cm, pathlengths=False)
            r0, _ = three_layer_reflectance(RHO_CM, mua_subcutis_per_cm=o["mua_subcutis"], **kw)
            r1, _ = three_layer_reflectance(
                RHO_CM, mua_subcutis_per_cm=o["mua_subcutis"] + 0.8 * 9.0 * held, **kw)
            out[f"{wl:g}nm_skin_{10 * t_cm:g}mm"] = round(float(r1 / r0), 3)
    return {"held_mua_per_cm": held, "r_ratio_with_10x_fat": out}


def _lut_limits():
    wl = np.arange(1300.0, 1450.0, 0.5)
    mua = np.ravel(skin_layer_optics(wl, melanin_fraction=0.02)["mua_dermis"])
    ratio = (scattering.power_law_musp_per_cm(wl, *scattering.FAT_MUSP)
             / scattering.power_law_musp_per_cm(wl, *scattering.SKIN_MUSP))
    return {"mua_dermis_reaches_2_per_cm_nm": float(wl[np.argmax(mua >= 2.0)]),
            "musp_ratio_reaches_0p85_nm": float(wl[np.argmax(ratio >= 0.85)])}


def main() -> dict:
    t0 = time.process_time()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)  # the lipid hold, stated in SOURCES.md
        result = {
            "regime": _regime((850.0, 1150.0, 1450.0, 1550.0, 1650.0)),
            "lipid_hold": _lipid_hold(),
            "lut_limits": _lut_limits(),
        }
    result["cpu_s"] = round(time.process_time() - t0, 1)
    return result


if __name__ == "__main__":
    print(json.dumps(main()))
