"""The sweep's scenarios: built-in studies, ``--vary`` grids and their validation.

A :class:`Scenario` is one simulated condition (dotted config overrides on a preset,
optionally a separately simulated test cohort); :func:`grid_scenarios` builds the
Cartesian grid of ``--vary`` values, :func:`study_scenarios` the built-in studies
(:data:`STUDIES`, below), and
:func:`resolve_scenarios` the scenarios of one :func:`~nirglucose.evaluation.sweep.run_sweep`
call from its ``vary`` / ``study`` / ``preset`` arguments.

Studies (:data:`STUDIES`)
    ``noise-scale``
        ``noise_scale`` (every noise source together) over 0.25, 0.5, 1, 2, 4.
    ``pmf-noise``
        ``noise.pmf_measurement.scale`` (the error of the measured physiological
        vector) over 0, 0.5, 1, 2, 4.
    ``ablation``
        Every noise source of :data:`~nirglucose.config.NOISE_SOURCES` switched off
        alone (``off``), and switched on alone (``only``), besides all sources on
        (``all-on``) and all off (``all-off``).
        :func:`~nirglucose.evaluation.sweep.analysis.ablation_effects` turns these
        into ΔRMSE per source, paired by seed.
    ``cohort``
        Domain shift. ``fitzpatrick``: train on measured Fitzpatrick types I–III, test
        on I–III (in domain) and on IV–VI (shifted); ``temperature``: train at
        20–25 °C ambient, test at 20–25 °C and at 5–35 °C. Training and test cohorts
        are simulated separately (the test seed is derived from the task's seed), so
        no subject is in both.
        :func:`~nirglucose.evaluation.sweep.analysis.shift_effects` gives the ΔRMSE of
        the shift.
    ``device``
        Each device capability (:data:`~nirglucose.config.DEVICE_CAPABILITIES`)
        switched off alone in ``paper`` and on alone in ``wearable``, besides both
        presets as they are; each scenario sets every key distinguishing the two.
    ``data-size``
        RMSE against the number of training subjects (:data:`DATA_SIZE_SUBJECTS`) on
        each preset of :data:`DATA_SIZE_PRESETS`: every model is trained on a draw of
        that many subjects and tested on an independent draw of
        :data:`DATA_SIZE_TEST_SUBJECTS` subjects (another seed, derived from the
        task's). :func:`~nirglucose.evaluation.sweep.analysis.ranking_crossings` says
        between which sizes two models swap places.
    ``mismatch``
        Model mismatch, the honest test of a physics model: data made by each forward
        model of :data:`~nirglucose.evaluation.sweep.studies.MISMATCH_FORWARD_MODELS`
        (``optics.model``) and the forward-model estimators
        (:data:`~nirglucose.evaluation.sweep.studies.MISMATCH_SUBJECTS`: the privileged
        ``physics-inversion`` and the deployable ``device-inversion``) assuming each one
        (their ``forward_model``), every pair; EBL, the GP, no skill and the oracle
        (default models, :data:`~nirglucose.evaluation.sweep.studies.STUDY_MODELS`) for
        reference, once per data model. The estimators always run, besides ``models``.
        The preset's tuned hyper-parameters were tuned on its own forward model's data,
        so every reference with an inner selection re-tunes itself on each task's
        training subjects (nested; :func:`~nirglucose.models.tuning.self_tuning_params`,
        :func:`study_model_params`); claims rest on several simulation seeds.
    ``wavelengths``
        LED sets: every subset of 1-6 candidate LEDs per detector ranked by the device
        bound (:func:`~nirglucose.design.search.rank_designs`), the best of each size
        simulated and scored by the oracle, EBL and the GP
        (:mod:`~nirglucose.evaluation.sweep.wavelengths`; preset ``wearable`` unless
        given; ``--vary detector=...``, ``n_leds=...``, ``top_n=...``).
        ``effects.csv``: :func:`~nirglucose.evaluation.sweep.wavelengths.wavelength_designs`.
    ``fleet``
        Unit-to-unit tolerance (:mod:`~nirglucose.evaluation.sweep.fleet`): units drawn from
        the parts' tolerances (:mod:`~nirglucose.design.fleet`) at each tolerance scale
        (0, 0.25, 0.5, 1, 2; ``vary={"tolerance_scale": [...]}``), a model trained on some
        units and tested on unseen ones, without and with a per-unit factory
        reference (per-channel bias or slope/bias in absorbance), besides the
        same-unit reference. ``effects.csv`` holds the table
        (:func:`~nirglucose.evaluation.sweep.fleet.fleet_table`); EBL, the GP and the oracle
        by default; ``n_subjects`` are the training subjects in all.

    Any other grid comes from ``vary={"dotted.key": [values]}`` (several keys make a
    Cartesian product), e.g. ``{"hardware.adc_bits": [10, 12, 14]}``.
"""

