"""What ``fit`` says about the data it fitted: where the file was read differently, the
small-data policy, and the model's own subject-grouped cross-validated error beside no
skill, broken down by group (cohort, site, device, visit, diabetes status:
:mod:`nirglucose.evaluation.cohorts`) where the file has one, each group against its
own training mean."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ._common import UserError, _say


def adc_spec(text: str | None, what: str = "--adc-bits"):
    """``--adc-bits`` / ``--adc-full-scale`` as given: None, an int, or a per-channel
    mapping (:func:`nirglucose.dataset.adc.parse_channel_spec`)."""
    from ..dataset.adc import parse_channel_spec

    return None if text is None else parse_channel_spec(text, what)


def load_device_file(data: Path, glucose_unit: str | None, adc_bits: str | None, *,
                     need_glucose: bool, adc_full_scale: str | None = None):
    """The file as a Dataset, its read notes printed, the ADC resolution resolved by
    the one policy (:mod:`nirglucose.dataset.adc`, one converter or one per channel) and
    recorded in its metadata; a declared channel whose codes never reach a quarter of
    its full scale, and a channel whose every reading sits at mid-scale (an AC-coupled
    front end), are warned about. The warnings are kept in the metadata
    (``file_warnings``), so the report of a benchmark on the file states them too."""
    import warnings

    from ..dataset import load_dataset
    from ..dataset.adc import check_dc_level, check_headroom
    from ..dataset.files import check_codes
    from ..dataset.schema import DeviceSchema

    bits, full = adc_spec(adc_bits), adc_spec(adc_full_scale, "--adc-full-scale")
    if full is not None and not isinstance(full, dict):
        raise UserError(f"--adc-full-scale {adc_full_scale!r}: name the channel, e.g. "
                        "adc_1050=200000")
    ds = load_dataset(data, glucose_unit=glucose_unit, adc_bits=bits, adc_full_scale=full)
    _check_reference(ds, data, need_glucose)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        schema = DeviceSchema.infer(ds)
        check_codes(ds.frame, schema.adc_bits, csv=Path(data).suffix == ".csv",
                    full_scales=schema.code_full_scales())
        if bits is not None:  # a declared converter: is it this channel's?
            check_headroom(ds.frame, tuple(f"adc_{w}" for w in schema.labels),
                           schema.full_scales,
                           schema.channel_bits or (schema.adc_bits,) * schema.n_channels)
        check_dc_level(ds.frame, tuple(f"adc_{w}" for w in schema.labels), schema.full_scales)
    for w in caught:
        _say(f"warning: {w.message}")
    ds.metadata["file_warnings"] = list(dict.fromkeys(str(w.message) for w in caught))
    # one resolution from here on, recorded (per channel where the device mixes them)
    ds.metadata.update(schema.converter_metadata())
    if need_glucose:
        check_zero_variance(ds, schema)
    return ds, schema


def _check_reference(ds, data: Path, need_glucose: bool) -> None:
    """Refuse a file to fit without reference glucose, or with empty cells in it."""
    if need_glucose and "glucose_mgdl" not in ds.frame.columns:
        cols = ", ".join(repr(str(c)) for c in ds.frame.columns[:12])
        raise UserError(f"{str(data)!r} has no reference glucose: add a 'glucose_mgdl' "
                        f"(mg/dL) or 'glucose_mmoll' (mmol/L) column; columns read: {cols}")
    if need_glucose and ds.frame["glucose_mgdl"].isna().any():
        from ..dataset.files import file_rows

        rows = file_rows(ds.frame["glucose_mgdl"].isna().to_numpy(), Path(data).suffix == ".csv")
        raise UserError(f"column 'glucose_mgdl' (the reference glucose) has empty cells at "
                        f"{rows}; every reading fitted needs its meter value")


def say_notes(ds) -> None:
    """Print how the file was read (after the command succeeded: an error stays one line)."""
    for note in ds.metadata.get("read_notes", []):
        _say(f"note: {note}")


def display_unit(ds, declared: str | None) -> str:
    """The unit glucose is printed in: the one asked for, else the unit the file's
    reference column was read in (``glucose_mmoll``: mmol/L), else mg/dL."""
    return declared or ds.metadata.get("glucose_unit") or "mg/dL"


def in_unit(value_mgdl: float, unit: str | None) -> str:
    """A glucose value or error printed in the requested unit."""
    from ..dataset.files import glucose_to_unit

    unit = unit or "mg/dL"
    v = float(glucose_to_unit(value_mgdl, unit))
    return f"{v:.2f} {unit}" if unit == "mmol/L" else f"{v:.1f} {unit}"


def grouped_cv(estimator, ds, folds: int, group_column: str | None = None):
    """Out-of-fold predictions of a clone of ``estimator``, of no skill (the pooled
    training mean) and of each row's own-group training mean (``group_column``; the
    pooled mean without one), folds grouped by subject (by row without ``subject_id``)."""
    from sklearn.base import clone
    from sklearn.model_selection import GroupKFold

    from ..evaluation.cohorts import own_group_baseline

    frame = ds.frame
    groups = (frame["subject_id"].to_numpy() if "subject_id" in frame
              else np.arange(len(frame)))
    k = min(folds, len(np.unique(groups)))
    y = frame["glucose_mgdl"].to_numpy(float)
    pred, base = np.empty(len(y)), np.empty(len(y))
    splits = list(GroupKFold(n_splits=k).split(y, y, groups))
    for tr, te in splits:
        model = clone(estimator).fit(ds.rows(tr))
        pred[te] = np.asarray(model.predict(ds.rows(te)), dtype=float)
        base[te] = y[tr].mean()
    own = (own_group_baseline(y, frame[group_column].to_numpy(), splits)
           if group_column is not None else base.copy())
    return y, pred, base, own, k


def _rmse(a, b) -> float:
    return float(np.sqrt(np.mean((np.asarray(a) - np.asarray(b)) ** 2)))


#: Resamples of the subject bootstrap behind "no better than no skill" (seed 0). [-]
_VERDICT_RESAMPLES = 1000


def skill_verdict(y, pred, base, subjects=None) -> str | None:
    """A warning unless the model beats no skill: "above" it when the 95 % interval of
    the paired MSE difference (a percentile bootstrap over subjects, Cameron, Gelbach &
    Miller 2008, doi:10.1162/rest.90.3.414; seed 0) lies above 0, "no better" when it
    holds 0 (equal within the interval); None when it lies below 0."""
    d = (np.asarray(y) - pred) ** 2 - (np.asarray(y) - base) ** 2
    ids = np.arange(len(d)) if subjects is None else np.asarray(subjects)
    _, inv = np.unique(ids, return_inverse=True)
    sums, counts = np.bincount(inv, weights=d), np.bincount(inv).astype(float)
    idx = np.random.default_rng(0).integers(0, len(sums), size=(_VERDICT_RESAMPLES, len(sums)))
    lo, hi = np.quantile(sums[idx].sum(axis=1) / counts[idx].sum(axis=1), [0.025, 0.975])
    if hi < 0:
        return None
    if lo > 0:
        return ("the grouped-CV error is above no skill: on new people this model does "
                "worse than predicting the training mean")
    return ("the grouped-CV error is no better than no skill (equal within its 95 % "
            "interval): on new people this model does not beat predicting the training mean")


def report_cv(estimator, ds, schema, folds: int, unit: str | None,
              group_column_name: str | None = None) -> None:
    """Print the grouped-CV RMSE beside no skill, and the per-group breakdown: each
    group against its own training mean, in the file's unit unless ``unit`` is given."""
    from ..dataset.small_data import MIN_CV_SUBJECTS

    unit = display_unit(ds, unit)
    n_sub = ds.frame["subject_id"].nunique() if "subject_id" in ds.frame else len(ds)
    if folds < 2 or n_sub < 2:
        return
    gcol = group_column(ds.frame, group_column_name)
    y, pred, base, own, k = grouped_cv(estimator, ds, folds, gcol)
    cv_rmse, no_skill = _rmse(y, pred), _rmse(y, base)
    who = (f"{n_sub} subjects" if "subject_id" in ds.frame
           else f"{n_sub} readings (no subject_id: each taken as a subject)")
    _say(f"grouped {k}-fold CV over {who}: RMSE {in_unit(cv_rmse, unit)}; "
         f"no skill (the training mean) {in_unit(no_skill, unit)}", err=False)
    verdict = skill_verdict(y, pred, base,
                            ds.frame["subject_id"].to_numpy() if "subject_id" in ds.frame else None)
    if verdict:
        _say(f"warning: {verdict}")
    if n_sub < MIN_CV_SUBJECTS:
        _say(f"warning: a CV estimate from {n_sub} subjects (< {MIN_CV_SUBJECTS}) is "
             "unstable; quote it only with that number")
    if gcol is not None:
        report_groups(ds, schema, gcol, y, pred, base, own, unit)


