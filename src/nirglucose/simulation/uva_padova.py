"""The UVA/Padova meal–glucose–insulin model: plasma glucose over days of meals.

Two variants of one model (Dalla Man, Rizza & Cobelli 2007 [1]_), written here from the
paper's equations:

* ``"meal_2007"``: the paper's model of a person whose pancreas secretes insulin
  (normal and type 2 subjects): gut absorption (stomach, grinding, emptying that slows
  with the meal's size, intestine), glucose kinetics (plasma and tissue compartments),
  endogenous production (suppressed by glucose, delayed and portal insulin), utilisation
  (insulin-independent and Michaelis–Menten insulin-dependent), renal excretion above a
  threshold, insulin kinetics (liver and plasma, hepatic extraction falling with
  secretion) and secretion (static and dynamic responses to glucose).
* ``"type1"``: the same glucose, gut and insulin-action subsystems without secretion;
  insulin enters under the skin (two subcutaneous compartments, Dalla Man et al. 2007
  [2]_ and the type 1 simulator [3]_) from a basal rate and meal boluses.

Parameters are data (``data/uva_padova/``, SOURCES.md there): the paper's average
normal and type 2 subjects (Table I) and the type 1 simulator's ten adult virtual
patients. States are per kg of body weight: glucose in mg/kg, insulin in pmol/kg,
stomach and gut contents in mg.

Integration: classical fourth-order Runge–Kutta with a fixed 1-minute step, written with
NumPy element-wise operations (and :mod:`nirglucose.portable` for ``tanh``), vectorised
over subjects (:func:`integrate_reference`); :func:`integrate` runs the same operations
compiled (:mod:`.kernels.uva_padova_rk4`), to the same bits.
:func:`scipy.integrate.solve_ivp` would adapt its steps to each problem (so a subject's
trajectory would depend on which subjects share its array) and sums its stages with
``np.dot`` (BLAS, whose kernel and hence last bits depend on the CPU); a fixed step
keeps every subject's bits independent of its neighbours and of the CPU. The fastest
rate of either model is below 1.3 /min (``kabs``, ``m1 + m30``), so λh < 1.3, inside
RK4's stability region (abs(λh) < 2.78) with a local error of order (λh)^5/120;
``tests/simulation/test_uva_padova.py`` checks the trajectories against ``solve_ivp``
(LSODA, rtol 1e-8).

References
----------
.. [1] C. Dalla Man, R. A. Rizza, C. Cobelli, "Meal simulation model of the
   glucose-insulin system", IEEE Trans. Biomed. Eng. 54(10), 1740-1749 (2007),
   doi:10.1109/TBME.2007.893506.
.. [2] C. Dalla Man, D. M. Raimondo, R. A. Rizza, C. Cobelli, "GIM, simulation software
   of meal glucose-insulin model", J. Diabetes Sci. Technol. 1(3), 323-330 (2007)
   (subcutaneous insulin kinetics).
.. [3] B. P. Kovatchev, M. Breton, C. Dalla Man, C. Cobelli, "In silico preclinical
   trials: a proof of concept in closed-loop control of type 1 diabetes", J. Diabetes
   Sci. Technol. 3(1), 44-55 (2009).
"""

from __future__ import annotations

import csv
from functools import cache
from importlib import resources

import numpy as np

from .. import portable as pm
from ..exceptions import ConfigError

__all__ = [
    "MODEL_KINDS",
    "STEP_MIN",
    "STATES_2007",
    "STATES_TYPE1",
    "meal_model_2007_table",
    "type1_patients",
    "parameters_2007",
    "basal_2007",
    "basal_type1",
    "gastric_emptying_per_min",
    "rhs_2007",
    "rhs_type1",
    "integrate",
    "integrate_reference",
]

