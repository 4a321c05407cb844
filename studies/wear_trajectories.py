"""Check the wear simulation's glucose trajectories against published ones (outside the
package's tests): a simglucose trajectory replayed, and the time in range per diabetes
status beside published CGM values.

1. Replay. simglucose (J. Xie, github.com/jxx123/simglucose) ships runs of its virtual
   patients with a basal-bolus controller. Two are replayed with this package's type 1
   model (``simulation.uva_padova``) fed the same meal and insulin, and the plasma glucose
   (column BG) compared at the times below:

   * ``examples/results/2022-11-27_09-54-45/adolescent#001.csv`` (commit 763dc728, the
     current simglucose; its basal 0.013933 U/min equals the patient's tabulated u2ss):
     40 g at 07:33 (13.333 g/min for 3 min), bolus 1.125042 U/min for 3 min from 07:36.
     The patient's parameters (not in the packaged adult subset) are the
     ``vpatient_params.csv`` row ``adolescent#001`` (commit b48b4aa1), quoted below.
   * ``examples/results/2017-12-31_17-46-32/adult#001.csv`` (commit 72ef682b, a 2017
     simglucose): 46 g at 07:30 (15.333 g/min for 3 min), 0.532233 U/min for 3 min from
     07:33, basal 0.021125 U/min. simglucose changed its gastric-emptying dose D since
     (its issue 41: D in mg), so this run is expected to differ.

   Meals enter as per-minute intakes over the same 3 minutes, the boluses as per-minute
   doses.
2. Time in range. 14 days of the wear scenario (``simulation.meal_scenario``) for
   :data:`N_PER_STATUS` subjects of each status: share of plasma glucose 70-180 mg/dL
   (TIR) and below 70 mg/dL (TBR), beside the international consensus targets
   (Battelino et al., Diabetes Care 42, 1593-1603 (2019): TIR > 70 %, TBR < 4 % for
   type 1 and type 2) and CGM in healthy adults (Shah et al., J. Clin. Endocrinol.
   Metab. 104, 4356-4364 (2019): about 96 % of the time within 70-140 mg/dL, about 1 %
   below 70). Type 1 also beside what adults with type 1 diabetes show: the DPV
   registry's 233 adults using CGM in real-life care (Diabetes Technol. Ther. (2020),
   doi:10.1089/dia.2020.0019: TIR 54 % / 49 %, TBR 7 % / 5 %, TAR 38 % / 46 %, glucose
   CV 36 % / 37 % at >= 30 / 18-30 years) and the control arm of a 26-week trial,
   adults on injections or pump with finger-prick monitoring, masked CGM (McAuley et
   al., Diabetes Care 43(12), 3024-3033 (2020): TIR 55 % (SD 13) at 26 weeks). The
   type 1 patients' therapy departs from the ideal as ``simulation.therapy`` draws it
   (carb-count error, missed boluses, the day's insulin sensitivity: published values,
   not tuned to these outcomes).

Prints one JSON object on its last line.
"""

from __future__ import annotations

import json
import os

import numpy as np

from nirglucose.metrics import time_in_ranges

N_PER_STATUS = int(os.environ.get("NIRGLUCOSE_BENCH_TIR_SUBJECTS", 10))
DAYS = int(os.environ.get("NIRGLUCOSE_BENCH_TIR_DAYS", 14))

#: Replays: patient, meal start [min], meal [g/min for 3 min], bolus [U/min for 3 min from
#: meal start + 3 min], basal [U/min], {minutes after the meal: simglucose BG [mg/dL]}.
REPLAYS = {
    "simglucose 2022 adolescent#001": (
        "adolescent#001", 30, 13.333333333333334, 1.1250416666666667, 0.013933333333333336,
        {9: 149.0404, 18: 149.2823, 27: 150.2035, 42: 153.2912, 57: 156.7358,
         72: 158.1757, 87: 156.7208, 102: 153.2142, 117: 148.7886, 132: 144.2250,
         147: 139.9636, 177: 133.2060, 207: 129.4339, 252: 127.4198}),
    "simglucose 2017 adult#001": (
        "adult#001", 30, 15.333333333333334, 0.5322333333333333, 0.021125,
        {15: 139.1002, 30: 148.1334, 45: 168.6903, 60: 191.4335, 75: 209.1530,
         90: 219.7730, 105: 224.1196, 111: 224.4850, 120: 223.9162, 135: 220.8049,
         150: 216.0375, 165: 210.4656, 180: 204.6273, 195: 198.8433, 201: 196.5884}),
}

