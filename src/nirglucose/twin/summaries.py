"""Summary statistics of a device file: pure functions, frame -> one vector.

The same function summarises the user's file and every simulated one, so the twin
compares like with like. Per LED channel (codes as shares of the mean, so the LED power
sets only the level):

* ``level``: log10 of the mean code over full scale;
* ``between``: log10 of the SD of the people's mean codes, relative to the mean code;
* ``within``: log10 of the pooled within-person SD after the within-person glucose
  slope, relative to the mean code;
* ``slope``: the pooled within-person slope of the code on glucose, relative to the mean
  code, per 100 mg/dL (the glucose signal), as asinh(slope / 0.002): linear near 0,
  logarithmic for the large slopes of large gains (so a few do not dominate the
  estimator's scaling);
* ``hetero``: the correlation, over people, of log mean code and log within-person SD
  (an additive white noise gives a negative one, a multiplicative noise none);
* ``kurtosis``: log10 of the kurtosis of the pooled within-person residuals (Gaussian
  log10 3);

for each pair of channels the within-person correlation of their residuals
(``corr``: a shared placement noise against each channel's own) and the correlation of
the people's means (``bcorr``); with reference codes their level and, for a monitor,
the within-person SD of log(code / reference); and per physiological column its pooled
within-person SD (log10; the Fitzpatrick type: the share of readings off a person's
most frequent type). With reading times (``time_min``), per channel ``drift``: the
pooled within-person loss of code over time after the glucose slope (minus the slope on
time, the two fitted together), relative to the mean code, per 1000 h, as
asinh(loss / 0.001) (0.001: the
package's LED ageing, 0.1 % per 1000 h). The glucose column is in mg/dL
(:func:`nirglucose.load_dataset` converts).
"""

from __future__ import annotations

import itertools

import numpy as np
import pandas as pd

from .device import TIME_COLUMNS, TwinDevice, subject_codes

__all__ = ["SUMMARY_VERSION", "summary_names", "summaries", "channel_pairs"]

#: Version of the summaries' definitions, part of a cached estimator's identity: change
#: it with any change of what a summary computes.
SUMMARY_VERSION = 3
#: Relative slope per 100 mg/dL below which asinh is near linear: about the slope of
#: glucose at its published magnitude (a few codes in a thousand per 100 mg/dL). [-]
_SLOPE_SCALE = 0.002

#: Relative drift per 1000 h below which asinh is near linear: the package's LED ageing
#: (constants.LED_AGEING_PER_1000H). [1/(1000 h)]
_DRIFT_SCALE = 0.001

#: Floor added to a within-person SD of a physiological column before its log, in
#: the column's unit: a tenth of the smallest step its instruments report.
_PMF_FLOOR = {
    "age_yr": 0.01, "bmi_kgm2": 0.01, "melanin_fraction": 1e-4, "skin_thickness_mm": 1e-3,
    "hydration_pct": 0.01, "systolic_bp_mmhg": 0.1, "heart_rate_bpm": 0.1,
    "resp_rate_bpm": 0.1, "skin_temp_c": 0.01, "humidity_pct": 0.1, "pressure_mbar": 0.1,
    "blood_volume_pct": 1e-3, "spo2_pct": 0.1,
}
#: Floor of a relative SD before its log. [-]
_REL_FLOOR = 1e-5


def channel_pairs(device: TwinDevice) -> list[tuple[int, int]]:
    """Channel pairs summarised: every pair up to four LEDs, neighbours beyond."""
    n = len(device.wavelengths_nm)
    if n <= 4:
        return list(itertools.combinations(range(n), 2))
    return [(i, i + 1) for i in range(n - 1)]


def summary_names(device: TwinDevice) -> list[str]:
    """Names of the entries of :func:`summaries`, in order."""
    names = []
    for w in device.labels:
        names += [f"{s}_{w}" for s in ("level", "between", "within", "slope", "hetero",
                                        "kurtosis")]
    lab = device.labels
    for i, j in channel_pairs(device):
        names += [f"corr_{lab[i]}_{lab[j]}", f"bcorr_{lab[i]}_{lab[j]}"]
    if device.reference:
        names += [f"ref_level_{w}" for w in lab]
        if device.monitor:
            names += [f"ratio_within_{w}" for w in lab]
    names += [f"within_{c}" for c in device.physiology]
    if device.times:
        names += [f"drift_{w}" for w in device.labels]
    return names


