"""The training extras of the torch networks: schedules, early stopping, batches.

:class:`~nirglucose.models._torch_base.TorchRegressor` runs the epochs; the pieces
here decide the learning rate of each epoch (:func:`make_scheduler`), when to stop and
which weights to keep (:class:`EarlyStopping`), how many epochs the refit on every row
runs (:func:`smoothed_argmin`), how rows are batched (:func:`batches`), and where an
untrained network starts (:func:`start_at_mean`), and how large a physics term's
gradient is against the data term's (:func:`gradient_norms`; read by
:mod:`~nirglucose.models.physics_effect`).
"""

from __future__ import annotations

import copy
import math
from collections.abc import Iterable, Iterator
from contextlib import contextmanager

import numpy as np
import torch
from torch import nn

from .physics_effect import GRADIENT_KEYS

__all__ = [
    "LR_SCHEDULES",
    "MIN_IMPROVEMENT",
    "SMALL_FIT_ROWS",
    "SMOOTHING_EPOCHS",
    "EarlyStopping",
    "batches",
    "gradient_norms",
    "make_scheduler",
    "smoothed_argmin",
    "start_at_mean",
    "step_scheduler",
    "training_threads",
]

#: Valid ``lr_schedule`` names.
LR_SCHEDULES = ("plateau", "cosine", "none")
#: Relative improvement of the monitored loss that resets the early-stopping counter.
MIN_IMPROVEMENT = 1e-4
#: Window of the validation curve's moving average (the refit's epoch count only).
SMOOTHING_EPOCHS = 5
#: Fits on fewer training rows than this run on one torch thread (:func:`training_threads`).
#: On such small tensors extra threads only add synchronisation, and spin against other
#: processes on a shared machine. Measured (``benchmarks/fit_threads.py``, SDNN, 300
#: full-batch epochs, a shared 2-core machine): one thread against torch's default two,
#: 0.39 / 17.6 s on 25 rows, 0.41 / 16.7 s on 1,000, 1.1 / 5.2 s on 4,000, 2.7 / 41 s on
#: 8,000 and 9.0 / 45 s on 20,000, with bit-identical predictions; the largest size
#: measured is the bound. Larger fits keep the caller's thread count.
SMALL_FIT_ROWS = 20_000


@contextmanager
def training_threads(n_rows: int) -> Iterator[int]:
    """Torch on one intra-op thread while training on fewer than :data:`SMALL_FIT_ROWS`
    rows; the caller's thread count otherwise. Restores the previous count on exit.

    Yields the number of threads the fit runs on. One thread also makes a small fit's
    arithmetic independent of the machine's core count.

    Examples
    --------
    >>> import torch
    >>> before = torch.get_num_threads()
    >>> with training_threads(25) as n:
    ...     n, torch.get_num_threads()
    (1, 1)
    >>> torch.get_num_threads() == before
    True
    """
    saved = torch.get_num_threads()
    n = 1 if n_rows < SMALL_FIT_ROWS else saved
    if n != saved:
        torch.set_num_threads(n)
    try:
        yield n
    finally:
        if torch.get_num_threads() != saved:
            torch.set_num_threads(saved)


def smoothed_argmin(values: list[float], window: int) -> int:
    """1-based index of the minimum of a centred moving average of ``values``.

    The edges average over the part of the window that exists. A small validation set
    gives a noisy loss curve whose raw minimum is often a lucky epoch; the smoothed
    minimum picks the epoch count for the refit more stably.
    """
    v = np.asarray(values, dtype=float)
    half = window // 2
    c = np.concatenate(([0.0], np.cumsum(v)))
    idx = np.arange(len(v))
    lo, hi = np.maximum(idx - half, 0), np.minimum(idx + half + 1, len(v))
    return int(np.argmin((c[hi] - c[lo]) / (hi - lo))) + 1


def start_at_mean(module: nn.Module) -> nn.Module:
    """Zero the glucose output layer(s) of a fresh ``module``; return it.

    Every network here ends its glucose head in a ``Linear(n, 1)`` (the only one-output
    layer; the RTE networks' optics head has two per wavelength). With its weights and
    bias at zero the untrained network predicts 0 in standardised target units, the
    training mean: training starts from the no-skill predictor, and early stopping on
    a validation split can return it (epoch 0) when no epoch beats it. The hidden
    layers keep PyTorch's default initialisation, so no symmetry is introduced; a
    zero-initialised last layer is common practice (Goyal et al. 2017, "Accurate,
    large minibatch SGD", arXiv:1706.02677, sec. 5.1, zero-initialises the last
    normalisation of each residual block for the same reason: start at a simple
    function).
    """
    with torch.no_grad():
        for layer in module.modules():
            if isinstance(layer, nn.Linear) and layer.out_features == 1:
                layer.weight.zero_()
                layer.bias.zero_()
    return module


