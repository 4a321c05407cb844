"""Where an LED band's light comes from in the ``swir`` table: shares by dermal absorption.

The ``swir`` table's own error grows with the dermal absorption (fewer photons reach the
detector with a path short enough to count; ``studies/optics_reference.py --grid
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
import time
import warnings

import numpy as np
from optics_reference import MUA_DERMIS_BINS as BINS
from optics_reference import N_TISSUE, RHO_CM, T_EPI_CM, use_bench_cache
from optics_reference import mua_dermis_bin_names as _bin_names

SKIN_CM = 0.15  # nominal skin thickness of the bands [cm]
LEDS_NM = (1300.0, 1350.0, 1450.0, 1550.0, 1600.0, 1650.0)
FWHMS_NM = (50.0, 100.0)
MELANIN = {"I": 0.015, "VI": 0.15}


def _bin_errors(ap: argparse.ArgumentParser, text: str | None) -> dict[str, float] | None:
    """``--bin-errors`` read: a JSON object of known bins to finite numbers, else one line."""
    if not text:
        return None
    try:
        doc = json.loads(text)
    except json.JSONDecodeError as exc:
        ap.error(f"--bin-errors is not JSON: {exc.msg}")
    names = _bin_names()
    if not isinstance(doc, dict) or set(doc) - set(names):
        ap.error(f"--bin-errors must be a JSON object of bins among {', '.join(names)}")
    try:
        out = {k: float(v) for k, v in doc.items()}
    except (TypeError, ValueError):
        ap.error("--bin-errors: every value must be a number (an RMS relative error)")
    if not all(np.isfinite(v) and v >= 0 for v in out.values()):
        ap.error("--bin-errors: every value must be a finite number >= 0")
    return out


def main(argv: list[str] | None = None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--bin-errors", default=None,
                    help="JSON object: dermal-mua bin (e.g. '8-14') -> RMS relative error")
    args = ap.parse_args(argv)
    bin_errors = _bin_errors(ap, args.bin_errors)
    use_bench_cache()
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
                    row["error_bound"] = round(sum(share[k] * bin_errors.get(k, 0.0)
                                                   for k in share), 5)
                out["bands"][f"{centre:g}nm/{fwhm:g}nm/{skin}"] = row
    out["seconds"] = round(time.perf_counter() - start, 2)
    return out


if __name__ == "__main__":
    print(json.dumps(main()))
