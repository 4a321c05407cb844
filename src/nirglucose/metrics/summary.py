"""One-call clinical accuracy summary of a glucose estimate."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from nirglucose.metrics._validation import _to_mgdl, _unit_factor, _validate_pairs
from nirglucose.metrics.error_grids import (
    _check_diabetes_type,
    _clarke_codes,
    _dts_codes,
    _parkes_codes,
    _percentages_from_codes,
)
from nirglucose.metrics.iso15197 import _iso_within_count
from nirglucose.metrics.regression import (
    _bland_altman_from_diff,
    _mard,
    _mean_bias,
    _rmse,
    _within_mask,
)

__all__ = ["SUMMARY_KEYS", "summary"]

#: Keys of :func:`summary`, in order; the suffix gives the unit.
SUMMARY_KEYS: tuple[str, ...] = (
    "n",
    "rmse_mgdl",
    "mard_pct",
    "bias_mgdl",
    "clarke_a_pct",
    "clarke_ab_pct",
    "clarke_b_pct",
    "clarke_c_pct",
    "clarke_d_pct",
    "clarke_e_pct",
    "parkes_a_pct",
    "parkes_ab_pct",
    "within15_pct",
    "within20_pct",
    "iso15197_pct",
    "iso15197_zone_ab_pct",
    "loa_low_mgdl",
    "loa_high_mgdl",
    "dts_a_pct",
)


def summary(
    y_true: ArrayLike,
    y_pred: ArrayLike,
    *,
    units: str = "mg/dL",
    diabetes_type: int = 1,
) -> dict[str, float]:
    """Every clinical accuracy metric of the package in one dictionary.

    The inputs are validated once and converted to mg/dL; every metric is then
    computed as defined in its own function: RMSE and bias (:func:`rmse`,
    :func:`mean_bias`), MARD (:func:`mard`), Clarke zones (Clarke et al. 1987,
    :func:`clarke_zones`), Parkes zones for ``diabetes_type`` (Parkes et al. 2000 with
    the Pfützner et al. 2013 coordinates, :func:`parkes_zones`), the share within
    ±15 % / ±20 % (:func:`within_percent`), both ISO 15197:2013 6.3.3 criteria (the
    zone A + B criterion always uses the type 1 grid, as the standard prescribes) and
    the Bland–Altman 95 % limits of agreement (:func:`bland_altman`, absolute
    differences) and the share in zone A of the DTS error grid (Klonoff et al. 2024,
    :func:`dts_zones`).

    Parameters
    ----------
    y_true : array_like
        Reference glucose, strictly positive. [mg/dL, or ``units``]
    y_pred : array_like
        Predicted glucose, non-negative (the error grids need it), same length.
        [mg/dL, or ``units``]
    units : {"mg/dL", "mmol/L"}, optional
        Unit of both inputs; results are always reported in mg/dL (18.016 mg/dL per
        mmol/L). [-]
    diabetes_type : {1, 2}, optional
        Parkes grid used for ``parkes_a_pct`` and ``parkes_ab_pct``. [-]

    Returns
    -------
    dict of str to float
        Keys :data:`SUMMARY_KEYS`, every value a plain Python ``float`` (``n``
        included, so that all values share one type): ``n`` [-], ``rmse_mgdl``,
        ``bias_mgdl``, ``loa_low_mgdl``, ``loa_high_mgdl`` [mg/dL], the ``*_pct`` keys
        [%]. ``clarke_ab_pct`` is A + B; ``within15_pct`` / ``within20_pct`` are the
        shares within ±15 % / ±20 % of the reference; ``iso15197_pct`` and
        ``iso15197_zone_ab_pct`` are ISO 15197:2013 criteria a) and b); ``dts_a_pct``
        the share in DTS zone A (the paper's measure; it advises against pooling A + B).
        With a single pair the limits of agreement are undefined and reported as NaN.

    Raises
    ------
    DataError
        On a length mismatch, empty input, NaN or infinite values, a reference value
        <= 0, a negative prediction, unknown ``units`` or ``diabetes_type``.

    References
    ----------
    .. [1] Clarke WL, Cox D, Gonder-Frederick LA, Carter W, Pohl SL. Evaluating clinical
       accuracy of systems for self-monitoring of blood glucose. Diabetes Care
       10(5):622-628, 1987. doi:10.2337/diacare.10.5.622
    .. [2] Parkes JL, Slatin SL, Pardo S, Ginsberg BH. A new consensus error grid to
       evaluate the clinical significance of inaccuracies in the measurement of blood
       glucose. Diabetes Care 23(8):1143-1148, 2000. doi:10.2337/diacare.23.8.1143
    .. [3] Pfützner A, Klonoff DC, Pardo S, Parkes JL. Technical aspects of the Parkes
       error grid. J Diabetes Sci Technol 7(5):1275-1281, 2013.
       doi:10.1177/193229681300700517
    .. [4] ISO 15197:2013, In vitro diagnostic test systems -- Requirements for
       blood-glucose monitoring systems for self-testing in managing diabetes
       mellitus, clause 6.3.3.
    .. [5] Bland JM, Altman DG. Statistical methods for assessing agreement between two
       methods of clinical measurement. Lancet 327(8476):307-310, 1986.
       doi:10.1016/S0140-6736(86)90837-8
    .. [6] Klonoff DC, Freckmann G, Pleus S, et al. The Diabetes Technology Society Error
       Grid and Trend Accuracy Matrix for glucose monitors. J Diabetes Sci Technol
       18(6):1346-1361, 2024. doi:10.1177/19322968241275701

    Examples
    --------
    >>> s = summary([100.0, 200.0], [110.0, 190.0])
    >>> s["n"], s["rmse_mgdl"], s["bias_mgdl"], s["clarke_a_pct"]
    (2.0, 10.0, 0.0, 100.0)
    """
    dtype = _check_diabetes_type(diabetes_type)
    _unit_factor(units)
    ref, pred = _validate_pairs(y_true, y_pred, allow_negative_pred=False)
    ref, pred = _to_mgdl(ref, pred, units)
    n = ref.shape[0]
    diff = pred - ref
    absdiff = np.abs(diff)

    clarke_codes = _clarke_codes(ref, pred)
    clarke = _percentages_from_codes(clarke_codes)
    parkes_type1 = _parkes_codes(ref, pred, 1)
    parkes = parkes_type1 if dtype == 1 else _parkes_codes(ref, pred, dtype)
    parkes_a = 100.0 * np.count_nonzero(parkes == 0) / n
    zone_ab_type1 = 100.0 * np.count_nonzero(parkes_type1 <= 1) / n
    ba = _bland_altman_from_diff(diff)

    values = (
        n,
        _rmse(diff),
        _mard(absdiff, ref),
        _mean_bias(diff),
        clarke["A"],
        100.0 * np.count_nonzero(clarke_codes <= 1) / n,
        clarke["B"],
        clarke["C"],
        clarke["D"],
        clarke["E"],
        parkes_a,
        100.0 * np.count_nonzero(parkes <= 1) / n,
        100.0 * np.count_nonzero(_within_mask(absdiff, ref, 15.0)) / n,
        100.0 * np.count_nonzero(_within_mask(absdiff, ref, 20.0)) / n,
        100.0 * _iso_within_count(absdiff, ref) / n,
        zone_ab_type1,
        ba.lower_loa,
        ba.upper_loa,
        100.0 * np.count_nonzero(_dts_codes(ref, pred) == 0) / n,
    )
    return {key: float(value) for key, value in zip(SUMMARY_KEYS, values, strict=True)}
