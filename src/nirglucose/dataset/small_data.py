"""The one small-data policy: how many *subjects* each claim needs.

Readings of one person are not independent (they share a skin, a physiology and a
device placement), so every threshold counts subjects, not rows.

========================================  =====  ==========================================
claim                                     min    below it
========================================  =====  ==========================================
a fit at all (:data:`MIN_FIT_SUBJECTS`)     2    refused (grouped inner validation)
a fit that can learn more than an offset   10    fit warns (:data:`MIN_LEARNING_SUBJECTS`)
a cross-validated error estimate           10    the estimate is printed with a warning
                                                 (:data:`MIN_CV_SUBJECTS`)
a 90 % prediction interval                  9    none calibrated (held-out subjects,
                                                 :data:`MIN_INTERVAL_SUBJECTS`)
a significance statement / "best model"    10    not made; the result says so
                                                 (test subjects,
                                                 :data:`MIN_SIGNIFICANCE_SUBJECTS`)
========================================  =====  ==========================================

Sources: split-conformal coverage needs ceil(0.9 (n + 1)) <= n held-out units, n >= 9
(Lei et al., J. Am. Stat. Assoc. 113, 1094 (2018), doi:10.1080/01621459.2017.1307116);
a cluster (subject) bootstrap over fewer than about 10 clusters over-rejects (Cameron,
Gelbach & Miller, Rev. Econ. Stat. 90, 414 (2008), doi:10.1162/rest.90.3.414); five
grouped folds need two subjects each for a fold's error to be more than one person's.

Examples
--------
>>> significance_withheld(5)[:47]
'no significance or best model claimed: only 5 t'
>>> significance_withheld(25) is None
True
"""

from __future__ import annotations

__all__ = [
    "MIN_FIT_ROWS",
    "MIN_FIT_SUBJECTS",
    "MIN_LEARNING_SUBJECTS",
    "MIN_CV_SUBJECTS",
    "MIN_INTERVAL_SUBJECTS",
    "MIN_SIGNIFICANCE_SUBJECTS",
    "fit_size_warning",
    "significance_withheld",
]

#: Fewest rows any model fits on (the inner CV's default 5 folds need one row each). [-]
MIN_FIT_ROWS = 5
#: Fewest subjects any model fits on when subject ids are known (subject-grouped inner
#: validation holds out at least one subject). [-]
MIN_FIT_SUBJECTS = 2
#: Fewest subjects for a fit to be more than a per-person offset. [-]
MIN_LEARNING_SUBJECTS = 10
#: Fewest subjects for a grouped cross-validated error worth quoting. [-]
MIN_CV_SUBJECTS = 10
#: Fewest held-out subjects for a split-conformal 90 % interval. [-]
MIN_INTERVAL_SUBJECTS = 9
#: Fewest test subjects for a significance statement or a "best model". [-]
MIN_SIGNIFICANCE_SUBJECTS = 10


def fit_size_warning(n_subjects: int, n_rows: int) -> str | None:
    """The one-line warning of a fit on fewer than :data:`MIN_LEARNING_SUBJECTS`."""
    if n_subjects >= MIN_LEARNING_SUBJECTS:
        return None
    return (f"only {n_subjects} subjects ({n_rows} readings): below "
            f"{MIN_LEARNING_SUBJECTS} a model learns little beyond each group's offset; "
            "treat its error estimate as a rough guide (small-data policy: README)")


def significance_withheld(n_test_subjects: int) -> str | None:
    """Why no significance or best model is claimed, or None when enough subjects."""
    if n_test_subjects >= MIN_SIGNIFICANCE_SUBJECTS:
        return None
    return (f"no significance or best model claimed: only {n_test_subjects} test subjects, "
            f"fewer than the {MIN_SIGNIFICANCE_SUBJECTS} a paired comparison needs "
            "(small-data policy: README); use grouped-cv to test every subject")
