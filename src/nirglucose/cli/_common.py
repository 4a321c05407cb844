"""What every command shares: option types, argument checks, one-line printing, tidying.

Every check raises :class:`UserError` (exit status 2, one line; see :mod:`._main`).
"""

from __future__ import annotations

import functools
import os
import warnings
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Annotated

import typer

from ..calibration.personal import MAX_CALIBRATION_READINGS
from ..config import PRESETS
from ..evaluation.engine.tasks import clear_outputs
from ..evaluation.sweep.studies import STUDIES
from ..exceptions import NirGlucoseError
from ..metrics.resampling import DEFAULT_N_BOOT
from ._app import console, out_console

#: Preset names for the --preset help texts.
_PRESET_NAMES = ", ".join(PRESETS)
#: Built-in sweep studies for the --study help text.
_STUDY_NAMES = ", ".join(STUDIES)


class UserError(NirGlucoseError, ValueError):
    """A problem with the command line itself (exit status 2)."""


# --- options shared by several commands ----------------------------------------------------
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
DEFAULT_RESAMPLES = DEFAULT_N_BOOT
#: --out of the commands that write a results directory (benchmark, sweep).
OutDirOption = Annotated[
    Path, typer.Option(help="Output directory (created if its parent exists).")
]
#: --glucose-unit of every command that reads or writes glucose.
GlucoseUnitOption = Annotated[
    str | None,
    typer.Option(help="Unit of the file's reference glucose and of the glucose printed or "
                 "written: mg/dL or mmol/L (default: the column's, glucose_mgdl mg/dL, "
                 "glucose_mmoll mmol/L)."),
]
#: --adc-bits of benchmark (fit has its own help text).
AdcBitsOption = Annotated[
    int | None,
    typer.Option(help="The ADC resolution [bit]: of the --data device (needed when every "
                 "code fits 10 bits), or of the simulated one (hardware.adc_bits)."),
]
#: --group-by of fit and benchmark --data: the column that groups the subjects.
GroupByOption = Annotated[
    str | None,
    typer.Option(help="Column grouping the subjects (cohort, site, device, visit, diabetes "
                 "status): each group is scored against its own training mean (default: "
                 "detected by name, e.g. cohort, site, diabetic)."),
]
#: --adc-bits of fit and benchmark: one resolution, or one per channel.
ChannelBitsOption = Annotated[
    str | None,
    typer.Option("--adc-bits", help="The ADC resolution [bit]: N for every channel, or per "
                 "channel for a device that mixes converters (adc_940=10,adc_1050=18; "
                 "default=N for the rest). Needed when every code fits 10 bits; else 12 is "
                 "assumed, with a warning. Of a simulated device: N (hardware.adc_bits)."),
]
#: --adc-full-scale of fit and benchmark: a channel's full-scale code other than 2^bits-1.
FullScaleOption = Annotated[
    str | None,
    typer.Option(help="Per channel, a full-scale code other than 2^bits - 1 (the I0 of a "
                 "device without reference codes), e.g. adc_1050=200000."),
]
PerSubjectOption = Annotated[int, typer.Option(help="Measurements per subject.")]
ProtocolOption = Annotated[str, typer.Option(help="grouped-cv or paper-split.")]
FoldsOption = Annotated[int, typer.Option(help="Folds of grouped-cv.")]
RepeatsOption = Annotated[int, typer.Option(help="Repeats of grouped-cv.")]


# --- printing ------------------------------------------------------------------------------
#: ``warning:`` lines held while a command's input is checked (None: none held).
_HELD: list[str] | None = None


def _say(text: str, *, err: bool = True) -> None:
    """Print one plain line (no markup, no highlighting) to stderr or stdout; a
    ``warning:`` line inside :func:`held_warnings` waits for the input to pass."""
    if err and _HELD is not None and text.startswith("warning:"):
        _HELD.append(text)
        return
    (console if err else out_console).print(
        text, markup=False, highlight=False, soft_wrap=True
    )


@contextmanager
def held_warnings() -> Iterator[None]:
    """Hold the ``warning:`` lines of the block: printed (each once) when it ends, dropped
    when it raises. A refusal is one line: the warnings about a run that will not happen
    (an assumed ADC resolution, too few subjects) stay unsaid. Nested blocks hold into
    the outer one."""
    global _HELD
    outer = _HELD
    if outer is not None:  # the outer block decides
        yield
        return
    _HELD = []
    try:
        yield
    except BaseException:
        _HELD = None
        raise
    lines, _HELD = _HELD, None
    for line in dict.fromkeys(lines):
        _say(line)


