"""The ``sweep`` command: scenarios x seeds x models, locally or on Dask."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer
from rich.markup import escape
from rich.table import Table

from ._app import app, out_console
from ._common import (
    _PRESET_NAMES,
    _STUDY_NAMES,
    DEFAULT_RESAMPLES,
    FoldsOption,
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
    runs_workers,
    twin_start,
)

#: The sweep's own options (the shared ones are in :mod:`._common`).
VaryOption = Annotated[
    list[str] | None,
    typer.Option(help="KEY=V1,V2,... config values to sweep (dotted key); repeat for a grid."),
]
StudyOption = Annotated[
    str | None,
    typer.Option(help=f"Built-in study: {_STUDY_NAMES}, wear (calibration schedule x days of "
                 "wear x preset: --vary wear_days=1,3,7, --preset paper,wearable; each task a "
                 "worn run of --subjects subjects, a reading every 15 min; --jobs and "
                 "--scheduler as for the other studies)."),
]
SweepPresetOption = Annotated[
    str | None,
    typer.Option(help=f"Scenario preset every task starts from: {_PRESET_NAMES} (default "
                 "paper); data-size: comma-separated presets (default paper,wearable); "
                 "wavelengths: default wearable."),
]
SeedsOption = Annotated[
    int | None,
    typer.Option(help="Seeds per scenario (seed, seed+1, ...); default 5, data-size 1."),
]
SweepModelsOption = Annotated[
    str | None,
    typer.Option(help="Comma-separated model names (default: ebl,pls,oracle; data-size: all)."),
]
SchedulerOption = Annotated[
    str | None,
    typer.Option(help="Dask scheduler address, e.g. tcp://host:8786, or 'local': a "
                 "Dask cluster of --jobs worker processes started for this run."),
]
SweepCalibrationOption = Annotated[
    int,
    typer.Option(
        help="Personal calibration: each test subject's first K readings (1 or 2) "
        "calibrate them and only later readings are scored (sweep.csv: "
        "later_rmse_mgdl, offset_rmse_mgdl, ...); 0: none. Needs --per-subject > K."
    ),
]


@app.command()
@_tidy_out
@runs_workers
def sweep(
    ctx: typer.Context,
    out: OutDirOption,
    vary: VaryOption = None,
    study: StudyOption = None,
    preset: SweepPresetOption = None,
    seeds: SeedsOption = None,
    seed: Annotated[int, typer.Option(help="First seed.")] = 0,
    models: SweepModelsOption = None,
    protocol: ProtocolOption = "grouped-cv",
    subjects: Annotated[int, typer.Option(help="Subjects per simulated dataset.")] = 80,
    per_subject: PerSubjectOption = 3,
    folds: FoldsOption = 5,
    repeats: RepeatsOption = 3,
    resamples: ResamplesOption = DEFAULT_RESAMPLES,
    jobs: JobsOption = None,
    scheduler: SchedulerOption = None,
    figures: Annotated[bool, typer.Option(help="Write figures to OUT/figures.")] = True,
    calibration: SweepCalibrationOption = 0,
    set_: SetOption = None,
    twin: TwinOption = None,
    twin_mode: TwinModeOption = None,
) -> None:
    """Sweep scenarios x seeds x models (local processes or Dask); resumable (out/.tasks).

    --twin: every scenario starts from a device's twin (the wavelengths study carries
    the twin's per-LED values to the LEDs it chooses)."""
    from ..evaluation.sweep.run import run_sweep

    if twin is not None and study == "data-size":
        raise UserError("--study data-size compares presets and --twin is one device: run "
                        "data-size without --twin, or benchmark --twin at each --subjects")
    start = twin_start(ctx, twin, twin_mode, seed, set_=None if study == "wear" else set_,
                       own_leds=study != "wavelengths")
    if study == "wear":
        from .wear_command import wear_sweep

        return wear_sweep(out, vary, preset, seeds or 1, seed, models, subjects, folds,
                          resamples, set_, jobs=_jobs(jobs), scheduler=scheduler, twin=start)
    overrides = _parse_sets(set_)
    if start is not None:
        preset, overrides = start.preset, {**start.overrides, **overrides}
    if seeds is None:
        seeds = 1 if study == "data-size" else 5
    _check_counts(("--subjects", subjects), ("--per-subject", per_subject), ("--folds", folds),
                  ("--repeats", repeats), ("--seeds", seeds), ("--resamples", resamples))
    jobs = _jobs(jobs)
    grid, names = _check_sweep_args(seed, subjects, per_subject, calibration, study, vary,
                                    models, out)
    with _warnings_as_lines() as extra:
        res = run_sweep(grid or None, study=study, preset=preset,
                        seeds=list(range(seed, seed + seeds)), models=names,
                        overrides=overrides, protocol=protocol, n_splits=folds,
                        repeats=repeats, n_subjects=subjects, per_subject=per_subject,
                        n_boot=resamples, out=out, jobs=jobs, scheduler=scheduler,
                        progress=True, calibration=calibration,
                        led_fields=start.led_fields if start is not None else None,
                        twin=None if twin is None else str(twin))
        if figures:
            from ..report.sweep import save_sweep_figures

            save_sweep_figures(out)
        extra.extend(res.meta["warnings"])
    _print_sweep(res, out)


def _check_sweep_args(seed, subjects, per_subject, calibration, study, vary, models, out):
    """The checks of ``sweep`` after the counts, in order: ``(grid, model names)``."""
    _check_seed(seed)
    _check_size(subjects, per_subject)
    _check_calibration(calibration, per_subject)
    if study is None and not vary:
        raise UserError("give --vary KEY=V1,V2,... or --study NAME")
    grid = _sweep_grid(vary)
    names = _sweep_models(models, study)
    _check_out_dir(out)
    return grid, names