def group_column(frame, declared: str | None) -> str | None:
    """The grouping column (``--group-by``, else detected by name); a declared one not
    in the file is a UserError."""
    from ..evaluation.cohorts import detect_group_column

    try:
        return detect_group_column(frame, declared)
    except ValueError as exc:
        raise UserError(f"--group-by: {exc}") from None


def report_groups(ds, schema, gcol: str, y, pred, base, own, unit: str) -> None:
    """Per group: CV RMSE against the group's own training mean (and the pooled one),
    the correlation on the channel that carries the pooled one, and one line when the
    pooled skill is mostly between-group offset."""
    from ..evaluation.cohorts import (
        carrier_channel,
        group_skill_table,
        offset_message,
        offset_share,
    )

    frame = ds.frame
    subjects = frame["subject_id"].to_numpy() if "subject_id" in frame else None
    table = group_skill_table(y, pred, base, own, frame[gcol].to_numpy(), subjects)
    chan = carrier_channel(frame, y, [f"adc_{w}" for w in schema.labels])
    adc = frame[chan].to_numpy(float)
    pooled = float(np.corrcoef(adc, y)[0, 1]) if np.std(adc) and np.std(y) else np.nan
    labels = frame[gcol].astype(str).to_numpy()
    flipped = []
    for _, row in table.iterrows():
        idx = np.flatnonzero(labels == row["group"])
        r = (float(np.corrcoef(adc[idx], y[idx])[0, 1])
             if len(idx) > 2 and np.std(adc[idx]) and np.std(y[idx]) else np.nan)
        flipped += [row["group"]] if np.isfinite(r) and np.sign(r) == -np.sign(pooled) else []
        _say(f"  {gcol} {row['group']}: {row['n_readings']} readings, CV RMSE "
             f"{in_unit(row['rmse_mgdl'], unit)}, no skill (this group's own training mean) "
             f"{in_unit(row['no_skill_own_mgdl'], unit)} (pooled mean "
             f"{in_unit(row['no_skill_pooled_mgdl'], unit)}), r({chan}, glucose) {r:+.2f} "
             f"(pooled {pooled:+.2f})", err=False)
    msg = offset_message(gcol, offset_share(y, pred, base, own), table)
    if msg:
        _say(f"warning: {msg}")
    if flipped:
        _say(f"warning: within {gcol} {', '.join(flipped)} the {chan}-glucose correlation "
             "has the opposite sign of the pooled one: the pooled skill may be a group "
             "offset, not glucose")


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