#: ``vpatient_params.csv`` row adolescent#001 (simglucose commit b48b4aa1), the columns
#: the type 1 model reads.
ADOLESCENT_001 = dict(
    BW=68.706, Gb=149.02, Ib=97.554, kabs=0.091043, kmax=0.015865, kmin=0.0083338,
    b=0.83072, d=0.32294, Vg=1.6818, Vi=0.048153, Ipb=4.697517762, Vmx=0.074667, Km0=260.89,
    k2=0.067738, k1=0.057252, p2u=0.021344, m1=0.15221, m2=0.259067825939,
    m4=0.103627130376, m30=0.228315, Ilb=3.19814917262, ki=0.0088838, kp2=0.023318,
    kp3=0.023253, f=0.9, Gpb=250.621836, ke1=0.0005, ke2=339.0, Fsnc=1.0,
    Gtb=176.506559902, Vm0=5.92854753098, kd=0.0185, ka1=0.0025, ka2=0.0115,
    u2ss=1.21697571391, isc1ss=57.951224472, isc2ss=93.2258828462, kp1=11.5048231338)


def _patient(name: str) -> dict:
    from nirglucose.simulation import uva_padova as uva

    if name == "adolescent#001":
        return {k: np.array([v]) for k, v in ADOLESCENT_001.items()}
    names, cols = uva.type1_patients()
    i = names.index(name)
    return {k: v[i:i + 1] for k, v in cols.items()}


def replay(label: str) -> dict:
    from nirglucose.simulation import uva_padova as uva
    from nirglucose.simulation.meal_scenario import INSULIN_PMOL_PER_UNIT

    name, m0, meal_g_min, bolus_u_min, basal_u_min, bg = REPLAYS[label]
    p = _patient(name)
    per_u = INSULIN_PMOL_PER_UNIT / p["BW"][0]
    p["u2ss"] = np.array([basal_u_min * per_u])
    n_min = m0 + 300
    meals, bolus = np.zeros((1, n_min)), np.zeros((1, n_min))
    meals[0, m0:m0 + 3] = 1000.0 * meal_g_min
    bolus[0, m0 + 3:m0 + 6] = (bolus_u_min - basal_u_min) * per_u
    g = uva.integrate("type1", p, uva.basal_type1(p), meals, bolus)[0]
    t = np.array(list(bg))
    ref = np.array(list(bg.values()))
    ours = g[m0 + t]
    return {
        "simglucose_peak_mgdl": float(ref.max()),
        "simglucose_peak_min_after_meal": int(t[np.argmax(ref)]),
        "ours_peak_mgdl": round(float(g.max()), 2),
        "ours_peak_min_after_meal": int(np.argmax(g)) - m0,
        "basal_mgdl": round(float(g[0]), 2),
        "max_abs_diff_mgdl": round(float(np.abs(ours - ref).max()), 2),
        "rms_diff_mgdl": round(float(np.sqrt(np.mean((ours - ref) ** 2))), 2),
    }