def _norm(grads: Iterable[torch.Tensor | None]) -> float:
    """Euclidean norm of a gradient over all parameters (None: a parameter it misses)."""
    sq = [torch.sum(g.detach().double() ** 2) for g in grads if g is not None]
    return math.sqrt(float(torch.stack(sq).sum())) if sq else 0.0


def _ratio(num: float | None, den: float) -> float | None:
    return None if num is None or den == 0 else num / den


def gradient_norms(
    parameters: Iterable[torch.Tensor],
    data_loss: torch.Tensor,
    physics_loss: torch.Tensor | None,
    lambda_phys: float,
    glucose: torch.Tensor,
) -> dict[str, float | None]:
    r"""How hard the physics term pulls against the data term: gradient norms and ratios.

    Called before the step's ``backward`` (the graph is retained for it, so the step and
    hence the trained weights are bit-identical with or without the probe; it draws no
    random numbers). Two extra backward passes through the network, three where the
    term reads the glucose prediction (and one through the loss only).

    Parameters
    ----------
    parameters : iterable of torch.Tensor
        The network's parameters (those without ``requires_grad`` are skipped).
    data_loss : torch.Tensor
        The data term (MSE on standardised glucose), a scalar in the graph.
    physics_loss : torch.Tensor or None
        The physics term before its weight; None, or a tensor outside the graph (a
        term switched off), gives None for its norms and ratios.
    lambda_phys : float
        The weight the loss multiplies it by (0: left out of the loss). [-]
    glucose : torch.Tensor
        The network's glucose output for the batch (standardised), in the graph.

    Returns
    -------
    dict
        The keys of :data:`~nirglucose.models.physics_effect.GRADIENT_KEYS`, with
        :math:`M` the data term, :math:`P` the physics term, :math:`\theta` the
        parameters and :math:`z` the glucose predictions:
        ``grad_norm_data`` :math:`\|\nabla_\theta M\|`, ``grad_norm_physics``
        :math:`\lambda\|\nabla_\theta P\|`, ``grad_norm_physics_unit``
        :math:`\|\nabla_\theta P\|`, ``grad_ratio`` (the second over the first),
        ``pull_sd`` :math:`\lambda\frac n2\,\mathrm{RMS}_i(\partial P/\partial z_i)`,
        how far the term displaces each prediction against the data term's curvature
        :math:`\partial^2 M/\partial z_i^2 = 2/n` (in training-glucose SDs: :math:`z`
        is standardised; 0 for a term that does not read :math:`z`), and
        ``indirect_ratio`` :math:`\lambda\|\nabla_\theta P - J^T\partial P/\partial
        z\| / \|\nabla_\theta M\|` (the part of the physics gradient that does not
        pass through the glucose prediction, :math:`J = \partial z/\partial\theta`).

    Examples
    --------
    A "network" z = w (two predictions), data term mean((z - 1)^2), physics term
    sum(z) / 10 at weight 1: the physics term reads z only, so it has no indirect part.

    >>> w = torch.tensor([3.0, 5.0], requires_grad=True)
    >>> out = gradient_norms([w], ((w - 1) ** 2).mean(), w.sum() / 10, 1.0, w)
    >>> round(out["grad_ratio"], 4), round(out["pull_sd"], 4), out["indirect_ratio"]
    (0.0316, 0.1, 0.0)
    """
    params = [p for p in parameters if p.requires_grad]
    data = _norm(torch.autograd.grad(data_loss, params, retain_graph=True, allow_unused=True))
    out = dict.fromkeys(GRADIENT_KEYS)
    out["grad_norm_data"] = data
    if physics_loss is None or not physics_loss.requires_grad:
        return out
    lam = float(lambda_phys)
    grads = torch.autograd.grad(physics_loss, params, retain_graph=True, allow_unused=True)
    unit = _norm(grads)
    (dp,) = torch.autograd.grad(physics_loss, glucose, retain_graph=True, allow_unused=True)
    if dp is None:  # the term does not read the glucose prediction: all of it is indirect
        pull, indirect = 0.0, unit
    else:
        # the data term's curvature in each prediction is 2/n: the term displaces each by
        # n/2 times its gradient, RMS sqrt(n)/2 times the gradient's norm
        pull = math.sqrt(glucose.numel()) / 2.0 * _norm([dp])
        # one backward of P - <dP/dz, z>: the gradient less its share through z
        indirect = _norm(torch.autograd.grad(
            (physics_loss, glucose), params, grad_outputs=(torch.ones(()), -dp),
            retain_graph=True, allow_unused=True))
    out.update(grad_norm_physics=lam * unit, grad_norm_physics_unit=unit,
               grad_ratio=_ratio(lam * unit, data), pull_sd=lam * pull,
               indirect_ratio=_ratio(lam * indirect, data))
    return out


