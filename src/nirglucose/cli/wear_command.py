"""The ``wear-benchmark`` command: a device worn for days, every model on the series,
smoothed and calibrated on schedules, judged by the standards of a worn monitor."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer
from rich.markup import escape
from rich.table import Table

from ._app import app, out_console
from ._common import (
    _PRESET_NAMES,
    FoldsOption,
    OutDirOption,
    SetOption,
    TwinModeOption,
    TwinOption,
    UserError,
    _check_counts,
    _check_out_dir,
    _check_seed,
    _model_names,
    _say,
    _tidy_out,
    _warnings_as_lines,
    refuse_simulation_options,
    runs_workers,
)
from .benchmark_command import runs_of


def _schedule_names(schedules: str) -> list[str]:
    from ..calibration.schedules import SCHEDULES

    names = [s.strip() for s in schedules.split(",") if s.strip()]
    unknown = [s for s in names if s not in SCHEDULES]
    if not names or unknown:
        raise UserError(f"--schedules {schedules!r}: unknown or none; choose among "
                        f"{', '.join(SCHEDULES)}")
    return names


@app.command("wear-benchmark")
@_tidy_out
@runs_workers
def wear_benchmark(
    ctx: typer.Context,
    out: OutDirOption,
    preset: Annotated[
        str,
        typer.Option(help=f"Preset(s) to simulate, comma-separated: {_PRESET_NAMES}; several "
                     "write OUT/<preset>/ each."),
    ] = "paper",
    data: Annotated[
        Path | None,
        typer.Option(help="A saved worn dataset (from simulate --wear-days) instead."),
    ] = None,
    subjects: Annotated[int, typer.Option(help="Subjects, each wearing one device.")] = 20,
    wear_days: Annotated[int, typer.Option(help="Days of wear. [d]")] = 7,
    every_min: Annotated[int, typer.Option(help="Minutes between readings. [min]")] = 15,
    models: Annotated[
        str | None,
        typer.Option(help="Comma-separated model names (default: ebl, pls, gp, mean, oracle)."),
    ] = None,
    schedules: Annotated[
        str,
        typer.Option(help="Calibration schedules, comma-separated: factory, day1-1, day1-2, "
                     "every-24h, every-12h."),
    ] = "factory,day1-1,day1-2,every-24h,every-12h",
    folds: FoldsOption = 5,
    train_readings: Annotated[
        int, typer.Option(help="Readings each training subject contributes to a fit.")
    ] = 48,
    seed: Annotated[int, typer.Option(help="Seed of data, splits, models and bootstrap.")] = 0,
    resamples: Annotated[int, typer.Option(help="Subject-bootstrap resamples (>= 100).")] = 1000,
    set_: SetOption = None,
    twin: TwinOption = None, twin_mode: TwinModeOption = None,
) -> None:
    """Benchmark a device worn for days: every model on the series, a causal smoother,
    calibration schedules and the CGM standards (wear_*.csv); --twin: a device's twin
    worn."""
    from ..evaluation.engine.tasks import clear_outputs
    from ..evaluation.wear import WEAR_FILES, WEAR_MODELS, run_wear_benchmark

    _check_counts(("--subjects", subjects), ("--wear-days", wear_days),
                  ("--every-min", every_min), ("--folds", folds),
                  ("--train-readings", train_readings), ("--resamples", resamples))
    _check_seed(seed)
    refuse_simulation_options(ctx, data, ("preset", "subjects", "wear_days", "every_min"))
    if resamples < 100:
        raise UserError(f"--resamples {resamples} is too few for a lower confidence bound; "
                        "give at least 100")
    names = _model_names(models) or list(WEAR_MODELS)
    sched = _schedule_names(schedules)
    _check_out_dir(out)
    stale = (*WEAR_FILES, "report.html")
    runs, overrides = runs_of(ctx, preset, data, set_, out, (twin, twin_mode, seed),
                              stale=stale)  # the benchmark's rule
    for p, run_out in runs:
        ds = _worn_data(p, data, subjects, wear_days, every_min, seed, overrides)
        clear_outputs(run_out, stale)  # its input read: a stopped run leaves no stale files
        with _warnings_as_lines():
            res = run_wear_benchmark(ds, names, preset=p, n_splits=folds, seed=seed,
                                     schedules=sched, train_readings_per_subject=train_readings,
                                     n_boot=resamples)
        run_out.mkdir(exist_ok=True)
        res.save(run_out)
        _print(res, p or str(data), run_out)


def _worn_data(preset, data, subjects, wear_days, every_min, seed, overrides):
    if preset is None:
        from ..dataset import load_dataset

        ds = load_dataset(data)
        if "time_min" not in ds.frame.columns:
            raise UserError(f"{str(data)!r} has no time_min column: simulate it with "
                            "`nirglucose simulate --wear-days D` or add the reading times")
        return ds
    from ..api import simulate_wear

    return simulate_wear(preset, subjects, wear_days, every_min, seed, overrides=overrides)


def _print(res, name: str, out: Path) -> None:
    """RMSE per model and schedule (raw / smoothed) and where the files are."""
    s = res.schedules
    table = Table(title=escape(f"{name}: RMSE [mg/dL] by calibration schedule "
                               "(raw / smoothed)"))
    table.add_column("model")
    order = list(dict.fromkeys(s["schedule"]))
    for sched in order:
        table.add_column(sched, justify="right")
    for model, g in s.groupby("model", sort=False):
        cells = []
        for sched in order:
            v = g[g["schedule"] == sched].set_index("variant")["rmse_mgdl"]
            raw, smooth = v.get("raw", float("nan")), v.get("smoothed", float("nan"))
            cells.append(f"{raw:.1f} / {smooth:.1f}")
        table.add_row(escape(str(model)), *cells)
    out_console.print(table)
    _say(f"wrote {out}/ (wear_schedules.csv, wear_by_day.csv, wear_standards.csv, "
         "wear_icgm.csv, wear_predictions.csv)", err=False)


def wear_sweep(out: Path, vary, preset, seeds: int, seed: int, models, subjects: int,
               folds: int, resamples: int, set_, jobs: int | None = 1,
               scheduler: str | None = None, twin=None) -> None:
    """``sweep --study wear``: :func:`nirglucose.evaluation.wear.run_wear_sweep`;
    ``twin`` (a :class:`~nirglucose.twin.twin.TwinStart`): its device in place of the
    presets, labelled ``twin``."""
    from ..evaluation.wear import WEAR_DAYS, WEAR_PRESETS, WEAR_SWEEP_FILES, run_wear_sweep

    _check_counts(("--subjects", subjects), ("--folds", folds), ("--seeds", seeds),
                  ("--resamples", resamples))
    _check_seed(seed)
    if set_:
        raise UserError("--set is not taken by --study wear; it sweeps presets as they are")
    days = list(WEAR_DAYS)
    for item in vary or []:
        key, _, values = item.partition("=")
        if key.strip() != "wear_days" or not values:
            raise UserError(f"--vary {item!r}: --study wear varies only wear_days "
                            "(--vary wear_days=1,3,7)")
        try:
            days = [int(v) for v in values.split(",")]
        except ValueError:
            raise UserError(f"--vary {item!r}: wear_days must be whole days, e.g. 1,3,7") from None
    presets = ([p.strip() for p in preset.split(",") if p.strip()] if preset
               else list(WEAR_PRESETS))
    extra = {}
    if twin is not None:
        presets = [twin.preset]
        extra = {"overrides": twin.overrides, "label": "twin"}
    _check_out_dir(out)
    n = len(presets) * len(days) * seeds
    done = [0]

    def on_task(spec, cached):
        done[0] += 1
        _say(f"wear: {done[0]}/{n} tasks ({extra.get('label', spec['preset'])}, "
             f"{spec['wear_days']} d, seed "
             f"{spec['seed']}{', cached' if cached else ''})")

    with _warnings_as_lines():
        summary = run_wear_sweep(out, presets=presets, wear_days=days,
                                 seeds=list(range(seed, seed + seeds)),
                                 models=_model_names(models) or _default_models(),
                                 n_subjects=subjects, folds=folds, n_boot=resamples,
                                 on_task=on_task, jobs=jobs, scheduler=scheduler, **extra)
    best = summary[summary["variant"] == "raw"].pivot_table(
        index=["preset", "wear_days", "model"], columns="schedule", values="rmse_mgdl")
    out_console.print(escape(best.round(1).to_string()))
    _say(f"wrote {out}/ ({', '.join(WEAR_SWEEP_FILES)})", err=False)


def _default_models() -> list[str]:
    from ..evaluation.wear import WEAR_MODELS

    return list(WEAR_MODELS)
