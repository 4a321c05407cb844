"""Prediction as a library call: estimates, their 90 % interval, personal calibration,
meter flags and the inputs outside the training range (what ``nirglucose predict`` writes).

:func:`predict` (``ng.predict``) is the entry point; the other functions are its steps,
each on an already loaded estimator and :class:`~nirglucose.dataset.Dataset`. It
imports the models, the dataset and :mod:`nirglucose.calibration` only (never the
evaluation); the package exposes its names lazily, so that ``import nirglucose`` does
not load the models.
"""

from __future__ import annotations

import os
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from .calibration.conformal import calibration_of, interval
from .calibration.personal import apply_offset
from .dataset import Dataset, load_dataset
from .dataset.adc import check_dc_level
from .dataset.columns import GLUCOSE_REPORTING_RANGE_MGDL, ID_COLUMNS
from .dataset.files import (
    check_codes,
    check_glucose_unit,
    file_rows,
    glucose_to_unit,
    validate_frame,
)
from .dataset.schema import meter_flags, rows_seen_in_training
from .exceptions import ConfigError, DataError
from .models._validate import check_predictions
from .models.registry import model_from

__all__ = [
    "INTERVAL_LEVEL",
    "TRAINING_ROWS_SHARE",
    "PredictionResult",
    "predict",
    "check_model_codes",
    "calibrate_by_person",
    "prediction_table",
    "in_unit_columns",
]

#: Nominal coverage of the interval in the table (``glucose_lower_mgdl`` /
#: ``glucose_upper_mgdl``): the level a calibrated model file always stores. [-]
INTERVAL_LEVEL = 0.9
#: Share of the readings predicted that must match training rows (values and ids) before
#: ``predict`` says it was given the rows the model was fitted on: one LED's integer
#: codes and small subject ids repeat across files by chance (a few per cent), a
#: re-used file or its training part matches far above that. [-]
TRAINING_ROWS_SHARE = 0.25


@dataclass(frozen=True)
class PredictionResult:
    """What :func:`nirglucose.predict` returns.

    Attributes
    ----------
    frame : pandas.DataFrame
        One row per reading: ``measurement_id`` / ``subject_id`` (where the data has
        them), ``predicted_glucose_mgdl``, ``glucose_lower_mgdl`` and
        ``glucose_upper_mgdl`` (the 90 % interval, NaN when the model carries no
        calibration, both bounds clipped to the meter's range 20-600 mg/dL, the range
        of the flags), ``flag`` (``LO`` / ``HI`` / empty), ``outside_training`` (the
        inputs outside the fitted range, empty where none) and, with calibration
        readings, ``calibrated`` (bool). In mmol/L the glucose columns end ``_mmoll``.
    has_intervals : bool
        Whether the model carried an interval calibration.
    read_notes : tuple of str
        How the data file was read differently from the schema's spelling.
    glucose_unit : str
        Unit of the glucose columns: ``"mg/dL"`` or ``"mmol/L"``.
    training_rows : tuple of int
        ``(matched, checked)``: of the rows the model file's fingerprints can check, how
        many are rows the model was fitted on (``(0, 0)``: none checked).
    """

    frame: pd.DataFrame
    has_intervals: bool
    read_notes: tuple[str, ...] = ()
    glucose_unit: str = "mg/dL"
    training_rows: tuple[int, int] = (0, 0)

    @property
    def training_note(self) -> str | None:
        """One line when rows the model was fitted on are among those predicted (at
        least :data:`TRAINING_ROWS_SHARE` of those checked)."""
        matched, checked = self.training_rows
        if not matched or matched < TRAINING_ROWS_SHARE * checked:
            return None
        n = len(self.frame)
        share = (f"all {n}" if matched == checked == n else
                 f"{matched} of the {n}" if checked == n else
                 f"{matched} of {checked} sampled")
        return (f"{share} readings predicted are rows the model was fitted on (same "
                "values and ids): their error says nothing about new readings; judge the "
                "model on readings it has not seen")

    @property
    def n_flagged(self) -> int:
        """Readings flagged ``LO`` or ``HI``."""
        return int((self.frame["flag"] != "").sum())

    @property
    def n_outside_training(self) -> int:
        """Readings with an input outside the model's training range."""
        return int((self.frame["outside_training"] != "").sum())

    @property
    def n_calibrated(self) -> int | None:
        """Readings corrected by their person's calibration (None: none were given)."""
        if "calibrated" not in self.frame.columns:
            return None
        return int(self.frame["calibrated"].sum())


