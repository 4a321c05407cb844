"""The ``benchmark`` command: fit and score every model on subject-grouped splits."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer
from rich.console import Console
from rich.markup import escape
from rich.table import Table

from ._app import app, out_console
from ._common import (
    _PRESET_NAMES,
    DEFAULT_RESAMPLES,
    ChannelBitsOption,
    FoldsOption,
    FullScaleOption,
    GlucoseUnitOption,
    GroupByOption,
    JobsOption,
    OutDirOption,
    PerSubjectOption,
    ProtocolOption,
    RepeatsOption,
    ResamplesOption,
    SetOption,
    TwinModeOption,
    TwinOption,
    UserError,
    _check_calibration,
    _check_counts,
    _check_out_dir,
    _check_seed,
    _check_size,
    _jobs,
    _model_names,
    _parse_sets,
    _say,
    _tidy_out,
    _warnings_as_lines,
    clear_previous_runs,
    held_warnings,
    refuse_simulation_options,
    runs_workers,
    twin_start,
)
from .fit_report import (
    adc_spec,
    display_unit,
    group_column,
    in_unit,
    report_benchmark_cohorts,
    say_notes,
)

#: ``--drop-one``: the models refitted without each LED.
_DropOneOption = Annotated[
    str | None,
    typer.Option(
        "--drop-one",
        help="Models refitted without each LED (drop_one.csv: RMSE lost per LED, first "
        "repeat): comma-separated names among --models, 'all' or 'none' (default: ebl, pls "
        "and oracle where benchmarked).",
    ),
]

#: ``--preset-models``: another model set on one preset of several.
_PresetModelsOption = Annotated[
    list[str] | None,
    typer.Option(
        "--preset-models",
        help="PRESET=NAMES: the comma-separated models to benchmark on that preset instead "
        "of --models (repeatable; PRESET among --preset), e.g. physical=mean,ebl,oracle.",
    ),
]


#: ``--calibration``: personal calibration readings per test subject.
_CalibrationOption = Annotated[
    int,
    typer.Option(
        help="Personal calibration: each test subject's first K readings (1 or 2) "
        "calibrate them and only later readings are scored (calibration.csv); 0: none. "
        "Needs --per-subject > K."
    ),
]


@app.command()
@_tidy_out
@runs_workers
def benchmark(
    ctx: typer.Context,
    out: OutDirOption,
    preset: Annotated[
        str,
        typer.Option(
            help=f"Scenario preset to simulate: {_PRESET_NAMES}; several comma-separated "
            "(paper,wearable) write OUT/<preset>/ each."
        ),
    ] = "paper",
    data: Annotated[
        Path | None, typer.Option(help="Benchmark a saved dataset (.parquet/.csv) instead.")
    ] = None,
    models: Annotated[
        str | None, typer.Option(help="Comma-separated model names (default: all registered).")
    ] = None,
    protocol: ProtocolOption = "grouped-cv",
    subjects: Annotated[int, typer.Option(help="Number of subjects to simulate.")] = 80,
    per_subject: PerSubjectOption = 3,
    folds: FoldsOption = 5,
    repeats: RepeatsOption = 3,
    seed: Annotated[int, typer.Option(help="Seed of data, splits, models and bootstrap.")] = 0,
    jobs: JobsOption = None,
    resamples: ResamplesOption = DEFAULT_RESAMPLES,
    references: Annotated[
        bool, typer.Option(help="Add the reference rows (mean, gp, gbr) to --models.")
    ] = True,
    ablation: Annotated[
        bool, typer.Option(help="Also run each PINN with its physics term off (lambda_phys=0).")
    ] = True,
    calibration: _CalibrationOption = 0,
    drop_one: _DropOneOption = None,
    preset_models: _PresetModelsOption = None,
    set_: SetOption = None,
    adc_bits: ChannelBitsOption = None,
    adc_full_scale: FullScaleOption = None,
    glucose_unit: GlucoseUnitOption = None,
    group_by: GroupByOption = None,
    twin: TwinOption = None, twin_mode: TwinModeOption = None,
) -> None:
    """Fit and score every model on subject-grouped splits; resumable (out/.tasks).

    Files written keep mg/dL (their column names say so); --glucose-unit sets the unit
    of the --data file and of the printed table (default: the unit of its reference
    column). A --data file with a grouping column (--group-by, else detected) gets each
    group's error against that group's own training mean. --twin simulates a device's
    twin."""
    _check_counts(("--subjects", subjects), ("--per-subject", per_subject), ("--folds", folds),
                  ("--repeats", repeats), ("--resamples", resamples))
    refuse_simulation_options(ctx, data, ("preset", "subjects", "per_subject"))
    jobs = _jobs(jobs)
    names, per_preset = _check_benchmark_args(seed, protocol, calibration, data, subjects,
                                              per_subject, models, out, glucose_unit, preset,
                                              preset_models)
    runs, overrides = runs_of(ctx, preset, data,
                              _simulated_bits(set_, adc_bits, adc_full_scale, data), out,
                              (twin, twin_mode, seed))
    for p, run_out in runs:
        with held_warnings():  # a refusal of this run is one line
            ds = _benchmark_data(p, data, subjects, per_subject, seed, overrides,
                                 (adc_bits, adc_full_scale), glucose_unit)
            gcol, unit = _data_groups(ds, p, group_by, calibration, protocol, folds,
                                      glucose_unit)
        _benchmark_one(ds, per_preset.get(p, names), protocol, folds, repeats, seed, run_out,
                       jobs, resamples, references, ablation, calibration, unit, drop_one, gcol)


def _simulated_bits(set_, adc_bits, adc_full_scale, data):
    """``--set`` with the simulated device's ``--adc-bits N`` (one resolution: the
    simulator has one converter); --data keeps its options for the file."""
    if data is not None or (adc_bits is None and adc_full_scale is None):
        return set_
    bits = adc_spec(adc_bits)
    if adc_full_scale is not None or isinstance(bits, dict):
        raise UserError("per-channel converters (--adc-bits adc_940=10,... or "
                        "--adc-full-scale) describe a --data file; a simulated device has "
                        "one converter: give --adc-bits N")
    return [*(set_ or []), f"hardware.adc_bits={bits}"]


def _data_groups(ds, preset: str | None, group_by: str | None, calibration: int,
                 protocol: str, folds: int, glucose_unit: str | None
                 ) -> tuple[str | None, str]:
    """``(grouping column, printed unit)`` of one run after its checks: a --data file's
    grouping column (recorded in its metadata for the report; None for a simulated run)
    and its read notes printed once it passed them."""
    _check_run_data(ds, calibration, protocol, folds)
    unit = display_unit(ds, glucose_unit)
    if preset is not None:
        return None, unit
    gcol = group_column(ds.frame, group_by)
    if gcol is not None:
        ds.metadata["group_by"] = gcol  # dataset.parquet carries it to the report
    say_notes(ds)  # after the checks: an error stays one line
    return gcol, unit


def _check_benchmark_args(seed, protocol, calibration, data, subjects, per_subject, models,
                          out, glucose_unit=None, preset="paper", preset_models=None
                          ) -> tuple[list[str] | None, dict[str | None, list[str]]]:
    """The checks of ``benchmark`` after the counts, in order (before any previous result
    is cleared); the --models names and the --preset-models sets by preset."""
    from ..dataset.files import check_glucose_unit
    from ..evaluation.splits import check_protocol
    from ..models.registry import get_model_class

    check_glucose_unit(glucose_unit)
    _check_seed(seed)
    check_protocol(protocol)
    _check_calibration(calibration, None if data is not None else per_subject)
    if data is None:
        _check_size(subjects, per_subject)
    names = _model_names(models)
    for name in names or []:
        get_model_class(name)  # unknown names raise with the valid ones
    _check_out_dir(out)
    return names, _preset_models(preset_models, None if data is not None else
                                 [p.strip() for p in preset.split(",") if p.strip()])


def _preset_models(given: list[str] | None, presets: list[str] | None
                   ) -> dict[str | None, list[str]]:
    """``--preset-models PRESET=NAMES`` (repeatable) as ``{preset: [names]}``, checked:
    each PRESET is one of the run's presets, given once, and every name is registered."""
    from ..models.registry import get_model_class

    out: dict[str | None, list[str]] = {}
    for item in given or []:
        p, sep, models = item.partition("=")
        p = p.strip()
        if not sep or not p:
            raise UserError(f"--preset-models {item!r}: write PRESET=NAMES, e.g. "
                            "physical=mean,ebl,oracle")
        if presets is None:
            raise UserError("--preset-models chooses models per simulated preset; with "
                            "--data give --models")
        if p not in presets:
            named = ", ".join(presets)
            raise UserError(f"--preset-models {item!r}: {p!r} is not among the presets "
                            f"benchmarked ({named}); add it to --preset or drop it here")
        if p in out:
            raise UserError(f"--preset-models names {p!r} twice; give its models once")
        names = [m.strip() for m in models.split(",") if m.strip()]
        if not names:
            raise UserError(f"--preset-models {item!r} names no model")
        for name in names:
            get_model_class(name)  # unknown names raise with the valid ones
        out[p] = names
    return out


