"""Commands for a team's own device data: ``fit``, ``predict`` and ``export-c``."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from ..small_data import MIN_INTERVAL_SUBJECTS as _MIN_CALIBRATION_SUBJECTS
from ._app import app
from ._common import GlucoseUnitOption, UserError, _check_out_file, _check_seed, _say
from .fit_report import load_device_file, report_cv, say_notes, warn_overparameterised


@app.command("fit")
def fit_model(
    model: Annotated[str, typer.Option(help="Registered model name, e.g. ebl, pls, sdnn.")],
    data: Annotated[Path, typer.Option(help="Measurements (.parquet or .csv) with glucose_mgdl.")],
    out: Annotated[Path, typer.Option(help="Model file to write (.json).")],
    adc_bits: Annotated[
        int | None,
        typer.Option(help="The device's ADC resolution [bit] (default: the file's metadata; "
                     "needed when every code fits 10 bits; else 12 is assumed, with a warning)."),
    ] = None,
    glucose_unit: GlucoseUnitOption = None,
    cv_folds: Annotated[
        int, typer.Option(help="Folds of the subject-grouped CV printed beside no skill (0: none).")
    ] = 5,
    intervals: Annotated[
        str,
        typer.Option(
            help="Prediction intervals: split (hold out --calibration-share of the subjects "
            "to calibrate them; the model fits on the rest), none, or auto (split when "
            "the held-out subjects are enough for a 90 % interval, else none)."
        ),
    ] = "auto",
    calibration_share: Annotated[
        float, typer.Option(help="Share of subjects held out to calibrate the intervals.")
    ] = 0.2,
    seed: Annotated[
        int,
        typer.Option(
            help="Seed of the model's fit (its random_state: initialisation, shuffling, "
            "dropout, subsampling) and of the draw of calibration subjects."
        ),
    ] = 0,
) -> None:
    """Fit a model on your own measurements (any LEDs, any ADC) and save it.

    With intervals, a share of the subjects (never used for fitting) calibrates
    subject-grouped split-conformal 90 % and 80 % intervals, saved with the model.
    The same data, options and --seed write byte-identical model files.
    """
    from ..evaluation.benchmark import seeded_params
    from ..models.registry import get_model_class
    from ..models.tuning import untuned_params

    _check_seed(seed)
    _check_fit_args(out, intervals, calibration_share)
    cls = get_model_class(model)  # unknown names raise with the valid ones
    # nothing is tuned for a team's device: networks early-stop on held-out subjects
    estimator = cls(**seeded_params(cls, untuned_params(model), seed))
    ds, schema = _load_device_data(model, data, adc_bits, glucose_unit)
    intervals, note = _choose_intervals(ds, intervals, calibration_share)
    if intervals == "split":
        n_fit, note = _fit_with_intervals(estimator, ds, calibration_share, seed)
    else:
        estimator.fit(ds)
        n_fit = len(ds)
    estimator.save(out)
    say_notes(ds)
    device = estimator.schema_.describe() if hasattr(estimator, "schema_") else "simulated"
    _say(f"fitted {model!r} on {n_fit} measurements ({device}){note}; wrote {out}", err=False)
    warn_overparameterised(estimator, n_fit)
    if schema is not None and cv_folds:
        report_cv(estimator, ds, schema, cv_folds, glucose_unit)


def _check_fit_args(out: Path, intervals: str, calibration_share: float) -> None:
    if out.suffix != ".json":
        raise UserError(f"--out {str(out)!r}: the model file must end in .json")
    if intervals not in ("auto", "split", "none"):
        raise UserError(f"--intervals must be auto, split or none, got {intervals!r}")
    if not 0.0 < calibration_share < 1.0:
        raise UserError(f"--calibration-share must lie in (0, 1), got {calibration_share}")
    _check_out_file(out)


def _load_device_data(model: str, data: Path, adc_bits: int | None, unit: str | None):
    """``(measurements, schema)``: the file read and validated, its ADC resolution
    resolved by the one policy; a device file for any model but the oracle (schema
    None), checked against the small-data policy."""
    from ..small_data import fit_size_warning

    if model == "oracle":
        from ..dataset import load_dataset

        return load_dataset(data, glucose_unit=unit, adc_bits=adc_bits), None
    ds, schema = load_device_file(data, unit, adc_bits, need_glucose=True)
    n_sub = ds.frame["subject_id"].nunique() if "subject_id" in ds.frame else 0
    if "subject_id" not in ds.frame:
        _say("warning: no subject_id column: every row is taken as its own subject, so "
             "readings of one person may fall on both sides of a validation split")
    msg = fit_size_warning(n_sub or len(ds), len(ds))
    if msg:
        _say(f"warning: {msg}")
    return ds, schema


def _choose_intervals(ds, intervals: str, share: float) -> tuple[str, str]:
    """``auto`` resolved: ``split`` when enough subjects are held out, else ``none`` (noted)."""
    if intervals != "auto":
        return intervals, ""
    if "subject_id" not in ds.frame:
        return "none", "; no intervals (no subject_id column to hold out people)"
    n_sub = ds.frame["subject_id"].nunique()
    n_cal = round(share * n_sub)
    if _MIN_CALIBRATION_SUBJECTS <= n_cal < n_sub:
        return "split", ""
    return "none", (f"; no intervals ({n_sub} subjects: too few to hold out "
                    f"{_MIN_CALIBRATION_SUBJECTS} to calibrate)")


def _fit_with_intervals(estimator, ds, share: float, seed: int) -> tuple[int, str]:
    """Fit on the subjects not held out, calibrate on the rest: ``(n fitted, note)``."""
    from ..evaluation.conformal import calibration_of, split_conformal

    if "subject_id" not in ds.frame:
        raise UserError("--intervals split needs a subject_id column to hold out subjects")
    cal = calibration_of(split_conformal(estimator, ds, share=share, seed=seed))
    n_fit = len(ds) - cal["n_calibration_readings"]  # the rest of the rows were fitted
    note = (
        f"; 90 % interval ±{cal['half_width_mgdl']['90']:.1f} mg/dL from "
        f"{cal['n_calibration_subjects']} held-out subjects"
    )
    return n_fit, note


@app.command("predict")
def predict_glucose(
    model: Annotated[Path, typer.Option(help="Model file written by `nirglucose fit`.")],
    data: Annotated[Path, typer.Option(help="Measurements (.parquet or .csv).")],
    out: Annotated[Path, typer.Option(help="Predictions to write (.csv).")],
    calibration: Annotated[
        Path | None,
        typer.Option(
            help="A person's calibration readings (.csv/.parquet: subject_id, the device's "
            "columns and the fingerstick glucose_mgdl): each subject's mean error on them "
            "is added to their new predictions."
        ),
    ] = None,
    glucose_unit: GlucoseUnitOption = None,
) -> None:
    """Predict glucose for your own measurements; writes predicted_glucose_mgdl and flag.

    ``glucose_lower_mgdl`` / ``glucose_upper_mgdl`` bound the 90 % prediction interval
    when the model carries a calibration (empty otherwise). ``flag`` is ``LO`` / ``HI``
    where the estimate lies below 20 / above 600 mg/dL, as a meter shows it (the number
    itself is kept). With ``--calibration``, ``calibrated`` says which rows a person's
    calibration readings corrected. ``outside_training`` names the inputs outside the
    range the model was fitted on (``adc_940>``: above it). With ``--glucose-unit
    mmol/L`` the glucose columns are ``*_mmoll`` in mmol/L.
    """
    import numpy as np

    from ..dataset import atomic_write, load_dataset
    from ..io_files import check_glucose_unit
    from ..models import load_model
    from ..models._validate import check_predictions

    if out.suffix != ".csv":
        raise UserError(f"--out {str(out)!r}: predictions are written as .csv")
    check_glucose_unit(glucose_unit)
    _check_out_file(out)
    estimator = load_model(model)
    ds = load_dataset(data, glucose_unit=glucose_unit)
    _check_model_codes(estimator, ds, data)
    pred = np.asarray(check_predictions(estimator.predict(ds), model), dtype=float)
    calibrated = None
    if calibration is not None:
        pred, calibrated = _calibrate(estimator, ds, pred, calibration, glucose_unit)
    table, has_intervals = _prediction_table(estimator, ds, pred, calibrated)
    table = _in_unit_columns(table, glucose_unit)
    atomic_write(out, lambda tmp: table.to_csv(tmp, index=False))
    say_notes(ds)
    _say(_prediction_summary(table, calibrated, has_intervals, out), err=False)


def _check_model_codes(estimator, ds, data: Path) -> None:
    """Codes above the model's full scale refused with the file's rows."""
    from ..io_files import check_codes

    schema = getattr(estimator, "schema_", None)
    if schema is not None and not schema.is_plain:
        check_codes(ds.frame, schema.adc_bits, csv=Path(data).suffix == ".csv")


def _in_unit_columns(table, unit: str | None):
    """The glucose columns in mmol/L (renamed ``*_mmoll``) when asked for."""
    from ..io_files import glucose_to_unit

    if unit != "mmol/L":
        return table
    cols = [c for c in table.columns if c.endswith("_mgdl")]
    for c in cols:
        table[c] = glucose_to_unit(table[c].to_numpy(float), unit)
    return table.rename(columns={c: c[: -len("_mgdl")] + "_mmoll" for c in cols})


def _outside_training(estimator, ds) -> list[str]:
    """Per row, the inputs outside the model's training range (empty where none)."""
    schema = getattr(estimator, "schema_", None)
    if schema is None or schema.is_plain:
        return [""] * len(ds)
    return schema.outside_training(schema.raw(ds))


