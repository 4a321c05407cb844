"""The realism ledger's numbers (docs/user_guide/realism.md), computed by the package.

Every number the simulator contributes to the ledger comes from here; the published
numbers beside them are cited in the page. Sections of the JSON object:

``glucose_per_100_mgdl``
    Per LED band (the design search's FWHM rule, :func:`nirglucose.design.search.
    candidate_leds`), at the nominal skin (``optics.reference_tissue``; melanin 0.05,
    ForwardModel's documented state), glucose 100 -> 200 mg/dL at published magnitude
    (``physical``, gain 1): the dermis' absorption change (glucose's own absorption,
    water displacement, net) [1/cm], the relative mus' change [-], and the detected
    light's change, d ln I and dA = -d ln I / ln 10 [mAU] (and d ln I without glucose's
    scattering effect, ``glucose.scattering_rel_per_mm`` 0), by the default
    ``beer-lambert`` forward model (above 1400 nm it shortens the path about 2 x,
    SOURCES.md, so these light changes are low there).
``temperature_equivalence``
    Per band: water's d(mua)/dT over the band (Röttgers et al. 2014) [1/(cm degC)], the
    dermis' absorption change per degC [1/cm], and how many mg/dL of glucose one degC of
    skin (water) temperature mimics: in the dermis' absorption, and in the detected light
    (same forward model, ``noise.water_temperature`` on).
``devices``
    The ``physical`` preset's four-LED design (850-1150 nm): the design bound (device and
    oracle conditions, water temperature off and on), the bound against glucose's
    optical gain, and a simulated cohort (subject-grouped halves, seed 1): the oracle's,
    the EBL ridge's and no skill's (the training mean) RMSE, MARD and Parkes A+B, and
    the MARD of a device with no optical information but per-subject calibration (each
    reading predicted by the mean of the subject's other readings), all subjects and the
    type 2 subset.
``water_temperature_in_the_bound``
    The device bound with ``noise.water_temperature`` off and on, per preset, for the
    study's four LEDs and an InGaAs design on the water bands' long flanks
    (1300/1550/1600/1650 nm, G17190-010K, drive powers by the design search's rule).

Prints one JSON object on its last line (runs about a minute on one core).

Usage: ``python studies/realism_ledger.py [--subjects 150]``
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")  # one core

import argparse  # noqa: E402
import json  # noqa: E402
import platform  # noqa: E402
import time  # noqa: E402
import warnings  # noqa: E402

import numpy as np  # noqa: E402

BANDS_NM = (940, 1050, 1150, 1300, 1450, 1550, 1650)
GAINS = (1.0, 2.0, 4.0, 8.0, 11.0, 12.5)
#: ForwardModel's nominal state: ln blood 0.02, saturation 0.7, water 0.65, fat 0.8,
#: melanin 0.05, skin 1.8 mm, no LED shift, coupling 1.
THETA = (np.log(0.02), 0.7, 0.65, 0.8, 0.05, 1.8, 0.0, 0.0)
ON = {"noise.water_temperature.enabled": True}


def _band_config(nm: float, extra: dict | None = None):
    from nirglucose.config import resolve_config
    from nirglucose.design.search import candidate_leds

    led = {**candidate_leds([nm])[0], "responsivity_a_per_w": 0.5}
    return resolve_config("physical", {"leds": [led], **(extra or {})})


def _dermis_per_mgdl(cfg) -> dict:
    """Per band: band-averaged tissue terms of glucose (per mg/dL) and temperature."""
    from nirglucose.constants import MGDL_PER_MMOLL_GLUCOSE
    from nirglucose.simulation.simulator import scenario_band_spectra

    sp = scenario_band_spectra(cfg)
    w = sp.weights[0]
    water_frac = cfg.optics.reference_tissue.water_fraction
    per_mm = 1.0 / MGDL_PER_MMOLL_GLUCOSE
    g = cfg.glucose
    own = water_frac * float(sp.spectra["glucose"][0] @ w)  # W C eps_glc (tissue.py)
    disp = -water_frac * g.water_displacement_per_mm * float(sp.spectra["water"][0] @ w)
    return {
        "own_per_mgdl": own * per_mm,
        "displacement_per_mgdl": disp * per_mm,
        "musp_rel_per_mgdl": g.scattering_rel_per_mm * per_mm,
        "dmua_dt": float(sp.spectra["water_dt"][0] @ w),
        "water_fraction": water_frac,
    }


def _light(cfg, glucose, temp_c=None) -> float:
    from nirglucose.simulation.forward_model import ForwardModel

    fm = ForwardModel(cfg, "beer-lambert")
    theta = np.array([THETA])
    if temp_c is not None:
        theta = np.column_stack([theta, [temp_c]])
    return float(fm.log_ratio(np.array([float(glucose)]), theta)[0, 0])


def glucose_and_temperature() -> tuple[list, list]:
    """The per-band tables (sections ``glucose_per_100_mgdl`` and
    ``temperature_equivalence``)."""
    rows, temps = [], []
    for nm in BANDS_NM:
        cfg = _band_config(nm)
        d = _dermis_per_mgdl(cfg)
        dlnI = _light(cfg, 200.0) - _light(cfg, 100.0)
        no_scat = _band_config(nm, {"glucose.scattering_rel_per_mm": 0.0})
        dlnI_abs = _light(no_scat, 200.0) - _light(no_scat, 100.0)
        rows.append({
            "band_nm": nm, "fwhm_nm": cfg.leds.fwhm_nm[0],
            "dmua_glucose_own_per_cm": 100 * d["own_per_mgdl"],
            "dmua_displacement_per_cm": 100 * d["displacement_per_mgdl"],
            "dmua_net_per_cm": 100 * (d["own_per_mgdl"] + d["displacement_per_mgdl"]),
            "dmusp_rel": 100 * d["musp_rel_per_mgdl"],
            "dlnI": dlnI, "dA_mAU": -1000 * dlnI / np.log(10.0),
            "dlnI_absorption_only": dlnI_abs,
        })
        on = _band_config(nm, ON)
        t0 = on.physiology.skin_temp_c_neutral
        dT = _light(on, 100.0, t0 + 1.0) - _light(on, 100.0, t0)
        dg = (_light(on, 200.0, t0) - _light(on, 100.0, t0)) / 100.0
        d_on = _dermis_per_mgdl(on)
        net = d_on["own_per_mgdl"] + d_on["displacement_per_mgdl"]
        temps.append({
            "band_nm": nm, "dmua_water_dt_per_cm_per_c": d_on["dmua_dt"],
            "dmua_dermis_per_c": d_on["water_fraction"] * d_on["dmua_dt"],
            "mgdl_per_c_absorption": d_on["water_fraction"] * d_on["dmua_dt"] / net,
            "dlnI_per_c": dT, "dlnI_per_mgdl": dg, "mgdl_per_c_light": dT / dg,
        })
    return rows, temps


def _scores(y, pred, diabetes_status) -> dict:
    from nirglucose.metrics import mard, parkes_zones

    y = np.asarray(y, float)
    pred = np.maximum(np.asarray(pred, float), 1.0)
    t2 = np.asarray(diabetes_status) == "type2"
    zones = parkes_zones(y, pred, diabetes_type=1)
    return {"rmse_mgdl": float(np.sqrt(np.mean((pred - y) ** 2))), "mard_pct": mard(y, pred),
            "parkes_ab_pct": float(100 * np.isin(zones, ["A", "B"]).mean()),
            "mard_type2_pct": mard(y[t2], pred[t2]) if t2.any() else None}


def _per_subject_calibration(frame) -> dict:
    """MARD of predicting each reading by the mean of its subject's other readings."""
    from nirglucose.metrics import mard

    g = frame.groupby("subject_id")["glucose_mgdl"]
    s, k = g.transform("sum"), g.transform("count")
    pred = (s - frame["glucose_mgdl"]) / (k - 1)
    t2 = frame["diabetes_status"].astype(str) == "type2"
    y = frame["glucose_mgdl"]
    return {"mard_pct": mard(y, pred), "mard_type2_pct": mard(y[t2], pred[t2]),
            "n_readings_per_subject": int(k.iloc[0])}