def predict(
    model: Any,
    data: Dataset | pd.DataFrame | str | os.PathLike,
    calibration: Dataset | pd.DataFrame | str | os.PathLike | None = None,
    *,
    glucose_unit: str | None = None,
) -> PredictionResult:
    """Predict glucose with its 90 % interval, personal calibration and meter flags.

    The library form of ``nirglucose predict``: the same table, column for column.

    Parameters
    ----------
    model : fitted estimator, str or path-like
        A fitted model, or a model file written by ``model.save`` / ``nirglucose fit``.
    data : Dataset, pandas.DataFrame, str or path-like
        The readings to predict (a file is read by :func:`~nirglucose.load_dataset`).
    calibration : Dataset, pandas.DataFrame, str or path-like, optional
        A person's calibration readings (``subject_id``, the device's columns and the
        fingerstick ``glucose_mgdl`` or ``glucose_mmoll``): each person's mean error on
        them is added to their new predictions, and their intervals use the
        offset-calibrated width where the model stores one.
    glucose_unit : {"mg/dL", "mmol/L"}, optional
        Unit of the reference glucose in the files read (default: the column's own,
        ``glucose_mgdl`` or ``glucose_mmoll``) and of the glucose columns returned
        (default: the unit of the reference column the model was fitted on; with
        ``"mmol/L"`` they are named ``*_mmoll``).

    Returns
    -------
    PredictionResult
        ``.frame``: ``predicted_glucose_mgdl``, ``glucose_lower_mgdl`` /
        ``glucose_upper_mgdl`` (the 90 % interval, NaN when the model carries no
        interval calibration, both bounds clipped to the meter's 20-600 mg/dL, the
        range of the flags), ``flag`` (``LO`` below 20,
        ``HI`` above 600 mg/dL; the number is kept), ``outside_training`` (the inputs
        outside the fitted range, e.g. ``adc_940>``) and, with ``calibration``,
        ``calibrated``; the identity columns of the data first.

    Raises
    ------
    DataError
        An unreadable model or data file, codes above the model's ADC full scale,
        predictions no sound model makes, or calibration readings without
        ``subject_id`` / reference glucose.

    Warns
    -----
    UserWarning
        When calibration readings are among the readings predicted.

    Examples
    --------
    >>> import nirglucose as ng
    >>> train = ng.simulate("paper", n_subjects=12, per_subject=2, seed=0)
    >>> model = ng.models.make_model("ebl").fit(train)
    >>> new = ng.simulate("paper", n_subjects=2, per_subject=2, seed=1)
    >>> result = ng.predict(model, new)
    >>> list(result.frame.columns)  # doctest: +NORMALIZE_WHITESPACE
    ['measurement_id', 'subject_id', 'predicted_glucose_mgdl', 'glucose_lower_mgdl',
     'glucose_upper_mgdl', 'flag', 'outside_training']
    >>> result.has_intervals  # fitted without a conformal calibration
    False
    """
    unit = check_glucose_unit(glucose_unit)
    estimator, source = _estimator(model)
    ds, csv = _readings(data, unit)
    check_model_codes(estimator, ds, csv=csv)
    pred = check_predictions(estimator.predict(ds), source)
    calibrated = None
    if calibration is not None:
        cal, cal_csv = _readings(calibration, unit)
        name = str(calibration) if isinstance(calibration, str | os.PathLike) else "calibration"
        pred, calibrated = calibrate_by_person(estimator, ds, pred, cal, name, csv=cal_csv)
    table, has_intervals = prediction_table(estimator, ds, pred, calibrated)
    schema = getattr(estimator, "schema_", None)
    unit = unit or getattr(schema, "glucose_unit", None) or "mg/dL"
    return PredictionResult(
        frame=in_unit_columns(table, unit),
        has_intervals=has_intervals,
        read_notes=tuple(ds.metadata.get("read_notes", ())),
        glucose_unit=unit,
        training_rows=_seen_rows(schema, ds),
    )