from __future__ import annotations

import itertools
import json
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from ...config import (
    DEVICE_CAPABILITIES,
    NOISE_SOURCES,
    PRESETS,
    is_valid_key,
    parse_override,
    resolve_config,
)
from ...config.noise import DEFAULT_OFF_NOISE_SOURCES
from ...design.fleet import MAX_TOLERANCE_SCALE
from ...exceptions import ConfigError, is_finite_number, unknown_name
from ...models.tuning import SELF_TUNING, self_tuning_params
from .fleet import FLEET_DEFAULTS, FLEET_TOLERANCE_SCALES, FLEET_VARIANTS
from .scenarios import Scenario
from .wavelengths import WAVELENGTHS_MODELS, WAVELENGTHS_PRESET, wavelength_scenarios

__all__ = [
    "STUDIES",
    "STUDY_GRIDS",
    "COHORT_SHIFTS",
    "DATA_SIZE_SUBJECTS",
    "DATA_SIZE_TEST_SUBJECTS",
    "DATA_SIZE_PRESETS",
    "MISMATCH_FORWARD_MODELS",
    "MISMATCH_SUBJECT",
    "MISMATCH_SUBJECTS",
    "STUDY_MODELS",
    "study_model_params",
    "FLEET_STUDY",
    "FLEET_KEY",
    "Scenario",
    "parse_vary",
    "grid_scenarios",
    "study_scenarios",
    "resolve_scenarios",
]

#: Built-in studies (``--study``).
STUDIES = ("noise-scale", "ablation", "pmf-noise", "cohort", "device", "data-size", "mismatch",
           "wavelengths", "fleet")
#: The ``fleet`` study (unit-to-unit tolerance, :mod:`~nirglucose.evaluation.sweep.fleet`), and
#: the key of ``--vary`` that sets its tolerance scales.
FLEET_STUDY = "fleet"
FLEET_KEY = "tolerance_scale"
#: The varied key and default values of the one-key studies.
STUDY_GRIDS: dict[str, tuple[str, tuple[float, ...]]] = {
    "noise-scale": ("noise_scale", (0.25, 0.5, 1.0, 2.0, 4.0)),
    "pmf-noise": ("noise.pmf_measurement.scale", (0.0, 0.5, 1.0, 2.0, 4.0)),
}
#: Domain shifts of the ``cohort`` study: training domain, in-domain and shifted test.
COHORT_SHIFTS: dict[str, dict[str, Any]] = {
    "fitzpatrick": {
        "column": "fitzpatrick_type",  # the measured (self-reported) type, 1-6
        "train": ("I-III", (1, 2, 3)),
        "in_domain": ("I-III", (1, 2, 3)),
        "shifted": ("IV-VI", (4, 5, 6)),
    },
    "temperature": {
        "key": "environment.temperature_c",
        "train": ("20-25 degC", (20.0, 25.0)),
        "in_domain": ("20-25 degC", (20.0, 25.0)),
        "shifted": ("5-35 degC", (5.0, 35.0)),
    },
}
#: Training-set sizes of the ``data-size`` study (subjects; a bigger setting:
#: ``vary={"n_train_subjects": [80, 160, 320, 640, 1280, 2560]}`` and several seeds).
DATA_SIZE_SUBJECTS = (80, 320, 1280)
#: Subjects of the independent test draw of the ``data-size`` study.
DATA_SIZE_TEST_SUBJECTS = 200
#: Presets of the ``data-size`` study when none are named.
DATA_SIZE_PRESETS = ("paper", "wearable")
#: Forward models of the ``mismatch`` study: every one makes data, and the estimator
#: assumes every one (``optics.model``; the ``rte-lut`` table is filled by the
#: three-layer diffusion solver, ``optics.lut_solver = "diffusion"``, about 40 s per
#: geometry and cached, instead of the 2-CPU-hour Monte Carlo).
MISMATCH_FORWARD_MODELS = ("beer-lambert", "diffusion", "rte-lut")
#: The estimators whose assumed forward model the ``mismatch`` study varies (their
#: ``forward_model`` parameter); the study always runs them: the privileged inversion
#: (it reads the generating scenario) and the deployable one (the device's parts and
#: published tables only; its rte-lut table filled by the diffusion solver, as the data's).
MISMATCH_SUBJECTS = ("physics-inversion", "device-inversion")
#: The privileged one of :data:`MISMATCH_SUBJECTS`.
MISMATCH_SUBJECT = MISMATCH_SUBJECTS[0]
#: Default models of a study when none are given (others: the sweep's defaults).
STUDY_MODELS: dict[str, tuple[str, ...]] = {
    "mismatch": (*MISMATCH_SUBJECTS, "ebl", "gp", "mean", "oracle"),
    "wavelengths": WAVELENGTHS_MODELS,
    FLEET_STUDY: ("ebl", "gp", "oracle"),
}


