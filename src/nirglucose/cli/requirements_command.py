"""``sweep --study requirements``: what would a device need to read glucose on real skin?

Runs :func:`~nirglucose.evaluation.sweep.requirements.requirements_study` (the least
design per detector at published magnitudes, confirmed by simulation), writes its
tables, ``requirements.json`` and figures into ``--out`` and prints one answer line per
detector. The sweep's options that describe a grid of scenarios (``--seeds``,
``--repeats``, ``--protocol``, ``--scheduler``, ``--calibration``) do not apply and are
refused when given; ``--set KEY=VALUE`` overrides the preset for every design (e.g.
``--set noise.water_temperature.enabled=true``: water absorbing at the skin temperature).
"""

from __future__ import annotations

from pathlib import Path

import typer

from ._common import (
    UserError,
    _check_counts,
    _check_out_dir,
    _check_seed,
    _check_size,
    _model_names,
    _parse_sets,
    _say,
    _warnings_as_lines,
)

__all__ = ["REQUIREMENTS_STUDY", "requirements_sweep"]

#: The ``--study`` name.
REQUIREMENTS_STUDY = "requirements"
#: Sweep options with no meaning here (parameter names), refused when given.
_NOT_TAKEN = ("seeds", "repeats", "protocol", "scheduler", "calibration")
#: The name of the study's own photodiode with its four LEDs in ``--vary detector=``.
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
    """``sweep --study requirements`` (module docstring).

    ``--subjects`` and ``--per-subject`` size each confirming simulation; left out, the
    study's defaults (60 x 3) apply, not the sweep's. ``--resamples`` left out: 500.
    """
    from ..config import PRESETS
    from ..evaluation.sweep.requirements import requirements_study
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
    _say(f"requirements: searching each detector's least design in {preset or 'physical'}, "
         f"then simulating the named designs ({n_subjects} subjects x {n_per})")
    with _warnings_as_lines():
        res = requirements_study(preset or "physical", confirm_subjects=n_subjects,
                                 confirm_per_subject=n_per, confirm_folds=folds,
                                 confirm_resamples=n_boot, seed=seed, jobs=jobs, **opts)
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