def _competitors(metrics) -> list[str]:
    """The benchmark's competing rows, best first: no reference row (oracle, no skill),
    no ablation row, nothing privileged."""
    from ..models.registry import privileged_knowledge

    def privileged(name: str) -> bool:
        try:
            return privileged_knowledge(name) is not None
        except (KeyError, ValueError, TypeError):
            return False

    m = metrics.sort_values("rmse_mgdl")
    return [str(n) for n in m["model"] if n not in ("oracle", "mean") and "/" not in str(n)
            and not privileged(str(n))]


def report_benchmark_cohorts(res, ds, gcol: str, unit: str) -> None:
    """After ``benchmark --data``: the best competitor's error in each group of ``gcol``
    against the group's own training mean, and one line when its pooled skill is mostly
    between-group offset."""
    from ..evaluation.cohorts import cohort_errors, offset_message

    names = _competitors(res.metrics)
    if not names or "fold" not in res.predictions.columns:
        return
    best = names[0]
    t = cohort_errors(res.predictions, ds.frame, gcol, [best])
    label = dict(zip(res.metrics["model"], res.metrics["label"], strict=True)).get(best, best)
    _say(f"by {gcol} ({label}, the lowest-RMSE competitor; no skill is each group's own "
         "training mean):", err=False)
    for _, r in t.iterrows():
        _say(f"  {gcol} {r['group']}: {r['n_subjects']} subjects, RMSE "
             f"{in_unit(r['rmse_mgdl'], unit)}, no skill {in_unit(r['no_skill_own_mgdl'], unit)}"
             f" (pooled mean {in_unit(r['no_skill_pooled_mgdl'], unit)})", err=False)
    msg = offset_message(gcol, float(t["offset_share"].iloc[0]) if len(t) else float("nan"), t)
    if msg:
        _say(f"warning: {label}: {msg}")