#: The model variants: with insulin secretion (normal, prediabetes, type 2) or type 1.
MODEL_KINDS = ("meal_2007", "type1")
#: Integration step. [min]
STEP_MIN = 1.0
#: State order of the secreting model [1]_ (mg, mg/kg, pmol/kg, pmol/L; Y in pmol/kg/min).
STATES_2007 = ("qsto1", "qsto2", "qgut", "gp", "gt", "il", "ip", "i1", "id", "x", "y", "ipo")
#: State order of the type 1 model [3]_.
STATES_TYPE1 = ("qsto1", "qsto2", "qgut", "gp", "gt", "ip", "x", "i1", "id", "il", "isc1", "isc2")


def _data_path(name: str):
    return resources.files("nirglucose.data").joinpath("uva_padova", name)


@cache
def meal_model_2007_table() -> dict[str, dict[str, float]]:
    """The paper's Table I [1]_: ``{"normal": {...}, "type2": {...}}`` (SOURCES.md)."""
    with _data_path("meal_model_2007.csv").open(encoding="utf-8") as fh:
        rows = list(csv.DictReader(fh))
    return {s: {r["parameter"]: float(r[s]) for r in rows} for s in ("normal", "type2")}


@cache
def type1_patients() -> tuple[tuple[str, ...], dict[str, np.ndarray]]:
    """The type 1 simulator's adult virtual patients: names and parameter columns [3]_."""
    with _data_path("type1_adult_patients.csv").open(encoding="utf-8") as fh:
        rows = list(csv.DictReader(fh))
    names = tuple(r["patient"] for r in rows)
    cols = {k: np.array([float(r[k]) for r in rows]) for k in rows[0] if k != "patient"}
    return names, cols


def parameters_2007(status: str) -> dict[str, float]:
    """Parameters of a status's average subject.

    ``normal`` and ``type2`` are the paper's [1]_; ``prediabetes`` has no published set
    and takes the mean of the two (an assumption of this package: a subject halfway
    between normal and type 2 glucose tolerance).

    Examples
    --------
    >>> parameters_2007("normal")["Km0"]
    225.59
    """
    table = meal_model_2007_table()
    if status in table:
        return dict(table[status])
    if status == "prediabetes":
        return {k: 0.5 * (table["normal"][k] + table["type2"][k]) for k in table["normal"]}
    raise ConfigError(f"no meal-model parameters for status {status!r}; valid: "
                      "normal, prediabetes, type2 (type1 uses the virtual patients)")


def basal_2007(p: dict) -> tuple[dict, np.ndarray]:
    """Derived parameters and the basal (fasting steady) state of the secreting model.

    The paper's basal constraints [1]_: Sb = (m6 - HEb)/m5 (Eq. 6); m4 and m2 from the
    basal insulin Ib (Eq. 9); Gt and Gp from the utilisation and production balance
    (Eqs. 20-22, with the tabulated Vm0); kp1 from Eq. 12; Ipo = Sb/gamma (Eq. 23); the
    secretion threshold h is the model's basal glucose.

    Parameters
    ----------
    p : dict
        Table I parameters (scalars or arrays over subjects).

    Returns
    -------
    tuple
        (parameters with ``Sb``, ``m2``, ``m4``, ``kp1``, ``h``, ``Gb_model`` added;
        state (12, n) in :data:`STATES_2007` order).
    """
    q = dict(p)
    hb = q["HEb"]
    q["Sb"] = (q["m6"] - hb) / q["m5"]
    ipb = q["Ib"] * q["VI"]
    q["m4"] = 0.4 * q["Sb"] / ipb * (1.0 - hb)  # [1], Eq. 9
    q["m2"] = (q["Sb"] / ipb - q["m4"] / (1.0 - hb)) * (1.0 - hb) / hb
    uid_b = q["EGPb"] - q["Fcns"]
    gtb = uid_b * q["Km0"] / (q["Vm0"] - uid_b)  # [1], Eqs. 20-22
    gpb = (uid_b + q["k2"] * gtb) / q["k1"]
    ipob = q["Sb"] / q["gamma"]
    q["kp1"] = q["EGPb"] + q["kp2"] * gpb + q["kp3"] * q["Ib"] + q["kp4"] * ipob  # Eq. 12
    q["Gb_model"] = q["h"] = gpb / q["VG"]
    ilb = (q["m2"] + q["m4"]) * ipb / q["m1"]
    zero = np.zeros_like(np.asarray(gpb, dtype=float))
    state = np.array([zero, zero, zero, gpb + zero, gtb + zero, ilb + zero, ipb + zero,
                      q["Ib"] + zero, q["Ib"] + zero, zero, zero, ipob + zero], dtype=float)
    return q, state.reshape(len(STATES_2007), -1)


