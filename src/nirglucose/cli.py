"""Command-line interface: parses into a config, calls the library, maps errors to exit 2.

Every error a user can cause (bad option, unknown preset or key, malformed data file)
ends the program with exit status 2 and one line on stderr saying what is wrong and
how to fix it; no traceback.
"""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Annotated

import typer
from rich.console import Console
from rich.table import Table
from typer.exceptions import TyperException

from .exceptions import NirGlucoseError

__all__ = ["app", "main"]

app = typer.Typer(
    name="nirglucose",
    help="Simulate a noise-stressed NIR glucose sensor and benchmark estimators on it.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
)
console = Console(stderr=True)


@app.callback()
def _root() -> None:
    """Simulate a noise-stressed NIR glucose sensor and benchmark estimators on it."""


out_console = Console()


class UserError(NirGlucoseError, ValueError):
    """A problem with the command line itself (exit status 2)."""


def _parse_sets(values: list[str] | None) -> dict:
    from .config import parse_override

    return dict(parse_override(v) for v in (values or []))


def _positive(name: str, value: int) -> None:
    if value < 1:
        raise UserError(f"{name} must be a positive integer, got {value}")


SetOption = Annotated[
    list[str] | None,
    typer.Option("--set", help="Config override KEY=VALUE (dotted key), repeatable."),
]


@app.command()
def simulate(
    out: Annotated[Path, typer.Option(help="Output .parquet, .csv, or a directory (partitioned).")],
    preset: Annotated[
        str, typer.Option(help="Scenario preset: paper, physical, lab, field.")
    ] = "paper",
    subjects: Annotated[int, typer.Option(help="Number of subjects.")] = 80,
    per_subject: Annotated[int, typer.Option(help="Measurements per subject.")] = 3,
    seed: Annotated[int, typer.Option(help="Random seed.")] = 0,
    jobs: Annotated[int, typer.Option(help="Worker processes (same result for any value).")] = 1,
    set_: SetOption = None,
) -> None:
    """Generate a dataset and print a summary of it."""
    from .config import resolve_config
    from .dataset import Dataset

    _positive("--subjects", subjects)
    _positive("--per-subject", per_subject)
    _positive("--jobs", jobs)
    if seed < 0:
        raise UserError(f"--seed must be non-negative, got {seed}")
    cfg = resolve_config(preset, _parse_sets(set_))
    if out.suffix and out.suffix not in (".parquet", ".csv"):
        raise UserError(f"--out {str(out)!r}: use a .parquet or .csv file, or a directory")
    if not out.parent.exists():
        raise UserError(f"output directory {str(out.parent)!r} does not exist; create it first")
    if not out.suffix:
        from .simulate.partitioned import write_partitioned

        n = write_partitioned(cfg, out, subjects, per_subject, seed, n_jobs=jobs)
        out_console.print(f"wrote {n} snapshots to {out}/ (partitioned Parquet)")
        return
    from .simulate.simulator import simulate_frame

    frame = simulate_frame(cfg, subjects, per_subject, seed, n_jobs=jobs)
    ds = Dataset(frame, config=cfg, seed=seed)
    ds.save(out)
    _print_summary(ds)
    out_console.print(f"wrote {len(ds)} snapshots to {out}")


@app.command()
def keys() -> None:
    """List every config key accepted by --set, with its default on the paper preset."""
    from .config import resolve_config, valid_keys

    data = resolve_config("paper").model_dump(mode="json")
    for key in valid_keys():
        node = data
        for part in key.split("."):
            node = node[part]
        out_console.print(f"{key} = {node}", highlight=False, soft_wrap=True)


@app.command()
def benchmark(
    out: Annotated[Path, typer.Option(help="Output directory (created if its parent exists).")],
    preset: Annotated[
        str,
        typer.Option(
            help="Scenario preset to simulate; several comma-separated (paper,wearable) "
            "write OUT/<preset>/ each."
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
    jobs: Annotated[int, typer.Option(help="Worker processes (same result for any value).")] = 1,
    resamples: Annotated[int, typer.Option(help="Bootstrap resamples for the CIs.")] = 2000,
    references: Annotated[
        bool, typer.Option(help="Add the reference rows (mean, gp, gbr) to --models.")
    ] = True,
    ablation: Annotated[
        bool, typer.Option(help="Also run each PINN with its physics term off (lambda_phys=0).")
    ] = True,
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
        ("--jobs", jobs),
        ("--resamples", resamples),
    ):
        _positive(name, value)
    if seed < 0:
        raise UserError(f"--seed must be non-negative, got {seed}")
    check_protocol(protocol)
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
                       references, ablation)


def _benchmark_one(ds, names, protocol, folds, repeats, seed, out, jobs, resamples,
                   references, ablation) -> None:
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
            progress=sys.stderr.isatty(),
            n_boot=resamples,
            references=references,
            ablation=ablation,
        )
    for msg in dict.fromkeys(str(w.message).replace("\n", " ") for w in caught):
        console.print(f"warning: {msg}", highlight=False, soft_wrap=True)
    from rich import box

    table = Table(title=f"benchmark ({res.meta['protocol']}): {ds!r}", box=box.SIMPLE_HEAD)
    for col in ("model", "RMSE mg/dL (95% CI)", "MARD %", "Clarke A %", "params", "ms"):
        table.add_column(col, justify="left" if col == "model" else "right", no_wrap=True)
    for _, r in res.metrics.iterrows():
        table.add_row(
            r["model"],
            f"{r['rmse_mgdl']:.1f} ({r['rmse_ci_low']:.1f}-{r['rmse_ci_high']:.1f})",
            f"{r['mard_pct']:.1f}",
            f"{r['clarke_a_pct']:.1f}",
            f"{int(r['n_parameters']):,}",
            f"{r['latency_single_ms']:.3f}",
        )
    # not a terminal (a log file, make): wide enough that no column is truncated
    (out_console if out_console.is_terminal else Console(width=110)).print(table)
    m = res.meta
    out_console.print(
        f"wrote results to {out}/ ({m['tasks_computed']} tasks computed, "
        f"{m['tasks_cached']} reused, {m['wall_time_s']:.0f} s)",
        highlight=False,
        soft_wrap=True,
    )