def _benchmark_runs(preset: str, data: Path | None, set_: list[str] | None, out: Path,
                    stale: tuple[str, ...] | None = None, adc_bits: int | None = None):
    """``([(preset or None for --data, output directory), ...], overrides)``.

    Every preset is resolved first, so an unknown one fails before anything runs;
    several presets write ``OUT/<preset>/`` each, and their previous results ``stale``
    (default: the benchmark's, ``STALE_FILES``) are removed first
    (:func:`~._common.clear_previous_runs`). ``adc_bits`` (``--adc-bits``) sets the
    simulated device's resolution (``hardware.adc_bits``); with ``data`` it is the file's.
    """
    if adc_bits is not None and data is None:  # the simulated device's resolution
        set_ = [*(set_ or []), f"hardware.adc_bits={adc_bits}"]
    presets = list(dict.fromkeys(p.strip() for p in preset.split(",") if p.strip()))
    if not presets:
        raise UserError(f"--preset {preset!r} names no preset")
    if len(presets) > 1 and data is not None:
        raise UserError("--data benchmarks one dataset; give one --preset or none")
    if data is not None:
        if set_:
            raise UserError("--set changes the simulation; it cannot apply to --data")
        return [(None, out)], {}
    from ..config import resolve_config

    overrides = _parse_sets(set_)
    for p in presets:
        resolve_config(p, overrides)  # an unknown preset fails before anything runs
    if len(presets) > 1:
        out.mkdir(exist_ok=True)
    runs = [(p, out / p if len(presets) > 1 else out) for p in presets]
    if stale is None:
        from ..evaluation.benchmark.result import STALE_FILES as stale
    clear_previous_runs(runs, out, stale)
    return runs, overrides