def _seen_rows(schema: Any, ds: Dataset) -> tuple[int, int]:
    """``(matched, checked)`` training rows among the readings (:class:`PredictionResult`)."""
    if schema is None or schema.is_plain or not schema.train_rows:
        return 0, 0
    return rows_seen_in_training(schema, schema.raw(ds), ds.frame)


def _estimator(model: Any) -> tuple[Any, str]:
    """``(estimator, its name in messages)``: a model file loaded, an estimator as is."""
    if isinstance(model, str | os.PathLike):
        return model_from(model), str(model)
    if not callable(getattr(model, "predict", None)):
        raise ConfigError(f"model must be a fitted estimator or the path of a model file, "
                          f"got a {type(model).__name__}")
    return model, type(model).__name__


def _readings(data: Any, unit: str | None) -> tuple[Dataset, bool]:
    """``(dataset, read from a CSV file)``: a file loaded, a frame validated (a copy)."""
    if isinstance(data, Dataset):
        return data, False
    if isinstance(data, pd.DataFrame):
        frame = data.copy()
        notes = validate_frame(frame, csv=False, glucose_unit=unit)
        return Dataset(frame, metadata={"read_notes": notes}), False
    if isinstance(data, str | os.PathLike):
        return load_dataset(data, glucose_unit=unit), Path(data).suffix == ".csv"
    raise ConfigError(f"data must be a Dataset, a DataFrame or a file path, "
                      f"got a {type(data).__name__}")


def check_model_codes(estimator: Any, ds: Dataset, *, csv: bool = False) -> None:
    """Refuse ADC codes above the full scale of the device the model was fitted on; warn
    of a channel whose every reading sits at mid-scale (an AC-coupled front end,
    :func:`~nirglucose.dataset.adc.check_dc_level`).

    Raises
    ------
    DataError
        One line naming the column and the rows (the file's line numbers when ``csv``).
    """
    schema = getattr(estimator, "schema_", None)
    if schema is not None and not schema.is_plain:
        check_codes(ds.frame, schema.adc_bits, csv=csv, full_scales=schema.code_full_scales())
        check_dc_level(ds.frame, tuple(f"adc_{w}" for w in schema.labels), schema.full_scales)


def _outside_training(estimator: Any, ds: Dataset) -> list[str]:
    """Per row, the inputs outside the model's training range (empty where none)."""
    schema = getattr(estimator, "schema_", None)
    if schema is None or schema.is_plain:
        return [""] * len(ds)
    return schema.outside_training(schema.raw(ds))


def calibrate_by_person(
    estimator: Any,
    ds: Dataset,
    predicted_mgdl: np.ndarray,
    calibration: Dataset,
    source: str | Path = "calibration",
    *,
    csv: bool = False,
) -> tuple[np.ndarray, np.ndarray]:
    """Each person's mean error on their calibration readings added to their predictions.

    Parameters
    ----------
    estimator : fitted estimator
        The model that predicted ``predicted_mgdl``.
    ds : Dataset
        The readings predicted; needs ``subject_id``.
    predicted_mgdl : numpy.ndarray
        The model's predictions for ``ds``. [mg/dL]
    calibration : Dataset
        A person's readings with the fingerstick ``glucose_mgdl`` and ``subject_id``.
    source : str or path
        Name of the calibration readings in error messages.
    csv : bool
        Whether they were read from a CSV file (messages then give its line numbers).

    Returns
    -------
    tuple of numpy.ndarray
        The corrected predictions [mg/dL] and a boolean mask of the rows whose person
        had calibration readings (the others unchanged).

    Warns
    -----
    UserWarning
        When calibration readings are among the readings predicted.
    """
    for name, frame in (("calibration", calibration.frame), ("data", ds.frame)):
        if "subject_id" not in frame.columns:
            raise DataError(f"the {name} readings need a subject_id column to match people")
    if "glucose_mgdl" not in calibration.frame.columns:
        raise DataError("the calibration readings need the reference glucose of each "
                        "reading (glucose_mgdl or glucose_mmoll)")
    numeric = {pd.api.types.is_numeric_dtype(f["subject_id"])
               for f in (calibration.frame, ds.frame)}
    if len(numeric) > 1:
        raise DataError("the calibration readings and the data spell subject_id differently "
                        "(numbers in one, text in the other); use the same ids in both")
    reference_mgdl = pd.to_numeric(calibration.frame["glucose_mgdl"], errors="coerce"
                                   ).to_numpy(float)
    if not np.isfinite(reference_mgdl).all():
        raise DataError(f"the calibration readings have no reference glucose at "
                        f"{file_rows(~np.isfinite(reference_mgdl), csv=csv)}: every "
                        "calibration reading needs its fingerstick value")
    _warn_overlap(estimator, calibration, ds)
    cal_pred = check_predictions(estimator.predict(calibration), source)
    return apply_offset(
        predicted_mgdl,
        ds.frame["subject_id"].to_numpy(),
        cal_pred,
        reference_mgdl,
        calibration.frame["subject_id"].to_numpy(),
    )


