"""Commands for a team's own device data: ``fit``, ``predict`` and ``export-c``."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from ..dataset.small_data import MIN_INTERVAL_SUBJECTS as _MIN_CALIBRATION_SUBJECTS
from ._app import app
from ._common import (
    ChannelBitsOption,
    FullScaleOption,
    GlucoseUnitOption,
    GroupByOption,
    UserError,
    _check_out_file,
    _check_seed,
    _say,
    _warnings_as_lines,
    holds_warnings,
)
from .fit_report import (
    adc_spec,
    display_unit,
    group_column,
    in_unit,
    load_device_file,
    report_cv,
    say_notes,
    warn_overparameterised,
)


@app.command("fit")
@holds_warnings
def fit_model(
    model: Annotated[str, typer.Option(help="Registered model name, e.g. ebl, pls, sdnn.")],
    data: Annotated[Path, typer.Option(help="Measurements (.parquet or .csv) with glucose_mgdl.")],
    out: Annotated[Path, typer.Option(help="Model file to write (.json).")],
    adc_bits: ChannelBitsOption = None,
    adc_full_scale: FullScaleOption = None,
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
    group_by: GroupByOption = None,
) -> None:
    """Fit a model on your own measurements (any LEDs, any ADC) and save it.

    With intervals, a share of the subjects (never used for fitting) calibrates
    subject-grouped split-conformal 90 % and 80 % intervals, saved with the model.
    The same data, options and --seed write byte-identical model files.
    """
    from ..evaluation.estimators import seeded_params
    from ..models.registry import get_model_class
    from ..models.tuning import untuned_params

    _check_seed(seed)
    _check_fit_args(out, intervals, calibration_share, cv_folds)
    cls = get_model_class(model)  # unknown names raise with the valid ones
    # nothing is tuned for a team's device: networks early-stop on held-out subjects
    estimator = cls(**seeded_params(cls, untuned_params(model), seed))
    ds, schema = _load_device_data(model, data, (adc_bits, adc_full_scale), glucose_unit)
    group_column(ds.frame, group_by)  # a --group-by not in the file: refused before the fit
    unit = display_unit(ds, glucose_unit)
    intervals, note = _choose_intervals(ds, intervals, calibration_share)
    if intervals == "split":
        n_fit, note = _fit_with_intervals(estimator, ds, calibration_share, seed, unit)
    else:
        estimator.fit(ds)
        n_fit = len(ds)
    estimator.save(out)
    say_notes(ds)
    device = estimator.schema_.describe() if hasattr(estimator, "schema_") else "simulated"
    _say(f"fitted {model!r} on {n_fit} measurements ({device}){note}; wrote {out}", err=False)
    warn_overparameterised(estimator, n_fit)
    if schema is not None and cv_folds:
        report_cv(estimator, ds, schema, cv_folds, glucose_unit, group_by)


def _check_fit_args(out: Path, intervals: str, calibration_share: float, cv_folds: int
                    ) -> None:
    if cv_folds == 1 or cv_folds < 0:
        raise UserError(f"--cv-folds {cv_folds}: give 0 (no cross-validation) or 2 or more")
    if out.suffix != ".json":
        raise UserError(f"--out {str(out)!r}: the model file must end in .json")
    if intervals not in ("auto", "split", "none"):
        raise UserError(f"--intervals must be auto, split or none, got {intervals!r}")
    if not 0.0 < calibration_share < 1.0:
        raise UserError(f"--calibration-share must lie in (0, 1), got {calibration_share}")
    _check_out_file(out)


def _load_device_data(model: str, data: Path, adc: tuple[str | None, str | None],
                      unit: str | None):
    """``(measurements, schema)``: the file read and validated, its ADC resolution
    resolved by the one policy; a device file for any model but the oracle (schema
    None), checked against the small-data policy."""
    from ..dataset.small_data import fit_size_warning

    if model == "oracle":
        from ..dataset import load_dataset

        ds = load_dataset(data, glucose_unit=unit, adc_bits=adc_spec(adc[0]))
        if ds.config is None:
            raise UserError(f"{str(data)!r} carries no scenario: the oracle reads the "
                            "simulator's true tissue state, which only a Parquet file "
                            "written by `nirglucose simulate` keeps; a device's own "
                            "file has none (fit another model)")
        return ds, None
    ds, schema = load_device_file(data, unit, adc[0], need_glucose=True, adc_full_scale=adc[1])
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


def _fit_with_intervals(estimator, ds, share: float, seed: int, unit: str = "mg/dL"
                        ) -> tuple[int, str]:
    """Fit on the subjects not held out, calibrate on the rest: ``(n fitted, note)``."""
    from ..calibration.conformal import calibration_of, split_conformal

    if "subject_id" not in ds.frame:
        raise UserError("--intervals split needs a subject_id column to hold out subjects")
    cal = calibration_of(split_conformal(estimator, ds, share=share, seed=seed))
    n_fit = len(ds) - cal["n_calibration_readings"]  # the rest of the rows were fitted
    note = (
        f"; 90 % interval ±{in_unit(cal['half_width_mgdl']['90'], unit)} from "
        f"{cal['n_calibration_subjects']} held-out subjects"
    )
    return n_fit, note


@app.command("predict")
@holds_warnings
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
    when the model carries a calibration (empty otherwise), clipped to the meter's range
    20-600 mg/dL (1.1-33.3 mmol/L), the range the flags use. ``flag`` is ``LO`` / ``HI``
    where the estimate lies below 20 / above 600 mg/dL, as a meter shows it (the number
    itself is kept). With ``--calibration``, ``calibrated`` says which rows a person's
    calibration readings corrected. ``outside_training`` names the inputs outside the
    range the model was fitted on (``adc_940>``: above it). The glucose columns are in
    the unit of the reference column the model was fitted on (``*_mmoll`` in mmol/L for
    a ``glucose_mmoll`` file) unless ``--glucose-unit`` says otherwise. Predicting the
    rows the model was fitted on is noted.
    """
    from ..dataset import atomic_write
    from ..dataset.files import check_glucose_unit
    from ..prediction import predict

    if out.suffix != ".csv":
        raise UserError(f"--out {str(out)!r}: predictions are written as .csv")
    check_glucose_unit(glucose_unit)
    _check_out_file(out)
    for option, given in (("--data", data), ("--calibration", calibration)):
        if given is not None and out.resolve() == given.resolve():
            raise UserError(f"--out {str(out)!r} is the {option} file: writing the predictions "
                            "there would replace your measurements; choose another --out")
    with _warnings_as_lines():
        result = predict(model, data, calibration, glucose_unit=glucose_unit)
    table = result.frame
    atomic_write(out, lambda tmp: table.to_csv(tmp, index=False))
    for note in result.read_notes:
        _say(f"note: {note}")
    if result.training_note:
        _say(f"note: {result.training_note}")
    _say(_prediction_summary(result, out), err=False)