@contextmanager
def _warnings_as_lines(extra: list[str] | None = None) -> Iterator[list[str]]:
    """Collect the warnings of a block and print each distinct one as a ``warning:`` line.

    Lines appended to the yielded list (e.g. a result's own warnings) are printed after
    the caught ones, duplicates once.
    """
    more: list[str] = list(extra or [])
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        yield more
    msgs = [str(w.message) for w in caught] + more
    for msg in dict.fromkeys(m.replace("\n", " ") for m in msgs):
        _say(f"warning: {msg}")


def holds_warnings(command):
    """Run ``command`` inside :func:`held_warnings` (``fit``, ``predict``: quick commands
    whose refusals may come late, at the fit)."""

    @functools.wraps(command)
    def wrapper(*args, **kwargs):
        with held_warnings():
            return command(*args, **kwargs)

    return wrapper


# --- checks --------------------------------------------------------------------------------
def _parse_sets(values: list[str] | None) -> dict:
    from ..config import parse_override

    pairs = [parse_override(v) for v in (values or [])]
    for key, _ in pairs:
        if key == "preset":
            raise UserError(
                "--set preset=... would only relabel the data; choose the scenario with "
                "--preset NAME"
            )
    return dict(pairs)


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


def _check_out_dir(out: Path) -> None:
    """Refuse a results directory that is a file or whose parent does not exist."""
    if out.exists() and not out.is_dir():
        raise UserError(f"--out {str(out)!r} exists and is not a directory")
    if not out.exists() and not out.parent.exists():
        raise UserError(f"output directory {str(out.parent)!r} does not exist; create it first")


def _check_size(subjects: int, per_subject: int) -> None:
    """Refuse a simulation that cannot fit in memory, before allocating anything."""
    from ..resources import check_simulation_size

    check_simulation_size(subjects, per_subject)


def _check_jobs(jobs: int | None) -> None:
    """Warn (one line) when more workers are asked for than there are cores."""
    from ..evaluation.engine.executors import available_cores

    cores = available_cores()
    if jobs is not None and jobs > cores:
        _say(f"warning: --jobs {jobs} exceeds the {cores} available cores; "
             "the run is not faster and uses more memory")


def _positive(name: str, value: int) -> None:
    if value < 1:
        raise UserError(f"{name} must be a positive integer, got {value}")


def _check_counts(*named: tuple[str, int]) -> None:
    """:func:`_positive` for each ``(option, value)`` in turn."""
    for name, value in named:
        _positive(name, value)


def _check_seed(seed: int) -> None:
    if seed < 0:
        raise UserError(f"--seed must be non-negative, got {seed}")


def _jobs(jobs: int | None) -> int:
    """``--jobs`` checked (positive; a warning beyond the cores), None as the cores."""
    from ..evaluation.engine.executors import available_cores

    if jobs is None:
        return available_cores()
    _positive("--jobs", jobs)
    _check_jobs(jobs)
    return jobs


def _check_calibration(k: int, per_subject: int | None) -> None:
    if not 0 <= k <= MAX_CALIBRATION_READINGS:
        raise UserError(
            f"--calibration must be 0, 1 or {MAX_CALIBRATION_READINGS} readings per person, "
            f"got {k}"
        )
    if k and per_subject is not None and per_subject <= k:
        raise UserError(
            f"--calibration {k} leaves no reading to score at --per-subject {per_subject}; "
            f"use --per-subject {k + 2} or more"
        )


def _model_names(models: str | None) -> list[str] | None:
    """``--models a,b`` as a list (None when not given); an empty list is refused."""
    if models is None:
        return None
    names = [m.strip() for m in models.split(",") if m.strip()]
    if not names:
        raise UserError(f"--models {models!r} names no model")
    return names


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


def runs_workers(command):
    """Run ``command`` inside
    :func:`~nirglucose.evaluation.engine.executors.worker_guard`, so that every joblib
    (loky) worker it starts exits when this process dies.

    Only the commands that start worker processes (``simulate``, ``benchmark``,
    ``sweep``, ``wear-benchmark``: each has ``--jobs``) run in it; the others leave
    joblib's configuration alone.
    """

    @functools.wraps(command)
    def wrapper(*args, **kwargs):
        from ..evaluation.engine.executors import worker_guard

        with worker_guard():
            return command(*args, **kwargs)

    return wrapper


