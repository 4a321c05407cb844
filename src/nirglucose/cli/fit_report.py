"""What ``fit`` says about the data it fitted: where the file was read differently, the
small-data policy, and the model's own subject-grouped cross-validated error beside no
skill, broken down by group (``cohort``) where the file has one."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ._common import UserError, _say

#: Columns read as a group label for the per-group breakdown (case-folded).
GROUP_COLUMNS = ("cohort", "group", "site", "study_arm")


def load_device_file(data: Path, glucose_unit: str | None, adc_bits: int | None, *,
                     need_glucose: bool):
    """The file as a Dataset, its read notes printed, the ADC resolution resolved by
    the one policy (:mod:`nirglucose.dataset.adc`) and recorded in its metadata."""
    import warnings

    from ..dataset import load_dataset
    from ..dataset.files import check_codes
    from ..dataset.schema import DeviceSchema

    ds = load_dataset(data, glucose_unit=glucose_unit, adc_bits=adc_bits)
    if need_glucose and "glucose_mgdl" not in ds.frame.columns:
        cols = ", ".join(repr(str(c)) for c in ds.frame.columns[:12])
        raise UserError(f"{str(data)!r} has no reference glucose: add a 'glucose_mgdl' "
                        f"(mg/dL) or 'glucose_mmoll' (mmol/L) column; columns read: {cols}")
    if need_glucose and ds.frame["glucose_mgdl"].isna().any():
        from ..dataset.files import file_rows

        rows = file_rows(ds.frame["glucose_mgdl"].isna().to_numpy(), Path(data).suffix == ".csv")
        raise UserError(f"column 'glucose_mgdl' (the reference glucose) has empty cells at "
                        f"{rows}; every reading fitted needs its meter value")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        schema = DeviceSchema.infer(ds)
    check_codes(ds.frame, schema.adc_bits, csv=Path(data).suffix == ".csv")
    for w in caught:
        _say(f"warning: {w.message}")
    ds.metadata["adc_bits"] = schema.adc_bits  # one resolution from here on, recorded
    if need_glucose:
        check_zero_variance(ds, schema)
    return ds, schema


def say_notes(ds) -> None:
    """Print how the file was read (after the command succeeded: an error stays one line)."""
    for note in ds.metadata.get("read_notes", []):
        _say(f"note: {note}")


def in_unit(value_mgdl: float, unit: str | None) -> str:
    """A glucose value or error printed in the requested unit."""
    from ..dataset.files import glucose_to_unit

    unit = unit or "mg/dL"
    v = float(glucose_to_unit(value_mgdl, unit))
    return f"{v:.2f} {unit}" if unit == "mmol/L" else f"{v:.1f} {unit}"


def _group_column(frame) -> str | None:
    for c in frame.columns:
        if str(c).strip().casefold() in GROUP_COLUMNS:
            return c
    return None


def grouped_cv(estimator, ds, folds: int):
    """Out-of-fold predictions of a clone of ``estimator`` and of no skill (the training
    mean), folds grouped by subject (by row without ``subject_id``)."""
    from sklearn.base import clone
    from sklearn.model_selection import GroupKFold

    frame = ds.frame
    groups = (frame["subject_id"].to_numpy() if "subject_id" in frame
              else np.arange(len(frame)))
    k = min(folds, len(np.unique(groups)))
    y = frame["glucose_mgdl"].to_numpy(float)
    pred, base = np.empty(len(y)), np.empty(len(y))
    for tr, te in GroupKFold(n_splits=k).split(y, y, groups):
        model = clone(estimator).fit(ds.rows(tr))
        pred[te] = np.asarray(model.predict(ds.rows(te)), dtype=float)
        base[te] = y[tr].mean()
    return y, pred, base, k


def _rmse(a, b) -> float:
    return float(np.sqrt(np.mean((np.asarray(a) - np.asarray(b)) ** 2)))


def report_cv(estimator, ds, schema, folds: int, unit: str | None) -> None:
    """Print the grouped-CV RMSE beside no skill, and the per-group breakdown."""
    from ..dataset.small_data import MIN_CV_SUBJECTS

    n_sub = ds.frame["subject_id"].nunique() if "subject_id" in ds.frame else len(ds)
    if folds < 2 or n_sub < 2:
        return
    y, pred, base, k = grouped_cv(estimator, ds, folds)
    cv_rmse, no_skill = _rmse(y, pred), _rmse(y, base)
    who = (f"{n_sub} subjects" if "subject_id" in ds.frame
           else f"{n_sub} readings (no subject_id: each taken as a subject)")
    _say(f"grouped {k}-fold CV over {who}: RMSE {in_unit(cv_rmse, unit)}; "
         f"no skill (the training mean) {in_unit(no_skill, unit)}", err=False)
    if cv_rmse > no_skill:
        _say("warning: the grouped-CV error is above no skill: on new people this model "
             "does worse than predicting the training mean")
    if n_sub < MIN_CV_SUBJECTS:
        _say(f"warning: a CV estimate from {n_sub} subjects (< {MIN_CV_SUBJECTS}) is "
             "unstable; quote it only with that number")
    gcol = _group_column(ds.frame)
    if gcol is None:
        return
    adc = ds.frame[f"adc_{schema.labels[0]}"].to_numpy(float)
    pooled = float(np.corrcoef(adc, y)[0, 1]) if np.std(adc) and np.std(y) else np.nan
    flipped = []
    for g, idx in ds.frame.groupby(gcol, sort=True).indices.items():
        r = (float(np.corrcoef(adc[idx], y[idx])[0, 1])
             if len(idx) > 2 and np.std(adc[idx]) and np.std(y[idx]) else np.nan)
        flipped += [str(g)] if np.isfinite(r) and np.sign(r) == -np.sign(pooled) else []
        _say(f"  {gcol} {g}: {len(idx)} readings, CV RMSE {in_unit(_rmse(y[idx], pred[idx]), unit)}"
             f", no skill {in_unit(_rmse(y[idx], base[idx]), unit)}, r(adc_{schema.labels[0]}, "
             f"glucose) {r:+.2f} (pooled {pooled:+.2f})", err=False)
    if flipped:
        _say(f"warning: within {gcol} {', '.join(flipped)} the ADC-glucose correlation has the "
             "opposite sign of the pooled one: the pooled skill may be a group offset, not "
             "glucose")


def warn_overparameterised(estimator, n_rows: int) -> None:
    """One warning when the fitted model has more parameters than readings (with the
    epochs early stopping chose, for a network that held out subjects)."""
    n_par = getattr(estimator, "n_parameters", None)
    stopped = ""
    if getattr(estimator, "start_val_mse_", None) is not None:
        n_ep = int(estimator.best_epoch_)
        stopped = (f"; early stopping on held-out subjects chose {n_ep} epochs"
                   + (" (the training mean: no epoch beat it)" if n_ep == 0 else ""))
    try:
        n_par = int(n_par() if callable(n_par) else n_par)
    except (TypeError, ValueError, AttributeError):
        return
    if n_par > n_rows:
        _say(f"warning: the model has {n_par:,} parameters for {n_rows} readings: its "
             f"in-sample fit says nothing; judge it by the grouped CV error{stopped}")


def check_zero_variance(ds, schema) -> None:
    """Refuse a fit whose ADC channels or reference glucose never change."""
    frame = ds.frame
    for col in [f"adc_{w}" for w in schema.labels] + ["glucose_mgdl"]:
        vals = frame[col].to_numpy(float)
        if len(vals) and np.ptp(vals) == 0:
            raise UserError(f"column {col!r} holds one value ({vals[0]:g}) in every row: "
                            "nothing to learn from; check the export of the file")
