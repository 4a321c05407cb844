"""The networks of the study as plain :class:`torch.nn.Module` objects.

Every module takes two inputs, the scaled NIR features ``x_nir`` (n, 4) and the scaled
physiological vector ``x_pmf`` (n, 12), and returns the scaled glucose estimate (n,)
(the RTE networks also return their optical-property heads). Scaling, losses and
training live in the estimators (:mod:`nirglucose.models._torch_base`,
:mod:`nirglucose.models.pinn`, :mod:`nirglucose.models.sdnn`); these modules hold only
the architecture, so that their parameter count is the architecture's.

Layer sizes follow the reference study's descriptions (DESIGN.md, "Estimators") where it
gives them; where it does not, the choice is stated in the class docstring.

Each network also offers :meth:`numpy_forward`: a snapshot of its current weights as
float32 NumPy arrays and a closure that evaluates the same function in eval mode
(dropout off). One small sample through a PyTorch module costs about 7 us of dispatch
per submodule call; the NumPy closure costs about 2.5 us per matrix product, so it is
the single-sample (latency) path of the estimators. TorchScript would be the classic
alternative but ``torch.jit.trace``/``freeze`` are deprecated in torch 2.13. The tests
check each closure against the module's own forward.

References
----------
.. [1] R. Gani, "Physics-Informed Neural Networks vs. Physics Models for Non-Invasive
   Glucose Monitoring: A Comparative Study Under Noise-Stressed Synthetic Conditions",
   University College London (the reference study).
.. [2] C. Srichan et al., "Non-invasively accuracy enhanced blood glucose sensor using
   shallow dense neural networks with NIR monitoring and medical features",
   Sci. Rep. 12, 1769 (2022). :doi:`10.1038/s41598-022-05570-8`
.. [3] A. Vaswani et al., "Attention is all you need", NeurIPS 30 (2017).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np
import torch
from torch import nn

__all__ = [
    "mlp",
    "numpy_mlp",
    "count_parameters",
    "NumpyForward",
    "OriginalPINNNet",
    "OptimizedPINNNet",
    "RTEPINNNet",
    "SDNNNet",
]


def mlp(
    sizes: Sequence[int], *, final_activation: bool = True, dropout: float = 0.0
) -> nn.Sequential:
    """A stack of ``Linear`` + ``ReLU`` layers through ``sizes``.

    Parameters
    ----------
    sizes : sequence of int
        Layer widths, input first (``[4, 32, 64, 32]`` is three Linear layers).
    final_activation : bool
        Put a ReLU (and dropout) after the last Linear layer too.
    dropout : float
        Dropout probability after each activation (0 adds no Dropout layer). [-]

    Returns
    -------
    torch.nn.Sequential
    """
    layers: list[nn.Module] = []
    n_linear = len(sizes) - 1
    for i in range(n_linear):
        layers.append(nn.Linear(sizes[i], sizes[i + 1]))
        if i < n_linear - 1 or final_activation:
            layers.append(nn.ReLU())
            if dropout > 0:
                layers.append(nn.Dropout(dropout))
    return nn.Sequential(*layers)


#: A NumPy forward: ``x = [x_nir | x_pmf]`` (n, 4 + 12) float32 -> glucose (n,) or, for
#: the RTE networks, ``(glucose, mua, musp)``. One concatenated input saves a copy per
#: call on the latency path.
NumpyForward = Callable[[np.ndarray], "np.ndarray | tuple[np.ndarray, ...]"]


def _np(t: torch.Tensor) -> np.ndarray:
    return t.detach().to("cpu", torch.float32).numpy().copy()


def _mlp_steps(seq: nn.Sequential) -> list[tuple[np.ndarray, np.ndarray] | None]:
    """(W^T, b) per Linear and None per ReLU of an eval-mode stack (dropout skipped)."""
    steps: list[tuple[np.ndarray, np.ndarray] | None] = []
    for layer in seq:
        if isinstance(layer, nn.Linear):
            steps.append((np.ascontiguousarray(_np(layer.weight).T), _np(layer.bias)))
        elif isinstance(layer, nn.ReLU):
            steps.append(None)
        elif not isinstance(layer, nn.Dropout):  # dropout is the identity in eval mode
            raise TypeError(f"numpy_mlp: unsupported layer {type(layer).__name__}")
    return steps


def _run_steps(steps: list, x: np.ndarray) -> np.ndarray:
    for step in steps:
        if step is None:
            np.maximum(x, 0.0, out=x)
        else:
            x = x @ step[0]
            x += step[1]
    return x


def numpy_mlp(*seqs: nn.Sequential) -> Callable[[np.ndarray], np.ndarray]:
    """NumPy closure of Linear/ReLU/Dropout stacks in eval mode (weights copied now).

    One stack gives ``f(x) = seq(x)``. Several stacks with the same layer pattern run
    side by side as one stack with block-diagonal weights:
    ``f(concat(x_1, x_2)) = concat(seq_1(x_1), seq_2(x_2))`` -- one matrix product per
    layer instead of one per branch, which halves the per-sample cost of two-branch
    networks.

    Parameters
    ----------
    *seqs : torch.nn.Sequential
        Layers built by :func:`mlp` (``Linear``, ``ReLU``, ``Dropout`` only).

    Returns
    -------
    callable
        ``f(x)`` for ``x`` of shape (n, total in_features), float32.
    """
    per = [_mlp_steps(seq) for seq in seqs]
    pattern = [[st is None for st in steps] for steps in per]
    if any(p != pattern[0] for p in pattern):
        raise ValueError("numpy_mlp: stacks run side by side need the same layer pattern")
    if not pattern[0] or pattern[0][0]:
        raise ValueError("numpy_mlp: a stack must start with a Linear layer")
    steps: list[tuple[np.ndarray, np.ndarray] | None] = []
    for i, is_relu in enumerate(pattern[0]):
        if is_relu:
            steps.append(None)
            continue
        ws = [p[i][0] for p in per]
        w = np.zeros((sum(a.shape[0] for a in ws), sum(a.shape[1] for a in ws)), np.float32)
        r = c = 0
        for a in ws:
            w[r : r + a.shape[0], c : c + a.shape[1]] = a
            r, c = r + a.shape[0], c + a.shape[1]
        steps.append((w, np.concatenate([p[i][1] for p in per])))
    return lambda x: _run_steps(steps, x)


def _np_layer_norm(norm: nn.LayerNorm) -> Callable[[np.ndarray], np.ndarray]:
    """LayerNorm over the last axis with the reductions as matrix products.

    ``x C`` with ``C = I - 11^T/d`` centres and ``(x_c * x_c) m`` with ``m = 1/d`` gives
    the (biased) variance: two small matrix products cost less than NumPy's
    reductions with ``keepdims`` on one sample.
    """
    w, b, eps = _np(norm.weight), _np(norm.bias), np.float32(norm.eps)
    d = w.shape[0]
    centre = (np.eye(d) - 1.0 / d).astype(np.float32)
    mean = np.full((d, 1), 1.0 / d, dtype=np.float32)

    def run(x: np.ndarray) -> np.ndarray:
        xc = x @ centre
        return xc / np.sqrt((xc * xc) @ mean + eps) * w + b

    return run


def count_parameters(module: nn.Module) -> int:
    """Trainable parameters of ``module``: ``sum(p.numel() for p in ... if p.requires_grad)``."""
    return int(sum(p.numel() for p in module.parameters() if p.requires_grad))


class OriginalPINNNet(nn.Module):
    """The study's Original PINN: two branches, concatenation, a dense head.

    NIR branch 4 -> 32 -> 64 -> 32, physiology (PMF) branch 12 -> 16 -> 32 -> 16, both
    with ReLU after every layer; the 48 concatenated features go through
    48 -> 128 -> 64 -> 1 (ReLU between, linear output) [1]_.

    Notes
    -----
    These sizes give 20,225 trainable parameters; the study's table reports 163,000 for
    the same description, which its stated layer sizes cannot produce. We keep the
    described layers and report the counted number.

    Parameters
    ----------
    dropout : float
        Dropout probability after each hidden activation (0, the study's network, adds
        no Dropout layer). [-]
    """

    NIR_SIZES = (4, 32, 64, 32)
    PMF_SIZES = (12, 16, 32, 16)
    HEAD_SIZES = (48, 128, 64, 1)

    def __init__(self, n_nir: int = 4, n_pmf: int = 12, dropout: float = 0.0) -> None:
        super().__init__()
        self.nir = mlp((n_nir, *self.NIR_SIZES[1:]), dropout=dropout)
        self.pmf = mlp((n_pmf, *self.PMF_SIZES[1:]), dropout=dropout)
        self.head = mlp(self.HEAD_SIZES, final_activation=False, dropout=dropout)

    def forward(self, x_nir: torch.Tensor, x_pmf: torch.Tensor) -> torch.Tensor:
        z = torch.cat((self.nir(x_nir), self.pmf(x_pmf)), dim=-1)
        return self.head(z).squeeze(-1)

    def numpy_forward(self) -> NumpyForward:
        """NumPy closure of :meth:`forward` (eval mode, current weights)."""
        branches, head = numpy_mlp(self.nir, self.pmf), numpy_mlp(self.head)

        def run(x: np.ndarray) -> np.ndarray:
            return head(branches(x))[:, 0]

        return run


class OptimizedPINNNet(nn.Module):
    """The study's Optimized PINN: deeper branches fused by multi-head attention.

    Each branch (NIR 4 -> d -> d -> d, PMF 12 -> d -> d -> d, ReLU, dropout) yields one
    token of width ``d_model``; a learned token-type embedding is added, and one
    Transformer-style encoder block [3]_ (multi-head self-attention over the two
    tokens, residual + LayerNorm, a 2d-wide feed-forward layer, residual + LayerNorm)
    fuses them. The two fused tokens are concatenated and a head 2d -> 2d -> d -> 1
    predicts glucose.

    Parameters
    ----------
    d_model : int
        Token width. [-]
    n_heads : int
        Attention heads; must divide ``d_model``. [-]
    dropout : float
        Dropout probability in the branches, attention and head. [-]

    Notes
    -----
    The study gives no layer sizes beyond "deeper, multi-head attention, dropout, weight
    decay" and reports 89,000 parameters; ``d_model=64``, 4 heads gives 76,225.
    """

    def __init__(
        self,
        d_model: int = 64,
        n_heads: int = 4,
        dropout: float = 0.1,
        n_nir: int = 4,
        n_pmf: int = 12,
    ) -> None:
        super().__init__()
        d = d_model
        self.nir = mlp((n_nir, d, d, d), dropout=dropout)
        self.pmf = mlp((n_pmf, d, d, d), dropout=dropout)
        self.token_type = nn.Parameter(torch.zeros(2, d))
        self.attn = nn.MultiheadAttention(d, n_heads, dropout=dropout, batch_first=True)
        self.norm1 = nn.LayerNorm(d)
        self.ff = nn.Sequential(
            nn.Linear(d, 2 * d), nn.ReLU(), nn.Dropout(dropout), nn.Linear(2 * d, d)
        )
        self.norm2 = nn.LayerNorm(d)
        self.drop = nn.Dropout(dropout)
        self.head = nn.Sequential(
            nn.Linear(2 * d, 2 * d),
            nn.ReLU(),
            nn.Dropout(dropout),
            nn.Linear(2 * d, d),
            nn.ReLU(),
            nn.Linear(d, 1),
        )

    def forward(self, x_nir: torch.Tensor, x_pmf: torch.Tensor) -> torch.Tensor:
        tokens = torch.stack((self.nir(x_nir), self.pmf(x_pmf)), dim=1) + self.token_type
        attended, _ = self.attn(tokens, tokens, tokens, need_weights=False)
        h = self.norm1(tokens + self.drop(attended))
        h = self.norm2(h + self.drop(self.ff(h)))
        return self.head(h.flatten(1)).squeeze(-1)

    def numpy_forward(self) -> NumpyForward:
        """NumPy closure of :meth:`forward` (eval mode, current weights).

        Multi-head attention written out: ``Q, K, V = T W_in^T + b_in`` split into
        heads, ``softmax(Q K^T / sqrt(d_head)) V``, heads merged, output projection.
        """
        branches, ff, head = numpy_mlp(self.nir, self.pmf), numpy_mlp(self.ff), numpy_mlp(self.head)
        norm1, norm2 = _np_layer_norm(self.norm1), _np_layer_norm(self.norm2)
        token_type = _np(self.token_type)
        w_in = np.ascontiguousarray(_np(self.attn.in_proj_weight).T)
        b_in = _np(self.attn.in_proj_bias)
        w_out = np.ascontiguousarray(_np(self.attn.out_proj.weight).T)
        b_out = _np(self.attn.out_proj.bias)
        h_n = self.attn.num_heads
        d = token_type.shape[1]
        d_h = d // h_n
        scale = np.float32(1.0 / np.sqrt(d_h))

        def run(x: np.ndarray) -> np.ndarray:
            n = x.shape[0]
            t = branches(x).reshape(n, 2, d)
            t += token_type  # (n, 2, d): the NIR and physiology tokens
            qkv = (t @ w_in + b_in).reshape(n, 2, 3, h_n, d_h).transpose(2, 0, 3, 1, 4)
            q, k, v = qkv[0], qkv[1], qkv[2]  # (n, h, 2, d_h)
            s = (q @ k.transpose(0, 1, 3, 2)) * scale  # (n, h, 2, 2)
            s = np.exp(s - s.max(axis=-1, keepdims=True))
            s /= s.sum(axis=-1, keepdims=True)
            a = (s @ v).transpose(0, 2, 1, 3).reshape(n, 2, d) @ w_out + b_out
            h = norm1(t + a)
            h = norm2(h + ff(h))
            return head(h.reshape(n, 2 * d))[:, 0]

        return run


class RTEPINNNet(nn.Module):
    """The study's RTE-inspired PINN: optical-property heads beside the glucose head.

    NIR branch 4 -> 128 -> 128 and PMF branch 12 -> 64 -> 64 feed a shared trunk
    192 -> 256 -> 256 -> 128. An optics head 128 -> 64 -> 2k predicts the absorption
    and reduced scattering coefficients at the ``k`` regularised wavelengths (positive
    through a softplus with a floor; the last layer's bias starts at the nominal skin
    values so training starts from plausible optics). The glucose head reads the trunk
    features together with ``log mua`` and ``log mus'``: (128 + 2k) -> 64 -> 1.

    Parameters
    ----------
    nominal_mua_per_cm, nominal_musp_per_cm : sequence of float
        Starting optical properties at the ``k`` wavelengths. [1/cm]
    mua_floor_per_cm, musp_floor_per_cm : float
        Lower bounds added to the softplus outputs. [1/cm]
    dropout : float
        Dropout probability after each hidden activation of the branches, the trunk
        and the glucose head (0 adds no Dropout layer; the optics head has none). [-]
    n_state : int
        Width of an optional state head 128 -> 64 -> n_state on the trunk plus a linear
        map from the inputs (the standardised tissue state of the 'forward' physics
        form, much of which the physiological vector nearly measures; the fourth output
        of :meth:`forward`); 0 (default) builds none. [-]

    Notes
    -----
    The study's RTE network has 1.34 M parameters (566 k for the selective variant); its
    layers are not given. This one has 187,849 (four wavelengths; 187,333 for two) so that it trains
    on 100,000 snapshots in minutes on two CPU cores; the count is reported by
    ``n_parameters``.
    """

    def __init__(
        self,
        nominal_mua_per_cm: Sequence[float],
        nominal_musp_per_cm: Sequence[float],
        mua_floor_per_cm: float = 1e-3,
        musp_floor_per_cm: float = 0.5,
        n_nir: int = 4,
        n_pmf: int = 12,
        dropout: float = 0.0,
        n_state: int = 0,
    ) -> None:
        super().__init__()
        k = len(nominal_mua_per_cm)
        if k == 0 or len(nominal_musp_per_cm) != k:
            raise ValueError("nominal_mua_per_cm and nominal_musp_per_cm need the same length >= 1")
        self.n_wavelengths = k
        self.mua_floor = float(mua_floor_per_cm)
        self.musp_floor = float(musp_floor_per_cm)
        self.nir = mlp((n_nir, 128, 128), dropout=dropout)
        self.pmf = mlp((n_pmf, 64, 64), dropout=dropout)
        self.trunk = mlp((192, 256, 256, 128), dropout=dropout)
        self.optics = mlp((128, 64, 2 * k), final_activation=False)
        self.glucose = mlp((128 + 2 * k, 64, 1), final_activation=False, dropout=dropout)
        with torch.no_grad():
            mua0 = torch.as_tensor(nominal_mua_per_cm, dtype=torch.float32) - self.mua_floor
            musp0 = torch.as_tensor(nominal_musp_per_cm, dtype=torch.float32) - self.musp_floor
            last = self.optics[-1]
            last.bias.copy_(_softplus_inverse(torch.cat((mua0, musp0)).clamp_min(1e-3)))
            last.weight.mul_(0.1)
        # built last, so the other layers draw the same initial weights with or without it
        self.n_state = int(n_state)
        self.state = mlp((128, 64, self.n_state), final_activation=False) if n_state else None
        # and a linear path from the inputs: much of the state is (nearly) measured
        self.state_skip = nn.Linear(n_nir + n_pmf, self.n_state) if n_state else None
        if self.state is not None:
            with torch.no_grad():  # start at the state's training mean (standardised 0)
                self.state[-1].weight.mul_(0.1)
                self.state[-1].bias.zero_()

    def forward(
        self, x_nir: torch.Tensor, x_pmf: torch.Tensor
    ) -> tuple[torch.Tensor, ...]:
        h = self.trunk(torch.cat((self.nir(x_nir), self.pmf(x_pmf)), dim=-1))
        raw = nn.functional.softplus(self.optics(h))
        k = self.n_wavelengths
        mua = raw[:, :k] + self.mua_floor
        musp = raw[:, k:] + self.musp_floor
        g = self.glucose(torch.cat((h, torch.log(mua), torch.log(musp)), dim=-1)).squeeze(-1)
        if self.state is not None:
            return g, mua, musp, self.state(h) + self.state_skip(torch.cat((x_nir, x_pmf), -1))
        return g, mua, musp

    def numpy_forward(self) -> NumpyForward:
        """NumPy closure of :meth:`forward` (eval mode, current weights)."""
        branches = numpy_mlp(self.nir, self.pmf)
        trunk, optics, glucose = (numpy_mlp(m) for m in (self.trunk, self.optics, self.glucose))
        state = numpy_mlp(self.state) if self.state is not None else None
        if self.state_skip is not None:
            skip_w = self.state_skip.weight.detach().numpy().T.copy()
            skip_b = self.state_skip.bias.detach().numpy().copy()
        k = self.n_wavelengths
        mua_floor, musp_floor = np.float32(self.mua_floor), np.float32(self.musp_floor)

        def run(x: np.ndarray):
            h = trunk(branches(x))
            raw = np.logaddexp(np.float32(0.0), optics(h))  # softplus
            mua, musp = raw[:, :k] + mua_floor, raw[:, k:] + musp_floor
            g = glucose(np.concatenate((h, np.log(mua), np.log(musp)), axis=-1))[:, 0]
            if state is not None:
                return g, mua, musp, state(h) + (x @ skip_w + skip_b)
            return g, mua, musp

        return run


def _softplus_inverse(y: torch.Tensor) -> torch.Tensor:
    """x with softplus(x) = y, for y > 0: log(expm1(y))."""
    return torch.log(torch.expm1(y))


class SDNNNet(nn.Module):
    """Shallow dense network after Srichan et al. (2022) [2]_: no physics.

    A shallow front end (one 4 -> 16 ReLU layer) on the four absorbances; its output is
    concatenated with the 12-dimensional physiological vector and a dense stack
    28 -> 48 -> 32 -> 16 -> 8 -> 1 (ReLU between) predicts glucose.

    Notes
    -----
    Srichan et al. fed multi-band NIR readings and personal medical features to a
    small dense network; neither they nor the reference study give the layer sizes
    used here. This arrangement gives 3,713 trainable parameters, the count the study
    reports for its SDNN.

    Parameters
    ----------
    dropout : float
        Dropout probability after each hidden activation (0 adds no Dropout layer). [-]
    """

    FRONT_SIZES = (4, 16)
    STACK_SIZES = (28, 48, 32, 16, 8, 1)

    def __init__(self, n_nir: int = 4, n_pmf: int = 12, dropout: float = 0.0) -> None:
        super().__init__()
        self.n_nir = n_nir
        front = self.FRONT_SIZES[1]
        self.front = mlp((n_nir, front), dropout=dropout)
        self.stack = mlp(
            (front + n_pmf, *self.STACK_SIZES[1:]), final_activation=False, dropout=dropout
        )

    def forward(self, x_nir: torch.Tensor, x_pmf: torch.Tensor) -> torch.Tensor:
        return self.stack(torch.cat((self.front(x_nir), x_pmf), dim=-1)).squeeze(-1)

    def numpy_forward(self) -> NumpyForward:
        """NumPy closure of :meth:`forward` (eval mode, current weights)."""
        front, stack = numpy_mlp(self.front), numpy_mlp(self.stack)
        k = self.n_nir

        def run(x: np.ndarray) -> np.ndarray:
            return stack(np.concatenate((front(x[:, :k]), x[:, k:]), axis=-1))[:, 0]

        return run