def make_scheduler(
    optimizer: torch.optim.Optimizer, schedule: str, *, patience: int | None, max_epochs: int
):
    """The learning-rate scheduler of ``schedule`` (None for ``'none'``).

    ``'plateau'`` halves the rate when the monitored loss stalls for ``patience // 4``
    epochs (20 // 4 without patience); ``'cosine'`` anneals over ``max_epochs``.
    """
    if schedule == "plateau":
        return torch.optim.lr_scheduler.ReduceLROnPlateau(
            optimizer, mode="min", factor=0.5, patience=max(1, (patience or 20) // 4)
        )
    if schedule == "cosine":
        return torch.optim.lr_scheduler.CosineAnnealingLR(optimizer, T_max=max_epochs)
    return None


def step_scheduler(sched, monitor: float) -> None:
    """Advance ``sched`` one epoch (the plateau scheduler reads ``monitor``)."""
    if isinstance(sched, torch.optim.lr_scheduler.ReduceLROnPlateau):
        sched.step(monitor)
    elif sched is not None:
        sched.step()


def batches(
    tensors: dict[str, torch.Tensor], batch_size: int | None, order: torch.Tensor | None = None
) -> Iterator[tuple[int, dict[str, torch.Tensor]]]:
    """``(rows, batch)`` pairs over ``tensors`` (one full batch when ``batch_size`` is
    None or covers every row), in ``order`` when given."""
    n = len(tensors["y"])
    if batch_size is None or batch_size >= n:
        yield n, tensors  # full batch: the row order does not change the step
        return
    for start in range(0, n, batch_size):
        if order is None:
            yield (
                min(batch_size, n - start),
                {k: v[start : start + batch_size] for k, v in tensors.items()},
            )
        else:
            idx = order[start : start + batch_size]
            yield len(idx), {k: v[idx] for k, v in tensors.items()}


class EarlyStopping:
    """Patience on a monitored loss, and the weights to return to.

    Parameters
    ----------
    patience : int or None
        Stop after this many epochs without a relative improvement of
        :data:`MIN_IMPROVEMENT`; None never stops early. [-]
    keep_best : bool
        Keep a copy of the best epoch's weights (a validation set is monitored) and
        count the module as built, epoch 0, as a candidate (:meth:`start`). False: the
        last epoch is the one kept (training loss, or a refit).

    Attributes
    ----------
    best_epoch : int
        The epoch whose weights are kept (0: the module as built).
    """

    def __init__(self, patience: int | None, keep_best: bool) -> None:
        self.patience = patience
        self.keep_best = keep_best
        self.best = math.inf
        self.best_epoch = 0
        self.best_state: dict | None = None
        self.stale = 0

    def start(self, monitor: float, module: nn.Module) -> float:
        """Record the untrained ``module`` (epoch 0) with its loss ``monitor``; return it."""
        self.best = monitor
        self.best_state = copy.deepcopy(module.state_dict())
        return monitor

    def update(self, monitor: float, epoch: int, module: nn.Module) -> bool:
        """Score ``epoch``; return True when training should stop."""
        if monitor < self.best - MIN_IMPROVEMENT * abs(self.best) or (
            epoch == 1 and not self.keep_best
        ):
            self.best, self.stale = monitor, 0
            if self.keep_best:
                self.best_epoch = epoch
                self.best_state = copy.deepcopy(module.state_dict())
        else:
            self.stale += 1
        if not self.keep_best:
            self.best_epoch = epoch
        return self.patience is not None and self.stale >= self.patience

    def restore(self, module: nn.Module) -> None:
        """Load the kept weights into ``module`` (nothing to do without a copy)."""
        if self.best_state is not None:
            module.load_state_dict(self.best_state)
