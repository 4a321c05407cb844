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
    AdcBitsOption,
    FoldsOption,
    GlucoseUnitOption,
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
    refuse_simulation_options,
    runs_workers,
    twin_start,
)
from .fit_report import say_notes

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
    calibration: Annotated[
        int,
        typer.Option(
            help="Personal calibration: each test subject's first K readings (1 or 2) "
            "calibrate them and only later readings are scored (calibration.csv); 0: none. "
            "Needs --per-subject > K."
        ),
    ] = 0,
    drop_one: _DropOneOption = None,
    set_: SetOption = None,
    adc_bits: AdcBitsOption = None,
    glucose_unit: GlucoseUnitOption = None,
    twin: TwinOption = None, twin_mode: TwinModeOption = None,
) -> None:
    """Fit and score every model on subject-grouped splits; resumable (out/.tasks).

    Files written keep mg/dL (their column names say so); --glucose-unit sets the unit
    of the --data file and of the printed table. --twin simulates a device's twin."""
    _check_counts(("--subjects", subjects), ("--per-subject", per_subject), ("--folds", folds),
                  ("--repeats", repeats), ("--resamples", resamples))
    refuse_simulation_options(ctx, data, ("preset", "subjects", "per_subject"))
    jobs = _jobs(jobs)
    names = _check_benchmark_args(seed, protocol, calibration, data, subjects, per_subject,
                                  models, out, glucose_unit)
    runs, overrides = runs_of(ctx, preset, data, set_, out, (twin, twin_mode, seed), adc_bits)
    for p, run_out in runs:
        ds = _benchmark_data(p, data, subjects, per_subject, seed, overrides, adc_bits,
                             glucose_unit)
        _check_run_data(ds, calibration, protocol, folds)
        if p is None:
            say_notes(ds)  # after the checks: an error stays one line
        _benchmark_one(ds, names, protocol, folds, repeats, seed, run_out, jobs, resamples,
                       references, ablation, calibration, glucose_unit, drop_one)


def _check_benchmark_args(seed, protocol, calibration, data, subjects, per_subject, models,
                          out, glucose_unit=None) -> list[str] | None:
    """The checks of ``benchmark`` after the counts, in order; the --models names."""
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
    return names


def _benchmark_runs(preset: str, data: Path | None, set_: list[str] | None, out: Path,
                    stale: tuple[str, ...] | None = None):
    """``([(preset or None for --data, output directory), ...], overrides)``.

    Every preset is resolved first, so an unknown one fails before anything runs;
    several presets write ``OUT/<preset>/`` each, and their previous results ``stale``
    (default: the benchmark's, ``STALE_FILES``) are removed first
    (:func:`~._common.clear_previous_runs`).
    """
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


def _benchmark_data(preset, data, subjects, per_subject, seed, overrides, adc_bits=None,
                    glucose_unit=None):
    """The dataset of one run: the --data file (``preset`` None: read, validated whole
    and its ADC resolution resolved before any split) or a simulated one."""
    if preset is None:
        from .fit_report import load_device_file

        ds, _ = load_device_file(data, glucose_unit, adc_bits, need_glucose=True)
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
                   references, ablation, calibration=0, unit=None, drop_one=None) -> None:
    """Run the benchmark of one dataset, then print its table and summary lines."""
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
            f"{r['method']}: RMSE {r['rmse_mgdl']:.1f} mg/dL"
            + (f", gain {r['gain_mgdl']:+.1f} vs {r['baseline']}" if r["baseline"] else ""),
            err=False,
        )
    m = res.meta
    if m.get("significance_withheld"):
        _say(f"note: {m['significance_withheld']}", err=False)
    _say(
        f"wrote results to {out}/ ({m['tasks_computed']} tasks computed, "
        f"{m['tasks_cached']} reused, {m['wall_time_s']:.0f} s)",
        err=False,
    )
