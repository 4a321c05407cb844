"""Command-line interface: parses into a config, calls the library, maps errors to exit 2.

Every error a user can cause (bad option, unknown preset or key, malformed data file,
an output path that cannot be written) ends the program with exit status 2 and one
line on stderr saying what is wrong and how to fix it; no traceback. Ctrl-C ends it
with status 130 and SIGTERM with 143, each with one line; worker processes never
outlive the command (:func:`nirglucose.evaluation.executors.worker_guard`). Text
that came from the user or a file is printed without Rich markup.
"""

from __future__ import annotations

import functools
import os
import signal
import sys
from pathlib import Path
from typing import Annotated

import typer
from rich.console import Console
from rich.markup import escape
from rich.table import Table
from typer.exceptions import TyperException

from .config import PRESETS
from .exceptions import NirGlucoseError

__all__ = ["app", "main"]


#: Preset names for the --preset help texts.
_PRESET_NAMES = ", ".join(PRESETS)
#: Built-in sweep studies (kept in step with evaluation.sweep.STUDIES by a test).
_STUDY_NAMES = "noise-scale, ablation, pmf-noise, cohort, device, data-size"

app = typer.Typer(
    name="nirglucose",
    help="Simulate a noise-stressed NIR glucose sensor and benchmark estimators on it.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
)
console = Console(stderr=True)


def _version_callback(value: bool) -> None:
    if value:
        from . import __version__

        out_console.print(f"nirglucose {__version__}", markup=False, highlight=False)
        raise typer.Exit(0)


@app.callback()
def _root(
    version: Annotated[
        bool,
        typer.Option(
            "--version", help="Print the version and exit.", callback=_version_callback,
            is_eager=True,
        ),
    ] = False,
) -> None:
    """Simulate a noise-stressed NIR glucose sensor and benchmark estimators on it."""


out_console = Console()


class UserError(NirGlucoseError, ValueError):
    """A problem with the command line itself (exit status 2)."""


def _parse_sets(values: list[str] | None) -> dict:
    from .config import parse_override

    pairs = [parse_override(v) for v in (values or [])]
    for key, _ in pairs:
        if key == "preset":
            raise UserError(
                "--set preset=... would only relabel the data; choose the scenario with "
                "--preset NAME"
            )
    return dict(pairs)


def _say(text: str, *, err: bool = True) -> None:
    """Print one plain line (no markup, no highlighting) to stderr or stdout."""
    (console if err else out_console).print(
        text, markup=False, highlight=False, soft_wrap=True
    )


def _check_out_file(out: Path, what: str = "--out") -> None:
    """Refuse an output file path that names a directory or lies in no writable one."""
    if out.is_dir():
        raise UserError(f"{what} {str(out)!r} is a directory; give a file name")
    parent = out.parent
    if not parent.exists():
        raise UserError(f"output directory {str(parent)!r} does not exist; create it first")
    if not parent.is_dir():
        raise UserError(f"{what} {str(out)!r}: {str(parent)!r} is not a directory")
    if not os.access(parent, os.W_OK | os.X_OK):
        raise UserError(f"{what} {str(out)!r}: directory {str(parent)!r} is not writable")


def _check_size(subjects: int, per_subject: int) -> None:
    """Refuse a simulation that cannot fit in memory, before allocating anything."""
    from .resources import check_simulation_size

    check_simulation_size(subjects, per_subject)


def _check_jobs(jobs: int | None) -> None:
    """Warn (one line) when more workers are asked for than there are cores."""
    from .evaluation.executors import available_cores

    cores = available_cores()
    if jobs is not None and jobs > cores:
        _say(f"warning: --jobs {jobs} exceeds the {cores} available cores; "
             "the run is not faster and uses more memory")


def _tidy_out(command):
    """On failure or interrupt, remove the empty ``OUT/.tasks`` (and ``OUT`` if this
    command created it and left it empty); finished task files are kept."""

    @functools.wraps(command)
    def wrapper(*args, **kwargs):
        out = kwargs.get("out")
        existed = out is None or Path(out).exists()
        try:
            return command(*args, **kwargs)
        except BaseException:
            if out is not None:
                for d in (Path(out) / ".tasks", *(() if existed else (Path(out),))):
                    try:
                        d.rmdir()  # only when empty
                    except OSError:
                        pass
            raise

    return wrapper