def summaries(frame: pd.DataFrame, device: TwinDevice) -> np.ndarray:
    """The summary vector of a device file (:func:`summary_names` names its entries).

    Parameters
    ----------
    frame : pandas.DataFrame
        ``subject_id``, ``glucose_mgdl`` [mg/dL], the device's ``adc_<nm>`` (and
        ``adc_ref_<nm>``) codes and its physiological columns.
    device : TwinDevice
        What the file declares.

    Returns
    -------
    numpy.ndarray
        One float per summary; NaN where the file cannot give one (a channel that never
        changes within a person).

    Examples
    --------
    >>> import pandas as pd
    >>> from nirglucose.twin.device import TwinDevice
    >>> dev = TwinDevice((940.0,), 10, False, False, (), False, 2, 3)
    >>> f = pd.DataFrame({"subject_id": [0, 0, 0, 1, 1, 1],
    ...                   "glucose_mgdl": [90., 120., 150., 100., 130., 160.],
    ...                   "adc_940": [500, 510, 520, 600, 612, 618]})
    >>> s = dict(zip(summary_names(dev), summaries(f, dev)))
    >>> # by hand: sum(dev code x dev glucose) / sum(dev glucose^2) = 1140 / 3600 codes per
    >>> # mg/dL, x 100 / mean code 560 = 0.0565 of the mean per 100 mg/dL
    >>> round(float(np.sinh(s["slope_940"]) * 0.002), 4)
    0.0565
    """
    sid, k = subject_codes(frame)
    n_per = np.bincount(sid, minlength=k).astype(float)
    glucose = frame["glucose_mgdl"].to_numpy(float)
    g_dev = glucose - (np.bincount(sid, glucose, k) / n_per)[sid]
    codes = frame[[f"adc_{w}" for w in device.labels]].to_numpy(float)
    out, resid, means = [], [], []
    for c in range(codes.shape[1]):
        values, r, m = _channel(codes[:, c], sid, k, n_per, g_dev, device.full_scale)
        out += values
        resid.append(r)
        means.append(m)
    for i, j in channel_pairs(device):
        out += [_corr(resid[i], resid[j]), _corr(np.log(means[i]), np.log(means[j]))]
    if device.reference:
        refs = frame[[f"adc_ref_{w}" for w in device.labels]].to_numpy(float)
        out += list(np.log10(refs.mean(axis=0) / device.full_scale))
        if device.monitor:
            ratio = np.log(np.maximum(codes, 1.0) / np.maximum(refs, 1.0))
            for c in range(codes.shape[1]):
                out.append(np.log10(_pooled_sd(ratio[:, c], sid, k, n_per, 0) + _REL_FLOOR))
    for col in device.physiology:
        out.append(_pmf_summary(frame[col].to_numpy(float), col, sid, k, n_per))
    if device.times:
        hours = frame[TIME_COLUMNS[0]].to_numpy(float) / 60.0
        t_dev = hours - (np.bincount(sid, hours, k) / n_per)[sid]
        sgg = float(g_dev @ g_dev)
        # Frisch-Waugh: time's slope fitted with glucose's = the residuals' slope on time's
        # part that glucose does not explain
        t_res = t_dev - (float(t_dev @ g_dev) / sgg if sgg > 0 else 0.0) * g_dev
        stt = float(t_res @ t_res)
        for c in range(codes.shape[1]):
            level = max(float(codes[:, c].mean()), 0.5)
            slope = float(resid[c] @ t_res) / stt if stt > 0 else 0.0  # codes per hour
            out.append(float(np.arcsinh(-1000.0 * slope / level / _DRIFT_SCALE)))
    return np.asarray(out, dtype=float)


def _channel(y, sid, k, n_per, g_dev, full_scale):
    """One channel's six summaries, its within-person residuals and its people's means."""
    mean_s = np.bincount(sid, y, k) / n_per
    level = float(y.mean())
    dev = y - mean_s[sid]
    sgg = float(g_dev @ g_dev)
    slope = float(dev @ g_dev) / sgg if sgg > 0 else 0.0
    resid = dev - slope * g_dev
    dof = max(len(y) - k - 1, 1)
    within = float(np.sqrt(resid @ resid / dof))
    sd_s = np.sqrt(np.bincount(sid, resid * resid, k) / np.maximum(n_per - 1, 1))
    ok = (n_per >= 2) & (sd_s > 0)
    hetero = _corr(np.log(mean_s[ok]), np.log(sd_s[ok])) if ok.sum() >= 3 else 0.0
    z = resid / within if within > 0 else resid
    values = [
        np.log10(max(level, 0.5) / full_scale),
        np.log10(float(np.std(mean_s, ddof=1)) / level + _REL_FLOOR),
        np.log10(within / level + _REL_FLOOR),
        float(np.arcsinh(100.0 * slope / level / _SLOPE_SCALE)),
        hetero,
        float(np.log10(np.mean(z ** 4))) if within > 0 else float(np.log10(3.0)),
    ]
    return values, resid, np.maximum(mean_s, 0.5)


def _pooled_sd(x, sid, k, n_per, n_fitted: int) -> float:
    """Pooled within-person SD of ``x`` (``n_fitted`` extra terms fitted)."""
    dev = x - (np.bincount(sid, x, k) / n_per)[sid]
    return float(np.sqrt(dev @ dev / max(len(x) - k - n_fitted, 1)))


def _pmf_summary(x, col, sid, k, n_per) -> float:
    """A physiological column's within-person spread (module docstring)."""
    if col == "fitzpatrick_type":
        t = np.clip(np.rint(x).astype(np.int64), 1, 6)
        counts = np.bincount(sid * 7 + t, minlength=7 * k).reshape(k, 7)
        return float(np.mean(t != counts.argmax(axis=1)[sid]))
    return float(np.log10(_pooled_sd(x, sid, k, n_per, 0) + _PMF_FLOOR[col]))


def _corr(a, b) -> float:
    """Pearson correlation, 0 where either side does not vary."""
    a = np.asarray(a, float) - np.mean(a)
    b = np.asarray(b, float) - np.mean(b)
    den = float(np.sqrt((a @ a) * (b @ b)))
    return float(a @ b) / den if den > 0 else 0.0
