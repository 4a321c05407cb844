r"""Does a PINN's physics term move its fit? The training loop's gradient probes, read.

A term added to the loss can change what a network learns only through its gradient.
The shared training loop (:class:`~nirglucose.models._torch_base.TorchRegressor`)
measures it on a few epochs of every fit with a physics term (:func:`is_probe_epoch`:
the first, every ``ceil(max_epochs / GRADIENT_PROBES)``-th and the last), on the epoch's
first training batch before the optimiser step
(:func:`~nirglucose.models._training.gradient_norms`). With :math:`M` the data term
(MSE on standardised glucose), :math:`P` the physics term, :math:`\lambda` its weight,
:math:`\theta` the parameters and :math:`z` the n glucose predictions (standardised):

* ``grad_norm_data`` :math:`\|\nabla_\theta M\|`; ``grad_norm_physics_unit``
  :math:`\|\nabla_\theta P\|`; ``grad_norm_physics`` :math:`\lambda\|\nabla_\theta P\|`
  (0 at :math:`\lambda = 0`, where the term is left out of the loss); ``grad_ratio``,
  the last over the first;
* ``pull_sd``: how far the term displaces each prediction against the data term,
  :math:`\lambda\,\mathrm{RMS}_i\big(\partial P/\partial z_i \,/\,
  \partial^2 M/\partial z_i^2\big)` with :math:`\partial^2 M/\partial z_i^2 = 2/n`,
  in standard deviations of the training glucose;
* ``indirect_ratio``: the part of :math:`\lambda\nabla_\theta P` that does not pass
  through the glucose predictions (optics heads, a state head, collocation readings),
  over :math:`\|\nabla_\theta M\|`.

They join the epoch's row of ``history_`` (None on epochs not probed) and hence the
benchmark's ``histories.json``. Their names carry no ``train_``/``val_`` prefix: they
are not losses, and the training-dynamics figure draws only those.
:func:`physics_verdict` reads a history and says whether the term moves the fit, by a
documented rule (:data:`PULL_INERT_SD`, :data:`INERT_RATIO`, :data:`CONSTANT_CHANGE`).

Why a pull and not only the parameter ratio: a term that pushes every prediction the
same way (the study's Beer-Lambert residual, see :mod:`~nirglucose.models.pinn`) adds
its gradients over the rows coherently, while the data term's partly cancel, and with
decoupled weight decay the data gradient never vanishes; so the parameter-space ratio
(0.006-0.5 for that term at :math:`\lambda = 1`) overstates what the term does, which
is to shift the predictions to where the data term's restoring force balances it:
:math:`4\times10^{-5}` SD, 0.0023 mg/dL on ``paper`` with the published glucose
constants the study PINNs use (``studies/records/pinn_physics_gradient.json``; 0.026
mg/dL when the term read the data's ×11 gain). A first-order estimate, and a good one:
with the ×11 gain, at :math:`\lambda = 1000` the predicted mean shift was 26 mg/dL and
the fitted Original PINN's held-out predictions rose by 27-33 mg/dL (``paper``, 40 x 3,
seeds 0-2 of ``random_state``).

This module needs neither torch nor a fitted model: the report calls it on
``histories.json``.

Examples
--------
>>> rows = [{"epoch": 1, "train_physics": 0.11197, "grad_norm_data": 2.0,
...          "grad_norm_physics": 0.05, "grad_norm_physics_unit": 0.05,
...          "grad_ratio": 0.025, "pull_sd": 4e-4, "indirect_ratio": 0.0},
...         {"epoch": 2, "train_physics": 0.11199, "grad_norm_data": 1.0,
...          "grad_norm_physics": 0.05, "grad_norm_physics_unit": 0.05,
...          "grad_ratio": 0.05, "pull_sd": 4e-4, "indirect_ratio": 0.0}]
>>> v = physics_verdict(rows)
>>> v["verdict"], v["physics_constant"]
('inert', True)
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from typing import Any

import numpy as np

__all__ = [
    "GRADIENT_KEYS",
    "GRADIENT_PROBES",
    "PULL_INERT_SD",
    "INERT_RATIO",
    "CONSTANT_CHANGE",
    "VERDICTS",
    "is_probe_epoch",
    "physics_verdict",
]

#: History keys of a gradient probe (see the module notes).
GRADIENT_KEYS = ("grad_norm_data", "grad_norm_physics", "grad_norm_physics_unit", "grad_ratio",
                 "pull_sd", "indirect_ratio")
#: Probed epochs per training run besides the first: 6 of 200 epochs. Each probe costs
#: two or three extra backward passes through the retained graph: 3-4 % of the fit's CPU
#: time (``studies/pinn_physics_gradient.py`` measures it per model).
GRADIENT_PROBES = 5
#: A term whose median pull over the probes is below this displaces the predictions by
#: less than a hundredth of the training glucose's standard deviation (0.6 mg/dL on
#: ``paper``, SD 58 mg/dL): less than what any perturbation of the training does to
#: these networks (``lambda_phys`` 1e-3 instead of 0 moves the Original PINN's held-out
#: predictions by 2-3.5 mg/dL RMS on ``paper``, 40 x 3, ``random_state`` 0-2, while its
#: pull there is 1e-6 SD). [training-glucose SD]
PULL_INERT_SD = 1e-2
#: A term whose median indirect gradient ratio (the part that does not pass through the
#: glucose predictions) is below this moves no parameter by more than a thousandth of
#: what the data term moves it, per step of plain gradient descent. [-]
INERT_RATIO = 1e-3
#: A physics term whose training value changes by less than this relative amount
#: between the first and the last epoch is constant during training. [-]
CONSTANT_CHANGE = 1e-3
#: What :func:`physics_verdict` can say.
VERDICTS = ("active", "inert", "off", "unmeasured")


def is_probe_epoch(epoch: int, max_epochs: int) -> bool:
    """Whether the training loop probes the gradients on ``epoch`` (1-based) of a run of
    at most ``max_epochs``: the first, the last, and every
    ``ceil(max_epochs / GRADIENT_PROBES)``-th.

    Examples
    --------
    >>> [e for e in range(1, 201) if is_probe_epoch(e, 200)]
    [1, 40, 80, 120, 160, 200]
    """
    stride = max(1, math.ceil(max_epochs / GRADIENT_PROBES))
    return epoch == 1 or epoch == max_epochs or epoch % stride == 0


def _rows(history: Any) -> list[Mapping[str, Any]]:
    if hasattr(history, "to_dict"):  # a pandas DataFrame (the report's histories)
        return history.to_dict(orient="records")
    return list(history)


def _finite(values: Iterable[Any]) -> np.ndarray:
    out = np.array([np.nan if v is None else float(v) for v in values], dtype=float)
    return out[np.isfinite(out)]


def physics_verdict(
    history: Any,
    *,
    pull_inert_sd: float = PULL_INERT_SD,
    inert_ratio: float = INERT_RATIO,
    constant_change: float = CONSTANT_CHANGE,
) -> dict[str, Any]:
    """Whether the physics term of a training history moves the fit.

    Parameters
    ----------
    history : list of dict or pandas.DataFrame
        Per-epoch rows, as ``history_`` of a fitted network or one model's entry of
        the benchmark's ``histories.json``.
    pull_inert_sd : float
        Median pull under which the term's direct effect on the predictions is nil
        (:data:`PULL_INERT_SD`). [training-glucose SD]
    inert_ratio : float
        Median indirect gradient ratio under which its effect through other outputs is
        nil (:data:`INERT_RATIO`). [-]
    constant_change : float
        Relative change of the training physics loss, first to last epoch, under which
        the term counts as constant (:data:`CONSTANT_CHANGE`). [-]

    Returns
    -------
    dict
        ``verdict``: one of :data:`VERDICTS`; ``reason``: one sentence; ``probes``
        (probed epochs); the medians over the probes ``median_pull_sd``,
        ``median_grad_ratio``, ``median_indirect_ratio`` and ``max_grad_ratio``;
        ``physics_first``, ``physics_last``, ``physics_relative_change``
        (``|last - first| / |first|``) and ``physics_constant`` (that change below
        ``constant_change``); None where not recorded.

    Notes
    -----
    The rule, in order:

    1. ``unmeasured``: no probe recorded (a network without a physics term, or a
       history written before the probes existed).
    2. ``off``: the loss holds no physics gradient: ``lambda_phys`` is 0 (the term is
       left out of the loss; its unweighted gradient is still reported), or the term is
       switched off (no physics gradient at all: no optics for the data, or a
       forward-model term at ``lambda_phys`` 0).
    3. ``inert``: the median pull is below ``pull_inert_sd`` and the median indirect
       ratio below ``inert_ratio``: the term neither displaces the predictions nor
       moves the parameters by another route, so it cannot change the fit and an
       ablation (``lambda_phys = 0``) cannot show an effect.
    4. ``active`` otherwise.

    ``grad_ratio`` and ``physics_constant`` are reported beside the verdict, not used
    by it: the first overstates a coherent push (module notes), and a constant term is
    a sign of inertness but not a proof (a term that holds the fit in place is constant
    too).
    """
    rows = _rows(history)
    out: dict[str, Any] = dict.fromkeys(
        ("median_pull_sd", "median_grad_ratio", "median_indirect_ratio", "max_grad_ratio",
         "physics_first", "physics_last", "physics_relative_change", "physics_constant"))
    phys = _finite(r.get("train_physics") for r in rows)
    if phys.size:
        first, last = float(phys[0]), float(phys[-1])
        change = abs(last - first) / abs(first) if first != 0 else (0.0 if last == 0 else math.inf)
        out.update(physics_first=first, physics_last=last, physics_relative_change=change,
                   physics_constant=bool(change < constant_change))
    probed = [r for r in rows if _finite([r.get("grad_norm_data")]).size]
    out["probes"] = len(probed)
    if not probed:
        return {"verdict": "unmeasured", "reason": "no gradient probe in the history "
                "(no physics term, or written before the probes existed)", **out}
    weighted = _finite(r.get("grad_norm_physics") for r in probed)
    if weighted.size == 0:
        return {"verdict": "off", "reason": "the physics term is switched off "
                "(no physics gradient recorded)", **out}
    if not np.any(weighted > 0):
        return {"verdict": "off", "reason": "lambda_phys is 0: the term is left out of "
                "the loss", **out}
    for key in ("pull_sd", "grad_ratio", "indirect_ratio"):
        values = _finite(r.get(key) for r in probed)
        out[f"median_{key}"] = float(np.median(values)) if values.size else None
        if key == "grad_ratio" and values.size:
            out["max_grad_ratio"] = float(values.max())
    pull, indirect = out["median_pull_sd"], out["median_indirect_ratio"]
    what = (f"it displaces the predictions by {pull:.2g} training SD and its gradient "
            f"outside them is {indirect:.2g} of the data term's (medians over "
            f"{len(probed)} probes)") if pull is not None and indirect is not None else ""
    if pull is not None and indirect is not None and pull < pull_inert_sd \
            and indirect < inert_ratio:
        return {"verdict": "inert", "reason": f"{what}: below {pull_inert_sd:g} and "
                f"{inert_ratio:g}, it does not move the fit", **out}
    return {"verdict": "active", "reason": what or "the data term had no gradient where "
            "the physics term had one", **out}