def _calibrate(estimator, ds, pred, calibration: Path, unit: str | None = None):
    """Each subject's mean error on their calibration readings added to their predictions:
    ``(predictions, which rows were corrected)``."""
    from ..dataset import load_dataset
    from ..evaluation.calibration import apply_offset
    from ..models._validate import check_predictions

    cal = load_dataset(calibration, glucose_unit=unit)
    for name, frame in (("--calibration", cal.frame), ("--data", ds.frame)):
        if "subject_id" not in frame.columns:
            raise UserError(f"{name} needs a subject_id column to match people")
    if "glucose_mgdl" not in cal.frame.columns:
        raise UserError("--calibration needs the reference glucose of each reading "
                        "(glucose_mgdl or glucose_mmoll)")
    _warn_overlap(estimator, cal, ds)
    cal_pred = check_predictions(estimator.predict(cal), calibration)
    return apply_offset(
        pred,
        ds.frame["subject_id"].to_numpy(),
        cal_pred,
        cal.frame["glucose_mgdl"].to_numpy(float),
        cal.frame["subject_id"].to_numpy(),
    )


def _warn_overlap(estimator, cal, ds) -> None:
    """Warn when calibration readings are among the readings predicted (their error is
    then no test of the calibration)."""
    cols = list(getattr(estimator.schema_, "raw_columns", ()))
    key = ["subject_id", "measurement_id"] if "measurement_id" in cal.frame and \
        "measurement_id" in ds.frame else ["subject_id", *cols]
    if not all(c in cal.frame and c in ds.frame for c in key):
        return
    both = ds.frame[key].merge(cal.frame[key].drop_duplicates(), on=key, how="inner")
    if len(both):
        _say(f"warning: {len(both)} of the {len(ds)} readings predicted are also calibration "
             f"readings (same {', '.join(key[:2])}{'...' if len(key) > 2 else ''}): their "
             "error says nothing about the calibration; predict on other readings")