# --------------------------------------------------------------------------- scenarios
def _label_value(value: Any) -> Any:
    """A CSV-friendly form of a varied value (lists as compact JSON)."""
    if isinstance(value, list | tuple | dict):
        return json.dumps(value, separators=(",", ":"))
    return value


def _fmt_value(value: Any) -> str:
    if isinstance(value, float):
        return f"{value:g}"
    return str(_label_value(value)).lower() if isinstance(value, bool) else str(_label_value(value))


def parse_vary(text: str) -> tuple[str, list[Any]]:
    """Parse ``"key=v1,v2,..."`` from the command line.

    Values are read as one JSON list when they can be (so ``[5,35],[20,25]`` gives two
    ranges), else split on commas, each read as :func:`~nirglucose.config.parse_override`
    reads a value.

    Parameters
    ----------
    text : str
        ``dotted.key=value,value,...``.

    Returns
    -------
    tuple of (str, list)
        The key and its values (in order, duplicates removed).

    Raises
    ------
    ConfigError
        No ``=``, an empty key, no values, or an empty value.

    Examples
    --------
    >>> parse_vary("noise_scale=0.25,0.5,1")
    ('noise_scale', [0.25, 0.5, 1])
    >>> parse_vary("environment.temperature_c=[5,35],[20,25]")
    ('environment.temperature_c', [[5, 35], [20, 25]])
    """
    if "=" not in text:
        raise ConfigError(f"--vary {text!r} must look like key=v1,v2,... e.g. noise_scale=0.5,1,2")
    key, raw = (s.strip() for s in text.split("=", 1))
    if not key:
        raise ConfigError(f"--vary {text!r} has an empty key")
    if not raw:
        raise ConfigError(f"--vary {key}= lists no values; give e.g. {key}=0.5,1,2")
    try:
        values = json.loads(f"[{raw}]")
    except json.JSONDecodeError:
        tokens = [t.strip() for t in raw.split(",")]
        if any(not t for t in tokens):
            raise ConfigError(f"--vary {key}={raw}: empty value in the list") from None
        values = [parse_override(f"{key}={t}")[1] for t in tokens]
    if not values:
        raise ConfigError(f"--vary {key}= lists no values; give e.g. {key}=0.5,1,2")
    unique: list[Any] = []
    for v in values:
        if v not in unique:
            unique.append(v)
    return key, unique


