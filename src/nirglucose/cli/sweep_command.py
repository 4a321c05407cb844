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
                 "--scheduler as for the other studies), requirements (what a device would "
                 "need at published magnitudes: the least design per detector, one answer "
                 "line each, its named designs confirmed on --subjects x --per-subject "
                 "(default 60 x 3); --preset default physical, --vary "
                 "detector=study,BPW34,G17190-010K, --models the confirming models, --set "
                 "for every design)."),
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

    start = _twin_start(ctx, study, twin, twin_mode, seed, set_)
    if study == "wear":
        from .wear_command import wear_sweep

        return wear_sweep(out, vary, preset, seeds or 1, seed, models, subjects, folds,
                          resamples, set_, jobs=_jobs(jobs), scheduler=scheduler, twin=start)
    if study == "requirements":
        return requirements_sweep(ctx, out, vary, preset, seed, models, subjects, per_subject,
                                  folds, resamples, _jobs(jobs), figures, set_)
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


def _twin_start(ctx, study, twin, twin_mode, seed, set_):
    """``--twin``'s start of the sweep (None without it), refused in one line for the
    studies that cannot start from one device's twin."""
    if twin is not None and study == "data-size":
        raise UserError("--study data-size compares presets and --twin is one device: run "
                        "data-size without --twin, or benchmark --twin at each --subjects")
    if twin is not None and study == "requirements":
        raise UserError("--study requirements searches designs at the published magnitudes "
                        "from the study's device; it does not start from a twin yet: run it "
                        "without --twin (design_bound(twin_scenario(...)) gives a twin's "
                        "bound in Python)")
    return twin_start(ctx, twin, twin_mode, seed, set_=None if study == "wear" else set_,
                      own_leds=study != "wavelengths")


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


#: Sweep options with no meaning in ``--study requirements`` (parameter names), refused
#: when given.
_NOT_TAKEN = ("seeds", "repeats", "protocol", "scheduler", "calibration")
#: ``--study requirements``: the study's own photodiode with its four LEDs in
#: ``--vary detector=``.
_STUDY_DETECTOR = "study"


def _given(ctx: typer.Context, name: str) -> bool:
    return getattr(ctx.get_parameter_source(name), "name", None) == "COMMANDLINE"


def _detectors(vary: list[str] | None) -> list[str | None] | None:
    """``--vary detector=study,BPW34,...`` as the study's ``detectors`` (None: default)."""
    from ..config.parts import detector_part
    from ..exceptions import ConfigError

    out: list[str | None] | None = None
    for item in vary or []:
        key, _, values = item.partition("=")
        if key.strip() != "detector" or not values.strip():
            raise UserError(f"--vary {item!r}: --study requirements varies only the detector "
                            "(--vary detector=study,BPW34,G17190-010K; 'study' is the study's "
                            "photodiode with its four LEDs)")
        if out is not None:
            raise UserError("--vary detector=... is given twice; list all detectors once")
        out = []
        for name in (v.strip() for v in values.split(",")):
            if name == _STUDY_DETECTOR:
                out.append(None)
                continue
            try:
                detector_part(name)
            except ConfigError as exc:
                raise UserError(f"--vary {item!r}: {exc}") from None
            out.append(name)
    return out


def requirements_sweep(ctx: typer.Context, out: Path, vary: list[str] | None,
                       preset: str | None, seed: int, models: str | None, subjects: int,
                       per_subject: int, folds: int, resamples: int, jobs: int,
                       figures: bool, set_: list[str] | None = None) -> None:
    """``sweep --study requirements``: what would a device need to read glucose on real skin?

    Runs :func:`~nirglucose.evaluation.sweep.requirements.requirements_study` (the least
    design per detector at published magnitudes, confirmed by simulation), writes its
    tables, ``requirements.json`` and figures into ``--out`` and prints one answer line
    per detector. The sweep's grid options (``--seeds``, ``--repeats``, ``--protocol``,
    ``--scheduler``, ``--calibration``) do not apply and are refused when given;
    ``--set KEY=VALUE`` overrides the preset for every design (e.g.
    ``--set noise.water_temperature.enabled=true``).

    ``--subjects`` and ``--per-subject`` size each confirming simulation; left out, the
    study's defaults (60 x 3) apply, not the sweep's. ``--resamples`` left out: 500.
    """
    opts = _requirements_options(ctx, out, vary, preset, seed, models, subjects, per_subject,
                                 folds, resamples, set_)
    from ..evaluation.sweep.requirements import requirements_study

    n_subjects, n_per = opts["confirm_subjects"], opts["confirm_per_subject"]
    _say(f"requirements: searching each detector's least design in {preset or 'physical'}, "
         f"then simulating the named designs ({n_subjects} subjects x {n_per})")
    with _warnings_as_lines():
        res = requirements_study(preset or "physical", seed=seed, jobs=jobs, **opts)
        res.to_dir(out)
        written = []
        if figures:
            from ..report.requirements import save_requirements_figures

            written = save_requirements_figures(res, out / "figures")
    for line in res.answer_lines():
        _say(line, err=False)
    t = res.meta["timings_s"]
    _say(f"wrote {out}/minimal_designs.csv, requirements.json and {len(written)} figure files "
         f"({t['total_s']:.0f} s: search {t['search_s']:.0f} s, confirmation "
         f"{t['confirm_s']:.0f} s); `nirglucose report {out}` renders them", err=False)


def _requirements_options(ctx: typer.Context, out: Path, vary, preset, seed, models,
                          subjects, per_subject, folds, resamples, set_) -> dict:
    """The checked options of ``sweep --study requirements`` as the study's keywords."""
    from ..config import PRESETS
    from ..exceptions import unknown_name

    refused = [f"--{n.rstrip('_').replace('_', '-')}" for n in _NOT_TAKEN if _given(ctx, n)]
    if refused:
        raise UserError(f"{', '.join(refused)} do not apply to --study requirements (one "
                        "search per detector, its named designs confirmed once); leave them "
                        "out")
    if preset is not None and preset not in PRESETS:
        raise UserError(unknown_name("preset", preset, PRESETS))
    n_subjects = subjects if _given(ctx, "subjects") else 60
    n_per = per_subject if _given(ctx, "per_subject") else 3
    n_boot = resamples if _given(ctx, "resamples") else 500
    _check_counts(("--subjects", n_subjects), ("--per-subject", n_per), ("--folds", folds),
                  ("--resamples", n_boot))
    _check_seed(seed)
    _check_size(n_subjects, n_per)
    detectors = _detectors(vary)
    names = _model_names(models)
    if names is not None:
        from ..models.registry import available_models

        for m in names:
            if m not in available_models():
                raise UserError(unknown_name("model", m, available_models()))
    overrides = _parse_sets(set_)
    if overrides:
        from ..config import resolve_config
        from ..exceptions import ConfigError

        try:
            resolve_config(preset or "physical", overrides)
        except ConfigError as exc:
            raise UserError(f"--set: {exc}") from None
    _check_out_dir(out)
    opts: dict = {} if detectors is None else {"detectors": detectors}
    if overrides:
        opts["overrides"] = overrides
    if names is not None:
        opts["confirm_models"] = names
    opts.update(confirm_subjects=n_subjects, confirm_per_subject=n_per, confirm_folds=folds,
                confirm_resamples=n_boot)
    return opts
