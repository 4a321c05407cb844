"""Hashes of the optics results, to show a refactor leaves them bit-identical.

Prints one JSON object on its last line: the SHA-256 of every array of a seeded run of
each photon engine front end (``mc_layers``, ``mc_slab``, ``mc_detected_paths`` and
``reweight_detected``), of the tiny look-up table built by both solvers, of its
interpolation (both variants) and of a small ``optics.model = rte-lut`` simulation
(tiny table, diffusion solver). ``tests/optics/data/optics_hashes_main.json`` holds the
output recorded at main's HEAD before the issue-22 split; ``tests/optics/
test_optics_hashes.py`` compares against it.

Usage: ``python tools/optics_hashes.py [--default-diffusion]`` (the flag adds the
default grid's diffusion table and a simulation through it: about a minute of CPU).
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import sys
import tempfile
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "validation"))  # nirglucose_reference


def _h(*arrays) -> str:
    d = hashlib.sha256()
    for a in arrays:
        a = np.ascontiguousarray(np.asarray(a))
        d.update(str((a.dtype.str, a.shape)).encode())
        d.update(a.tobytes())
    return d.hexdigest()[:24]


def _mc_hashes() -> dict:
    import dataclasses

    from nirglucose_reference.mc_paths import mc_detected_paths, reweight_detected
    from nirglucose_reference.monte_carlo import mc_layers, mc_slab

    out = {}
    res = mc_layers([1.0, 0.3, 2.0], [120.0, 80.0, 60.0], [0.9, 0.8, 0.7], [0.01, 0.05, 0.1],
                    [1.37, 1.4, 1.44], 1.0, 3000, rng=1,
                    rho_edges_cm=np.linspace(0.0, 0.3, 7))
    out["mc_layers"] = _h(*[v for v in dataclasses.astuple(res) if v is not None])
    res = mc_layers([0.5, 0.2], [100.0, 50.0], [0.9, 0.8], [0.02, np.inf], [1.4, 1.4], 1.33,
                    2000, rng=np.random.default_rng(5), rho_edges_cm=[0.0, 0.1, 0.2, 0.4])
    out["mc_layers_semi_infinite"] = _h(*[v for v in dataclasses.astuple(res) if v is not None])
    res = mc_slab(10.0, 90.0, 0.75, 0.02, 1.0, n_photons=3000, rng=0)
    out["mc_slab"] = _h(*[v for v in dataclasses.astuple(res) if v is not None])
    res = mc_slab(0.0, 0.0, 0.0, 0.1, 1.5, n_photons=500, rng=2)  # clear slab
    out["mc_slab_clear"] = _h(*[v for v in dataclasses.astuple(res) if v is not None])
    det = mc_detected_paths([0.2, 0.1, 0.05], [150.0, 100.0, 60.0], [0.85, 0.9, 0.8],
                            [0.01, 0.15], (0.1, 0.35), n_photons=3000, rng=3)
    out["mc_detected_paths"] = _h(det.weight, det.pathlength_cm, det.batch, det.n_photons,
                                  det.ring_area_cm2, det.mua_ref_per_cm,
                                  det.diffuse_reflectance)
    r, se, p = reweight_detected(det, [1.0, 0.3, 0.5])
    out["reweight_detected"] = _h(r, se, p)
    return out


def _lut_hashes(default_diffusion: bool) -> dict:
    from nirglucose.optics import lut as L
    from nirglucose_reference import lut_checks as LV

    out = {}
    rng = np.random.default_rng(11)
    for solver in ("diffusion", "monte-carlo"):
        t = L.build_lut(0.3, 0.008, grid="tiny", solver=solver)
        out[f"tiny_{solver}_values"] = _h(t.values, *[t.axis_nodes(k) for k in L.LUT_AXES])
        pts = LV.random_lut_points(t, 50, rng=rng)
        r, paths = L.interpolate_lut(t, **pts, pathlengths=True)
        out[f"tiny_{solver}_interpolate"] = _h(r, paths)
        nl = L.node_lut(t, pts["musp_subcutis_per_cm"] / pts["musp_dermis_per_cm"])
        out[f"tiny_{solver}_node_interpolate"] = _h(L.interpolate_node_lut(nl, **pts))
    if default_diffusion:
        t = L.build_lut(0.3, 0.008, grid="default", solver="diffusion")
        out["default_diffusion_values"] = _h(t.values)
    return out


def _sim_hashes(default_diffusion: bool) -> dict:
    import pandas as pd

    import nirglucose as ng

    out = {}
    grids = ["tiny", "default"] if default_diffusion else ["tiny"]
    before = os.environ.get("NIRGLUCOSE_LUT_GRID")
    try:
        for grid in grids:
            os.environ["NIRGLUCOSE_LUT_GRID"] = grid
            ds = ng.simulate("paper", n_subjects=4, per_subject=3, seed=7,
                             overrides={"optics.model": "rte-lut",
                                        "optics.lut_solver": "diffusion"})
            out[f"simulate_rte_lut_{grid}_diffusion"] = _h(
                pd.util.hash_pandas_object(ds.frame, index=True).to_numpy())
    finally:  # leave the caller's environment as it was
        if before is None:
            os.environ.pop("NIRGLUCOSE_LUT_GRID", None)
        else:
            os.environ["NIRGLUCOSE_LUT_GRID"] = before
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--default-diffusion", action="store_true",
                    help="also hash the default grid's diffusion table and a simulation")
    args = ap.parse_args(argv)
    with tempfile.TemporaryDirectory() as tmp:
        os.environ["NIRGLUCOSE_CACHE"] = tmp
        out = {"numpy": np.__version__, **_mc_hashes(), **_lut_hashes(args.default_diffusion),
               **_sim_hashes(args.default_diffusion)}
    print(json.dumps(out))
    return 0


if __name__ == "__main__":
    sys.exit(main())