def _warn_overlap(estimator: Any, cal: Dataset, ds: Dataset) -> None:
    """Warn when calibration readings are among the readings predicted (their error is
    then no test of the calibration)."""
    cols = list(getattr(getattr(estimator, "schema_", None), "raw_columns", ()))
    key = ["subject_id", "measurement_id"] if "measurement_id" in cal.frame and \
        "measurement_id" in ds.frame else ["subject_id", *cols]
    if not all(c in cal.frame and c in ds.frame for c in key):
        return
    both = ds.frame[key].merge(cal.frame[key].drop_duplicates(), on=key, how="inner")
    if len(both):
        warnings.warn(
            f"{len(both)} of the {len(ds)} readings predicted are also calibration "
            f"readings (same {', '.join(key[:2])}{'...' if len(key) > 2 else ''}): their "
            "error says nothing about the calibration; predict on other readings",
            UserWarning,
            stacklevel=3,
        )


def prediction_table(
    estimator: Any,
    ds: Dataset,
    predicted_mgdl: np.ndarray,
    calibrated: np.ndarray | None = None,
) -> tuple[pd.DataFrame, bool]:
    """The rows of the predictions file and whether the model carried an interval
    calibration (columns: see :class:`PredictionResult`; glucose in mg/dL)."""
    ids = [c for c in ID_COLUMNS if c in ds.frame.columns]
    table = ds.frame[ids].reset_index(drop=True).copy()
    table["predicted_glucose_mgdl"] = pd.Series(predicted_mgdl, dtype=float).to_numpy()
    lower, upper, has_intervals = _interval_bounds(estimator, predicted_mgdl, calibrated)
    table["glucose_lower_mgdl"] = lower
    table["glucose_upper_mgdl"] = upper
    table["flag"] = meter_flags(predicted_mgdl)
    table["outside_training"] = _outside_training(estimator, ds)
    if calibrated is not None:
        table["calibrated"] = calibrated
    return table, has_intervals


def _interval_bounds(estimator: Any, pred: np.ndarray, calibrated: np.ndarray | None):
    """The 90 % interval (NaN without a calibration; the offset-calibrated width on
    calibrated rows where the model has one), both bounds clipped to the meter's range
    (:data:`~nirglucose.dataset.GLUCOSE_REPORTING_RANGE_MGDL`, the range of the flags):
    ``(lo, up, has)``."""
    cal_doc = calibration_of(estimator)
    if cal_doc is None:
        return np.full(len(pred), np.nan), np.full(len(pred), np.nan), False
    lower, upper = interval(estimator, pred, INTERVAL_LEVEL)
    if calibrated is not None and (cal_doc.get("half_width_offset1_mgdl") or {}).get("90"):
        lo_c, up_c = interval(estimator, pred, INTERVAL_LEVEL, offset_calibrated=True)
        lower, upper = np.where(calibrated, lo_c, lower), np.where(calibrated, up_c, upper)
    lo, hi = GLUCOSE_REPORTING_RANGE_MGDL  # the range the flags use
    return np.clip(lower, lo, hi), np.clip(upper, lo, hi), True


def in_unit_columns(table: pd.DataFrame, unit: str | None) -> pd.DataFrame:
    """The glucose columns in mmol/L (renamed ``*_mmoll``) when ``unit`` is mmol/L."""
    if unit != "mmol/L":
        return table
    cols = [c for c in table.columns if c.endswith("_mgdl")]
    for c in cols:
        table[c] = glucose_to_unit(table[c].to_numpy(float), unit)
    return table.rename(columns={c: c[: -len("_mgdl")] + "_mmoll" for c in cols})