def _sweep_grid(vary: list[str] | None) -> dict:
    """``--vary KEY=V1,V2`` options as ``{key: values}``; a key given twice is refused."""
    from ..evaluation.sweep.run import parse_vary

    grid: dict = {}
    for text in vary or []:
        key, values = parse_vary(text)
        if key in grid:
            raise UserError(f"--vary {key} is given twice; list all its values once")
        grid[key] = values
    return grid


def _sweep_models(models: str | None, study: str | None) -> list[str]:
    """--models, else the study's own models
    (:data:`~nirglucose.evaluation.sweep.studies.STUDY_MODELS`), every registered model
    (data-size) or the registered defaults."""
    from ..evaluation.sweep.run import DEFAULT_MODELS
    from ..evaluation.sweep.studies import STUDY_MODELS
    from ..models.registry import available_models

    if models is None and study in STUDY_MODELS:
        return [m for m in STUDY_MODELS[study] if m in available_models()]
    if models is None and study == "data-size":
        return available_models()
    if models is None:
        return [m for m in DEFAULT_MODELS if m in available_models()]
    return _model_names(models)


def _print_sweep(res, out: Path) -> None:
    """The summary table, the study's findings and where the results are."""
    meta = res.meta
    s = res.summary
    table = Table(title=escape(f"sweep {meta['study']}: mean over {len(meta['seeds'])} seeds "
                               "[95 % CI over seeds]"))
    for col in ("scenario", "model", "RMSE mg/dL", "MARD %", "Clarke A %"):
        table.add_column(col, justify="left" if col in ("scenario", "model") else "right")
    for _, r in s.iterrows():
        table.add_row(escape(str(r["scenario"])), escape(str(r["model"])),
                      f"{r['rmse_mgdl_mean']:.1f} [{r['rmse_mgdl_ci_low']:.1f}, "
                      f"{r['rmse_mgdl_ci_high']:.1f}]", f"{r['mard_pct_mean']:.1f}",
                      f"{r['clarke_a_pct_mean']:.1f}")
    out_console.print(table)
    if len(meta["varied"]) == 1 and meta["varied"][0] in s:
        _print_crossings(s, meta["varied"][0])
    if res.effects is not None:
        _print_effects(res.effects)
    _say(f"wrote {out}/sweep.csv ({meta['tasks_computed']} tasks computed, "
         f"{meta['tasks_cached']} reused, {meta['wall_time_s']:.0f} s)", err=False)


def _print_crossings(summary, key: str) -> None:
    """Where each model's MARD crosses 15 % along the one varied key."""
    from ..evaluation.sweep.run import threshold_crossing

    for _, r in threshold_crossing(summary, key).iterrows():
        where = {"crosses": f"crosses 15 % at {key} = {r['crossing']:.2f}",
                 "above at every x": f"is above 15 % at every {key}",
                 "below at every x": f"stays below 15 % at every {key}"}[r["status"]]
        _say(f"{r['model']}: MARD {where}", err=False)


def _print_effects(effects) -> None:
    """A study's findings: costliest noise source, ranking swaps, domain shifts."""
    if "source" in effects and len(effects):
        for model, g in effects.groupby("model", sort=False):
            top = g.iloc[0]
            alone = g.sort_values("delta_only", ascending=False).iloc[0]
            _say(
                f"{model}: costliest source {top['source']} (ΔRMSE {top['delta_off']:+.2f} "
                f"mg/dL when switched off); alone: {alone['source']} "
                f"({alone['delta_only']:+.2f} mg/dL)", err=False)
    if "overtaker" in effects:
        if not len(effects):
            _say("rankings: no two models swap places between the sizes run", err=False)
        for _, r in effects.iterrows():
            _say(
                f"{r['preset']}: {r['overtaker']} overtakes {r['overtaken']} between "
                f"{r['n_before']} and {r['n_after']} training subjects (RMSE difference "
                f"{r['diff_before']:+.1f} -> {r['diff_after']:+.1f} mg/dL)", err=False)
    if "oracle_bound_rmse_mgdl" in effects:
        _print_designs(effects)
    if "rmse_vs_same_unit" in effects:
        from ..evaluation.sweep.fleet import format_fleet_table

        out_console.print(format_fleet_table(effects), markup=False, highlight=False)
    if "shift" in effects:
        for _, r in effects.iterrows():
            _say(
                f"{r['model']}: {r['shift']} shift (train {r['train_domain']}, test "
                f"{r['test_domain']}) ΔRMSE {r['delta']:+.1f} mg/dL", err=False)


def _print_designs(designs) -> None:
    """The wavelengths study: each confirmed design's bounds and RMSE per model."""
    keys = ["detector", "n_leds", "rank", "wavelengths_nm"]
    for (det, k, rank, wl), d in designs.groupby(keys, sort=False):
        r = d.iloc[0]
        scores = ", ".join(f"{m} {x:.1f}" for m, x in zip(d["model"], d["rmse_mgdl"], strict=True))
        _say(f"{det}, {k} LEDs #{rank} ({wl} nm; keeps the study's {r['study_leds_kept']}): "
             f"device bound {r['bound_rmse_mgdl']:.1f}, oracle-conditioned "
             f"{r['oracle_bound_rmse_mgdl']:.1f}; RMSE {scores} mg/dL", err=False)
