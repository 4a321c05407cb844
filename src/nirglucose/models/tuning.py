"""Tuned hyper-parameters per preset and model, and the search space they came from.

``tools/tune.py`` chooses each model family's hyper-parameters per preset by
subject-grouped cross-validation on simulation seeds disjoint from the reported ones
(reported: 0-4; tuning: :data:`TUNING_SEEDS`), with the same budget for every family
(:data:`N_CONFIGS` configurations x :data:`N_FOLDS` folds x the tuning seeds), and
writes them to the packaged ``data/tuned_params.json``. :func:`tuned_params` reads
that file; the benchmark constructs every model with what it returns.

The reference learners: gradient boosting (``gbr``) is tuned like every other family
(:func:`search_space`); the Gaussian process (``gp``) has no grid: it fits its kernel's
hyper-parameters (signal and noise variances, one length scale per input) by maximising
the log marginal likelihood inside every ``fit`` (Rasmussen & Williams 2006, ch. 5), on
the training rows only, which is its tuning; the no-skill ``mean`` has nothing to tune.

Examples
--------
>>> from nirglucose.models import tuned_params
>>> sorted(tuned_params("sdnn", "wearable"))  # doctest: +SKIP
['dropout', 'lr', 'max_epochs', 'val_fraction', 'weight_decay']
"""

from __future__ import annotations

import copy
import json
from functools import lru_cache
from importlib import resources

from ..config import PRESETS
from ..exceptions import ConfigError, unknown_name
from .linear import DEFAULT_ALPHAS
from .registry import get_model_class, is_network, is_pinn

__all__ = [
    "tuned_params",
    "untuned_params",
    "preset_params",
    "UNTUNED_NETWORK_PARAMS",
    "tuning_record",
    "search_space",
    "TUNING_SEEDS",
    "N_CONFIGS",
    "N_FOLDS",
    "TUNED_PRESETS",
    "LAMBDA_PHYS_GRID",
    "lambda_curve",
    "best_positive_lambda",
    "TUNED_AS",
    "self_tuning_params",
    "SELF_TUNING",
]

#: Simulation seeds of the tuning data: disjoint from the reported seeds 0-4.
TUNING_SEEDS = (1000, 1001, 1002)
#: Configurations evaluated per family and preset (the same for every family).
N_CONFIGS = 12
#: Subject-grouped folds per tuning seed.
N_FOLDS = 3
#: Presets tuned by ``tools/tune.py``.
TUNED_PRESETS = ("wearable", "paper", "lab", "field", "physical")

#: Physics weights tried for every PINN; 0 (the plain network) is always on the grid.
LAMBDA_PHYS_GRID = (0.0, 0.01, 0.1, 1.0)

#: Networks tuned as their study twin until ``tools/tune.py`` has run for them: the
#: forward-model PINNs are the study networks with another physics term, so they take
#: the twin's tuned training parameters (same network, same data, same grid; their own
#: ``lambda_phys`` default, as the twin's λ was chosen for the study's term).
TUNED_AS = {
    "original-pinn-fm": "original-pinn",
    "optimized-pinn-fm": "optimized-pinn",
    "rte-pinn-fm": "rte-pinn",
    "selective-rte-pinn-fm": "selective-rte-pinn",
}

#: Training hyper-parameters shared by every network (same values, same draws).
#: ``val_fraction`` 0.2 early-stops on a fifth of the training subjects (epoch 0, the
#: training mean, included; Prechelt 1998, "Early stopping - but when?", in *Neural
#: Networks: Tricks of the Trade*, LNCS 1524, 55-69, doi:10.1007/3-540-49430-8_3) and
#: refits on every row for the chosen epochs; 0 trains ``max_epochs`` on every row.
_NETWORK_SPACE: dict[str, tuple] = {
    "lr": (3e-3, 1e-2),
    "weight_decay": (0.03, 0.3, 1.0, 3.0, 10.0),
    "max_epochs": (100, 200),
    "dropout": (0.0, 0.1),
    "val_fraction": (0.0, 0.2),
}