def cohort(n_subjects: int) -> dict:
    """Oracle, EBL and no skill on a simulated ``physical`` cohort (subject-grouped)."""
    import nirglucose as ng
    from nirglucose.models.oracle import Oracle
    from nirglucose.models.registry import make_model

    ds = ng.simulate("physical", n_subjects, 3, seed=1)
    fr = ds.frame
    train = fr["subject_id"] < n_subjects // 2
    tr = ng.Dataset(fr[train].reset_index(drop=True), config=ds.config)
    te = ng.Dataset(fr[~train].reset_index(drop=True), config=ds.config)
    y, status = te.frame["glucose_mgdl"], te.frame["diabetes_status"].astype(str)
    out = {"n_subjects": n_subjects, "per_subject": 3, "seed": 1,
           "glucose_range_mgdl": [float(fr["glucose_mgdl"].min()),
                                  float(fr["glucose_mgdl"].max())]}
    out["oracle"] = _scores(y, Oracle().fit(tr).predict(te), status)
    out["ebl"] = _scores(y, make_model("ebl").fit(tr).predict(te), status)
    out["no_skill"] = _scores(y, np.full(len(y), tr.frame["glucose_mgdl"].mean()), status)
    many = ng.simulate("physical", n_subjects, 10, seed=2).frame
    out["per_subject_calibration_no_optics"] = _per_subject_calibration(many)
    return out


