"""The evaluation protocol as one value: how the data are split, how often, with which
seed, how many bootstrap resamples, and how many personal calibration readings.

:func:`~nirglucose.evaluation.benchmark.run_benchmark` takes a :class:`Protocol` as its
``protocol`` argument (as scikit-learn's ``cross_validate`` takes one splitter object),
or a splitter name with the Protocol's defaults; its former keywords for the same
options (:data:`LEGACY_KEYWORDS`) warn until 0.3. :func:`~nirglucose.evaluation.sweep.run_sweep`
takes a :class:`Protocol` or, as before, the protocol's name with the options as
keywords.
"""

from __future__ import annotations

import warnings
from collections.abc import Mapping
from dataclasses import dataclass, fields
from typing import Any

from ..calibration.personal import check_k
from ..exceptions import ConfigError, check_positive_int, check_seed
from ..metrics.resampling import DEFAULT_N_BOOT
from .splits import check_protocol

__all__ = ["Protocol", "resolve_protocol", "protocol_of", "sweep_protocol", "LEGACY_KEYWORDS"]


@dataclass(frozen=True)
class Protocol:
    """How models are evaluated; checked when made.

    Parameters
    ----------
    splitter : {"grouped-cv", "paper-split"}
        Subject-grouped repeated K-fold, or the study's single 60/20/20 split
        (:data:`~nirglucose.evaluation.splits.PROTOCOLS`).
    n_splits : int
        Folds of ``grouped-cv``. [-]
    repeats : int
        Repeats of ``grouped-cv`` (``paper-split`` runs one split). [-]
    seed : int
        Seed of the splits, the models' initialisation and the bootstrap. [-]
    resamples : int
        Bootstrap resamples of every interval and paired test. [-]
    calibration : int
        Personal calibration readings per test subject: 0 (none), 1 or 2. [-]

    Raises
    ------
    ConfigError
        An unknown splitter, a count that is not a positive integer, a negative seed, or
        a calibration other than 0, 1 or 2.

    Examples
    --------
    >>> p = Protocol(repeats=5, seed=1)
    >>> p.splitter, p.n_splits, p.repeats, p.seed
    ('grouped-cv', 5, 5, 1)
    >>> Protocol(splitter="k-fold")
    Traceback (most recent call last):
    ...
    nirglucose.exceptions.ConfigError: unknown protocol 'k-fold'; valid: grouped-cv, paper-split
    """

    splitter: str = "grouped-cv"
    n_splits: int = 5
    repeats: int = 3
    seed: int = 0
    resamples: int = DEFAULT_N_BOOT
    calibration: int = 0

    def __post_init__(self) -> None:
        check_protocol(self.splitter)
        for name in ("n_splits", "repeats", "resamples"):
            object.__setattr__(self, name, check_positive_int(name, getattr(self, name)))
        object.__setattr__(self, "seed", check_seed(self.seed))
        object.__setattr__(self, "calibration", check_k(self.calibration))


def resolve_protocol(
    protocol: str | Protocol, given: Mapping[str, Any],
    defaults: Mapping[str, Any] | None = None,
) -> Protocol:
    """The :class:`Protocol` a function was asked for.

    Parameters
    ----------
    protocol : str or Protocol
        A splitter name (the options then come from ``given``) or a whole protocol.
    given : mapping
        The function's protocol keywords as called, by :class:`Protocol` field name.
    defaults : mapping, optional
        The same keywords' defaults in the function's signature (default: the
        :class:`Protocol`'s own).

    Raises
    ------
    ConfigError
        A :class:`Protocol` together with a keyword that differs from its default (the
        options belong in one place), or invalid options.

    Examples
    --------
    >>> resolve_protocol("paper-split", {"seed": 3}, {"seed": 0}).seed
    3
    >>> resolve_protocol(Protocol(seed=2), {"seed": 0}, {"seed": 0}).seed
    2
    """
    if defaults is None:
        defaults = {f.name: f.default for f in fields(Protocol)}
    if isinstance(protocol, Protocol):
        clash = [f"{k}={v!r}" for k, v in given.items() if v != defaults[k]]
        if clash:
            raise ConfigError(
                f"give the protocol's options in the Protocol or as keywords, not both: "
                f"{', '.join(clash)} beside {protocol!r}"
            )
        return protocol
    if not isinstance(protocol, str):
        raise ConfigError(f"protocol must be a splitter name or a Protocol, got "
                          f"{type(protocol).__name__}")
    known = {f.name for f in fields(Protocol)}
    return Protocol(splitter=protocol, **{k: v for k, v in given.items() if k in known})


#: :func:`~nirglucose.evaluation.benchmark.run_benchmark`'s former keywords for the
#: Protocol's options -> the :class:`Protocol` field each sets (deprecated; removed in 0.3).
LEGACY_KEYWORDS = {"n_splits": "n_splits", "repeats": "repeats", "seed": "seed",
                   "n_boot": "resamples", "calibration": "calibration"}


def protocol_of(protocol: str | Protocol, legacy: Mapping[str, Any],
                caller: str = "run_benchmark") -> Protocol:
    """The :class:`Protocol` of a call that may still give its options as keywords.

    Parameters
    ----------
    protocol : str or Protocol
        The call's ``protocol`` argument.
    legacy : mapping
        The call's other keywords: only :data:`LEGACY_KEYWORDS`, each folded into the
        Protocol with a ``DeprecationWarning`` (once per call).
    caller : str
        The function's name, for the messages.

    Raises
    ------
    TypeError
        A keyword that is none of :data:`LEGACY_KEYWORDS` (as Python says of any
        unexpected keyword argument).
    ConfigError
        A Protocol together with a keyword that differs from its default, or invalid
        options.

    Examples
    --------
    >>> protocol_of(Protocol(repeats=1), {}).repeats
    1
    >>> import warnings
    >>> with warnings.catch_warnings():
    ...     warnings.simplefilter("ignore", DeprecationWarning)
    ...     protocol_of("grouped-cv", {"n_boot": 200}).resamples
    200
    """
    unknown = sorted(set(legacy) - set(LEGACY_KEYWORDS))
    if unknown:
        raise TypeError(f"{caller}() got an unexpected keyword argument {unknown[0]!r}")
    if legacy:
        given = ", ".join(f"{k}=" for k in legacy)
        fields_ = ", ".join(f"{LEGACY_KEYWORDS[k]}=" for k in legacy)
        warnings.warn(f"{caller}({given}...) is deprecated and removed in nirglucose 0.3: "
                      f"give protocol=Protocol({fields_}...)", DeprecationWarning,
                      stacklevel=3)
    return resolve_protocol(protocol, {LEGACY_KEYWORDS[k]: v for k, v in legacy.items()})


def sweep_protocol(protocol: str | Protocol, seeds: Any, sizes: tuple[int, int],
                   resamples: int, given: dict[str, Any]) -> Protocol:
    """The protocol of every task of a sweep, checked with the cohort ``(n_subjects,
    per_subject)``, ``resamples`` its default bootstrap size; a Protocol's seed must stay
    0 (a sweep's are ``seeds``)."""
    defaults = {**{f.name: f.default for f in fields(Protocol)}, "resamples": resamples}
    proto = resolve_protocol(protocol, given, defaults)
    for name, value in zip(("n_subjects", "per_subject"), sizes, strict=True):
        check_positive_int(name, value)
    if proto.seed != 0:
        raise ConfigError(f"a sweep's seeds are its seeds argument ({seeds!r}); leave the "
                          f"Protocol's seed at 0, got {proto.seed}")
    return proto
