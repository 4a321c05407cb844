"""The ``wavelengths`` sweep study: LED sets ranked by the bound, the best confirmed.

:func:`wavelength_scenarios` ranks every subset of 1 ... 6 candidate LEDs per
detector by the device bound (:func:`~nirglucose.design.search.rank_designs`) and
returns one :class:`~nirglucose.evaluation.sweep.scenarios.Scenario` per top design (the
design's ``leds`` and ``detector`` as overrides, its bounds as labels), so the sweep
engine simulates each design and scores the oracle, EBL and the GP on it, locally or
on Dask, resumably. The ranking is deterministic, so a rerun plans the same tasks.
:func:`wavelength_designs` joins the bounds with the confirmed RMSEs: the sweep's
``effects.csv`` for this study.

Options (``--vary`` with ``--study wavelengths``): ``detector`` (catalogue parts,
default :data:`~nirglucose.design.search.SEARCH_DETECTORS`), ``n_leds`` (the numbers
of LEDs confirmed, default 1-6) and ``top_n`` (designs confirmed per detector and
number of LEDs, default :data:`WAVELENGTHS_TOP_N`).
"""

from __future__ import annotations

import json
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
import pandas as pd

from ...design.search import SEARCH_DETECTORS, rank_designs
from ...exceptions import ConfigError
from .scenarios import Scenario

__all__ = [
    "WAVELENGTHS_PRESET",
    "WAVELENGTHS_N_LEDS",
    "WAVELENGTHS_TOP_N",
    "WAVELENGTHS_MODELS",
    "WAVELENGTHS_VARY_KEYS",
    "wavelength_scenarios",
    "wavelength_designs",
]

#: Preset of the study when none is given (a worn device without a monitor photodiode).
WAVELENGTHS_PRESET = "wearable"
#: Numbers of LEDs per design the study confirms. [-]
WAVELENGTHS_N_LEDS = (1, 2, 3, 4, 5, 6)
#: Designs confirmed per detector and number of LEDs (the best by the bound). [-]
WAVELENGTHS_TOP_N = 1
#: Models scoring each design: the oracle (to compare with the oracle-conditioned
#: bound) and two data-driven estimators.
WAVELENGTHS_MODELS = ("oracle", "ebl", "gp")
#: ``--vary`` keys the study takes.
WAVELENGTHS_VARY_KEYS = ("detector", "n_leds", "top_n")
#: Label columns of a design (``sweep.csv``), in order.
DESIGN_LABELS = ("detector", "n_leds", "rank", "wavelengths_nm", "study_leds_kept",
                 "bound_rmse_mgdl", "oracle_bound_rmse_mgdl")


def _ints(name: str, values: Sequence[Any], low: int) -> list[int]:
    out = []
    for v in values:
        if isinstance(v, bool) or not isinstance(v, int | np.integer) or v < low:
            raise ConfigError(f"--vary {name}: give integers >= {low}, got {list(values)!r}")
        out.append(int(v))
    return sorted(set(out))