def basal_type1(p: dict) -> np.ndarray:
    """The type 1 patients' tabulated basal state [3]_, (12, n) in :data:`STATES_TYPE1`."""
    z = np.zeros_like(np.asarray(p["Gpb"], dtype=float))
    return np.array([z, z, z, p["Gpb"], p["Gtb"], p["Ipb"], z, p["Ib"], p["Ib"], p["Ilb"],
                     p["isc1ss"], p["isc2ss"]], dtype=float).reshape(len(STATES_TYPE1), -1)


def gastric_emptying_per_min(qsto, dose_mg, kmax, kmin, b, d) -> np.ndarray:
    """Rate of gastric emptying, falling and recovering with the stomach's content [1]_.

    k_empt = kmin + (kmax - kmin)/2 [tanh(a (Qsto - b D)) - tanh(c (Qsto - d D)) + 2],
    a = 5 / (2 D (1 - b)), c = 5 / (2 D d) (the paper's Eq. 13, after Dalla Man et al.
    2006); kmax where no meal has been eaten (D = 0). [1/min]

    Examples
    --------
    >>> float(gastric_emptying_per_min(0.0, 0.0, 0.0558, 0.008, 0.82, 0.01))  # no meal yet
    0.0558
    >>> k = gastric_emptying_per_min(np.array([45e3, 20e3]), 45e3, 0.0558, 0.008, 0.82, 0.01)
    >>> bool(k[1] < k[0])  # emptying slows once part of the meal has left the stomach
    True
    """
    terms = _emptying_terms(dose_mg, b, d)
    return _kempt(np.asarray(qsto, dtype=float), terms, kmax, kmin)


def _emptying_terms(dose_mg, b, d) -> tuple:
    """The dose-dependent terms of :func:`gastric_emptying_per_min`: (D > 0, b D, d D, a,
    c), computed once per meal rather than at every evaluation."""
    dose = np.asarray(dose_mg, dtype=float)
    has = dose > 0
    safe = np.where(has, dose, 1.0)
    return has, b * safe, d * safe, 5.0 / (2.0 * safe * (1.0 - b)), 5.0 / (2.0 * safe * d)


def _kempt(qsto, terms: tuple, kmax, kmin) -> np.ndarray:
    """:func:`gastric_emptying_per_min` from :func:`_emptying_terms`. [1/min]"""
    has, b_dose, d_dose, a, c = terms
    k = kmin + 0.5 * (kmax - kmin) * (
        pm.tanh(a * (qsto - b_dose)) - pm.tanh(c * (qsto - d_dose)) + 2.0
    )
    return np.where(has, k, kmax + 0.0 * k)


def _glucose_flows(p: dict, gp, gt, xx, egp, ra, fcns):
    """dGp/dt and dGt/dt: production, appearance, utilisation, excretion [1]_. [mg/kg/min]"""
    uid = (p["Vm0"] + p["Vmx"] * xx) * gt / (p["Km0"] + gt)
    renal = p["ke1"] * np.maximum(gp - p["ke2"], 0.0)
    dgp = egp + ra - fcns - renal - p["k1"] * gp + p["k2"] * gt
    dgt = -uid + p["k1"] * gp - p["k2"] * gt
    return dgp, dgt