def _default_value(preset: str, key: str, base: Mapping[str, Any]) -> Any:
    node: Any = resolve_config(preset, dict(base)).model_dump(mode="json")
    for part in key.split("."):
        node = node[part]
    return node


def _check_values(preset: str, key: str, values: Sequence[Any], base: Mapping[str, Any]) -> None:
    """Check every value of a varied key against the key's type and range."""
    if not is_valid_key(key):
        resolve_config(preset, {**base, key: values[0]})  # raises with a hint
    default = _default_value(preset, key, base)
    for v in values:
        if is_finite_number(default) and not is_finite_number(v):
            raise ConfigError(
                f"--vary {key}: {v!r} is not a number; {key} takes numbers (default {default!r})"
            )
        if isinstance(default, bool) and not isinstance(v, bool):
            raise ConfigError(f"--vary {key}: {v!r} is not true/false; {key} is a switch")
        resolve_config(preset, {**base, key: v})  # type and range checks


def grid_scenarios(
    vary: Mapping[str, Sequence[Any]],
    *,
    preset: str = "paper",
    base_overrides: Mapping[str, Any] | None = None,
) -> list[Scenario]:
    """The Cartesian grid of varied config values, validated.

    Parameters
    ----------
    vary : mapping of str to sequence
        Dotted config key -> values (one key: a curve; several: a grid).
    preset : str
        Preset the values apply to (for validation).
    base_overrides : mapping, optional
        Overrides every scenario shares.

    Returns
    -------
    list of Scenario

    Raises
    ------
    ConfigError
        Unknown key, empty list, a non-numeric value for a numeric key, a value out of
        range, or a key also given in ``base_overrides``.

    Examples
    --------
    >>> [s.name for s in grid_scenarios({"noise_scale": [0.5, 2]})]
    ['noise_scale=0.5', 'noise_scale=2']
    """
    base = dict(base_overrides or {})
    if not vary:
        raise ConfigError("nothing to vary: give --vary key=v1,v2,... or --study")
    for key, values in vary.items():
        if not isinstance(values, Sequence) or isinstance(values, str) or len(values) == 0:
            raise ConfigError(f"--vary {key}: give a non-empty list of values")
        if key in base:
            raise ConfigError(f"{key} is both varied and set (--set); drop one")
        _check_values(preset, key, list(values), base)
    keys = list(vary)
    out = []
    for combo in itertools.product(*(list(vary[k]) for k in keys)):
        name = ",".join(f"{k}={_fmt_value(v)}" for k, v in zip(keys, combo, strict=True))
        out.append(
            Scenario(
                name=name,
                labels={k: _label_value(v) for k, v in zip(keys, combo, strict=True)},
                overrides=dict(zip(keys, combo, strict=True)),
            )
        )
    return out


def study_scenarios(
    study: str, values: Sequence[Any] | None = None, presets: Sequence[str] | None = None
) -> list[Scenario]:
    """The scenarios of a built-in study (:data:`STUDIES`).

    Parameters
    ----------
    study : str
        One of :data:`STUDIES`.
    values : sequence, optional
        Replace the default values of a one-key study (``noise-scale``, ``pmf-noise``)
        or the training sizes of ``data-size``.
    presets : sequence of str, optional
        Presets of the ``data-size`` study (default :data:`DATA_SIZE_PRESETS`); the
        first is the ``wavelengths`` study's (default ``wearable``).

    Returns
    -------
    list of Scenario

    Examples
    --------
    >>> [s.name for s in study_scenarios("ablation")][:3]
    ['all-on', 'all-off', 'off:led_thermal_drift']
    """
    if study == "requirements":
        raise ConfigError("the requirements study is a search, not a grid of scenarios: call "
                          "nirglucose.evaluation.sweep.requirements.requirements_study (command "
                          "line: nirglucose sweep --study requirements)")
    if study not in STUDIES:
        raise ConfigError(unknown_name("study", study, STUDIES))
    if study in STUDY_GRIDS:
        key, default = STUDY_GRIDS[study]
        return grid_scenarios({key: list(values if values is not None else default)})
    if study == "data-size":
        return _data_size_scenarios(values, presets)
    if study == FLEET_STUDY:
        return _fleet_scenarios(values)
    if values is not None:
        raise ConfigError(f"the {study!r} study takes no values")
    if study == "ablation":
        return _ablation_scenarios()
    if study == "device":
        return _device_scenarios()
    if study == "mismatch":
        return _mismatch_scenarios()
    if study == "wavelengths":
        return wavelength_scenarios(presets[0] if presets else WAVELENGTHS_PRESET)
    return _cohort_scenarios()