def wavelength_scenarios(
    preset: str = WAVELENGTHS_PRESET,
    vary: Mapping[str, Sequence[Any]] | None = None,
    base: Mapping[str, Any] | None = None,
    led_fields: Mapping[str, Any] | None = None,
) -> list:
    """The scenarios of the ``wavelengths`` study: the best designs by the bound.

    Parameters
    ----------
    preset : str
        Preset the designs are ranked and simulated on.
    vary : mapping, optional
        Study options :data:`WAVELENGTHS_VARY_KEYS` (``detector``, ``n_leds``,
        ``top_n``, one value for ``top_n``).
    base : mapping, optional
        Overrides every scenario shares (``--set``; not ``leds`` or ``detector``).
    led_fields : mapping, optional
        Fields every candidate LED takes, in the ranking and in the confirmed designs
        (a device's twin's per-LED values, :meth:`nirglucose.twin.Twin.study_start`).

    Returns
    -------
    list of Scenario
        One per (detector, number of LEDs, rank), named
        ``"<detector>:k=<n>:#<rank>:<wavelengths>"``, labelled with
        ``DESIGN_LABELS``.

    Raises
    ------
    ConfigError
        An unknown option, detector or preset; bad numbers; ``leds`` or ``detector``
        in ``base``.
    """
    vary = dict(vary or {})
    bad = [k for k in vary if k not in WAVELENGTHS_VARY_KEYS]
    if bad:
        raise ConfigError(
            f"--vary {bad[0]} does not apply to --study wavelengths; it takes "
            f"{', '.join(WAVELENGTHS_VARY_KEYS)}"
        )
    base = dict(base or {})
    for key in ("leds", "detector"):
        if key in base:
            raise ConfigError(
                f"--study wavelengths chooses {key} itself; drop --set {key} "
                "(detectors: --vary detector=BPW34,FGA01)"
            )
    detectors = [str(d) for d in vary.get("detector", SEARCH_DETECTORS)]
    n_leds = _ints("n_leds", vary.get("n_leds", WAVELENGTHS_N_LEDS), 1)
    top = _ints("top_n", vary.get("top_n", [WAVELENGTHS_TOP_N]), 1)
    if len(top) != 1:
        raise ConfigError(f"--vary top_n takes one value, got {top}")
    ranking = rank_designs(preset, detectors=detectors, k_max=max(n_leds), top=top[0],
                           overrides=base or None, led_fields=led_fields)
    ranking = ranking[ranking["n_leds"].isin(n_leds)]
    out = []
    for _, r in ranking.iterrows():
        labels = {c: (r[c].item() if hasattr(r[c], "item") else r[c]) for c in DESIGN_LABELS}
        name = f"{r['detector']}:k={r['n_leds']}:#{r['rank']}:{r['wavelengths_nm']}"
        out.append(Scenario(name, labels, {"leds": json.loads(r["leds"]),
                                           "detector": r["detector"]}, preset=preset))
    return out


def wavelength_designs(frame: pd.DataFrame) -> pd.DataFrame:
    """The top designs with their bounds and confirmed RMSEs (one row per design × model).

    Parameters
    ----------
    frame : pandas.DataFrame
        ``sweep.csv`` of a ``wavelengths`` study.

    Returns
    -------
    pandas.DataFrame
        :data:`DESIGN_LABELS`, ``model``, ``n_seeds``, ``rmse_mgdl`` (mean over seeds),
        ``rmse_ci_low`` / ``rmse_ci_high`` and ``ci`` (how the interval was made: a
        95 % Student-t interval over seeds with two or more seeds, else the one
        task's subject-cluster bootstrap 95 % interval). [mg/dL]
    """
    from scipy import stats

    keys = [c for c in ("scenario", *DESIGN_LABELS) if c in frame]
    rows = []
    for vals, g in frame.groupby([*keys, "model"], sort=False, dropna=False):
        *vals, model = vals
        rmse = pd.to_numeric(g["rmse_mgdl"], errors="coerce").dropna().to_numpy(float)
        n = len(rmse)
        mean = float(rmse.mean()) if n else np.nan
        if n >= 2:
            half = float(stats.t.ppf(0.975, n - 1) * rmse.std(ddof=1) / np.sqrt(n))
            lo, hi, how = mean - half, mean + half, "t over seeds"
        else:
            lo = float(g["rmse_ci_low"].iloc[0]) if "rmse_ci_low" in g else np.nan
            hi = float(g["rmse_ci_high"].iloc[0]) if "rmse_ci_high" in g else np.nan
            how = "subject bootstrap"
        rows.append({**dict(zip(keys, vals, strict=True)), "model": model, "n_seeds": n,
                     "rmse_mgdl": mean, "rmse_ci_low": lo, "rmse_ci_high": hi, "ci": how})
    return pd.DataFrame(rows)
