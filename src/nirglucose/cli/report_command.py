"""The ``report`` command: one self-contained HTML file of a benchmark run."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from ._app import app
from ._common import JobsOption, UserError, _check_out_file, _jobs, _say


@app.command()
def report(
    results: Annotated[Path, typer.Argument(
        help="Results directory of `nirglucose benchmark` (or of `wear-benchmark`, `twin`, "
        "`sweep --study requirements`).")],
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
    jobs: JobsOption = None,
) -> None:
    """Write the figures and tables of a benchmark run as one self-contained HTML file."""
    from ..report import build_report
    from ..report.wear import build_wear_report, is_wear_results

    if out is not None and out.suffix not in (".html", ".htm"):
        raise UserError(f"--out {str(out)!r}: the report is written as .html")
    if figures is not None and figures.exists() and not figures.is_dir():
        raise UserError(f"--figures {str(figures)!r} is a file; give a directory for the "
                        "PNG and SVG figures")
    from ..report.requirements import is_requirements_dir
    jobs = _jobs(jobs)  # the benchmark report's figures are drawn on this many processes
    from ..report.twin import build_twin_report, is_twin_dir

    if results.is_dir() and is_requirements_dir(results):  # sweep --study requirements
        return _requirements_page(results, out, figures, sweep)

    if results.is_dir() and is_twin_dir(results) and not sweep:  # a device's twin
        if out is not None:
            _check_out_file(out)
        path = build_twin_report(results, out if out is not None else results / "report.html",
                                 figures_dir=figures)
        _say(f"wrote {path}", err=False)
        return
    if results.is_dir() and is_wear_results(results):  # a worn run (wear-benchmark)
        if out is not None:
            _check_out_file(out)
        if sweep:
            raise UserError("--sweep adds to a benchmark report, not to a worn run's report")
        path = build_wear_report(results, out if out is not None else results / "report.html",
                                 figures_dir=figures)
        _say(f"wrote {path}", err=False)
        return
    _check_results_dir(results)
    if out is not None:
        _check_out_file(out)
    for d in sweep or []:
        if not (d / "sweep.csv").exists():
            raise UserError(f"--sweep {str(d)!r} holds no sweep.csv; run `nirglucose sweep` first")
    path = build_report(results, out if out is not None else results / "report.html",
                        figures_dir=figures, sweep_dirs=sweep or [], jobs=jobs)
    _say(f"wrote {path}", err=False)


def _requirements_page(results: Path, out: Path | None, figures: Path | None,
                       sweep: list[Path] | None) -> None:
    """The page of a ``sweep --study requirements`` directory."""
    from ..report.requirements import build_requirements_report

    if sweep:
        raise UserError("--sweep adds to a benchmark report, not to the requirements "
                        "study's page")
    if out is not None:
        _check_out_file(out)
    path = build_requirements_report(
        results, out if out is not None else results / "report.html", figures_dir=figures)
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
    from ..report.presets import preset_dirs

    has_run = any((results / f).is_file() for f in ("meta.json", "metrics.csv", "metrics.json"))
    if not has_run and not preset_dirs(results):  # a run, or one run per preset
        raise UserError(
            f"{str(results)!r} holds no meta.json or metrics; it is not the output of "
            "`nirglucose benchmark` (run it first)"
        )
