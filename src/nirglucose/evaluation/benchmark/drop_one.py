"""Drop-one-LED refits: what a model loses when one LED is left out of the device.

Each chosen model is refitted on the same folds with the same seeds on a copy of the
data without one LED's columns (its code ``adc_<nm>`` and, where the device records
one, its reference ``adc_ref_<nm>``; the scenario's LED record is removed with them, so
the copy is a valid device with one LED fewer, :func:`without_led`) and scored on the
same held-out subjects. The answer is the paired difference in RMSE, *without the LED
minus with all LEDs*, with a percentile cluster-bootstrap 95 % CI over subjects and a
bootstrap p-value, Holm-adjusted over the model's LEDs
(:func:`~nirglucose.metrics.resampling.compare_models`, the benchmark's own paired
statistics): positive means the LED carries information the others do not.

Why refits and not permutation importance
    The four channels of a skin reading correlate at 0.95-0.999 (they share the
    subject's optics), so shuffling one channel across rows builds inputs no device can
    produce, and a model's response to them measures its extrapolation, not the LED's
    information [1]_. A refit asks the question a designer asks: "what do I lose if I
    leave this LED out?" (leave-one-covariate-out, [2]_).

The benchmark plans the refits as tasks of its engine
(:func:`~nirglucose.evaluation.benchmark.run_benchmark`, option ``drop_one_models``);
this module holds what they share: the choice of models, the reduced dataset and the
table.

References
----------
.. [1] Hooker G, Mentch L, Zhou S. Unrestricted permutation forces extrapolation:
   variable importance requires at least one more model, or there is no free variable
   importance. Stat Comput 31:82, 2021. doi:10.1007/s11222-021-10057-z
.. [2] Lei J, G'Sell M, Rinaldo A, Tibshirani RJ, Wasserman L. Distribution-free
   predictive inference for regression. J Am Stat Assoc 113(523):1094-1111, 2018.
   doi:10.1080/01621459.2017.1307116
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from typing import Any, Final

import numpy as np
import pandas as pd

from ...dataset import Dataset
from ...dataset.columns import led_wavelengths_in
from ...dataset.small_data import MIN_SIGNIFICANCE_SUBJECTS
from ...exceptions import ConfigError, DataError
from ...metrics.resampling import compare_models
from ...models.labels import ablation_base, label
from .aggregate import scored
from .finding import Finding, Value
from .result import DROP_ONE_COLUMNS

__all__ = [
    "DEFAULT_DROP_ONE_MODELS",
    "DROP_ONE_COLUMNS",
    "DROP_ONE_REPEATS",
    "drop_one_findings",
    "drop_one_row",
    "drop_one_table",
    "led_verdicts",
    "led_wavelengths",
    "refit_predictions",
    "resolve_drop_one_models",
    "without_led",
]

#: Models refitted without each LED by default (those among the benchmarked ones): the
#: linear chemometric pair and the oracle (the LED's information with every nuisance
#: known). Measured on ``paper`` (80 × 3, ``make run``'s models, seed 0, 2 loaded
#: cores): their 60 refits (5 folds × 4 LEDs × 3 models) took 0.9 CPU-s against 156
#: CPU-s for the 240 other tasks. The Gaussian process (about 3 s a fit there: some
#: 60 s more per preset) and the networks (seconds to tens of seconds a fit) would take
#: ``make run`` past its 3-minute budget; ask for them by name or with ``"all"``.
DEFAULT_DROP_ONE_MODELS: Final = ("ebl", "pls", "oracle")

#: Repeats of the protocol refitted without each LED: the first one only (every subject
#: is held out once in it; the other repeats would triple the cost). [-]
DROP_ONE_REPEATS: Final = 1


#: The words of ``drop_one_models`` that are not model names.
_NONE, _ALL = "none", "all"


def drop_one_row(model: str, wavelength_nm: float) -> str:
    """The prediction row name of ``model`` refitted without the LED at ``wavelength_nm``.

    >>> drop_one_row("ebl", 1050.0)
    'ebl/without-1050nm'
    """
    return f"{model}/without-{float(wavelength_nm):g}nm"


def led_wavelengths(dataset: Dataset) -> list[float]:
    """The dataset's LEDs (those with an ``adc_<nm>`` column, as the models read them),
    ascending. [nm]"""
    return list(led_wavelengths_in(dataset.frame.columns))


def resolve_drop_one_models(
    drop_one_models: Sequence[str] | str | None, names: Sequence[str]
) -> list[str]:
    """The benchmarked rows refitted without each LED, in benchmark order.

    Parameters
    ----------
    drop_one_models : sequence of str, comma-separated str, or None
        None: :data:`DEFAULT_DROP_ONE_MODELS` among ``names``; ``"none"`` (or an empty
        sequence): no refits; ``"all"``: every row of ``names``; otherwise model names,
        each of which must be benchmarked.
    names : sequence of str
        The benchmark's rows (ablation rows are never refitted without an LED).

    Raises
    ------
    ConfigError
        A name that is not benchmarked (the message lists those that are).

    Examples
    --------
    >>> resolve_drop_one_models(None, ["pls", "mean", "ebl"])
    ['pls', 'ebl']
    >>> resolve_drop_one_models("none", ["pls", "ebl"])
    []
    """
    rows = [n for n in names if ablation_base(n) is None]
    if drop_one_models is None:
        return [n for n in rows if n in DEFAULT_DROP_ONE_MODELS]
    if isinstance(drop_one_models, str):
        drop_one_models = [m.strip() for m in drop_one_models.split(",") if m.strip()]
    asked = list(dict.fromkeys(drop_one_models))
    if asked in ([], [_NONE]):
        return []
    if asked == [_ALL]:
        return rows
    unknown = [m for m in asked if m not in rows]
    if unknown:
        raise ConfigError(
            f"drop-one models {unknown} are not benchmarked; choose among {rows}, "
            f"'{_ALL}' or '{_NONE}'"
        )
    return [n for n in rows if n in asked]


def without_led(dataset: Dataset, wavelength_nm: float) -> Dataset:
    """The dataset as a device without the LED at ``wavelength_nm``.

    Its ``adc_<nm>`` and ``adc_ref_<nm>`` columns are removed and, where the dataset
    carries its scenario, that LED's record is removed from ``config.leds`` (so models
    that read the scenario, the oracle and the physics inversion, see the same
    three-LED device as those that read the columns). Everything else is unchanged.

    Raises
    ------
    DataError
        No such LED, or it is the device's only one.

    Examples
    --------
    >>> import nirglucose as ng
    >>> ds = without_led(ng.simulate("paper", 4, 1, seed=0), 940)
    >>> ds.config.leds.wavelengths_nm, "adc_940" in ds.frame, "adc_ref_940" in ds.frame
    ((850.0, 1050.0, 1150.0), False, False)
    """
    wl = led_wavelengths(dataset)
    w = float(wavelength_nm)
    if w not in wl:
        raise DataError(
            f"no LED at {w:g} nm to leave out; the device's LEDs: "
            f"{', '.join(f'{x:g}' for x in wl)} nm"
        )
    if len(wl) == 1:
        raise DataError(f"the device has one LED ({w:g} nm): leaving it out leaves no device")
    frame = dataset.frame.drop(columns=[c for c in (f"adc_{w:g}", f"adc_ref_{w:g}")
                                        if c in dataset.frame.columns])
    config = dataset.config
    if config is not None and w in config.leds.wavelengths_nm:
        doc = json.loads(config.to_json())
        doc["leds"]["emitters"] = [e for e in doc["leds"]["emitters"]
                                   if float(e["wavelength_nm"]) != w]
        config = type(config).model_validate(doc)
    return Dataset(frame, config=config, seed=dataset.seed, metadata=dict(dataset.metadata))


def refit_predictions(frame: pd.DataFrame, runs: Sequence[tuple[Any, Any, Any]]) -> pd.DataFrame:
    """The refits' scored held-out predictions, the input of :func:`drop_one_table`.

    Parameters
    ----------
    frame : pandas.DataFrame
        The benchmarked data (``subject_id``, ``glucose_mgdl``).
    runs : sequence of (spec, Split, result)
        The refit tasks: ``spec["model"]`` and ``spec["drop_nm"]``, the split, and the
        result's ``predicted_mgdl`` and ``fallback_mgdl`` (scored as the benchmark
        scores, :func:`~nirglucose.evaluation.benchmark.aggregate.scored`).
    """
    sid = frame["subject_id"].to_numpy()
    yref = frame["glucose_mgdl"].to_numpy(float)
    parts = [pd.DataFrame({
        "model": spec["model"],
        "dropped_wavelength_nm": float(spec["drop_nm"]),
        "subject_id": sid[split.test],
        "repeat": split.repeat,
        "fold": split.fold,
        "reference_mgdl": yref[split.test],
        "scored_mgdl": scored(np.asarray(res["predicted_mgdl"], dtype=float),
                              res["fallback_mgdl"]),
    }) for spec, split, res in runs]
    return pd.concat(parts, ignore_index=True) if parts else pd.DataFrame()


def drop_one_table(
    predictions: pd.DataFrame,
    refits: pd.DataFrame,
    *,
    n_boot: int,
    seed: int,
    alpha: float = 0.05,
) -> pd.DataFrame:
    """Each model without each LED against itself with all LEDs: paired RMSE difference.

    Parameters
    ----------
    predictions : pandas.DataFrame
        The benchmark's predictions (``model``, ``subject_id``, ``repeat``,
        ``reference_mgdl``, ``scored_mgdl``), every LED in.
    refits : pandas.DataFrame
        The refits' predictions, the same columns plus ``dropped_wavelength_nm``;
        ``model`` is the model refitted. Only the repeats present here are compared.
    n_boot, seed : int
        Bootstrap resamples and their seed. [-]
    alpha : float
        Level of the CI (``1 - alpha``) and of ``significant`` (Holm over each model's
        LEDs). [-]

    Returns
    -------
    pandas.DataFrame
        :data:`DROP_ONE_COLUMNS`, one row per (model, LED), ``delta_rmse_mgdl`` =
        ``rmse_without_mgdl - rmse_all_mgdl``.
    """
    cols = list(DROP_ONE_COLUMNS)
    if refits is None or not len(refits):
        return pd.DataFrame(columns=cols)
    rows = []
    for model, part in refits.groupby("model", sort=False):
        repeats = sorted(pd.unique(part["repeat"]))
        full = predictions[(predictions["model"] == model)
                           & predictions["repeat"].isin(repeats)]
        if not len(full):
            raise DataError(f"no predictions of {model!r} with every LED to compare with")
        wls = list(dict.fromkeys(part["dropped_wavelength_nm"].astype(float)))
        named = part.assign(model=[drop_one_row(model, w) for w in
                                   part["dropped_wavelength_nm"].astype(float)])
        both = pd.concat([full, named], ignore_index=True)
        pairs = [(drop_one_row(model, w), str(model)) for w in wls]
        c = compare_models(both, pairs=pairs, pred_col="scored_mgdl", n_boot=n_boot,
                           seed=seed, alpha=alpha)
        n_sub = int(full["subject_id"].nunique())
        for w, (_, r) in zip(wls, c.iterrows(), strict=True):
            rows.append({
                "model": str(model),
                "dropped_wavelength_nm": w,
                "rmse_all_mgdl": r["reference_rmse_mgdl"],
                "rmse_without_mgdl": r["rmse_mgdl"],
                "delta_rmse_mgdl": r["rmse_diff_mgdl"],
                "ci_low": r["ci_low"],
                "ci_high": r["ci_high"],
                "p_value": r["p_value"],
                "p_holm": r["p_holm"],
                "significant": bool(r["significant"]),
                "n_test_subjects": n_sub,
                "n_repeats": len(repeats),
            })
    out = pd.DataFrame(rows, columns=cols)
    out["dropped_wavelength_nm"] = out["dropped_wavelength_nm"].astype(float)
    return out.reset_index(drop=True)



def led_verdicts(table: pd.DataFrame | None) -> list[dict[str, Any]]:
    """Per model of ``drop_one.csv``: the LED whose removal costs most, where it is shown.

    One dict per model: ``model``, ``n_subjects`` (held-out subjects), ``withheld``
    (fewer than :data:`~nirglucose.dataset.small_data.MIN_SIGNIFICANCE_SUBJECTS`: nothing is
    claimed), ``row`` (the LED with the largest Δ RMSE among those whose 95 % CI lies
    above 0; None when no CI does, or when withheld). An LED whose CI includes 0 is
    never named as the one that matters.
    """
    if table is None or not len(table):
        return []
    out = []
    for model, part in table.groupby("model", sort=False):
        n_sub = int(part["n_test_subjects"].min()) if "n_test_subjects" in part else 0
        withheld = n_sub < MIN_SIGNIFICANCE_SUBJECTS
        shown = part[part["ci_low"].astype(float) > 0]
        row = None if withheld or not len(shown) else shown.loc[
            shown["delta_rmse_mgdl"].astype(float).idxmax()]
        out.append({"model": str(model), "n_subjects": n_sub, "withheld": withheld,
                    "row": row})
    return out


def drop_one_findings(preset: str, table: pd.DataFrame | None, anchor: str) -> list:
    """Findings on one preset's drop-one refits: per model, the LED that costs most.

    An LED is named only where its 95 % CI lies above 0 and the run held out enough
    subjects (:func:`led_verdicts`); the sources name
    ``<preset>/drop_one.csv:<model>:<wavelength>:<column>``.
    """
    verdicts = led_verdicts(table)
    out = []
    for v in (v for v in verdicts if v["row"] is not None):
        r, m = v["row"], v["model"]
        wl = float(r["dropped_wavelength_nm"])
        src = f"{preset}/drop_one.csv:{m}:{wl:g}"
        vals = (Value(float(r["delta_rmse_mgdl"]), 2, (f"{src}:delta_rmse_mgdl",), sign=True),
                Value(float(r["ci_low"]), 2, (f"{src}:ci_low",), sign=True),
                Value(float(r["ci_high"]), 2, (f"{src}:ci_high",), sign=True),
                Value(float(r["rmse_all_mgdl"]), 1, (f"{src}:rmse_all_mgdl",)))
        out.append(Finding("leds", preset, (
            f"LEDs on {preset}, {label(m)}: leaving out the {wl:g} nm LED costs most, Δ RMSE "
            "{} mg/dL [95 % CI {}, {}] over {} mg/dL with every LED (refitted without it "
            "on the same folds and subjects)."), vals, anchor))
    none = [v["model"] for v in verdicts if v["row"] is None and not v["withheld"]]
    if none:
        out.append(Finding("leds", preset, (
            f"LEDs on {preset}: for {', '.join(label(m) for m in none)}, no single LED's "
            "removal raises the RMSE with a 95 % CI above 0: the other LEDs make up for any "
            "one."), (), anchor))
    withheld = [v for v in verdicts if v["withheld"]]
    if withheld:
        out.append(Finding("leds", preset, (
            f"LEDs on {preset}: no LED is named as mattering most: only "
            f"{min(v['n_subjects'] for v in withheld)} held-out subjects, fewer than the "
            f"{MIN_SIGNIFICANCE_SUBJECTS} a paired comparison needs (small-data policy)."),
            (), anchor))
    return out
