"""The ``twin`` command: fit the simulator to a device's own file (``nirglucose.twin``)."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer
from rich.markup import escape
from rich.table import Table

from ._app import app, out_console
from ._common import (
    AdcBitsOption,
    GlucoseUnitOption,
    JobsOption,
    UserError,
    check_out_dir,
    check_seed,
    jobs_or_cores,
    say,
    warnings_as_lines,
)

#: --simulations' default: the library's ``InferenceSettings().n_simulations``, so the CLI
#: and ``ng.fit_twin`` share one cached estimator (a test keeps them equal; importing the
#: twin package here would slow ``nirglucose --help``).
DEFAULT_SIMULATIONS = 6000


@app.command("twin")
def twin(
    data: Annotated[Path, typer.Option(help="The device's file (CSV or Parquet; the format "
                                       "of the user guide), with subject_id and glucose.")],
    out: Annotated[Path, typer.Option(help="Directory for twin.json (created if its parent "
                                      "exists).")],
    adc_bits: AdcBitsOption = None,
    glucose_unit: GlucoseUnitOption = None,
    simulations: Annotated[int, typer.Option(help="Simulated devices to train the posterior "
                                             "estimator on (once per device: cached).")
                           ] = DEFAULT_SIMULATIONS,
    seed: Annotated[int, typer.Option(help="Seed of the simulations, training and draws.")] = 0,
    jobs: JobsOption = None,
    cache: Annotated[bool, typer.Option(help="Reuse (and keep) the device's trained "
                                        "estimator in the package's cache.")] = True,
) -> None:
    """Fit the simulator to a device's file: the posterior over its scenario parameters."""
    from ..twin import InferenceSettings, fit_twin

    check_seed(seed)
    check_out_dir(out)
    if not data.exists():
        raise UserError(f"--data {str(data)!r} does not exist")
    try:
        settings = InferenceSettings(n_simulations=simulations, seed=seed)
    except ValueError as exc:
        raise UserError(str(exc).replace("n_simulations", "--simulations")) from None
    with warnings_as_lines():
        result = fit_twin(data, adc_bits=adc_bits, glucose_unit=glucose_unit,
                          settings=settings, n_jobs=jobs_or_cores(jobs), cache=cache)
    _print_twin(result)
    path = result.save(out)
    t = result.info["timing"]
    how = "a cached estimator" if t["cached_estimator"] else (
        f"{t['n_train']} simulated devices, trained anew")
    say(f"wrote {path} ({t['total_s']} s; {how})", err=False)


def _print_twin(result) -> None:
    """The posterior of each parameter as a table on stdout."""
    table = Table(title="twin: 90 % posterior intervals (scenario keys)")
    table.add_column("key", overflow="fold")
    for col in ("median", "90 % interval", "identified", "base"):
        table.add_column(col)
    for p in result.parameters:
        table.add_row(escape(p["key"]), f"{p['median']:.4g}",
                      f"{p['lower']:.4g} - {p['upper']:.4g}",
                      "yes" if p["identified"] else "no" + (" (held)" if not p["fitted"] else ""),
                      f"{p['preset']:.4g}")
    out_console.print(table)
