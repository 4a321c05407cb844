"""scikit-learn's common estimator checks for the reference learners (mean, gp, gbr).

On plain arrays every learner fits a plain schema (the array's columns as generic
spectral inputs, no physiology), through the same boundary as a device's frame. EBL and
PLS are checked in ``test_models_linear.py``, the networks in ``test_models_torch_base.py``.
"""

from __future__ import annotations

from sklearn.utils.estimator_checks import parametrize_with_checks

from nirglucose.models.reference import GBRReference, GPReference, MeanReference

#: Checks a reference learner is expected to fail, with the limit each one names.
EXPECTED_FAILED: dict[str, dict[str, str]] = {
    "MeanReference": {},
    "GPReference": {},
    "GBRReference": {},
}

ESTIMATORS = [
    MeanReference(),
    GPReference(max_fit_rows=200, random_state=0),
    GBRReference(n_estimators=20, random_state=0),
]


@parametrize_with_checks(
    ESTIMATORS,
    expected_failed_checks=lambda est: EXPECTED_FAILED[type(est).__name__],
    xfail_strict=True,
)
def test_sklearn_common_checks(estimator, check):
    check(estimator)