#: Gradient boosting's grid (2 x 3 x 2 x 3 = 36 points, 12 drawn). Shrinkage at or below
#: scikit-learn's 0.1, with more stages for the smaller steps (Friedman 2001, Ann.
#: Statist. 29, 1189, doi:10.1214/aos/1013203451: shrinkage < 0.1 with more stages
#: generalises better); trees of 4 or 8 leaves (depth 2, 3; Hastie, Tibshirani &
#: Friedman, *The Elements of Statistical Learning*, 2nd ed., Springer 2009, sec. 10.11:
#: 4 <= leaves <= 8 work well); row fractions 0.5-1 (Friedman 2002, Comput. Stat. Data
#: Anal. 38, 367, doi:10.1016/S0167-9473(01)00065-2: 0.5-0.8 improves on all rows).
_GBR_SPACE: dict[str, tuple] = {
    "n_estimators": (100, 300),
    "learning_rate": (0.02, 0.05, 0.1),
    "max_depth": (2, 3),
    "subsample": (0.5, 0.8, 1.0),
}
#: The forward-model estimator's grid (4 x 3 = 12 points): how far to trust the
#: learned nuisance priors at prediction (``prior_scale`` widens them) and how many
#: empirical-Bayes rounds learn them (``n_em``; Dempster, Laird & Rubin 1977, J. R.
#: Stat. Soc. B 39, 1: each round cannot lower the marginal likelihood, fewer rounds
#: stop early, a form of regularisation).
_INVERSION_SPACE: dict[str, tuple] = {
    "prior_scale": (0.5, 1.0, 2.0, 4.0),
    "n_em": (5, 10, 30),
}
#: The hybrids' grids (12 points each): the backbone's own knob and whether the
#: residual GP learns from out-of-fold (``cv`` 3 grouped folds) or in-sample (0)
#: backbone predictions. EBL's ridge penalties: every other value of its default grid
#: from 1e-2 up (6 values); the inversion's prior widths x EM rounds (3 x 2).
_EBL_GP_ALPHAS = (0.01, 0.1, 1.0, 10.0, 100.0, 1000.0)
_HYBRID_SPACE: dict[str, dict[str, tuple]] = {
    "ebl+gp": {
        "backbone_params": tuple({"alphas": (a,)} for a in _EBL_GP_ALPHAS),
        "cv": (0, 3),
    },
    "physics-inversion+gp": {
        "backbone_params": tuple(
            {"prior_scale": s, "n_em": n} for s in (0.5, 1.0, 2.0) for n in (10, 30)
        ),
        "cv": (0, 3),
    },
}
#: Families tuned elsewhere or not at all, with the reason search_space gives.
_NO_GRID = {
    "gp": "it fits its kernel's hyper-parameters by marginal likelihood inside each fit",
    "mean": "the no-skill reference has nothing to tune",
    "oracle": "the oracle knows the simulator's parameters",
}