def bounds() -> dict:
    """The physical preset's four-LED design: bounds, water temperature off/on, by gain."""
    from nirglucose.design import design_bound

    out = {}
    for label, ov in (("water_temperature_off", {}), ("water_temperature_on", ON)):
        out[label] = {c: design_bound("physical", condition=c, overrides=ov).rmse_mgdl
                      for c in ("device", "oracle")}
    out["by_gain"] = [
        {"gain": g, **{c: design_bound("physical", condition=c,
                                       overrides={"glucose.signal_gain": g}).rmse_mgdl
                       for c in ("device", "oracle")}} for g in GAINS]
    out["glucose_sd_mgdl"] = design_bound("physical").glucose_sd_mgdl
    return out


def water_temperature_in_the_bound() -> list:
    """Device bound with the switch off and on, per preset and design."""
    from nirglucose.design import design_bound
    from nirglucose.design.search import candidate_leds, drive_powers_mw

    det = "G17190-010K"
    swir = candidate_leds((1300, 1550, 1600, 1650))
    rows = []
    for preset in ("physical", "wearable", "paper"):
        powers = drive_powers_mw(preset, swir, det)
        leds = [{**led, "power_mw": p} for led, p in zip(swir, powers, strict=True)]
        for design, kw in (("study LEDs 850-1150 nm", {}),
                           ("InGaAs 1300/1550/1600/1650 nm", {"leds": leds, "detector": det})):
            off, on = (design_bound(preset, overrides=ov, **kw).rmse_mgdl for ov in ({}, ON))
            rows.append({"preset": preset, "design": design, "off_mgdl": off, "on_mgdl": on,
                         "change_pct": 100 * (on / off - 1)})
    return rows


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--subjects", type=int, default=150, help="cohort size (halved)")
    args = ap.parse_args()
    start = time.perf_counter()
    with warnings.catch_warnings():
        # the 1650 nm band reaches past the lipid table's end (stated, warned assumption)
        warnings.filterwarnings("ignore", message="lipid absorption above")
        glucose, temps = glucose_and_temperature()
        devices = {"design": "physical preset, LEDs 850/940/1050/1150 nm",
                   "bounds": bounds(), "cohort": cohort(args.subjects)}
        in_bound = water_temperature_in_the_bound()
    print(json.dumps({
        "benchmark": "realism_ledger", "python": platform.python_version(),
        "regime": "physical (glucose.signal_gain 1) unless a gain is given",
        "glucose_per_100_mgdl": glucose, "temperature_equivalence": temps,
        "devices": devices, "water_temperature_in_the_bound": in_bound,
        "elapsed_s": time.perf_counter() - start,
    }))


if __name__ == "__main__":
    main()