def _fleet_scenarios(scales: Sequence[Any] | None) -> list[Scenario]:
    """Every tolerance scale x fleet variant (:mod:`~nirglucose.evaluation.sweep.fleet`)."""

    scales = list(FLEET_TOLERANCE_SCALES if scales is None else scales)
    bad = [v for v in scales if not is_finite_number(v) or not 0 <= v <= MAX_TOLERANCE_SCALE]
    if not scales or bad:
        raise ConfigError(
            f"fleet study: {FLEET_KEY} values must be numbers in 0-{MAX_TOLERANCE_SCALE:g} "
            f"(0: identical units, 1: the stated tolerances), got {bad or scales!r}"
        )
    return [
        Scenario(
            f"{FLEET_KEY}={float(s):g}:{v}",
            {FLEET_KEY: float(s), "variant": v},
            {},
            fleet={**FLEET_DEFAULTS, FLEET_KEY: float(s), "variant": v},
        )
        for s in dict.fromkeys(float(x) for x in scales)
        for v in FLEET_VARIANTS
    ]


def study_model_params(
    study: str | None, models: Sequence[str], given: Mapping[str, Mapping[str, Any]] | None
) -> tuple[dict[str, dict[str, Any]], dict[str, str]]:
    """The constructor arguments of a study's models, and how each was tuned.

    In the ``mismatch`` study every model but :data:`MISMATCH_SUBJECTS` that can re-tune
    itself (:func:`~nirglucose.models.tuning.self_tuning_params`) does so on each task's
    training subjects, since the preset's tuned values come from its own forward
    model's data; the caller's ``given`` arguments win. Other studies: ``given``.

    Returns
    -------
    tuple of (dict, dict)
        Model -> arguments (only models with any), and model -> how it was tuned
        (``mismatch`` only: ``"re-tuned per dataset: ..."``, ``"the preset's tuned
        parameters"``, ``"nothing to tune"`` or ``"as given"``).
    """
    params = {k: dict(v) for k, v in (given or {}).items()}
    how: dict[str, str] = {}
    if study != "mismatch":
        return params, how
    for m in models:
        own = self_tuning_params(m)
        if m in params:
            how[m] = "as given (model_params)"
        elif m in MISMATCH_SUBJECTS or own is None:
            how[m] = ("the preset's tuned parameters where it has them (tuned on its own "
                      "forward model's data), else its defaults")
        elif not own and m in ("mean", "oracle"):
            how[m] = SELF_TUNING[m]
        else:
            how[m] = f"re-tuned per dataset: {SELF_TUNING[m]}"
            if own:
                params[m] = own
    return params, how


def _mismatch_scenarios() -> list[Scenario]:
    """Data from each forward model x the estimators assuming each one (every pair).

    Scenarios with the same data share their other models' tasks (a task is named by
    its specification, which the assumed model changes only for
    :data:`MISMATCH_SUBJECTS`), so the references run once per data model.
    """
    out = []
    for made in MISMATCH_FORWARD_MODELS:
        for assumed in MISMATCH_FORWARD_MODELS:
            out.append(
                Scenario(
                    f"data={made}:assumed={assumed}",
                    {"data_model": made, "assumed_model": assumed, "mismatched": made != assumed},
                    {"optics.model": made, "optics.lut_solver": "diffusion"},
                    model_params={
                        "physics-inversion": {"forward_model": assumed},
                        "device-inversion": {"forward_model": assumed,
                                             "lut_solver": "diffusion"},
                    },
                )
            )
    return out


