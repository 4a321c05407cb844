"""Commands about the simulated data: ``simulate``, ``keys`` and ``models``."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer
from rich.markup import escape
from rich.table import Table

from ._app import app, out_console
from ._common import (
    _PRESET_NAMES,
    JobsOption,
    PerSubjectOption,
    SetOption,
    TwinModeOption,
    TwinOption,
    UserError,
    _check_counts,
    _check_out_dir,
    _check_out_file,
    _check_seed,
    _check_size,
    _jobs,
    _parse_sets,
    _say,
    runs_workers,
    twin_base,
)


@app.command()
@runs_workers
def simulate(
    ctx: typer.Context,
    out: Annotated[Path, typer.Option(help="Output .parquet, .csv, or a directory (partitioned).")],
    preset: Annotated[
        str, typer.Option(help=f"Scenario preset: {_PRESET_NAMES}.")
    ] = "paper",
    subjects: Annotated[int, typer.Option(help="Number of subjects.")] = 80,
    per_subject: PerSubjectOption = 3,
    seed: Annotated[int, typer.Option(help="Random seed.")] = 0,
    jobs: JobsOption = None,
    set_: SetOption = None,
    wear_days: Annotated[
        int | None,
        typer.Option(help="Simulate a device worn this many days by each subject (a reading "
                     "every --every-min minutes; glucose from the UVA/Padova meal model) "
                     "instead of independent snapshots; rows get time_min, wear_day and "
                     "seating_id."),
    ] = None,
    every_min: Annotated[
        int | None,
        typer.Option(help="Minutes between the readings of a --wear-days run (default 5); "
                     "must divide a day (1440 min)."),
    ] = None,
    twin: TwinOption = None,
    twin_mode: TwinModeOption = None,
) -> None:
    """Generate a dataset and print a summary of it."""
    from ..config import resolve_config
    from ..dataset import Dataset

    _check_counts(("--subjects", subjects), ("--per-subject", per_subject))
    jobs = _jobs(jobs)
    _check_seed(seed)
    cfg = resolve_config(twin_base(ctx, preset, twin, twin_mode, seed, set_),
                         _parse_sets(set_))
    if wear_days is not None or every_min is not None:
        _simulate_wear(cfg, out, subjects, per_subject, seed, jobs, wear_days, every_min)
        return
    _check_simulate_out(out, subjects, per_subject)
    if not out.suffix:
        from ..simulation.partitioned import write_partitioned

        n = write_partitioned(cfg, out, subjects, per_subject, seed, n_jobs=jobs)
        _say(f"wrote {n} snapshots to {out}/ (partitioned Parquet)", err=False)
        return
    from ..simulation.simulator import simulate_frame

    frame = simulate_frame(cfg, subjects, per_subject, seed, n_jobs=jobs)
    ds = Dataset(frame, config=cfg, seed=seed)
    ds.save(out)
    _print_summary(ds)
    _say(f"wrote {len(ds)} snapshots to {out}", err=False)


def _simulate_wear(cfg, out: Path, subjects: int, per_subject: int, seed: int, jobs: int,
                   wear_days: int | None, every_min: int | None) -> None:
    """``simulate --wear-days D --every-min M``: the wear simulation, written chunk by chunk
    to a directory, or in memory to a file."""
    from ..dataset import Dataset
    from ..simulation import wear

    if wear_days is None:
        raise UserError("--every-min applies to a wear simulation; give --wear-days too")
    if per_subject != 3:
        raise UserError("--per-subject does not apply with --wear-days: each subject has "
                        "wear-days x 1440 / every-min readings")
    every_min = 5 if every_min is None else every_min
    try:
        n_t = wear.readings_per_subject(wear_days, every_min)
    except ValueError as exc:
        raise UserError(str(exc).replace("wear_days", "--wear-days")
                        .replace("every_min", "--every-min")) from None
    _check_simulate_out(out, subjects, n_t)
    if not out.suffix:
        n = wear.write_wear_partitioned(cfg, out, subjects, wear_days, every_min, seed,
                                        n_jobs=jobs)
        _say(f"wrote {n} readings ({subjects} subjects x {wear_days} d, every {every_min} min) "
             f"to {out}/ (partitioned Parquet)", err=False)
        return
    frame = wear.simulate_wear_frame(cfg, subjects, wear_days, every_min, seed, n_jobs=jobs)
    ds = Dataset(frame, config=cfg, seed=seed,
                 metadata={"wear": wear.wear_metadata(wear_days, every_min, None)})
    ds.save(out)
    _print_summary(ds)
    _say(f"wrote {len(ds)} readings to {out}", err=False)


def _check_simulate_out(out: Path, subjects: int, per_subject: int) -> None:
    """``simulate --out``: a writable .parquet/.csv file (that fits in memory) or a directory."""
    if out.suffix and out.suffix not in (".parquet", ".csv"):
        raise UserError(f"--out {str(out)!r}: use a .parquet or .csv file, or a directory")
    if out.suffix:
        _check_out_file(out)
        _check_size(subjects, per_subject)
    else:
        _check_out_dir(out)


@app.command()
def keys() -> None:
    """List every config key accepted by --set: paper preset default, unit, range, meaning."""
    from ..config import resolve_config, valid_keys
    from ..config.keys import key_info, key_range

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
def list_models(
    model: Annotated[
        Path | None,
        typer.Option(help="A model file written by `nirglucose fit`: describe it on the "
                     "device it was fitted on (its inputs and parameters)."),
    ] = None,
) -> None:
    """List the registered model names, one line each (or describe one fitted model).

    A model that knows more than the measured columns (the oracle's truth, the
    generating scenario) is marked ``[privileged: ...]``: a reference, never "best".
    """
    from ..models.labels import describe
    from ..models.registry import available_models, load_model, privileged_knowledge

    def tag(m) -> str:
        known = privileged_knowledge(m)
        return f"  [privileged: {known}; a reference]" if known else ""

    if model is not None:
        fitted = load_model(model)
        _say(f"{describe(fitted)}{tag(fitted)}", err=False)
        return
    names = available_models()
    width = max(map(len, names)) + 2
    for name in names:
        _say(f"{name:<{width}}{describe(name)}{tag(name)}".rstrip(), err=False)


@app.command("parts")
def list_parts() -> None:
    """List the parts catalogue: photodiodes (detector=NAME) and NIR LEDs (leds=[NAME, ...])."""
    from ..config.parts import DETECTOR_PARTS, LED_PARTS

    _say("photodiodes (--set detector=NAME): material, area [mm^2], dark current at 25 degC "
         "[nA], shunt [MOhm]", err=False)
    for name, d in DETECTOR_PARTS.items():
        shunt = "-" if d.shunt_resistance_mohm is None else f"{d.shunt_resistance_mohm:g}"
        _say(f"  {name:<12} {d.vendor:<10} {d.material:<7} {d.active_area_mm2:<7g} "
             f"{d.dark_current_25c_na:<6g} {shunt}", err=False)
    _say("LEDs (--set 'leds=[\"NAME\", ...]'): centre (bin) [nm], FWHM [nm], power [mW]",
         err=False)
    for name, p in LED_PARTS.items():
        bin_nm = (f"({p.wavelength_min_nm:g}-{p.wavelength_max_nm:g})"
                  if p.wavelength_min_nm is not None else "(no bin)")
        flag = "  UNCERTAIN: verify the datasheet" if p.uncertain else ""
        _say(f"  {name:<12} {p.wavelength_nm:g} {bin_nm:<11} {p.fwhm_nm:<4g} "
             f"{p.power_mw:g}{flag}", err=False)


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