def _positive(name: str, value: int) -> None:
    if value < 1:
        raise UserError(f"{name} must be a positive integer, got {value}")


SetOption = Annotated[
    list[str] | None,
    typer.Option("--set", help="Config override KEY=VALUE (dotted key), repeatable."),
]
#: --jobs of every command: the same default (the available cores) and meaning.
JobsOption = Annotated[
    int | None,
    typer.Option(help="Worker processes (default: the available cores); any value gives "
                 "the same result."),
]
#: --resamples of every command that reports bootstrap CIs.
ResamplesOption = Annotated[int, typer.Option(help="Bootstrap resamples for each 95 % CI.")]
DEFAULT_RESAMPLES = 2000


def _jobs(jobs: int | None) -> int:
    """``--jobs`` checked (positive; a warning beyond the cores), None as the cores."""
    from .evaluation.executors import available_cores

    if jobs is None:
        return available_cores()
    _positive("--jobs", jobs)
    _check_jobs(jobs)
    return jobs


@app.command()
def simulate(
    out: Annotated[Path, typer.Option(help="Output .parquet, .csv, or a directory (partitioned).")],
    preset: Annotated[
        str, typer.Option(help=f"Scenario preset: {_PRESET_NAMES}.")
    ] = "paper",
    subjects: Annotated[int, typer.Option(help="Number of subjects.")] = 80,
    per_subject: Annotated[int, typer.Option(help="Measurements per subject.")] = 3,
    seed: Annotated[int, typer.Option(help="Random seed.")] = 0,
    jobs: JobsOption = None,
    set_: SetOption = None,
) -> None:
    """Generate a dataset and print a summary of it."""
    from .config import resolve_config
    from .dataset import Dataset

    _positive("--subjects", subjects)
    _positive("--per-subject", per_subject)
    jobs = _jobs(jobs)
    if seed < 0:
        raise UserError(f"--seed must be non-negative, got {seed}")
    cfg = resolve_config(preset, _parse_sets(set_))
    if out.suffix and out.suffix not in (".parquet", ".csv"):
        raise UserError(f"--out {str(out)!r}: use a .parquet or .csv file, or a directory")
    if out.suffix:
        _check_out_file(out)
        _check_size(subjects, per_subject)
    elif out.exists() and not out.is_dir():
        raise UserError(f"--out {str(out)!r} exists and is not a directory")
    elif not out.parent.exists():
        raise UserError(f"output directory {str(out.parent)!r} does not exist; create it first")
    if not out.suffix:
        from .simulate.partitioned import write_partitioned

        n = write_partitioned(cfg, out, subjects, per_subject, seed, n_jobs=jobs)
        _say(f"wrote {n} snapshots to {out}/ (partitioned Parquet)", err=False)
        return
    from .simulate.simulator import simulate_frame

    frame = simulate_frame(cfg, subjects, per_subject, seed, n_jobs=jobs)
    ds = Dataset(frame, config=cfg, seed=seed)
    ds.save(out)
    _print_summary(ds)
    _say(f"wrote {len(ds)} snapshots to {out}", err=False)


@app.command()
def keys() -> None:
    """List every config key accepted by --set: paper preset default, unit, range, meaning."""
    from .config import resolve_config, valid_keys
    from .config_keys import key_info, key_range

    data = resolve_config("paper").model_dump(mode="json")
    for key in valid_keys():
        node = data
        for part in key.split("."):
            node = node[part]
        info = key_info(key)
        unit = f" [{info.unit}]" if info.unit else ""
        desc = f"  # {info.description}" if info.description else ""
        rng = f" ({key_range(key)})" if key_range(key) else ""
        _say(f"{key} = {node}{unit}{rng}{desc}", err=False)


@app.command("models")
def list_models() -> None:
    """List the registered model names, one line each."""
    from .models.registry import available_models, get_model_class

    for name in available_models():
        doc = (get_model_class(name).__doc__ or "").strip().splitlines()
        _say(f"{name:<20} {doc[0] if doc else ''}".rstrip(), err=False)


