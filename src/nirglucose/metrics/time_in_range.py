"""Time in ranges (TIR / TBR / TAR) of the international consensus, from reference and
from a monitor's readings (Battelino et al. 2019, Diabetes Care 42:1593).
"""

from __future__ import annotations

from types import MappingProxyType
from typing import Final

import numpy as np
import pandas as pd
from numpy.typing import ArrayLike

from nirglucose.exceptions import DataError
from nirglucose.metrics._validation import (
    as_1d_float,
    describe_bad,
    subject_codes,
    validate_pairs,
)
from nirglucose.metrics.cgm import EUGLYCAEMIC_HIGH_MGDL, EUGLYCAEMIC_LOW_MGDL

__all__ = ["TIME_IN_RANGE_TARGETS_PCT", "time_in_ranges", "time_in_range_agreement"]

#: Consensus targets for most adults with type 1 or type 2 diabetes (Battelino et al.
#: 2019, Table 2 / Figure 2): ('>' or '<', value). [%]
TIME_IN_RANGE_TARGETS_PCT: Final = MappingProxyType({
    "tbr_lt54_pct": ("<", 1.0),
    "tbr_lt70_pct": ("<", 4.0),
    "tir_70_180_pct": (">", 70.0),
    "tar_gt180_pct": ("<", 25.0),
    "tar_gt250_pct": ("<", 5.0),
})

#: Range edges of the consensus (Battelino et al. 2019, Table 1). [mg/dL]
_VERY_LOW_MGDL: Final[float] = 54.0
_VERY_HIGH_MGDL: Final[float] = 250.0


def _tir_table(glucose, subj, uniq) -> pd.DataFrame:
    k = uniq.shape[0]
    n = np.bincount(subj, minlength=k).astype(np.float64)
    masks = {
        "tbr_lt54_pct": glucose < _VERY_LOW_MGDL,
        "tbr_lt70_pct": glucose < EUGLYCAEMIC_LOW_MGDL,
        "tir_70_180_pct": (glucose >= EUGLYCAEMIC_LOW_MGDL) & (glucose <= EUGLYCAEMIC_HIGH_MGDL),
        "tar_gt180_pct": glucose > EUGLYCAEMIC_HIGH_MGDL,
        "tar_gt250_pct": glucose > _VERY_HIGH_MGDL,
    }
    data = {"subject_id": uniq, "n_readings": n.astype(np.int64)}
    for key, mask in masks.items():
        data[key] = 100.0 * np.bincount(subj, weights=mask.astype(np.float64), minlength=k) / n
    return pd.DataFrame(data)


def time_in_ranges(glucose_mgdl: ArrayLike, subject_id: ArrayLike) -> pd.DataFrame:
    """Time below, in and above range per subject (international consensus, 2019).

    The share of each subject's readings in the consensus ranges: below 54 mg/dL
    (TBR level 2), below 70 mg/dL (TBR, level 1 and 2 together), 70-180 mg/dL (TIR,
    both edges included), above 180 mg/dL (TAR, level 1 and 2) and above 250 mg/dL
    (TAR level 2). With uniform sampling the share of readings is the share of time;
    resample unevenly spaced readings first. The targets for most adults with type 1
    or type 2 diabetes are in :data:`TIME_IN_RANGE_TARGETS_PCT` (TIR > 70 %, TBR < 4 %,
    < 54 mg/dL < 1 %, TAR < 25 %, > 250 mg/dL < 5 %).

    Parameters
    ----------
    glucose_mgdl : array_like
        Glucose readings, finite. [mg/dL]
    subject_id : array_like
        Subject of each reading. [-]

    Returns
    -------
    pandas.DataFrame
        One row per subject (sorted): ``subject_id``, ``n_readings`` [-],
        ``tbr_lt54_pct``, ``tbr_lt70_pct``, ``tir_70_180_pct``, ``tar_gt180_pct``,
        ``tar_gt250_pct`` [%].

    Raises
    ------
    DataError
        On non-finite glucose or a ``subject_id`` of the wrong length.

    References
    ----------
    .. [1] Battelino T, Danne T, Bergenstal RM, et al. Clinical targets for continuous
       glucose monitoring data interpretation: recommendations from the international
       consensus on time in range. Diabetes Care 42(8):1593-1603, 2019.
       doi:10.2337/dci19-0028

    Examples
    --------
    >>> time_in_ranges([50, 100, 150, 300], [1, 1, 1, 1])["tir_70_180_pct"].tolist()
    [50.0]
    """
    g = as_1d_float(glucose_mgdl, "glucose_mgdl")
    if g.shape[0] == 0:
        raise DataError("glucose_mgdl is empty; at least one reading is needed")
    bad = ~np.isfinite(g)
    if bad.any():
        raise DataError(f"glucose_mgdl contains NaN or infinite values: {describe_bad(bad)}")
    subj, uniq = subject_codes(subject_id, g.shape[0])
    return _tir_table(g, subj, uniq)


def time_in_range_agreement(
    reference_mgdl: ArrayLike, predicted_mgdl: ArrayLike, subject_id: ArrayLike
) -> pd.DataFrame:
    """Time in ranges from the reference and from the device, per subject, and the gap.

    Each metric of :func:`time_in_ranges` is computed from the reference series and
    from the predicted series of each subject; the difference is predicted minus
    reference (a device that over-reads shows positive TAR differences). The consensus
    target of each metric (Battelino et al. 2019) is listed beside it, with whether the
    reference and the device each meet it -- a device that changes the verdict is
    clinically wrong even where its point accuracy looks fine.

    Parameters
    ----------
    reference_mgdl : array_like
        Reference glucose, strictly positive. [mg/dL]
    predicted_mgdl : array_like
        Device / predicted glucose, same length. [mg/dL]
    subject_id : array_like
        Subject of each reading. [-]

    Returns
    -------
    pandas.DataFrame
        Long format, one row per (subject, metric): ``subject_id``, ``metric``,
        ``reference_pct``, ``predicted_pct``, ``difference_pct`` [%], ``target`` (e.g.
        '> 70 %'), ``reference_meets``, ``predicted_meets`` (bool).

    Raises
    ------
    DataError
        As :func:`time_in_ranges`, and on bad pairs.

    References
    ----------
    .. [1] Battelino T, Danne T, Bergenstal RM, et al. Clinical targets for continuous
       glucose monitoring data interpretation: recommendations from the international
       consensus on time in range. Diabetes Care 42(8):1593-1603, 2019.
       doi:10.2337/dci19-0028

    Examples
    --------
    >>> t = time_in_range_agreement([100, 200], [100, 170], [1, 1])
    >>> t.loc[t["metric"] == "tir_70_180_pct", "difference_pct"].tolist()
    [50.0]
    """
    ref, pred = validate_pairs(reference_mgdl, predicted_mgdl)
    subj, uniq = subject_codes(subject_id, ref.shape[0])
    a, b = _tir_table(ref, subj, uniq), _tir_table(pred, subj, uniq)
    frames = []
    for metric, (sign, value) in TIME_IN_RANGE_TARGETS_PCT.items():
        r, p = a[metric].to_numpy(), b[metric].to_numpy()
        meets = np.greater if sign == ">" else np.less
        frames.append(pd.DataFrame({
            "subject_id": uniq, "metric": metric, "reference_pct": r, "predicted_pct": p,
            "difference_pct": p - r, "target": f"{sign} {value:g} %",
            "reference_meets": meets(r, value), "predicted_meets": meets(p, value),
        }))
    return pd.concat(frames, ignore_index=True)
