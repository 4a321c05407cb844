"""What a model is called where people read it: one :func:`label` for every table,
figure, finding and report, and the registry's summaries as plain text.

The display names (:data:`MODEL_LABELS`) sit beside the registry that names the models;
the benchmark's rows that vary a model (a PINN with its physics term off,
``<pinn>/no-physics``, or refitted at another physics weight, ``<pinn>/lambda=<λ>``)
are named here too (:func:`ablation_base`, :func:`lambda_row`), so a label never
depends on the evaluation that made the row.

Examples
--------
>>> label("ebl"), label("rte-pinn/no-physics"), label("my-ridge")
('Enhanced Beer–Lambert', 'RTE-inspired PINN (no physics)', 'my-ridge')
"""

from __future__ import annotations

import re
from typing import Any

from ..exceptions import ConfigError
from .registry import describe_model, privileged_knowledge

__all__ = ["MODEL_LABELS", "NO_PHYSICS", "LAMBDA_ROW", "label", "ablation_base",
           "lambda_row", "plain_text", "describe", "row_privilege", "knows"]

#: Display names of the registered models (the study's own names for its six).
MODEL_LABELS: dict[str, str] = {
    "ebl": "Enhanced Beer–Lambert",
    "pls": "PLS",
    "oracle": "Oracle (true nuisances)",
    "original-pinn": "Original PINN",
    "optimized-pinn": "Optimized PINN",
    "rte-pinn": "RTE-inspired PINN",
    "selective-rte-pinn": "Selective RTE PINN",
    "sdnn": "SDNN",
    "mean": "No skill (training mean)",
    "gp": "Gaussian process (ARD)",
    "gbr": "Gradient boosting",
    "physics-inversion": "Physics inversion (forward model)",
    "device-inversion": "Device inversion (published tables)",
    "ebl+gp": "EBL + residual GP",
    "physics-inversion+gp": "Physics inversion + residual GP",
    "original-pinn-fm": "Original PINN, forward-model physics",
    "optimized-pinn-fm": "Optimized PINN, forward-model physics",
    "rte-pinn-fm": "RTE-inspired PINN, forward-model physics",
    "selective-rte-pinn-fm": "Selective RTE PINN, forward-model physics",
}
#: Suffix of a PINN's row with its physics term off.
NO_PHYSICS = "/no-physics"
#: Infix of a PINN's row refitted at another physics weight (``<pinn>/lambda=0.1``):
#: where tuning chose ``lambda_phys = 0`` the ablation also runs the best weight > 0
#: of the tuning's validation curve.
LAMBDA_ROW = "/lambda="


def lambda_row(name: str, lambda_phys: float) -> str:
    """The row name of PINN ``name`` refitted at physics weight ``lambda_phys``.

    >>> lambda_row("rte-pinn", 0.1)
    'rte-pinn/lambda=0.1'
    """
    return f"{name}{LAMBDA_ROW}{lambda_phys:g}"


def ablation_base(row: str) -> str | None:
    """The PINN an ablation row (``/no-physics`` or ``/lambda=``) belongs to; None for
    any other row.

    >>> ablation_base("rte-pinn/lambda=0.1"), ablation_base("rte-pinn")
    ('rte-pinn', None)
    """
    if row.endswith(NO_PHYSICS):
        return row[: -len(NO_PHYSICS)]
    if LAMBDA_ROW in row:
        return row.split(LAMBDA_ROW)[0]
    return None


def label(model: str) -> str:
    """Display name of a model or benchmark row: the registered model's
    (:data:`MODEL_LABELS`), with ``(no physics)`` or ``(λ = …)`` for an ablation row;
    any other name (an estimator object's label, a user's model) as it is.

    >>> label("original-pinn/lambda=10")
    'Original PINN (λ = 10)'
    """
    base = ablation_base(model)
    if base is None:
        return MODEL_LABELS.get(model, model)
    if model.endswith(NO_PHYSICS):
        return f"{MODEL_LABELS.get(base, base)} (no physics)"
    return f"{MODEL_LABELS.get(base, base)} (λ = {model.split(LAMBDA_ROW)[1]})"


def row_privilege(row: str) -> str | None:
    """What a benchmark row's estimator knows beyond the measured columns (None: deployable).

    :func:`~nirglucose.models.registry.privileged_knowledge` of the registered model;
    a ``/lambda=`` row is its PINN's, a ``/no-physics`` row has no physics term and so
    reads nothing more than the measured columns (None); a name the registry does not
    know (a user's own estimator, a reference row written by an older run) is taken as
    deployable, as :func:`~nirglucose.models.registry.privileged_knowledge` takes an
    estimator that declares nothing.

    >>> row_privilege("ebl") is None, row_privilege("original-pinn-fm/no-physics") is None
    (True, True)
    >>> row_privilege("physics-inversion").startswith("the generating scenario")
    True
    """
    if row.endswith(NO_PHYSICS):
        return None
    base = ablation_base(row) or row
    try:
        return privileged_knowledge(base)
    except ConfigError:
        return None


def knows(privileged: str) -> str:
    """A privileged declaration as the report words it: ``"knows the …"``, parentheses out.

    >>> knows("the generating scenario and the simulator's forward model (Dataset.config)")
    "knows the generating scenario and the simulator's forward model"
    >>> knows("true nuisances (true_* columns) and the generating scenario")
    'knows the true nuisances and the generating scenario'
    """
    text = re.sub(r"\s*\([^)]*\)", "", privileged).strip()
    return "knows " + (text if text.startswith("the ") else "the " + text)


#: A reST cross-reference in parentheses to a private name, `` (:class:`_Hybrid`)``:
#: nothing a user can look up, so the plain text leaves it out.
_PRIVATE_REF = re.compile(r"\s*\(:\w+:`~?_[^`]*`\)")
#: Any other reST role, ``:class:`~pkg.Name``` -> ``Name`` (its last dotted part with
#: ``~``, else the whole target).
_ROLE = re.compile(r":\w+:`(~?)([^`]+)`")


def plain_text(text: str) -> str:
    """Docstring text (reST) as a terminal prints it: roles as their names, literals
    without backquotes, references to private names left out.

    >>> plain_text("A GP on its residual (:class:`_ResidualHybrid`).")
    'A GP on its residual.'
    >>> plain_text("Trees (scikit-learn ``GradientBoostingRegressor``), :func:`~a.b.fit`.")
    'Trees (scikit-learn GradientBoostingRegressor), fit.'
    """
    text = _PRIVATE_REF.sub("", text)
    text = _ROLE.sub(lambda m: m.group(2).rsplit(".", 1)[-1] if m.group(1) else m.group(2),
                     text)
    return text.replace("``", "")


def describe(model: Any) -> str:
    """:func:`~nirglucose.models.registry.describe_model` as plain text
    (:func:`plain_text`): what ``nirglucose models`` prints.

    >>> describe("mean")
    'No skill: predicts the training mean of glucose for every row.'
    """
    return plain_text(describe_model(model))
