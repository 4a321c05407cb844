"""Loading a benchmark results directory: :class:`Results` and :func:`load_results`.

Required inputs: ``metrics.csv`` (or ``metrics.json``) and ``predictions.parquet``.
Everything else (``meta.json``, ``table.md``, ``comparisons.csv``, ``histories.json``,
``drop_one.csv``, ``dataset.parquet``) is optional; what is missing is listed in
:attr:`Results.notes` and the figures that need it say so instead of drawing nothing.
"""

from __future__ import annotations

import json
import logging
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Final

import pandas as pd

from ...config import ScenarioConfig
from ...dataset import load_dataset
from ...dataset.files import check_result_table
from ...exceptions import DataError
from .inputs import model_order

__all__ = ["REQUIRED_METRIC_COLUMNS", "REQUIRED_PREDICTION_COLUMNS", "Results",
           "RenderedFigure", "load_results"]

logger = logging.getLogger(__package__)  # the package's name, as before the split

#: Columns ``metrics.csv`` must have.
REQUIRED_METRIC_COLUMNS: Final = ("model", "rmse_mgdl")
#: Columns ``predictions.parquet`` must have.
REQUIRED_PREDICTION_COLUMNS: Final = ("model", "reference_mgdl", "predicted_mgdl")

_OPTIONAL_FILES: Final = {
    "meta.json": "run metadata (taken from metrics.json where present)",
    "table.md": "the benchmark's table and significance statements",
    "comparisons.csv": "paired model comparisons",
    "histories.json": "training histories (figure 7)",
    "drop_one.csv": "drop-one-LED refits (wavelength utilisation)",
    "dataset.parquet": "the simulated dataset (figure 1)",
}


@dataclass
class Results:
    """What a benchmark results directory holds, loaded.

    Attributes
    ----------
    directory : pathlib.Path
        The results directory.
    metrics : pandas.DataFrame
        One row per model (``metrics.csv``).
    predictions : pandas.DataFrame
        Out-of-fold predictions (``predictions.parquet``).
    meta : dict
        Run metadata (``meta.json``, else the ``meta`` of ``metrics.json``).
    table_md : str or None
        ``table.md`` text.
    comparisons : pandas.DataFrame or None
        ``comparisons.csv``.
    histories : dict of str to pandas.DataFrame, or None
        Per-epoch histories of the networks (models with an empty history left out);
        None when ``histories.json`` is absent.
    drop_one : pandas.DataFrame or None
        ``drop_one.csv`` (the drop-one-LED refits); None when absent or empty.
    dataset : nirglucose.Dataset or None
        ``dataset.parquet``.
    notes : list of str
        What is missing or was adapted, in words, for the page.
    """

    directory: Path
    metrics: pd.DataFrame
    predictions: pd.DataFrame
    meta: dict[str, Any] = field(default_factory=dict)
    table_md: str | None = None
    comparisons: pd.DataFrame | None = None
    histories: dict[str, pd.DataFrame] | None = None
    drop_one: pd.DataFrame | None = None
    dataset: Any = None
    notes: list[str] = field(default_factory=list)

    @property
    def models(self) -> list[str]:
        """Models in display order (:func:`model_order`)."""
        return model_order(self.metrics["model"])

    @property
    def user_data(self) -> bool:
        """Whether the run is on a user's measurements: no configuration and no preset recorded."""
        return self.config is None and not self.meta.get("preset")

    @property
    def config(self):
        """The resolved scenario configuration (dataset's, else the metadata's), or None."""
        if self.dataset is not None and getattr(self.dataset, "config", None) is not None:
            return self.dataset.config
        cfg = self.meta.get("config")
        if isinstance(cfg, str):
            try:
                cfg = json.loads(cfg)
            except json.JSONDecodeError:
                return None
        if isinstance(cfg, dict):
            try:
                return ScenarioConfig.model_validate(cfg)
            except ValueError:
                logger.warning("meta config does not validate as a ScenarioConfig")
        return None


@dataclass
class RenderedFigure:
    """One figure of the report.

    Attributes
    ----------
    key : str
        Stable identifier (HTML anchor, file stem).
    number : str
        Figure number as printed (``"1a"``, ``"12"``).
    title : str
        Short title.
    caption : str
        One sentence stating what the figure shows.
    png : bytes
        The figure as PNG (embedded in the page).
    files : list of pathlib.Path
        PNG/SVG files written, if a figure directory was given.
    note : str or None
        Why the figure is reduced or missing, when it is.
    """

    key: str
    number: str
    title: str
    caption: str
    png: bytes = b""
    files: list[Path] = field(default_factory=list)
    note: str | None = None


# --------------------------------------------------------------------------- loading


def _read_json(path: Path) -> Any:
    try:
        return json.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise DataError(f"{path.name} in {str(path.parent)!r} is not valid JSON: {exc}") from exc


def _read_csv(path: Path) -> pd.DataFrame:
    try:
        if path.stat().st_size == 0 or not path.read_text(encoding="utf-8").strip():
            return pd.DataFrame()  # e.g. no comparisons in a one-model run
        return pd.read_csv(path)
    except (OSError, ValueError, pd.errors.ParserError) as exc:
        raise DataError(
            f"{path.name} in {str(path.parent)!r} is not a readable CSV: {exc}") from exc


