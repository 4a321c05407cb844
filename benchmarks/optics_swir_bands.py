"""Where an LED band's light comes from in the ``swir`` table: shares by dermal absorption.

The ``swir`` table's own error grows with the dermal absorption (fewer photons reach the
detector with a path short enough to count; ``benchmarks/optics_reference.py --grid
swir`` measures it per absorption bin). What a device sees is the band integral, in which
the nodes near the 1450 nm water peak weigh little. For LED bands at 1300-1650 nm (FWHM
50 and 100 nm, the simulator's band nodes and weights), nominal skin of
:func:`nirglucose.optics.layers.skin_layer_optics` (Fitzpatrick I and VI melanosome
fractions 0.015 and 0.15, skin 1.5 mm, 3 mm separation), this gives:

* ``share_by_mua_dermis``: the share of the band's detected light from nodes in each
  dermal absorption bin of ``optics_reference.py`` (0-2, 2-8, 8-14, above 14 /cm);
* ``table_over_diffusion``: the band's detected light, table over the three-layer
  diffusion model (how far transport departs from diffusion there);
* ``error_bound``: with ``--bin-errors`` (a JSON object bin -> RMS relative error,
  e.g. from ``optics_reference.py``), the band's RMS error were each node off by its
  bin's RMS error in the same direction (an upper bound for errors of one sign).

Needs the ``swir`` table in the cache (``NIRGLUCOSE_BENCH_LUT_CACHE`` or the user
cache; a cold cache builds it). Prints one JSON object on its last line.
"""

from __future__ import annotations

import argparse
import json
import os
import time
import warnings

import numpy as np

RHO_CM, T_EPI_CM, N_TISSUE, SKIN_CM = 0.3, 0.008, 1.4, 0.15
BINS = (0.0, 2.0, 8.0, 14.0, np.inf)
LEDS_NM = (1300.0, 1350.0, 1450.0, 1550.0, 1600.0, 1650.0)
FWHMS_NM = (50.0, 100.0)
MELANIN = {"I": 0.015, "VI": 0.15}


def _bin_names() -> list[str]:
    return [f"{lo:g}-{hi:g}" for lo, hi in zip(BINS[:-1], BINS[1:], strict=True)]


def main(argv: list[str] | None = None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--bin-errors", default=None,
                    help="JSON object: dermal-mua bin (e.g. '8-14') -> RMS relative error")
    args = ap.parse_args(argv)
    bin_errors = json.loads(args.bin_errors) if args.bin_errors else None
    cache = os.environ.get("NIRGLUCOSE_BENCH_LUT_CACHE")
    if cache:
        os.environ["NIRGLUCOSE_CACHE"] = cache
    from nirglucose.optics import lut as L
    from nirglucose.optics.layers import skin_layer_optics, three_layer_reflectance
    from nirglucose.optics.tissue import band_spectra

    start = time.perf_counter()
    lut = L.load_or_build_lut(RHO_CM, T_EPI_CM, N_TISSUE, grid="swir")
    out: dict = {"table_key": lut.key, "bins_mua_dermis_per_cm": _bin_names(), "bands": {}}
    for fwhm in FWHMS_NM:
        spectra = band_spectra(LEDS_NM, (fwhm,) * len(LEDS_NM), n_points=5)
        for i, centre in enumerate(LEDS_NM):
            nodes, weights = spectra.nodes_nm[i], spectra.weights[i]
            for skin, mel in MELANIN.items():
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore", UserWarning)  # the lipid hold
                    o = {k: np.ravel(v) for k, v in
                         skin_layer_optics(list(nodes), melanin_fraction=mel).items()}
                kw = {"mua_epidermis_per_cm": o["mua_epidermis"],
                      "mua_dermis_per_cm": o["mua_dermis"],
                      "musp_dermis_per_cm": o["musp_dermis"],
                      "mua_subcutis_per_cm": o["mua_subcutis"],
                      "musp_subcutis_per_cm": o["musp_subcutis"],
                      "skin_thickness_cm": np.full(nodes.size, SKIN_CM)}
                r_lut, _ = L.interpolate_lut(lut, **kw)
                r_dif, _ = three_layer_reflectance(RHO_CM, epidermis_thickness_cm=T_EPI_CM,
                                                   n_tissue=N_TISSUE, **kw)
                light = weights * r_lut
                which = np.digitize(o["mua_dermis"], BINS[1:-1])
                share = {name: round(float(light[which == b].sum() / light.sum()), 5)
                         for b, name in enumerate(_bin_names())}
                row = {"share_by_mua_dermis": share,
                       "table_over_diffusion": round(float(light.sum()
                                                           / (weights * r_dif).sum()), 4)}
                if bin_errors is not None:
                    row["error_bound"] = round(sum(share[k] * float(bin_errors.get(k, 0.0))
                                                   for k in share), 5)
                out["bands"][f"{centre:g}nm/{fwhm:g}nm/{skin}"] = row
    out["seconds"] = round(time.perf_counter() - start, 2)
    return out


if __name__ == "__main__":
    print(json.dumps(main()))