def _range_metrics(g: np.ndarray) -> dict:
    """Time in ranges (:func:`nirglucose.metrics.time_in_ranges`, per subject, then the
    mean: every subject has as many minutes), CV and extremes of (subjects, minutes)
    plasma glucose."""
    t = time_in_ranges(g.ravel(), np.repeat(np.arange(len(g)), g.shape[1]))
    return {
        "tir_70_180_pct": round(float(t["tir_70_180_pct"].mean()), 1),
        "tir_subject_range_pct": [round(float(t["tir_70_180_pct"].min()), 1),
                                  round(float(t["tir_70_180_pct"].max()), 1)],
        "within_70_140_pct": round(100 * float(((g >= 70) & (g <= 140)).mean()), 1),
        "tbr_below_70_pct": round(float(t["tbr_lt70_pct"].mean()), 2),
        "tbr_below_54_pct": round(float(t["tbr_lt54_pct"].mean()), 2),
        "tar_above_180_pct": round(float(t["tar_gt180_pct"].mean()), 1),
        "cv_pct": round(100 * float((g.std(axis=1) / g.mean(axis=1)).mean()), 1),
        "mean_mgdl": round(float(g.mean()), 1),
        "min_mgdl": round(float(g.min()), 1),
        "max_mgdl": round(float(g.max()), 1),
    }


def type1_ablation() -> dict:
    """Type 1 time in ranges with no therapy error, and with each alone (the same
    subjects and meals: each error's stream is its own)."""
    import nirglucose as ng
    from nirglucose.simulation import therapy, wear

    cfg = ng.resolve_config("paper", {"glucose.status_probs": {
        s: float(s == "type1") for s in ("normal", "prediabetes", "type1", "type2")}})
    codes = np.full(N_PER_STATUS, list(cfg.glucose.status_probs).index("type1"))
    runs = {"none": (), **{f"only_{e}": (e,) for e in therapy.THERAPY_ERRORS}}
    out = {}
    for label, errors in runs.items():
        g = wear.glucose_trajectories(cfg, 0, np.arange(N_PER_STATUS), codes, DAYS,
                                      therapy_errors=errors)["blood_mgdl"]
        m = _range_metrics(g)
        out[label] = {k: m[k] for k in ("tir_70_180_pct", "tbr_below_70_pct",
                                        "tar_above_180_pct", "cv_pct")}
    return out


def time_in_range() -> dict:
    import nirglucose as ng
    from nirglucose.simulation import wear

    out = {}
    for status in ("normal", "prediabetes", "type1", "type2"):
        cfg = ng.resolve_config("paper", {"glucose.status_probs": {
            s: float(s == status) for s in ("normal", "prediabetes", "type1", "type2")}})
        codes = np.full(N_PER_STATUS, list(cfg.glucose.status_probs).index(status))
        g = wear.glucose_trajectories(cfg, 0, np.arange(N_PER_STATUS), codes, DAYS)["blood_mgdl"]
        out[status] = _range_metrics(g)
    out["published"] = {
        "consensus_targets_type1_type2": "TIR > 70 %, TBR < 4 % (Battelino et al. 2019)",
        "healthy_adults_cgm": "about 96 % within 70-140 mg/dL, about 1 % below 70 "
                              "(Shah et al. 2019)",
        "type1_adults_dpv_registry_cgm": {
            "source": "DPV registry, 233 adults, real-life CGM, Diabetes Technol. Ther. "
                      "2020, doi:10.1089/dia.2020.0019",
            "age_30_plus": {"tir_70_180_pct": 54, "tbr_below_70_pct": 7,
                            "tar_above_180_pct": 38, "cv_pct": 36},
            "age_18_to_30": {"tir_70_180_pct": 49, "tbr_below_70_pct": 5,
                             "tar_above_180_pct": 46, "cv_pct": 37}},
        "type1_adults_trial_control_arm": {
            "source": "McAuley et al. 2020, Diabetes Care 43(12), 3024: injections or pump, "
                      "finger-prick monitoring, masked CGM at 26 weeks",
            "tir_70_180_pct": 55, "tir_sd_pct": 13},
    }
    return out


if __name__ == "__main__":
    result = {"benchmark": "wear_trajectories", "subjects_per_status": N_PER_STATUS,
              "days": DAYS, "replay": {k: replay(k) for k in REPLAYS},
              "time_in_range": time_in_range(), "type1_therapy_ablation": type1_ablation()}
    print(json.dumps(result))