def load_results(results_dir: str | Path) -> Results:
    """Load a benchmark results directory.

    Parameters
    ----------
    results_dir : str or path
        Directory written by ``nirglucose benchmark --out``.

    Returns
    -------
    Results

    Raises
    ------
    DataError
        If the directory is missing, or lacks ``metrics.csv``/``metrics.json`` or
        ``predictions.parquet``, or one of them is unreadable or lacks required columns.
    """
    d = Path(results_dir)
    if not d.is_dir():
        raise DataError(f"results directory {str(d)!r} does not exist; run `nirglucose "
                        f"benchmark --out {d}` first")
    notes: list[str] = []
    metrics, meta = _load_metrics(d)
    predictions = _load_predictions(d)
    meta = _load_meta(d, meta, notes)
    res = Results(directory=d, metrics=metrics, predictions=predictions, meta=meta, notes=notes)
    _load_tables(res, d)
    _load_histories(res, d)
    _load_drop_one_and_dataset(res, d)
    missing_pred = sorted(set(metrics["model"]) - set(predictions["model"]))
    if missing_pred:
        notes.append(f"No predictions for {', '.join(missing_pred)}: they are left out of the "
                     f"per-prediction figures (3-6).")
    return res


def _load_metrics(d: Path) -> tuple[pd.DataFrame, dict[str, Any]]:
    """``metrics.csv`` (else the rows of ``metrics.json``), and the ``meta`` of the JSON."""
    meta: dict[str, Any] = {}
    metrics: pd.DataFrame | None = None
    if (d / "metrics.json").is_file():
        data = _read_json(d / "metrics.json")
        if isinstance(data, dict):
            meta = dict(data.get("meta") or {})
            if isinstance(data.get("metrics"), list):
                metrics = pd.DataFrame(data["metrics"])
        elif isinstance(data, list):
            metrics = pd.DataFrame(data)
    if (d / "metrics.csv").is_file():
        metrics = _read_csv(d / "metrics.csv")
    if metrics is None:
        raise DataError(f"results directory {str(d)!r} is incomplete: no metrics.csv or "
                        f"metrics.json (rerun `nirglucose benchmark --out {d}`)")
    check_result_table(metrics, f"metrics.csv in {str(d)!r}", REQUIRED_METRIC_COLUMNS)
    if metrics.empty:
        raise DataError(f"metrics.csv in {str(d)!r} has no rows")
    return metrics.assign(model=metrics["model"].astype(str)), meta


def _load_predictions(d: Path) -> pd.DataFrame:
    """``predictions.parquet``, with its required columns checked."""
    pred_path = d / "predictions.parquet"
    if not pred_path.is_file():
        raise DataError(f"results directory {str(d)!r} is incomplete: no predictions.parquet "
                        f"(rerun `nirglucose benchmark --out {d}`)")
    try:
        predictions = pd.read_parquet(pred_path)
    except (OSError, ValueError) as exc:
        raise DataError(f"predictions.parquet in {str(d)!r} is unreadable: {exc}") from exc
    check_result_table(predictions, f"predictions.parquet in {str(d)!r}",
                       REQUIRED_PREDICTION_COLUMNS)
    return predictions.assign(model=predictions["model"].astype(str))


def _load_meta(d: Path, meta: dict[str, Any], notes: list[str]) -> dict[str, Any]:
    """``meta`` updated from ``meta.json``; a note when there is no metadata at all."""
    if (d / "meta.json").is_file():
        doc = _read_json(d / "meta.json") or {}
        if not isinstance(doc, dict):  # issue 20: one line, not a TypeError
            raise DataError(f"meta.json in {str(d)!r} must hold an object, not a list or value")
        return {**meta, **doc}
    if not meta:
        notes.append("No run metadata (meta.json, or meta in metrics.json): configuration, "
                     "seed, dataset hash and version are unknown.")
    return meta


def _load_tables(res: Results, d: Path) -> None:
    """``table.md`` and ``comparisons.csv`` into ``res`` (a note for each one missing)."""
    if (d / "table.md").is_file():
        res.table_md = (d / "table.md").read_text(encoding="utf-8")
    else:
        res.notes.append("No table.md: the significance statements are derived from "
                         "comparisons.csv.")
    if (d / "comparisons.csv").is_file():
        res.comparisons = _read_csv(d / "comparisons.csv")
    else:
        res.notes.append("No comparisons.csv: no paired model comparisons to report.")


def _load_histories(res: Results, d: Path) -> None:
    """``histories.json`` into ``res`` (models with an empty history left out)."""
    if not (d / "histories.json").is_file():
        res.notes.append("No histories.json: the training-dynamics figure is left out.")
        return
    raw = _read_json(d / "histories.json")
    if raw is not None and not isinstance(raw, dict):  # issue 20
        raise DataError(f"histories.json in {str(d)!r} must map model names to lists")
    res.histories = {
        str(m): pd.DataFrame(h) for m, h in (raw or {}).items()
        if isinstance(h, list) and h
    }


def _load_drop_one_and_dataset(res: Results, d: Path) -> None:
    """``drop_one.csv`` and ``dataset.parquet`` into ``res`` (a note for each missing)."""
    if (d / "drop_one.csv").is_file():
        table = _read_csv(d / "drop_one.csv")
        check_result_table(table, "drop_one.csv", ("model", "dropped_wavelength_nm",
                                                   "delta_rmse_mgdl", "ci_low", "ci_high"))
        res.drop_one = table if len(table) else None
    else:
        res.notes.append("No drop_one.csv: the wavelength-utilisation figure is left out.")
    if (d / "dataset.parquet").is_file():
        res.dataset = load_dataset(d / "dataset.parquet")
    else:
        res.notes.append("No dataset.parquet: the data-characteristics figures are left out.")
