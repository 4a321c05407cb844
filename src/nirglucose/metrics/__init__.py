"""Clinical accuracy metrics for glucose estimates.

Point accuracy (RMSE, MARD, bias, share within a percentage), Bland–Altman agreement,
the Clarke and Parkes (consensus) error grids, the ISO 15197:2013 accuracy criteria and
a one-call :func:`summary`. Every metric takes ``(y_true, y_pred, *, options)`` with the
reference first; glucose is in mg/dL unless ``units="mmol/L"`` is given.
"""

from __future__ import annotations

from nirglucose.metrics._validation import MGDL_PER_MMOLL, VALID_UNITS
from nirglucose.metrics.error_grids import (
    PARKES_LINES,
    PARKES_TYPE1_LINES,
    PARKES_TYPE2_LINES,
    ZONE_LABELS,
    clarke_zones,
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

__all__ = [
    "MGDL_PER_MMOLL",
    "VALID_UNITS",
    "ZONE_LABELS",
    "PARKES_LINES",
    "PARKES_TYPE1_LINES",
    "PARKES_TYPE2_LINES",
    "SUMMARY_KEYS",
    "BlandAltmanResult",
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
    "zone_percentages",
    "summary",
]
