"""Cross-validate the degrees of the rte-lut table's Monte Carlo correction fit.

The default table stores the three-layer diffusion model plus a least-squares fit of
(Monte Carlo - diffusion) over the scattering nodes (``nirglucose.optics.lut``,
``_residual_fit``). Its degrees, ``LUT_MC_SETTINGS["residual_fit_degrees"]`` (in
ln mus'_dermis, musp_ratio, ln tau), trade the nodes' Monte Carlo noise against bias.
This script chooses them from the table's own runs, without the hold-out references of
``studies/optics_reference.py``:

* node values from two disjoint halves of the default build's photons: photons
  0 .. N/2 - 1 and N/2 .. N - 1 of every run (N the default photons per run;
  ``first_photon`` of ``nirglucose.optics.kernels.mc_white.white_mc_run``), which together are
  exactly the default table's runs; each half takes about an hour of CPU and is saved
  in ``--work`` (default ``optics-fit-degrees/`` in the nirglucose cache directory) as
  it finishes, so a rerun resumes (the cross-validation is then of a table of half the
  photons: it errs towards fewer terms);
* ``node_noise``: RMS of ln R over the nodes, one half (from the halves' difference);
* ``node_cv``: fit one half, predict the other's nodes (ln R), both ways, RMS;
* ``leave_out_cv``: the same with thickness node j left out of the fit and predicted,
  for every interior thickness node but tau = 1 (the table evaluates the fit between
  the thickness nodes, at its refined ones, where a polynomial through noisy nodes can
  oscillate; node CV cannot see that);
* ``chosen``: the degrees with the least ``leave_out_cv``.

Usage::

    python studies/optics_fit_degrees.py [--work DIR]

Prints one JSON object on its last line.
"""

from __future__ import annotations

import argparse
import hashlib
import itertools
import json
import os
from pathlib import Path

import numpy as np
from _workdir import work_dir

RHO_CM, T_EPI_CM, N_TISSUE = 0.3, 0.008, 1.4

#: Candidate degrees (ln mus'_dermis, musp_ratio, ln tau); each is capped by the axis'
#: node count (the default grid: 7, 3, and 5 + 7 thickness nodes about tau = 1).
CANDIDATES = list(itertools.product((2, 3, 4, 5, 6), (1, 2), (3, 4, 5, 6, 7)))


def _setup():
    from nirglucose.optics import lut as L
    from nirglucose.optics.lut import build as LB
    from nirglucose.optics.lut import grid as LG

    grid = LG._resolve_grid("default")
    geo = LG._geometry(RHO_CM, T_EPI_CM, N_TISSUE, 1.0)
    coords, splits = LB._solve_axes(grid, geo)
    ax = {k: LG._inverse(L.LUT_AXES[k][0], coords[i]) for i, k in enumerate(L.LUT_AXES)}
    return L, grid, geo, coords, splits[-1], ax


def _half_path(work: Path, grid: dict, geo: dict, first: int, photons: int) -> Path:
    """Work file of one half, named by everything its node values depend on."""
    from nirglucose.optics import lut as L
    from nirglucose.optics.kernels import mc_white
    from nirglucose.optics.lut import grid as LG

    settings = {k: v for k, v in L.LUT_MC_SETTINGS.items() if k != "residual_fit_degrees"}
    payload = {"geometry": geo, "grid": grid, "mc": settings, "photons": photons,
               "first": first, "batch": mc_white._BATCH_PHOTONS,
               "split_survival": mc_white._SPLIT_SURVIVAL, "version": LG._FORMAT_VERSION}
    key = hashlib.sha256(json.dumps(payload, sort_keys=True).encode()).hexdigest()[:16]
    return work / f"nodes-{key}-first{first}-n{photons}.npz"


def _halves(work: Path, L, grid: dict, geo: dict, ax: dict) -> tuple[np.ndarray, np.ndarray]:
    """ln R at the solve nodes from each half of the default table's photons."""
    from nirglucose.optics.lut import build as LB

    photons = L.LUT_MC_PHOTONS["default"] // 2
    out = []
    for first in (0, photons):
        path = _half_path(work, grid, geo, first, photons)
        if not path.exists():
            values = LB._monte_carlo_nodes(ax, grid, geo, photons, first_photon=first)
            tmp = Path(str(path) + ".tmp.npz")
            np.savez(tmp, values=values)
            os.replace(tmp, path)  # atomic: a half is there whole or not at all
        with np.load(path, allow_pickle=False) as f:
            out.append(f["values"][..., :1])  # ln R
    return out[0], out[1]


def main(argv: list[str] | None = None) -> dict:
    from nirglucose.optics.lut import build as LB

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--work", default=None,
                    help="directory of the halves' node values (resumable)")
    args = ap.parse_args(argv)
    L, grid, geo, coords, split, ax = _setup()
    work = work_dir(ap, args.work, L.cache_dir() / "optics-fit-degrees")
    va, vb = _halves(work, L, grid, geo, ax)
    diff = LB._diffusion_nodes(ax, geo)[..., :1]
    n_tau = coords[-1].size

    def node_cv(deg) -> float:
        fa = LB._residual_fit(va, diff, coords, split, deg)
        fb = LB._residual_fit(vb, diff, coords, split, deg)
        return float(np.sqrt((np.mean((diff + fa - vb) ** 2)
                              + np.mean((diff + fb - va) ** 2)) / 2))

    def leave_out_cv(deg) -> float:
        err = []
        for j in range(1, n_tau - 1):
            if j == split:
                continue
            # (a side of tau = 1 with one node fewer caps its degree one lower)
            keep = [i for i in range(n_tau) if i != j]
            c = [*coords[:-1], coords[-1][keep]]
            at = (coords[0], coords[1], coords[-1][[j]])
            for fit, test in ((va, vb), (vb, va)):
                f = LB._residual_fit(fit[..., keep, :], diff[..., keep, :], c,
                                    split - (j < split), deg, at=at)
                err.append(np.mean((diff[..., [j], :] + f - test[..., [j], :]) ** 2))
        return float(np.sqrt(np.mean(err)))

    rows = [{"degrees": list(d), "node_cv": round(node_cv(d), 5),
             "leave_out_cv": round(leave_out_cv(d), 5)} for d in CANDIDATES]
    best = min(rows, key=lambda r: r["leave_out_cv"])
    current = list(L.LUT_MC_SETTINGS["residual_fit_degrees"])
    return {
        "photons_per_half": L.LUT_MC_PHOTONS["default"] // 2,
        "node_noise": round(float(np.sqrt(np.mean((va - vb) ** 2) / 2)), 5),
        "chosen": best["degrees"],
        "current": current,
        "current_is_chosen": best["degrees"] == current,
        "candidates": sorted(rows, key=lambda r: r["leave_out_cv"]),
    }


if __name__ == "__main__":
    print(json.dumps(main()))
