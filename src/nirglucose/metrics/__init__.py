"""Clinical accuracy metrics for glucose estimates.

Point accuracy (RMSE, MARD, bias, share within a percentage), Bland–Altman agreement,
the Clarke, Parkes (consensus) and DTS error grids, the ISO 15197:2013 accuracy criteria,
a one-call :func:`summary`, and the standards of a worn monitor (:mod:`.cgm`: MARD by
range and day, agreement rates with clustered lower bounds and the iCGM criteria;
:mod:`.trend`: trend accuracy and lag; :mod:`.time_in_range`). Every metric takes
``(y_true, y_pred, *, options)`` with the reference first; glucose is in mg/dL unless
``units="mmol/L"`` is given.
"""

from __future__ import annotations

from nirglucose.metrics._validation import MGDL_PER_MMOLL, VALID_UNITS
from nirglucose.metrics.cgm import (
    AGREEMENT_LIMITS,
    CI_METHODS,
    GLUCOSE_RANGE_LABELS,
    ICGM_CRITERIA,
    agreement_rates,
    icgm_criteria,
    mard_by_day,
    mard_by_range,
)
from nirglucose.metrics.error_grids import (
    DTS_LINES,
    PARKES_LINES,
    PARKES_TYPE1_LINES,
    PARKES_TYPE2_LINES,
    ZONE_LABELS,
    clarke_zones,
    dts_zones,
    parkes_zones,
    zone_percentages,
)
from nirglucose.metrics.iso15197 import (
    iso15197_2013,
    iso15197_2013_passes,
    iso15197_2013_zone_ab,
)
from nirglucose.metrics.regression import (
    BlandAltmanResult,
    bland_altman,
    mard,
    mean_bias,
    rmse,
    within_percent,
)
from nirglucose.metrics.summary import SUMMARY_KEYS, summary
from nirglucose.metrics.time_in_range import (
    TIME_IN_RANGE_TARGETS_PCT,
    time_in_range_agreement,
    time_in_ranges,
)
from nirglucose.metrics.trend import (
    TREND_EDGES_MGDL_PER_MIN,
    LagEstimate,
    TrendAgreement,
    estimated_lag,
    rate_categories,
    rate_of_change,
    trend_agreement,
)

__all__ = [
    "MGDL_PER_MMOLL",
    "VALID_UNITS",
    "ZONE_LABELS",
    "PARKES_LINES",
    "PARKES_TYPE1_LINES",
    "PARKES_TYPE2_LINES",
    "DTS_LINES",
    "SUMMARY_KEYS",
    "GLUCOSE_RANGE_LABELS",
    "AGREEMENT_LIMITS",
    "CI_METHODS",
    "ICGM_CRITERIA",
    "TREND_EDGES_MGDL_PER_MIN",
    "TIME_IN_RANGE_TARGETS_PCT",
    "BlandAltmanResult",
    "TrendAgreement",
    "LagEstimate",
    "rmse",
    "mard",
    "mean_bias",
    "within_percent",
    "bland_altman",
    "iso15197_2013",
    "iso15197_2013_zone_ab",
    "iso15197_2013_passes",
    "clarke_zones",
    "parkes_zones",
    "dts_zones",
    "zone_percentages",
    "summary",
    "mard_by_range",
    "mard_by_day",
    "agreement_rates",
    "icgm_criteria",
    "rate_of_change",
    "rate_categories",
    "trend_agreement",
    "estimated_lag",
    "time_in_ranges",
    "time_in_range_agreement",
]