def runs_of(ctx, preset: str, data: Path | None, set_: list[str] | None, out: Path,
            twin: tuple, adc_bits: int | None = None, stale: tuple[str, ...] | None = None):
    """The runs of a benchmark command and their overrides: ``_benchmark_runs``, or with
    ``--twin`` (``twin``: path, mode, seed; :func:`~._common.twin_start`'s checks) one
    run of the twin; ``adc_bits`` of a simulated device joins ``--set``."""
    start = twin_start(ctx, *twin, set_=set_)
    if adc_bits is not None and data is None:  # the simulated device's resolution
        set_ = [*(set_ or []), f"hardware.adc_bits={adc_bits}"]
    if start is None:
        return _benchmark_runs(preset, data, set_, out, stale)
    return twin_runs(start, set_, out)


def twin_runs(start, set_: list[str] | None, out: Path):
    """``_benchmark_runs`` of a ``--twin`` run: one run into ``out``, the twin's base
    preset with its overrides and ``--set`` on top (resolved: a bad value fails here)."""
    from ..config import resolve_config

    overrides = {**start.overrides, **_parse_sets(set_)}
    resolve_config(start.preset, overrides)
    return [(start.preset, out)], overrides


def _benchmark_data(preset, data, subjects, per_subject, seed, overrides,
                    adc_bits=(None, None), glucose_unit=None):
    """The dataset of one run: the --data file (``preset`` None: read, validated whole
    and its ADC resolution resolved before any split) or a simulated one."""
    if preset is None:
        from .fit_report import load_device_file

        ds, _ = load_device_file(data, glucose_unit, adc_bits[0], need_glucose=True,
                                 adc_full_scale=adc_bits[1])
        if "subject_id" not in ds.frame.columns:
            raise UserError(f"{str(data)!r} has no subject_id column: the benchmark splits "
                            "by subject; add one (one id per person)")
        return ds
    from ..api import simulate as _simulate

    return _simulate(preset, subjects, per_subject, seed, overrides=overrides)


def _check_run_data(ds, k: int, protocol: str, folds: int) -> None:
    """Before any task runs, refuse --folds beyond the subjects (grouped CV), and
    --calibration K when no subject has a reading left to score."""
    n_sub = ds.frame["subject_id"].nunique()
    if protocol == "grouped-cv" and folds > n_sub:
        raise UserError(f"--folds {folds} exceeds the {n_sub} subjects (each fold tests at "
                        f"least one); give --folds {n_sub} or fewer")
    if not k:
        return
    counts = ds.frame.groupby("subject_id").size()
    if int(counts.max()) <= k:
        raise UserError(
            f"--calibration {k} uses each person's first {k} reading(s), but no subject has "
            f"more than {int(counts.max())}: nothing is left to score; give --calibration 0 "
            f"or data with at least {k + 1} readings per person"
        )