@app.command()
@_tidy_out
def benchmark(
    out: Annotated[Path, typer.Option(help="Output directory (created if its parent exists).")],
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
    protocol: Annotated[str, typer.Option(help="grouped-cv or paper-split.")] = "grouped-cv",
    subjects: Annotated[int, typer.Option(help="Number of subjects to simulate.")] = 80,
    per_subject: Annotated[int, typer.Option(help="Measurements per subject.")] = 3,
    folds: Annotated[int, typer.Option(help="Folds of grouped-cv.")] = 5,
    repeats: Annotated[int, typer.Option(help="Repeats of grouped-cv.")] = 3,
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
    set_: SetOption = None,
) -> None:
    """Fit and score every model on subject-grouped splits; resumable (out/.tasks)."""
    from .evaluation.splits import check_protocol
    from .models.registry import get_model_class

    for name, value in (
        ("--subjects", subjects),
        ("--per-subject", per_subject),
        ("--folds", folds),
        ("--repeats", repeats),
        ("--resamples", resamples),
    ):
        _positive(name, value)
    jobs = _jobs(jobs)
    if seed < 0:
        raise UserError(f"--seed must be non-negative, got {seed}")
    check_protocol(protocol)
    _check_calibration(calibration, None if data is not None else per_subject)
    if data is None:
        _check_size(subjects, per_subject)
    names = None
    if models is not None:
        names = [m.strip() for m in models.split(",") if m.strip()]
        if not names:
            raise UserError(f"--models {models!r} names no model")
        for name in names:
            get_model_class(name)
    if out.exists() and not out.is_dir():
        raise UserError(f"--out {str(out)!r} exists and is not a directory")
    if not out.exists() and not out.parent.exists():
        raise UserError(f"output directory {str(out.parent)!r} does not exist; create it first")
    presets = list(dict.fromkeys(p.strip() for p in preset.split(",") if p.strip()))
    if not presets:
        raise UserError(f"--preset {preset!r} names no preset")
    if len(presets) > 1 and data is not None:
        raise UserError("--data benchmarks one dataset; give one --preset or none")
    if data is not None:
        from .dataset import load_dataset

        if set_:
            raise UserError("--set changes the simulation; it cannot apply to --data")
        runs = [(None, out)]
    else:
        from .config import resolve_config

        overrides = _parse_sets(set_)
        for p in presets:
            resolve_config(p, overrides)  # an unknown preset fails before anything runs
        runs = [(p, out / p if len(presets) > 1 else out) for p in presets]
        if len(presets) > 1:
            out.mkdir(exist_ok=True)
    for p, run_out in runs:
        if p is None:
            ds = load_dataset(data)
        else:
            from .api import simulate as _simulate

            ds = _simulate(p, subjects, per_subject, seed, overrides=overrides)
        _benchmark_one(ds, names, protocol, folds, repeats, seed, run_out, jobs, resamples,
                       references, ablation, calibration)


def _check_calibration(k: int, per_subject: int | None) -> None:
    if k not in (0, 1, 2):
        raise UserError(f"--calibration must be 0, 1 or 2 readings per person, got {k}")
    if k and per_subject is not None and per_subject <= k:
        raise UserError(
            f"--calibration {k} leaves no reading to score at --per-subject {per_subject}; "
            f"use --per-subject {k + 2} or more"
        )