def _gut(p: dict, qsto1, qsto2, qgut, dose_mg):
    """Stomach and gut derivatives [mg/min] and the rate of appearance [mg/kg/min] [1]_."""
    terms = dose_mg if isinstance(dose_mg, tuple) else _emptying_terms(dose_mg, p["b"], p["d"])
    kempt = _kempt(qsto1 + qsto2, terms, p["kmax"], p["kmin"])
    kgri = p["kgri"] if "kgri" in p else p["kmax"]  # type 1 sets: kgri = kmax [3]
    ra = p["f"] * p["kabs"] * qgut / p["BW"]
    return (-kgri * qsto1, kgri * qsto1 - kempt * qsto2, kempt * qsto2 - p["kabs"] * qgut), ra


def rhs_2007(x: np.ndarray, p: dict, dose_mg) -> np.ndarray:
    """Right-hand side of the secreting model [1]_, (12, n) -> (12, n).

    Production EGP = max(kp1 - kp2 Gp - kp3 Id - kp4 Ipo, 0); secretion S = gamma Ipo
    with dIpo/dt = -gamma Ipo + Y + Sb + K max(dG/dt, 0) and the static response
    dY/dt = -alpha (Y - beta (G - h)), or -alpha (Y + Sb) where beta (G - h) < -Sb;
    hepatic extraction HE = m6 - m5 S. ``p`` from :func:`basal_2007`; ``dose_mg`` the
    last meal's carbohydrate (for gastric emptying). [per min]
    """
    qsto1, qsto2, qgut, gp, gt, il, ip, i1, id_, xx, y, ipo = x
    dgut, ra = _gut(p, qsto1, qsto2, qgut, dose_mg)
    egp = np.maximum(p["kp1"] - p["kp2"] * gp - p["kp3"] * id_ - p["kp4"] * ipo, 0.0)
    dgp, dgt = _glucose_flows(p, gp, gt, xx, egp, ra, p["Fcns"])
    g, i = gp / p["VG"], ip / p["VI"]
    s = p["gamma"] * ipo
    he = p["m6"] - p["m5"] * s
    m3 = he * p["m1"] / (1.0 - he)
    excess = p["beta"] * (g - p["h"])
    dy = np.where(excess >= -p["Sb"], -p["alpha"] * (y - excess), -p["alpha"] * (y + p["Sb"]))
    spo = y + p["Sb"] + p["K"] * np.maximum(dgp / p["VG"], 0.0)
    return np.array([
        *dgut, dgp, dgt,
        -(p["m1"] + m3) * il + p["m2"] * ip + s,
        -(p["m2"] + p["m4"]) * ip + p["m1"] * il,
        -p["ki"] * (i1 - i),
        -p["ki"] * (id_ - i1),
        -p["p2U"] * xx + p["p2U"] * (i - p["Ib"]),
        dy,
        -p["gamma"] * ipo + spo,
    ])


def rhs_type1(x: np.ndarray, p: dict, dose_mg, insulin_pmol_per_kg_min) -> np.ndarray:
    """Right-hand side of the type 1 model [3]_, (12, n) -> (12, n).

    No secretion: EGP = max(kp1 - kp2 Gp - kp3 Id, 0); insulin appears from the two
    subcutaneous compartments, dIsc1/dt = -(kd + ka1) Isc1 + u, dIsc2/dt = kd Isc1 -
    ka2 Isc2, Ra_I = ka1 Isc1 + ka2 Isc2 [2]_; liver insulin clearance m30. ``u`` is
    the basal delivery (boluses enter :func:`integrate` as jumps of Isc1). [per min]
    """
    qsto1, qsto2, qgut, gp, gt, ip, xx, i1, id_, il, isc1, isc2 = x
    dgut, ra = _gut(p, qsto1, qsto2, qgut, dose_mg)
    egp = np.maximum(p["kp1"] - p["kp2"] * gp - p["kp3"] * id_, 0.0)
    dgp, dgt = _glucose_flows(p, gp, gt, xx, egp, ra, p["Fsnc"])
    i = ip / p["Vi"]
    return np.array([
        *dgut, dgp, dgt,
        -(p["m2"] + p["m4"]) * ip + p["m1"] * il + p["ka1"] * isc1 + p["ka2"] * isc2,
        -p["p2u"] * xx + p["p2u"] * (i - p["Ib"]),
        -p["ki"] * (i1 - i),
        -p["ki"] * (id_ - i1),
        -(p["m1"] + p["m30"]) * il + p["m2"] * ip,
        -(p["kd"] + p["ka1"]) * isc1 + insulin_pmol_per_kg_min,
        p["kd"] * isc1 - p["ka2"] * isc2,
    ])