def _benchmark_one(ds, names, protocol, folds, repeats, seed, out, jobs, resamples,
                   references, ablation, calibration=0, unit=None, drop_one=None,
                   group_column_name=None) -> None:
    """Run the benchmark of one dataset, then print its table and summary lines (and
    each group's error against its own training mean, given a grouping column)."""
    from ..evaluation.benchmark.run import run_benchmark
    from ..evaluation.protocol import Protocol

    with _warnings_as_lines():
        res = run_benchmark(
            ds,
            names,
            protocol=Protocol(splitter=protocol, n_splits=folds, repeats=repeats, seed=seed,
                              resamples=resamples, calibration=calibration),
            out=out,
            jobs=jobs,
            progress=True,
            references=references,
            ablation=ablation,
            drop_one_models=drop_one,
            # the oracle bound needs the simulator's true_* columns: not asked of user data
            oracle_reference=any(str(c).startswith("true_") for c in ds.frame.columns),
        )
    _print_benchmark(res, ds, out, unit)
    if names is None and ds.config is None:
        _say_privileged_left_out(ds)
    if group_column_name is not None:
        report_benchmark_cohorts(res, ds, group_column_name, unit or "mg/dL")


def _say_privileged_left_out(ds) -> None:
    """One note: which registered models a device's file (no scenario) does not run, the
    ones :func:`~nirglucose.evaluation.benchmark.run.default_models` leaves out."""
    from ..evaluation.benchmark.run import default_models
    from ..models.registry import available_models

    kept = set(default_models(ds))
    left = [n for n in available_models() if n not in kept]
    if left:
        _say(f"note: the privileged references ({', '.join(left)}) did not run: they read "
             "the generating scenario or the true_* columns, which a device's file does not "
             "have; every other registered model did", err=False)


def _one_led(ds) -> bool:
    """Whether the dataset's device has a single LED (``adc_<nm>`` column)."""
    from ..dataset.columns import led_wavelengths_in

    return len(led_wavelengths_in(ds.frame.columns)) == 1


def _print_benchmark(res, ds, out: Path, unit: str | None = None) -> None:
    """The metrics table, one line per calibration method, and where the results are."""
    import numpy as np
    from rich import box

    table = Table(title=escape(f"benchmark ({res.meta['protocol']}): {ds!r}"),
                  box=box.SIMPLE_HEAD)
    from ..dataset.files import glucose_to_unit

    u = unit or "mg/dL"
    d = 2 if u == "mmol/L" else 1

    def g(v):
        return f"{float(glucose_to_unit(v, u)):.{d}f}"

    for col in ("model", f"RMSE {u} (95% CI)", "MARD %", "Clarke A %", "90% PI cover/width",
                "params", "ms"):
        table.add_column(col, justify="left" if col == "model" else "right", no_wrap=True)
    for _, r in res.metrics.iterrows():
        table.add_row(
            escape(str(r["model"])),
            f"{g(r['rmse_mgdl'])} ({g(r['rmse_ci_low'])}-{g(r['rmse_ci_high'])})",
            f"{r['mard_pct']:.1f}",
            f"{r['clarke_a_pct']:.1f}",
            (f"{r['coverage90_pct']:.0f}% / {g(r['width90_mgdl'])}"
             if np.isfinite(r["width90_mgdl"]) else "– (too few subjects)"),
            f"{int(r['n_parameters']):,}",
            f"{r['latency_single_ms']:.3f}",
        )
    # not a terminal (a log file, make): wide enough that no column is truncated
    (out_console if out_console.is_terminal else Console(width=110)).print(table)
    cal = res.calibration
    for _, r in cal[cal["method"] != "none"].iterrows():
        _say(
            f"calibration ({r['k']} reading{'s' if r['k'] > 1 else ''}): {r['model']} "
            f"{r['method']}: RMSE {in_unit(r['rmse_mgdl'], unit)}"
            + (f", gain {'+' if r['gain_mgdl'] >= 0 else ''}{g(r['gain_mgdl'])} vs "
               f"{r['baseline']}" if r["baseline"] else ""),
            err=False,
        )
    m = res.meta
    if _one_led(ds) and not len(res.drop_one):
        _say("note: drop_one.csv is empty: the device has one LED, so there is no LED to "
             "drop (the drop-one refits need two or more)", err=False)
    if m.get("significance_withheld"):
        _say(f"note: {m['significance_withheld']}", err=False)
    _say(
        f"wrote results to {out}/ ({m['tasks_computed']} tasks computed, "
        f"{m['tasks_cached']} reused, {m['wall_time_s']:.0f} s)",
        err=False,
    )