def _prediction_table(estimator, ds, pred, calibrated):
    """The predictions file's rows and whether the model carried an interval calibration."""
    import pandas as pd

    from ..schema import meter_flags

    ids = [c for c in ("measurement_id", "subject_id") if c in ds.frame.columns]
    table = ds.frame[ids].reset_index(drop=True).copy()
    table["predicted_glucose_mgdl"] = pd.Series(pred, dtype=float).to_numpy()
    lower, upper, has_intervals = _interval_bounds(estimator, pred, calibrated)
    table["glucose_lower_mgdl"] = lower
    table["glucose_upper_mgdl"] = upper
    table["flag"] = meter_flags(pred)
    table["outside_training"] = _outside_training(estimator, ds)
    if calibrated is not None:
        table["calibrated"] = calibrated
    return table, has_intervals


def _interval_bounds(estimator, pred, calibrated):
    """The 90 % interval (NaN without a calibration; the offset-calibrated width on
    calibrated rows where the model has one), lower bound clipped at 0: ``(lo, up, has)``."""
    import numpy as np

    from ..evaluation.conformal import calibration_of, interval

    cal_doc = calibration_of(estimator)
    if cal_doc is None:
        return np.full(len(pred), np.nan), np.full(len(pred), np.nan), False
    lower, upper = interval(estimator, pred, 0.9)
    if calibrated is not None and (cal_doc.get("half_width_offset1_mgdl") or {}).get("90"):
        lo_c, up_c = interval(estimator, pred, 0.9, offset_calibrated=True)
        lower, upper = np.where(calibrated, lo_c, lower), np.where(calibrated, up_c, upper)
    return np.maximum(lower, 0.0), upper, True


def _prediction_summary(table, calibrated, has_intervals: bool, out: Path) -> str:
    n_flag = int((table["flag"] != "").sum())
    flagged = f" ({n_flag} outside 20-600 mg/dL, flagged LO/HI)" if n_flag else ""
    cal_note = (
        f"; {int(calibrated.sum())} calibrated by their person's readings"
        if calibrated is not None
        else ""
    )
    no_int = "" if has_intervals else "; the model carries no interval calibration"
    n_out = int((table["outside_training"] != "").sum())
    extra = (f"; {n_out} with inputs outside the training range (column outside_training)"
             if n_out else "")
    return (f"predicted {len(table)} measurements{flagged}{extra}{cal_note}{no_int}; "
            f"wrote {out}")


@app.command("export-c")
def export_c_source(
    model: Annotated[Path, typer.Option(help="Linear model file (ebl or pls) from `fit`.")],
    out: Annotated[Path, typer.Option(help="Output directory for the .h and .c files.")],
) -> None:
    """Write C99 source + header of a linear model for a microcontroller."""
    from ..export import export_c
    from ..models import load_model

    header, source = export_c(load_model(model), out)
    _say(f"wrote {header} and {source}", err=False)