def integrate(kind: str, p: dict, x0: np.ndarray, meals_mg: np.ndarray,
              bolus_pmol_per_kg: np.ndarray | None = None,
              sensitivity: np.ndarray | None = None) -> np.ndarray:
    """Plasma glucose every minute, by fixed-step RK4 (module docstring).

    Computed by a compiled loop (:mod:`.kernels.uva_padova_rk4`, numba) that gives the
    same bits as :func:`integrate_reference`, the NumPy loop over :func:`rhs_2007` and
    :func:`rhs_type1`, in a fraction of its time (14 days of 16 subjects: 0.1 s, not 7).

    Parameters
    ----------
    kind : str
        ``"meal_2007"`` (``p`` from :func:`basal_2007`) or ``"type1"`` (``p`` a patient's
        columns of :func:`type1_patients`, with ``u2ss`` the basal delivery).
    p : dict
        Parameters, scalars or arrays over the n subjects.
    x0 : numpy.ndarray
        Initial state, (12, n).
    meals_mg : numpy.ndarray
        Carbohydrate eaten at the start of each minute, (n, n_min); it enters the
        stomach (Qsto1) and becomes the dose D of gastric emptying (the total of a meal
        eaten over consecutive minutes). [mg]
    bolus_pmol_per_kg : numpy.ndarray, optional
        Insulin bolus at the start of each minute (type 1), (n, n_min); it enters
        Isc1. [pmol/kg]
    sensitivity : numpy.ndarray, optional
        Insulin-sensitivity factor at each minute (type 1), (n, n_min): both insulin
        actions, ``Vmx`` and ``kp3``, are multiplied by it during that minute (the
        time-varying insulin sensitivity of the S2017 simulator, Visentin et al. 2018,
        J. Diabetes Sci. Technol. 12(2), 273-281; :mod:`.therapy`). Default 1. [-]

    Returns
    -------
    numpy.ndarray
        Plasma glucose at minutes 0 .. n_min - 1 (before that minute's meal), (n, n_min).
        [mg/dL]
    """
    meals_mg, n, n_min = _check(kind, meals_mg, sensitivity)
    from .kernels import uva_padova_rk4 as kernel  # numba: compiled on first use

    type1 = kind == "type1"
    x = np.array(x0, dtype=float).reshape(len(x0), n)
    has_bolus = type1 and bolus_pmol_per_kg is not None
    bolus = _per_minute(bolus_pmol_per_kg if has_bolus else None, n, n_min, "bolus_pmol_per_kg")
    sens = _per_minute(sensitivity, n, n_min, "sensitivity")
    return kernel.integrate_rk4(type1, _parameter_rows(kernel, type1, p, n), x,
                                np.ascontiguousarray(meals_mg), bolus, has_bolus, sens,
                                sensitivity is not None, STEP_MIN)