def _prediction_summary(result, out: Path) -> str:
    n_flag = result.n_flagged
    meter = ("1.1-33.3 mmol/L" if result.glucose_unit == "mmol/L" else "20-600 mg/dL")
    flagged = f" ({n_flag} outside {meter}, flagged LO/HI)" if n_flag else ""
    n_cal = result.n_calibrated
    cal_note = f"; {n_cal} calibrated by their person's readings" if n_cal is not None else ""
    no_int = ("; 90 % intervals clipped to the meter's range, as the flags"
              if result.has_intervals else "; the model carries no interval calibration")
    n_out = result.n_outside_training
    extra = (f"; {n_out} with inputs outside the training range (column outside_training)"
             if n_out else "")
    return (f"predicted {len(result.frame)} measurements{flagged}{extra}{cal_note}{no_int}; "
            f"wrote {out}")


@app.command("export-c")
def export_c_source(
    model: Annotated[Path, typer.Option(help="Linear model file (ebl or pls) from `fit`.")],
    out: Annotated[Path, typer.Option(help="Output directory for the .h and .c files.")],
) -> None:
    """Write C99 source + header of a linear model for a microcontroller."""
    from ..export import export_c

    header, source = export_c(model, out)  # a model file's path: loaded there
    _say(f"wrote {header} and {source}", err=False)