def refuse_simulation_options(ctx: typer.Context, data: Path | None,
                              names: tuple[str, ...]) -> None:
    """With --data nothing is simulated: the options ``names`` (parameter names) given on
    the command line would be silently ignored, so they are refused in one line."""
    given = [f"--{n.replace('_', '-')}" for n in names
             if getattr(ctx.get_parameter_source(n), "name", None) == "COMMANDLINE"]
    if data is not None and given:
        raise UserError(f"{', '.join(given)} describe a simulation; with --data nothing is "
                        "simulated: leave them out")


def clear_previous_runs(runs: list[tuple[str | None, Path]], out: Path,
                        names: tuple[str, ...]) -> None:
    """Before several presets' runs: remove every preset directory's previous results
    ``names`` and the report that compared them (``out/report.html``), so a run stopped
    during one preset leaves no other preset's old results looking like its own. (One
    run clears its own directory once its input is read: a bad --data file deletes
    nothing.)"""
    if len(runs) > 1:
        clear_outputs(out, ("report.html",))
        for _, run_out in runs:
            clear_outputs(run_out, names)


# --- the twin (nirglucose twin; --twin on simulate and every study) ----------------------
#: --twin of simulate and of every study.
TwinOption = Annotated[
    Path | None,
    typer.Option(help="A device's twin (twin.json of `nirglucose twin`, or its folder): "
                 "the run starts from its scenario in place of --preset; --set applies on "
                 "top."),
]
#: --twin-mode (only with --twin).
TwinModeOption = Annotated[
    str | None,
    typer.Option(help="With --twin: map (default), the twin's most probable parameters; "
                 "posterior, one posterior draw chosen by --seed."),
]
#: ``--set`` keys that replace a twin's LED set (its fitted per-LED values belong to it).
_LED_SET_KEYS = ("leds", "leds.emitters")


def check_twin_mode(mode: str) -> str:
    """``--twin-mode`` checked (map or posterior)."""
    from ..twin import TWIN_MODES

    if mode not in TWIN_MODES:
        raise UserError(f"--twin-mode {mode!r}: choose {' or '.join(TWIN_MODES)}")
    return mode


def _on_command_line(ctx: typer.Context | None, name: str) -> bool:
    return ctx is not None and getattr(ctx.get_parameter_source(name), "name",
                                       None) == "COMMANDLINE"


def twin_start(ctx: typer.Context | None, twin: Path | None, twin_mode: str | None,
               seed: int, *, set_: list[str] | None = None, own_leds: bool = True):
    """Where a ``--twin`` run starts (:class:`nirglucose.twin.twin.TwinStart`), or None
    without ``--twin``.

    One line (exit 2) for what makes no sense with a twin: ``--twin-mode`` without
    ``--twin``; ``--preset`` beside it (the twin replaces it); ``--data`` (nothing is
    simulated); ``--set leds=...`` (the twin's fitted per-LED values belong to its LEDs;
    ``leds.emitters.<i>.<field>`` changes one of them). ``own_leds``: as
    :meth:`nirglucose.twin.Twin.study_start`.
    """
    if twin is None:
        if twin_mode is not None:
            raise UserError("--twin-mode applies to a twin; give --twin TWIN too")
        return None
    if _on_command_line(ctx, "preset"):
        raise UserError("--twin replaces --preset: give one of them")
    if ctx is not None and ctx.params.get("data") is not None:
        raise UserError("--twin simulates the twin's device and --data reads a file: give "
                        "one of them")
    for text in set_ or []:
        key = text.partition("=")[0].strip()
        if key in _LED_SET_KEYS:
            raise UserError(f"--set {key}=... replaces the twin's LEDs, whose fitted values "
                            "belong to them: change one with --set leds.emitters.<i>.<field>"
                            "=..., or ask which LEDs with sweep --study wavelengths --twin")
    from ..twin import load_twin

    mode = check_twin_mode(twin_mode or "map")
    return load_twin(twin).study_start(mode, seed, own_leds=own_leds)


def twin_base(ctx: typer.Context | None, preset: str, twin: Path | None,
              twin_mode: str | None, seed: int, set_: list[str] | None = None):
    """The scenario a ``--twin`` command starts from: the twin's (``--twin-mode``), else
    ``preset`` (:func:`twin_start`'s checks)."""
    start = twin_start(ctx, twin, twin_mode, seed, set_=set_)
    if start is None:
        return preset
    from ..config import resolve_config

    return resolve_config(start.preset, start.overrides)


# public names of the helpers a newer command shares (the private ones above predate the
# ratchet on private imports, tests/test_layout.py)
say = _say
warnings_as_lines = _warnings_as_lines
check_out_dir = _check_out_dir
check_seed = _check_seed
jobs_or_cores = _jobs