def _benchmark_one(ds, names, protocol, folds, repeats, seed, out, jobs, resamples,
                   references, ablation, calibration=0) -> None:
    import warnings

    from .evaluation.benchmark import run_benchmark

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        res = run_benchmark(
            ds,
            names,
            protocol=protocol,
            n_splits=folds,
            repeats=repeats,
            seed=seed,
            out=out,
            jobs=jobs,
            progress=True,
            n_boot=resamples,
            references=references,
            ablation=ablation,
            calibration=calibration,
        )
    for msg in dict.fromkeys(str(w.message).replace("\n", " ") for w in caught):
        _say(f"warning: {msg}")
    import numpy as np
    from rich import box

    table = Table(title=escape(f"benchmark ({res.meta['protocol']}): {ds!r}"),
                  box=box.SIMPLE_HEAD)
    for col in ("model", "RMSE mg/dL (95% CI)", "MARD %", "Clarke A %", "90% PI cover/width",
                "params", "ms"):
        table.add_column(col, justify="left" if col == "model" else "right", no_wrap=True)
    for _, r in res.metrics.iterrows():
        table.add_row(
            escape(str(r["model"])),
            f"{r['rmse_mgdl']:.1f} ({r['rmse_ci_low']:.1f}-{r['rmse_ci_high']:.1f})",
            f"{r['mard_pct']:.1f}",
            f"{r['clarke_a_pct']:.1f}",
            (f"{r['coverage90_pct']:.0f}% / {r['width90_mgdl']:.0f}"
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
    _say(
        f"wrote results to {out}/ ({m['tasks_computed']} tasks computed, "
        f"{m['tasks_cached']} reused, {m['wall_time_s']:.0f} s)",
        err=False,
    )


@app.command()
@_tidy_out
def sweep(
    out: Annotated[Path, typer.Option(help="Output directory (created if its parent exists).")],
    vary: Annotated[
        list[str] | None,
        typer.Option(help="KEY=V1,V2,... config values to sweep (dotted key); repeat for a grid."),
    ] = None,
    study: Annotated[
        str | None,
        typer.Option(help=f"Built-in study: {_STUDY_NAMES}."),
    ] = None,
    preset: Annotated[
        str | None,
        typer.Option(help=f"Scenario preset every task starts from: {_PRESET_NAMES} (default "
                     "paper); data-size: comma-separated presets (default paper,wearable)."),
    ] = None,
    seeds: Annotated[
        int | None,
        typer.Option(help="Seeds per scenario (seed, seed+1, ...); default 5, data-size 1."),
    ] = None,
    seed: Annotated[int, typer.Option(help="First seed.")] = 0,
    models: Annotated[
        str | None,
        typer.Option(help="Comma-separated model names (default: ebl,pls,oracle; data-size: all)."),
    ] = None,
    protocol: Annotated[str, typer.Option(help="grouped-cv or paper-split.")] = "grouped-cv",
    subjects: Annotated[int, typer.Option(help="Subjects per simulated dataset.")] = 80,
    per_subject: Annotated[int, typer.Option(help="Measurements per subject.")] = 3,
    folds: Annotated[int, typer.Option(help="Folds of grouped-cv.")] = 5,
    repeats: Annotated[int, typer.Option(help="Repeats of grouped-cv.")] = 3,
    resamples: ResamplesOption = DEFAULT_RESAMPLES,
    jobs: JobsOption = None,
    scheduler: Annotated[
        str | None,
        typer.Option(help="Dask scheduler address, e.g. tcp://host:8786, or 'local': a "
                     "Dask cluster of --jobs worker processes started for this run."),
    ] = None,
    figures: Annotated[bool, typer.Option(help="Write figures to OUT/figures.")] = True,
    calibration: Annotated[
        int,
        typer.Option(
            help="Personal calibration: each test subject's first K readings (1 or 2) "
            "calibrate them and only later readings are scored (sweep.csv: "
            "later_rmse_mgdl, offset_rmse_mgdl, ...); 0: none. "
            "Needs --per-subject > K."
        ),
    ] = 0,
    set_: SetOption = None,
) -> None:
    """Sweep scenarios x seeds x models (local processes or Dask); resumable (out/.tasks)."""
    import warnings

    from .evaluation.sweep import DEFAULT_MODELS, parse_vary, run_sweep, threshold_crossing
    from .models.registry import available_models

    if seeds is None:
        seeds = 1 if study == "data-size" else 5

    for name, value in (("--subjects", subjects), ("--per-subject", per_subject),
                        ("--folds", folds), ("--repeats", repeats), ("--seeds", seeds),
                        ("--resamples", resamples)):
        _positive(name, value)
    jobs = _jobs(jobs)
    if seed < 0:
        raise UserError(f"--seed must be non-negative, got {seed}")
    _check_size(subjects, per_subject)
    _check_calibration(calibration, per_subject)
    if study is None and not vary:
        raise UserError("give --vary KEY=V1,V2,... or --study NAME")
    grid: dict = {}
    for text in vary or []:
        key, values = parse_vary(text)
        if key in grid:
            raise UserError(f"--vary {key} is given twice; list all its values once")
        grid[key] = values
    if models is None and study == "data-size":
        names = available_models()
    elif models is None:
        names = [m for m in DEFAULT_MODELS if m in available_models()]
    else:
        names = [m.strip() for m in models.split(",") if m.strip()]
        if not names:
            raise UserError(f"--models {models!r} names no model")
    if out.exists() and not out.is_dir():
        raise UserError(f"--out {str(out)!r} exists and is not a directory")
    if not out.exists() and not out.parent.exists():
        raise UserError(f"output directory {str(out.parent)!r} does not exist; create it first")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        res = run_sweep(grid or None, study=study, preset=preset,
                        seeds=list(range(seed, seed + seeds)), models=names,
                        overrides=_parse_sets(set_), protocol=protocol, n_splits=folds,
                        repeats=repeats, n_subjects=subjects, per_subject=per_subject,
                        n_boot=resamples, out=out, jobs=jobs, scheduler=scheduler,
                        progress=True, calibration=calibration)
        if figures:
            from .report.sweep import save_sweep_figures

            save_sweep_figures(out)
    msgs = [str(w.message) for w in caught] + res.meta["warnings"]
    for msg in dict.fromkeys(m.replace("\n", " ") for m in msgs):
        _say(f"warning: {msg}")
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
        key = meta["varied"][0]
        for _, r in threshold_crossing(s, key).iterrows():
            where = {"crosses": f"crosses 15 % at {key} = {r['crossing']:.2f}",
                     "above at every x": f"is above 15 % at every {key}",
                     "below at every x": f"stays below 15 % at every {key}"}[r["status"]]
            _say(f"{r['model']}: MARD {where}", err=False)
    if res.effects is not None and "source" in res.effects and len(res.effects):
        for model, g in res.effects.groupby("model", sort=False):
            top = g.iloc[0]
            alone = g.sort_values("delta_only", ascending=False).iloc[0]
            _say(
                f"{model}: costliest source {top['source']} (ΔRMSE {top['delta_off']:+.2f} "
                f"mg/dL when switched off); alone: {alone['source']} "
                f"({alone['delta_only']:+.2f} mg/dL)", err=False)
    if res.effects is not None and "overtaker" in res.effects:
        if not len(res.effects):
            _say("rankings: no two models swap places between the sizes run", err=False)
        for _, r in res.effects.iterrows():
            _say(
                f"{r['preset']}: {r['overtaker']} overtakes {r['overtaken']} between "
                f"{r['n_before']} and {r['n_after']} training subjects (RMSE difference "
                f"{r['diff_before']:+.1f} -> {r['diff_after']:+.1f} mg/dL)", err=False)
    if res.effects is not None and "shift" in res.effects:
        for _, r in res.effects.iterrows():
            _say(
                f"{r['model']}: {r['shift']} shift (train {r['train_domain']}, test "
                f"{r['test_domain']}) ΔRMSE {r['delta']:+.1f} mg/dL", err=False)
    _say(f"wrote {out}/sweep.csv ({meta['tasks_computed']} tasks computed, "
         f"{meta['tasks_cached']} reused, {meta['wall_time_s']:.0f} s)", err=False)


@app.command("fit")
def fit_model(
    model: Annotated[str, typer.Option(help="Registered model name, e.g. ebl, pls, sdnn.")],
    data: Annotated[Path, typer.Option(help="Measurements (.parquet or .csv) with glucose_mgdl.")],
    out: Annotated[Path, typer.Option(help="Model file to write (.json).")],
    adc_bits: Annotated[
        int | None,
        typer.Option(help="The device's ADC resolution [bit] (default: the file's, else 12)."),
    ] = None,
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
    seed: Annotated[int, typer.Option(help="Seed of the draw of calibration subjects.")] = 0,
) -> None:
    """Fit a model on your own measurements (any LEDs, any ADC) and save it.

    With intervals, a share of the subjects (never used for fitting) calibrates
    subject-grouped split-conformal 90 % and 80 % intervals, saved with the model.
    """
    from .dataset import load_dataset
    from .evaluation.conformal import calibration_subjects, split_conformal
    from .models import make_model

    if out.suffix != ".json":
        raise UserError(f"--out {str(out)!r}: the model file must end in .json")
    if intervals not in ("auto", "split", "none"):
        raise UserError(f"--intervals must be auto, split or none, got {intervals!r}")
    if not 0.0 < calibration_share < 1.0:
        raise UserError(f"--calibration-share must lie in (0, 1), got {calibration_share}")
    _check_out_file(out)
    estimator = make_model(model)  # unknown names raise with the valid ones
    ds = load_dataset(data)
    if adc_bits is not None:
        ds.metadata["adc_bits"] = adc_bits  # the declared resolution, read by the schema
    if model != "oracle":
        from .schema import DeviceSchema

        DeviceSchema.infer(ds, adc_bits)  # a device file: adc_<nm> columns (DataError)
    note = ""
    if intervals == "auto":
        n_sub = ds.frame["subject_id"].nunique() if "subject_id" in ds.frame else 0
        n_cal = round(calibration_share * n_sub)
        intervals = "split" if 9 <= n_cal < n_sub else "none"  # 9: ceil(0.9 (n+1)) <= n
        if intervals == "none":
            note = f"; no intervals ({n_sub} subjects: too few to hold out 9 to calibrate)"
    if intervals == "split":
        if "subject_id" not in ds.frame:
            raise UserError("--intervals split needs a subject_id column to hold out subjects")
        split_conformal(estimator, ds, share=calibration_share, seed=seed)
        cal = estimator.conformal_
        n_fit = int((~calibration_subjects(ds.frame["subject_id"].to_numpy(),
                                           calibration_share, seed)).sum())
        note = (
            f"; 90 % interval ±{cal['half_width_mgdl']['90']:.1f} mg/dL from "
            f"{cal['n_calibration_subjects']} held-out subjects"
        )
    else:
        estimator.fit(ds)
        n_fit = len(ds)
    estimator.save(out)
    device = estimator.schema_.describe() if hasattr(estimator, "schema_") else "simulated"
    _say(f"fitted {model!r} on {n_fit} measurements ({device}){note}; wrote {out}", err=False)


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
) -> None:
    """Predict glucose for your own measurements; writes predicted_glucose_mgdl and flag.

    ``glucose_lower_mgdl`` / ``glucose_upper_mgdl`` bound the 90 % prediction interval
    when the model carries a calibration (empty otherwise). ``flag`` is ``LO`` / ``HI``
    where the estimate lies below 20 / above 600 mg/dL, as a meter shows it (the number
    itself is kept). With ``--calibration``, ``calibrated`` says which rows a person's
    calibration readings corrected.
    """
    import numpy as np
    import pandas as pd

    from .dataset import atomic_write, load_dataset
    from .evaluation.calibration import apply_offset
    from .evaluation.conformal import calibration_of, interval
    from .models import load_model
    from .models._validate import check_predictions
    from .schema import meter_flags

    if out.suffix != ".csv":
        raise UserError(f"--out {str(out)!r}: predictions are written as .csv")
    _check_out_file(out)
    estimator = load_model(model)
    ds = load_dataset(data)
    pred = np.asarray(check_predictions(estimator.predict(ds), model), dtype=float)
    calibrated = None
    if calibration is not None:
        cal = load_dataset(calibration)
        for name, frame in (("--calibration", cal.frame), ("--data", ds.frame)):
            if "subject_id" not in frame.columns:
                raise UserError(f"{name} needs a subject_id column to match people")
        if "glucose_mgdl" not in cal.frame.columns:
            raise UserError("--calibration needs the reference glucose_mgdl of each reading")
        cal_pred = check_predictions(estimator.predict(cal), calibration)
        pred, calibrated = apply_offset(
            pred,
            ds.frame["subject_id"].to_numpy(),
            cal_pred,
            cal.frame["glucose_mgdl"].to_numpy(float),
            cal.frame["subject_id"].to_numpy(),
        )
    ids = [c for c in ("measurement_id", "subject_id") if c in ds.frame.columns]
    table = ds.frame[ids].reset_index(drop=True).copy()
    table["predicted_glucose_mgdl"] = pd.Series(pred, dtype=float).to_numpy()
    lower = np.full(len(pred), np.nan)
    upper = np.full(len(pred), np.nan)
    cal_doc = calibration_of(estimator)
    if cal_doc is not None:
        lower, upper = interval(estimator, pred, 0.9)
        if calibrated is not None and (cal_doc.get("half_width_offset1_mgdl") or {}).get("90"):
            lo_c, up_c = interval(estimator, pred, 0.9, offset_calibrated=True)
            lower, upper = np.where(calibrated, lo_c, lower), np.where(calibrated, up_c, upper)
        lower = np.maximum(lower, 0.0)
    table["glucose_lower_mgdl"] = lower
    table["glucose_upper_mgdl"] = upper
    table["flag"] = meter_flags(pred)
    if calibrated is not None:
        table["calibrated"] = calibrated
    atomic_write(out, lambda tmp: table.to_csv(tmp, index=False))
    n_flag = int((table["flag"] != "").sum())
    flagged = f" ({n_flag} outside 20-600 mg/dL, flagged LO/HI)" if n_flag else ""
    cal_note = (
        f"; {int(calibrated.sum())} calibrated by their person's readings"
        if calibrated is not None
        else ""
    )
    no_int = "" if cal_doc is not None else "; the model carries no interval calibration"
    _say(f"predicted {len(table)} measurements{flagged}{cal_note}{no_int}; wrote {out}",
         err=False)


@app.command("export-c")
def export_c_source(
    model: Annotated[Path, typer.Option(help="Linear model file (ebl or pls) from `fit`.")],
    out: Annotated[Path, typer.Option(help="Output directory for the .h and .c files.")],
) -> None:
    """Write C99 source + header of a linear model for a microcontroller."""
    from .export import export_c
    from .models import load_model

    header, source = export_c(load_model(model), out)
    _say(f"wrote {header} and {source}", err=False)


@app.command()
def report(
    results: Annotated[Path, typer.Argument(help="Results directory of `nirglucose benchmark`.")],
    out: Annotated[
        Path | None, typer.Option(help="HTML file to write (default: RESULTS/report.html).")
    ] = None,
    figures: Annotated[
        Path | None, typer.Option(help="Also write every figure here as PNG and SVG.")
    ] = None,
    sweep: Annotated[
        list[Path] | None,
        typer.Option(help="A `nirglucose sweep` output directory to add (repeatable)."),
    ] = None,
) -> None:
    """Write the figures and tables of a benchmark run as one self-contained HTML file."""
    from .report import build_report

    _check_results_dir(results)
    if out is not None:
        _check_out_file(out)
    for d in sweep or []:
        if not (d / "sweep.csv").exists():
            raise UserError(f"--sweep {str(d)!r} holds no sweep.csv; run `nirglucose sweep` first")
    path = build_report(results, out if out is not None else results / "report.html",
                        figures_dir=figures, sweep_dirs=sweep or [])
    _say(f"wrote {path}", err=False)


def _check_results_dir(results: Path) -> None:
    """Name the real problem with a `report` RESULTS argument."""
    if not results.exists():
        raise UserError(
            f"results directory {str(results)!r} does not exist; give the --out directory "
            "of `nirglucose benchmark`"
        )
    if not results.is_dir():
        raise UserError(
            f"{str(results)!r} is a file, not a results directory; give the --out "
            "directory of `nirglucose benchmark`"
        )
    from .report.presets import preset_dirs

    has_run = any((results / f).is_file() for f in ("meta.json", "metrics.csv", "metrics.json"))
    if not has_run and not preset_dirs(results):  # a run, or one run per preset
        raise UserError(
            f"{str(results)!r} holds no meta.json or metrics; it is not the output of "
            "`nirglucose benchmark` (run it first)"
        )


def _print_summary(ds) -> None:
    import numpy as np

    frame = ds.frame
    table = Table(title=escape(f"{ds!r}"))
    for col in ("column", "mean", "sd", "min", "max", "r(glucose, log ADC)"):
        table.add_column(col, justify="right" if col != "column" else "left")
    g = frame["glucose_mgdl"].to_numpy(float)
    for c in ["glucose_mgdl"] + [c for c in frame.columns if c.startswith("adc_")]:
        v = frame[c].to_numpy(float)
        r = ""
        if c.startswith("adc_") and not c.startswith("adc_ref") and np.std(v) > 0:
            r = f"{np.corrcoef(g, np.log(v))[0, 1]:+.3f}"
        table.add_row(
            escape(c), f"{v.mean():.1f}", f"{v.std(ddof=1):.1f}", f"{v.min():.0f}",
            f"{v.max():.0f}", r,
        )
    out_console.print(table)


class _Signals:
    """Turns SIGINT / SIGTERM into KeyboardInterrupt once, remembering which came."""

    def __init__(self) -> None:
        self.received: int | None = None
        self.saved: dict[int, object] = {}

    def _handler(self, signum, frame) -> None:
        if self.received is not None:  # a second signal while stopping: keep stopping
            return
        self.received = signum
        raise KeyboardInterrupt

    def __enter__(self) -> _Signals:
        import threading

        if threading.current_thread() is threading.main_thread():
            for sig in (signal.SIGINT, signal.SIGTERM):
                self.saved[sig] = signal.signal(sig, self._handler)
        return self

    def __exit__(self, *exc) -> None:
        for sig, old in self.saved.items():
            signal.signal(sig, old)


def _interrupted(signals: _Signals) -> int:
    if signals.received == signal.SIGTERM:
        _say("error: terminated (SIGTERM); finished results were kept, rerun to resume")
        return 128 + signal.SIGTERM
    _say("error: interrupted; finished results were kept, rerun to resume")
    return 130


def _user_path(name: object) -> str:
    """The file the user named, for an atomic write's temporary ``DIR/.NAME.xxxx.tmp``."""
    import re

    m = re.fullmatch(r"(.*/)?\.(.+)\.[A-Za-z0-9_]+\.tmp", str(name))
    return f"{m.group(1) or ''}{m.group(2)}" if m else str(name)


def _one_line(text: object) -> str:
    return " ".join(str(text).split())


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``nirglucose`` console script.

    Returns
    -------
    int
        0 on success, 2 for any user error (one line on stderr), 130 after Ctrl-C,
        143 after SIGTERM.
    """
    import numpy as np

    from .evaluation.executors import worker_guard

    with _Signals() as signals:
        try:
            # numpy's overflow chatter would add lines; a result that overflowed is
            # refused by the library (non-finite ADC input, model checks) in one line
            with worker_guard(), np.errstate(over="ignore", invalid="ignore", divide="ignore"):
                rv = app(args=argv, standalone_mode=False)
        except typer.Exit as exc:
            return int(getattr(exc, "exit_code", 0) or 0)
        except typer.Abort:
            return _interrupted(signals)
        except TyperException as exc:
            fmt = getattr(exc, "format_message", None)
            msg = _one_line(fmt() if fmt else exc)
            if not msg:  # help was shown for a bare command
                return 2
            _say(f"error: {msg} (see `nirglucose --help`)")
            return 2
        except NirGlucoseError as exc:
            _say(f"error: {_one_line(exc)}")
            return 2
        except KeyboardInterrupt:
            return _interrupted(signals)
        except MemoryError:
            _say("error: out of memory; use fewer subjects, measurements or jobs")
            return 2
        except OSError as exc:  # a file the user named cannot be read or written
            where = f" {_user_path(exc.filename)!r}" if exc.filename else ""
            _say(f"error: cannot access{where}: {exc.strerror or _one_line(exc)}")
            return 2
    code = rv if isinstance(rv, int) and not isinstance(rv, bool) else 0
    if code == 130:  # typer turns KeyboardInterrupt into exit 130 and returns it
        return _interrupted(signals)
    return code


if __name__ == "__main__":
    sys.exit(main())