def search_space(name: str) -> dict[str, tuple]:
    """The grid ``tools/tune.py`` samples :data:`N_CONFIGS` points of, for ``name``.

    Networks share one training grid (learning rate, AdamW weight decay, epochs,
    dropout, early stopping on a subject split or not); the PINNs add
    :data:`LAMBDA_PHYS_GRID`. EBL tunes its ridge penalty (one value per
    configuration, so its own inner CV is bypassed), PLS its number of components,
    gradient boosting (``gbr``) its stages, shrinkage, tree depth and row
    fraction, the forward-model estimators (``physics-inversion``, ``device-inversion``)
    their prior widths and empirical-Bayes rounds, the hybrids their backbone's knob and
    the residual GP's out-of-fold folds (``cv``). The new families' grids have
    :data:`N_CONFIGS` points. The Gaussian process (``gp``) has none: its kernel's
    hyper-parameters are fitted by marginal likelihood inside each ``fit``.

    Raises
    ------
    ConfigError
        If ``name`` has no search space (``gp``, ``mean``, ``oracle``).
    """
    if is_network(name):
        space = dict(_NETWORK_SPACE)
        if is_pinn(name):
            space["lambda_phys"] = LAMBDA_PHYS_GRID
        return space
    if name == "ebl":
        step = max(1, len(DEFAULT_ALPHAS) // N_CONFIGS)
        return {"alphas": tuple((a,) for a in DEFAULT_ALPHAS[::step][:N_CONFIGS])}
    if name == "pls":
        return {"n_components": tuple(range(1, N_CONFIGS + 1))}
    if name == "gbr":
        return dict(_GBR_SPACE)
    if name in ("physics-inversion", "device-inversion"):
        return dict(_INVERSION_SPACE)
    if name in _HYBRID_SPACE:
        return dict(_HYBRID_SPACE[name])
    why = f" ({_NO_GRID[name]})" if name in _NO_GRID else ""
    tuned = ("ebl, pls, gbr, physics-inversion, device-inversion, ebl+gp, "
             "physics-inversion+gp, every network")
    raise ConfigError(f"no tuning search space for model {name!r}{why}; tuned: {tuned}")


#: Families that can choose their own hyper-parameters inside ``fit``, on the rows they
#: are given only (so, inside an outer split, nested: subject-grouped inner folds of the
#: training subjects), and why. Where a preset's tuned values do not apply (the
#: ``mismatch`` study's data from another forward model than the tuning's), these
#: re-tune each family per dataset with the tuning's budget (:data:`N_CONFIGS`
#: candidates x :data:`N_FOLDS` subject-grouped folds).
SELF_TUNING: dict[str, str] = {
    "ebl": f"ridge penalty by {N_FOLDS}-fold subject-grouped inner CV over its tuning grid "
           f"({N_CONFIGS} penalties, 1e-6 to 1e5)",
    "pls": f"components by {N_FOLDS}-fold subject-grouped inner CV over 1-{N_CONFIGS}",
    "gp": "kernel's hyper-parameters by marginal likelihood on the training rows, one length "
          "scale per input or one for all by Schwarz's criterion (kernel='bic')",
    "mean": "nothing to tune",
    "oracle": "nothing to tune",
}


def self_tuning_params(name: str) -> dict | None:
    """Constructor arguments with which family ``name`` re-tunes itself inside ``fit``.

    EBL's ridge penalties are its tuning grid (:func:`search_space`, :data:`N_CONFIGS`
    values) scored by :data:`N_FOLDS` subject-grouped inner folds; PLS's components
    1-:data:`N_CONFIGS` likewise; the GP fits its kernel by marginal likelihood in every
    ``fit`` and here also chooses between one length scale per input and one for all
    (``kernel="bic"``: with few rows the per-input length scales over-fit); the
    no-skill mean and the oracle take their defaults. The arguments replace a preset's
    tuned ones (:func:`preset_params`).

    Returns
    -------
    dict or None
        The arguments, or None for a family without an inner selection
        (:data:`SELF_TUNING` lists those with one).

    Examples
    --------
    >>> self_tuning_params("pls")
    {'n_components': None, 'max_components': 12, 'cv': 3}
    >>> self_tuning_params("gbr") is None
    True
    """
    if name == "ebl":
        alphas = tuple(a for (a,) in search_space("ebl")["alphas"])
        return {"alphas": alphas, "cv": N_FOLDS}
    if name == "pls":
        return {"n_components": None, "max_components": N_CONFIGS, "cv": N_FOLDS}
    if name == "gp":
        return {"kernel": "bic"}
    if name in SELF_TUNING:
        return {}
    return None


@lru_cache(maxsize=1)
def _document() -> dict:
    path = resources.files("nirglucose").joinpath("data", "tuned_params.json")
    if not path.is_file():
        return {"params": {}}
    return json.loads(path.read_text())


def tuning_record() -> dict:
    """The whole tuning document (params, budget, seeds, presets, scores, time)."""
    return json.loads(json.dumps(_document()))


def tuned_params(name: str, preset: str) -> dict:
    """Hyper-parameters chosen by ``tools/tune.py`` for model ``name`` on ``preset``.

    Parameters
    ----------
    name : str
        Registered model name (``nirglucose.models.available_models()``).
    preset : str
        Preset name (``wearable``, ``paper``, ...).

    Returns
    -------
    dict
        Constructor keyword arguments (a fresh copy); empty when the model has nothing
        tuned on that preset (the oracle, an untuned preset), i.e. its defaults. A
        network of :data:`TUNED_AS` not tuned itself gets its twin's training
        parameters (without the twin's ``lambda_phys``).

    Raises
    ------
    ConfigError
        If ``name`` is not a registered model or ``preset`` is neither a preset nor
        in the tuning file.
    """
    get_model_class(name)  # an unknown name raises ConfigError (and no other model loads)
    params = _document().get("params", {})
    if preset not in params and preset not in PRESETS:
        raise ConfigError(unknown_name("preset", preset, sorted(set(PRESETS) | set(params))))
    out = copy.deepcopy(params.get(preset, {}).get(name, {}))
    if not out and name in TUNED_AS:  # not tuned itself yet: its twin's training
        twin = params.get(preset, {}).get(TUNED_AS[name], {})
        out = {k: copy.deepcopy(v) for k, v in twin.items() if k != "lambda_phys"}
    if isinstance(out.get("alphas"), list):  # JSON has no tuples; EBL's grid is one
        out["alphas"] = tuple(out["alphas"])
    return out


#: Training settings of a network fitted where nothing was tuned (a team's own device
#: file: ``fit``, ``benchmark --data``). The untuned constructor defaults train a fixed
#: 300 epochs on every row, which on 25 readings memorises them (SDNN, 3,137 parameters:
#: grouped-CV RMSE up to 2.2 x no skill on a file without signal, issue 28). Here: hold
#: out a fifth of the subjects and early-stop on them, the tuning's choice of
#: ``val_fraction`` on four of the five tuned presets (``data/tuned_params.json``), with
#: epoch 0 (the training mean) a candidate, so a network that learns nothing returns
#: the no-skill predictor (Prechelt 1998, LNCS 1524, 55-69,
#: doi:10.1007/3-540-49430-8_3), then refit on every row for the chosen epochs. Patience
#: 20 epochs: the plateau schedule's reference patience (``make_scheduler``); it stops
#: the 300-epoch run once the validation loss has stalled, so the refit does not chase
#: a lucky late epoch of a five-subject validation set.
UNTUNED_NETWORK_PARAMS: dict = {"val_fraction": 0.2, "patience": 20, "refit": True}


def untuned_params(name: str) -> dict:
    """Constructor keyword arguments for model ``name`` fitted without tuned ones.

    Networks get :data:`UNTUNED_NETWORK_PARAMS` (early stopping on held-out subjects);
    every other model its defaults (``{}``): the linear models, gradient boosting and the
    Gaussian process choose their own regularisation inside ``fit`` or have few knobs.

    Examples
    --------
    >>> untuned_params("sdnn")["val_fraction"]
    0.2
    >>> untuned_params("ebl")
    {}
    """
    return dict(UNTUNED_NETWORK_PARAMS) if is_network(name) else {}


def preset_params(name: str, preset: str | None) -> dict:
    """The constructor arguments every evaluation gives model ``name`` on ``preset``: its
    tuned ones (:func:`tuned_params`), or without a preset (a user's own data)
    :func:`untuned_params`.

    The one place the benchmark, the sweeps and the worn benchmark ask for tuned
    hyper-parameters.

    Examples
    --------
    >>> preset_params("sdnn", None) == untuned_params("sdnn")
    True
    """
    if preset is None:  # user data: networks early-stop on held-out subjects
        return untuned_params(name)
    return dict(tuned_params(name, preset))


def lambda_curve(name: str, preset: str) -> dict | None:
    """The tuning's validation curve of PINN ``name`` on ``preset``: CV RMSE against λ.

    Two curves, both on the tuning seeds and folds (never the reported seeds):

    * ``slice``: the tuned training parameters with each value of
      :data:`LAMBDA_PHYS_GRID` (the same random states; only ``lambda_phys`` changes),
      so the difference between two points is the physics weight's alone;
    * ``profile``: for each λ, the best of the tuning's own draws with that λ (what the
      search saw; the training parameters differ between points).

    Returns
    -------
    dict or None
        ``{"lambda_phys": [...], "slice_cv_rmse_mgdl": [...],
        "profile_cv_rmse_mgdl": [...], "tuned_lambda_phys": float,
        "no_skill_rmse_mgdl": float}``; None where the tuning file has no curve for
        ``name`` on ``preset`` (not a PINN, or not tuned there).
    """
    score = _document().get("scores", {}).get(preset, {}).get(name, {})
    curve = score.get("lambda_curve")
    if not curve:
        return None
    out = json.loads(json.dumps(curve))
    out["tuned_lambda_phys"] = _document()["params"][preset][name]["lambda_phys"]
    out["no_skill_rmse_mgdl"] = score.get("no_skill_rmse_mgdl")
    return out


def best_positive_lambda(name: str, preset: str) -> float | None:
    """The physics weight > 0 with the lowest tuning-CV RMSE at the tuned training
    parameters (the ``slice`` of :func:`lambda_curve`); None without a curve."""
    curve = lambda_curve(name, preset)
    if curve is None:
        return None
    pts = [
        (r, lam)
        for lam, r in zip(curve["lambda_phys"], curve["slice_cv_rmse_mgdl"], strict=True)
        if lam > 0 and r is not None
    ]
    return float(min(pts)[1]) if pts else None