def _ablation_scenarios() -> list[Scenario]:
    """All sources on, all off, each source off alone and on alone. A source off by
    default (:data:`~nirglucose.config.noise.DEFAULT_OFF_NOISE_SOURCES`: water's
    temperature dependence) is switched on where a row says it is on ("all-on", every
    "off:" row but its own, its "only:" row), so its rows measure it."""

    def off(sources):
        return {f"noise.{s}.enabled": False for s in sources}

    def on(sources):
        return {f"noise.{s}.enabled": True for s in sources if s in DEFAULT_OFF_NOISE_SOURCES}

    out = [
        Scenario("all-on", {"ablation": "all-on", "source": "all"}, on(NOISE_SOURCES)),
        Scenario("all-off", {"ablation": "all-off", "source": "none"}, off(NOISE_SOURCES)),
    ]
    out += [
        Scenario(f"off:{s}", {"ablation": "off", "source": s},
                 {**on(o for o in NOISE_SOURCES if o != s), **off([s])})
        for s in NOISE_SOURCES
    ]
    out += [
        Scenario(
            f"only:{s}",
            {"ablation": "only", "source": s},
            {**off([o for o in NOISE_SOURCES if o != s]), **on([s])},
        )
        for s in NOISE_SOURCES
    ]
    return out


def _cohort_scenarios() -> list[Scenario]:
    """Each domain shift of :data:`COHORT_SHIFTS`, tested in domain and shifted."""
    out = []
    for shift, d in COHORT_SHIFTS.items():
        train_label, train = d["train"]
        for which in ("in_domain", "shifted"):
            test_label, test = d[which]
            labels = {
                "shift": shift,
                "train_domain": train_label,
                "test_domain": test_label,
                "shifted": which == "shifted",
            }
            name = f"{shift}:{which.replace('_', '-')}"
            if "column" in d:
                out.append(
                    Scenario(
                        name,
                        labels,
                        {},
                        {},
                        {"column": d["column"], "values": list(train)},
                        {"column": d["column"], "values": list(test)},
                    )
                )
            else:
                out.append(Scenario(name, labels, {d["key"]: list(train)}, {d["key"]: list(test)}))
    return out


def _device_scenarios() -> list[Scenario]:
    """The ``device`` study: each capability off alone in ``paper``, on alone in ``wearable``.

    Every scenario sets all the keys that distinguish the two presets (the glucose gain
    and each :data:`~nirglucose.config.DEVICE_CAPABILITIES` key), so it is the same
    scenario on either base preset.
    """
    keys = ["glucose.signal_gain"] + [key for key, _, _ in DEVICE_CAPABILITIES.values()]

    def scenario(base, switch, capability):
        over = {k: PRESETS[base][k] for k in keys}
        if capability is not None:
            key, v_on, v_off = DEVICE_CAPABILITIES[capability]
            over[key] = v_on if switch == "on" else v_off
        name = base if capability is None else f"{base}:{switch}:{capability}"
        labels = {"base": base, "switch": switch, "capability": capability or "none"}
        return Scenario(name, labels, over)

    out = [scenario("paper", "base", None), scenario("wearable", "base", None)]
    out += [scenario("paper", "off", c) for c in DEVICE_CAPABILITIES]
    out += [scenario("wearable", "on", c) for c in DEVICE_CAPABILITIES]
    return out


def _data_size_scenarios(
    sizes: Sequence[Any] | None, presets: Sequence[str] | None
) -> list[Scenario]:
    sizes = list(DATA_SIZE_SUBJECTS if sizes is None else sizes)
    presets = list(DATA_SIZE_PRESETS if presets is None else presets)
    if not sizes or any(
        isinstance(n, bool) or not isinstance(n, int | np.integer) or n < 2 for n in sizes
    ):
        raise ConfigError(f"data-size training sizes must be integers >= 2, got {sizes!r}")
    if not presets:
        raise ConfigError(f"no presets given for the data-size study; valid: {', '.join(PRESETS)}")
    bad = [p for p in presets if p not in PRESETS]
    if bad:
        raise ConfigError(f"data-size study: {unknown_name('preset', bad[0], PRESETS)}")
    return [
        Scenario(
            f"{p}:n={int(n)}",
            {"preset": p, "n_train_subjects": int(n)},
            {},
            {},
            preset=p,
            n_subjects=int(n),
            n_test_subjects=DATA_SIZE_TEST_SUBJECTS,
        )
        for p in dict.fromkeys(presets)
        for n in dict.fromkeys(sizes)
    ]