def _check(kind: str, meals_mg, sensitivity) -> tuple:
    """:func:`integrate`'s argument checks: (meals as floats, n, n_min)."""
    if kind not in MODEL_KINDS:
        raise ConfigError(f"unknown model kind {kind!r}; valid: {', '.join(MODEL_KINDS)}")
    meals_mg = np.asarray(meals_mg, dtype=float)
    n, n_min = meals_mg.shape
    if sensitivity is not None and (kind != "type1" or np.shape(sensitivity) != (n, n_min)):
        raise ConfigError(f"sensitivity applies to the type1 model only, one factor per subject "
                          f"and minute ({n}, {n_min}); got kind {kind!r}, shape "
                          f"{np.shape(sensitivity)}")
    return meals_mg, n, n_min


def _per_minute(values, n: int, n_min: int, name: str) -> np.ndarray:
    """A per-subject, per-minute input as a C-contiguous (n, n_min) float array for the
    kernel, or an (n, 1) placeholder of zeros where it is absent."""
    if values is None:
        return np.zeros((n, 1))
    values = np.asarray(values, dtype=float)
    if values.shape != (n, n_min):
        raise ConfigError(f"{name} must have one value per subject and minute ({n}, {n_min}); "
                          f"got shape {values.shape}")
    return np.ascontiguousarray(values)


def _parameter_rows(kernel, type1: bool, p: dict, n: int) -> np.ndarray:
    """The kernel's parameter rows, (rows, n): each parameter, scalar or per subject,
    broadcast over the n subjects in the kernel's order."""
    names = kernel.COMMON + (kernel.EXTRA_TYPE1 if type1 else kernel.EXTRA_2007)
    alias = {"Fcns": "Fsnc"} if type1 else {}
    value = {**p, "kgri": p["kgri"] if "kgri" in p else p["kmax"]}
    return np.ascontiguousarray(np.stack([
        np.broadcast_to(np.asarray(value[alias.get(k, k)], dtype=float), (n,)) for k in names
    ]))


def integrate_reference(kind: str, p: dict, x0: np.ndarray, meals_mg: np.ndarray,
                        bolus_pmol_per_kg: np.ndarray | None = None,
                        sensitivity: np.ndarray | None = None) -> np.ndarray:
    """:func:`integrate` as NumPy element-wise operations over the subjects: the
    reference its compiled loop matches bit for bit (arguments and result as there).
    """
    meals_mg, n, n_min = _check(kind, meals_mg, sensitivity)
    if kind == "type1":
        u = p["u2ss"]
        base = p
        p = dict(p)

        def f(x, dose):
            return rhs_type1(x, p, dose, u)
        vg, gp_row, isc1_row = p["Vg"], STATES_TYPE1.index("gp"), STATES_TYPE1.index("isc1")
    else:
        def f(x, dose):
            return rhs_2007(x, p, dose)
        vg, gp_row, isc1_row = p["VG"], STATES_2007.index("gp"), None
    x = np.array(x0, dtype=float).reshape(len(x0), n)
    dose = np.zeros(n)
    eating = np.zeros(n, dtype=bool)
    terms = _emptying_terms(dose, p["b"], p["d"])
    out = np.empty((n, n_min))
    h = STEP_MIN
    factor = None
    for k in range(n_min):
        out[:, k] = x[gp_row] / vg
        if sensitivity is not None and (
                factor is None or (sensitivity[:, k] != factor).any()):
            factor = sensitivity[:, k].copy()
            p["Vmx"], p["kp3"] = base["Vmx"] * factor, base["kp3"] * factor
        meal = meals_mg[:, k]
        if meal.any() or eating.any():
            x[0] += meal
            # a meal eaten over consecutive minutes is one dose D, its total so far
            dose = np.where(meal > 0, np.where(eating, dose + meal, meal), dose)
            eating = meal > 0
            terms = _emptying_terms(dose, p["b"], p["d"])
        if isc1_row is not None and bolus_pmol_per_kg is not None:
            x[isc1_row] += bolus_pmol_per_kg[:, k]
        k1 = f(x, terms)
        k2 = f(x + (0.5 * h) * k1, terms)
        k3 = f(x + (0.5 * h) * k2, terms)
        k4 = f(x + h * k3, terms)
        x = x + (h / 6.0) * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
    return out