@app.command()
def sweep(
    out: Annotated[Path, typer.Option(help="Output directory (created if its parent exists).")],
    vary: Annotated[
        list[str] | None,
        typer.Option(help="KEY=V1,V2,... config values to sweep (dotted key); repeat for a grid."),
    ] = None,
    study: Annotated[
        str | None,
        typer.Option(help="Built-in study: noise-scale, ablation, pmf-noise, cohort, data-size."),
    ] = None,
    preset: Annotated[
        str | None,
        typer.Option(help="Scenario preset every task starts from (default paper); "
                     "data-size: comma-separated presets (default paper,wearable)."),
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
    resamples: Annotated[int, typer.Option(help="Bootstrap resamples per task.")] = 1000,
    jobs: Annotated[
        int | None, typer.Option(help="Local worker processes (default: available cores).")
    ] = None,
    scheduler: Annotated[
        str | None, typer.Option(help="Dask scheduler address, e.g. tcp://host:8786.")
    ] = None,
    figures: Annotated[bool, typer.Option(help="Write figures to OUT/figures.")] = True,
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
    if jobs is not None:
        _positive("--jobs", jobs)
    if seed < 0:
        raise UserError(f"--seed must be non-negative, got {seed}")
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
                        progress=sys.stderr.isatty())
        if figures:
            from .report.sweep import save_sweep_figures

            save_sweep_figures(out)
    msgs = [str(w.message) for w in caught] + res.meta["warnings"]
    for msg in dict.fromkeys(m.replace("\n", " ") for m in msgs):
        console.print(f"warning: {msg}", highlight=False, soft_wrap=True)
    meta = res.meta
    s = res.summary
    table = Table(title=f"sweep {meta['study']}: mean over {len(meta['seeds'])} seeds "
                  "[95 % CI over seeds]")
    for col in ("scenario", "model", "RMSE mg/dL", "MARD %", "Clarke A %"):
        table.add_column(col, justify="left" if col in ("scenario", "model") else "right")
    for _, r in s.iterrows():
        table.add_row(str(r["scenario"]), str(r["model"]),
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
            out_console.print(f"{r['model']}: MARD {where}", highlight=False)
    if res.effects is not None and "source" in res.effects and len(res.effects):
        for model, g in res.effects.groupby("model", sort=False):
            top = g.iloc[0]
            alone = g.sort_values("delta_only", ascending=False).iloc[0]
            out_console.print(
                f"{model}: costliest source {top['source']} (ΔRMSE {top['delta_off']:+.2f} "
                f"mg/dL when switched off); alone: {alone['source']} "
                f"({alone['delta_only']:+.2f} mg/dL)", highlight=False)
    if res.effects is not None and "overtaker" in res.effects:
        if not len(res.effects):
            out_console.print("rankings: no two models swap places between the sizes run",
                              highlight=False)
        for _, r in res.effects.iterrows():
            out_console.print(
                f"{r['preset']}: {r['overtaker']} overtakes {r['overtaken']} between "
                f"{r['n_before']} and {r['n_after']} training subjects (RMSE difference "
                f"{r['diff_before']:+.1f} -> {r['diff_after']:+.1f} mg/dL)", highlight=False)
    if res.effects is not None and "shift" in res.effects:
        for _, r in res.effects.iterrows():
            out_console.print(
                f"{r['model']}: {r['shift']} shift (train {r['train_domain']}, test "
                f"{r['test_domain']}) ΔRMSE {r['delta']:+.1f} mg/dL", highlight=False)
    out_console.print(f"wrote {out}/sweep.csv ({meta['tasks_computed']} tasks computed, "
                      f"{meta['tasks_cached']} reused, {meta['wall_time_s']:.0f} s)",
                      highlight=False)


@app.command("fit")
def fit_model(
    model: Annotated[str, typer.Option(help="Registered model name, e.g. ebl, pls, sdnn.")],
    data: Annotated[Path, typer.Option(help="Measurements (.parquet or .csv) with glucose_mgdl.")],
    out: Annotated[Path, typer.Option(help="Model file to write (.json).")],
) -> None:
    """Fit a model on your own measurements and save it."""
    from .dataset import load_dataset, validate_measurements
    from .models import make_model

    if out.suffix != ".json":
        raise UserError(f"--out {str(out)!r}: the model file must end in .json")
    if not out.parent.exists():
        raise UserError(f"output directory {str(out.parent)!r} does not exist; create it first")
    estimator = make_model(model)  # unknown names raise with the valid ones
    ds = load_dataset(data)
    validate_measurements(ds.frame, require_target=True)
    estimator.fit(ds)
    estimator.save(out)
    out_console.print(f"fitted {model!r} on {len(ds)} measurements; wrote {out}")


@app.command("predict")
def predict_glucose(
    model: Annotated[Path, typer.Option(help="Model file written by `nirglucose fit`.")],
    data: Annotated[Path, typer.Option(help="Measurements (.parquet or .csv).")],
    out: Annotated[Path, typer.Option(help="Predictions to write (.csv).")],
) -> None:
    """Predict glucose for your own measurements; writes predicted_glucose_mgdl."""
    import pandas as pd

    from .dataset import atomic_write, load_dataset, validate_measurements
    from .models import load_model

    if out.suffix != ".csv":
        raise UserError(f"--out {str(out)!r}: predictions are written as .csv")
    if not out.parent.exists():
        raise UserError(f"output directory {str(out.parent)!r} does not exist; create it first")
    estimator = load_model(model)
    ds = load_dataset(data)
    validate_measurements(ds.frame)
    pred = estimator.predict(ds)
    ids = [c for c in ("measurement_id", "subject_id") if c in ds.frame.columns]
    table = ds.frame[ids].reset_index(drop=True).copy()
    table["predicted_glucose_mgdl"] = pd.Series(pred, dtype=float).to_numpy()
    atomic_write(out, lambda tmp: table.to_csv(tmp, index=False))
    out_console.print(f"predicted {len(table)} measurements; wrote {out}")


@app.command("export-c")
def export_c_source(
    model: Annotated[Path, typer.Option(help="Linear model file (ebl or pls) from `fit`.")],
    out: Annotated[Path, typer.Option(help="Output directory for the .h and .c files.")],
) -> None:
    """Write C99 source + header of a linear model for a microcontroller."""
    from .export import export_c
    from .models import load_model

    header, source = export_c(load_model(model), out)
    out_console.print(f"wrote {header} and {source}")


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

    for d in sweep or []:
        if not (d / "sweep.csv").exists():
            raise UserError(f"--sweep {str(d)!r} holds no sweep.csv; run `nirglucose sweep` first")
    path = build_report(results, out if out is not None else results / "report.html",
                        figures_dir=figures, sweep_dirs=sweep or [])
    out_console.print(f"wrote {path}", highlight=False, soft_wrap=True)


def _print_summary(ds) -> None:
    import numpy as np

    frame = ds.frame
    table = Table(title=f"{ds!r}")
    for col in ("column", "mean", "sd", "min", "max", "r(glucose, log ADC)"):
        table.add_column(col, justify="right" if col != "column" else "left")
    g = frame["glucose_mgdl"].to_numpy(float)
    for c in ["glucose_mgdl"] + [c for c in frame.columns if c.startswith("adc_")]:
        v = frame[c].to_numpy(float)
        r = ""
        if c.startswith("adc_") and not c.startswith("adc_ref") and np.std(v) > 0:
            r = f"{np.corrcoef(g, np.log(v))[0, 1]:+.3f}"
        table.add_row(
            c, f"{v.mean():.1f}", f"{v.std(ddof=1):.1f}", f"{v.min():.0f}", f"{v.max():.0f}", r
        )
    out_console.print(table)


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``nirglucose`` console script."""
    try:
        app(args=argv, standalone_mode=False)
    except typer.Exit as exc:
        return int(getattr(exc, "exit_code", 0) or 0)
    except typer.Abort:
        console.print("error: aborted")
        return 130
    except TyperException as exc:
        fmt = getattr(exc, "format_message", None)
        msg = (fmt() if fmt else str(exc)).replace("\n", " ").strip()
        if not msg:  # help was shown for a bare command
            return 2
        console.print(f"error: {msg} (see `nirglucose --help`)", highlight=False, soft_wrap=True)
        return 2
    except NirGlucoseError as exc:
        console.print(f"error: {exc}", highlight=False, soft_wrap=True)
        return 2
    except KeyboardInterrupt:
        console.print("error: interrupted; finished results were kept, rerun to resume")
        return 130
    return 0


if __name__ == "__main__":
    sys.exit(main())