def resolve_scenarios(
    vary: Mapping[str, Sequence[Any]] | None,
    study: str | None,
    preset: str | None,
    base: Mapping[str, Any],
    led_fields: Mapping[str, Any] | None = None,
) -> tuple[list[Scenario], str]:
    """The scenarios of one sweep and the preset every task starts from.

    Parameters
    ----------
    vary : mapping, optional
        ``--vary`` values; with a study only the sizes of ``data-size``
        (``n_train_subjects``) and the scales of ``fleet``; a one-key study
        (``noise-scale``, ``pmf-noise``) runs its own values and refuses ``--vary`` of
        its key (that grid is ``--vary`` alone).
    study : str, optional
        A built-in study (:data:`STUDIES`).
    preset : str, optional
        Preset (default ``paper``); for ``data-size`` a comma-separated list.
    base : mapping
        Overrides every scenario shares (``--set``).
    led_fields : mapping, optional
        Fields of every LED the ``wavelengths`` study chooses (a twin's per-LED values);
        refused by the other studies, which keep the scenario's LEDs.

    Raises
    ------
    ConfigError
        Unknown study, ``vary`` combined with a study that does not take it, bad values.
    """
    if led_fields and study != "wavelengths":
        raise ConfigError(f"led_fields apply to the wavelengths study (it chooses the LEDs); "
                          f"--study {study or 'grid'} keeps the scenario's")
    if study == "data-size":
        presets = None
        if preset is not None:
            presets = [p.strip() for p in str(preset).split(",") if p.strip()]
        if vary and set(vary) != {"n_train_subjects"}:
            raise ConfigError(
                "--vary cannot be combined with --study data-size (except to set its "
                "sizes: --vary n_train_subjects=80,320,...)"
            )
        sizes = list(vary["n_train_subjects"]) if vary else None
        return study_scenarios(study, sizes, presets), "paper"
    if study == "wavelengths":  # the ranking's options come as --vary keys
        preset = WAVELENGTHS_PRESET if preset is None else preset
        return wavelength_scenarios(preset, vary, base, led_fields), preset
    if study == FLEET_STUDY:
        if vary and set(vary) != {FLEET_KEY}:
            raise ConfigError(
                f"--vary cannot be combined with --study {FLEET_STUDY} (except to set its "
                f"tolerance scales: --vary {FLEET_KEY}=0,0.5,1,2)"
            )
        scales = list(vary[FLEET_KEY]) if vary else None
        return study_scenarios(study, scales), preset or "paper"
    preset = "paper" if preset is None else preset
    if study is None:
        return grid_scenarios(vary or {}, preset=preset, base_overrides=base), preset
    if study == "requirements":
        raise ConfigError("the requirements study is a search, not a grid of scenarios: call "
                          "nirglucose.evaluation.sweep.requirements.requirements_study (command "
                          "line: nirglucose sweep --study requirements)")
    if study not in STUDIES:
        raise ConfigError(unknown_name("study", study, STUDIES))
    key = STUDY_GRIDS.get(study, (None,))[0]
    if vary and key is not None and key in vary:  # issue 43: which values would run?
        raise ConfigError(
            f"--study {study} runs its own {key} values "
            f"({', '.join(f'{v:g}' for v in STUDY_GRIDS[study][1])}); to sweep "
            f"{key}={','.join(str(v) for v in vary[key])} give --vary alone (no --study)"
        )
    if vary:
        raise ConfigError(f"--vary cannot be combined with --study {study}")
    if key is None:
        return study_scenarios(study), preset
    values = list(STUDY_GRIDS[study][1])
    return grid_scenarios({key: values}, preset=preset, base_overrides=base), preset
