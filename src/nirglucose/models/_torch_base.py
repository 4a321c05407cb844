"""One PyTorch training loop behind the scikit-learn estimator API.

:class:`TorchRegressor` is the base of every network estimator (the four PINNs and the
SDNN). It follows the scikit-learn contract (``__init__`` only stores keyword
arguments, validation happens in ``fit``, learned state ends in ``_``, ``fit`` returns
``self``, ``predict`` checks that the model is fitted) and the skorch habit of one
training loop split into small overridable steps [1]_:

``build_module()``
    the :class:`torch.nn.Module` (architecture only);
``get_loss(y_pred, y_true, batch)``
    ``(total, terms)``; a physics-informed variant calls the parent and adds its
    residual, it never copies the loop;
``train_step(batch)`` / ``validation_step(batch)``
    one optimiser step / one evaluation, returning the loss terms.

What the loop does, in order: read the measured columns (never ``true_*``), turn the
ADC codes into decadic absorbances :math:`A = \\log_{10}(I_0/I)` (robust to the LED
power and gain), standardise the absorbances, the physiological vector and the target
on the training rows, hold out a validation set by subject (``GroupShuffleSplit`` on
``subject_id``, or a random split when there are no subject ids, or the ``X_val`` the
caller passes), and train with AdamW [2]_ [3]_ (full batch by default: one step per
epoch), a learning-rate schedule and, when a validation set exists, early stopping on
the validation MSE, keeping the best weights and a per-epoch history (``history_``).
With an internal split the model is then refitted on every training row for the
selected number of epochs (``refit``; the epoch count is the minimum of the smoothed
validation curve), so the held-out subjects are not lost on small data. The default
has no split: a fixed, tuned number of full-batch epochs with cosine annealing.

Prediction: batches run through the module under :func:`torch.inference_mode` in
float32; up to :data:`NUMPY_ROWS` rows (and :meth:`TorchRegressor.predict_one`) run
through a NumPy snapshot of the same network, which avoids PyTorch's per-module
dispatch cost on one sample.

Training is seeded: the same ``random_state`` gives identical weights and predictions
(the weight initialisation, dropout and batch shuffling all draw from generators seeded
from it, inside :func:`torch.random.fork_rng` so the caller's global torch RNG is left
untouched). :func:`torch.use_deterministic_algorithms` is *not* switched on: in torch
2.13 the first call imports ``torch._inductor`` (several seconds), and every CPU kernel
these small networks use (linear, softplus, attention, Adam) is deterministic already,
which the tests check (same seed, bit-identical weights). Results are reproducible for
a given torch build and thread count.

Save/load writes a JSON document plus a safetensors weight file beside it (both
atomically); loading reads JSON and safetensors (or a ``weights_only`` torch file) and
never executes code from the files.

References
----------
.. [1] skorch developers, "skorch: a scikit-learn compatible neural network library
   that wraps PyTorch", https://skorch.readthedocs.io (NeuralNet.get_loss,
   train_step, validation_step).
.. [2] D. P. Kingma and J. Ba, "Adam: a method for stochastic optimization",
   ICLR (2015). arXiv:1412.6980
.. [3] I. Loshchilov and F. Hutter, "Decoupled weight decay regularization",
   ICLR (2019). arXiv:1711.05101
.. [4] A. Kessy, A. Lewin and K. Strimmer, "Optimal whitening and decorrelation",
   Am. Stat. 72, 309-314 (2018). :doi:`10.1080/00031305.2016.1277159`
.. [5] Y. LeCun, L. Bottou, G. B. Orr and K.-R. Mueller, "Efficient BackProp", in
   Neural Networks: Tricks of the Trade, LNCS 1524, 9-50 (1998), sec. 4.3
   (decorrelated inputs). :doi:`10.1007/3-540-49430-8_2`
"""

from __future__ import annotations

import copy
import inspect
import json
import logging
import math
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any, ClassVar

import numpy as np
import pandas as pd
import torch
from sklearn.base import BaseEstimator, RegressorMixin
from sklearn.exceptions import NotFittedError as _SklearnNotFittedError
from sklearn.model_selection import GroupShuffleSplit, ShuffleSplit
from sklearn.utils import check_random_state
from torch import nn

from ..dataset import Dataset, atomic_write
from ..exceptions import ConfigError, DataError, NotFittedError
from ..schema import DeviceSchema
from ._base import fit_input, predict_input, target_of
from ._validate import check_torch_doc, check_weights
from ._whitening import scale_of as _scale_of
from ._whitening import zca_whitening
from .networks import count_parameters

__all__ = [
    "TorchRegressor",
    "LR_SCHEDULES",
    "FORMAT_VERSION",
    "NUMPY_ROWS",
    "WHITENING_KEY",
    "nir_pmf_features",
    "zca_whitening",
]

logger = logging.getLogger(__name__)

#: Valid ``lr_schedule`` names.
LR_SCHEDULES = ("plateau", "cosine", "none")
#: Version of the saved-model JSON layout.
FORMAT_VERSION = 1

_PREDICT_CHUNK = 65536
#: Batches up to this many rows are predicted through the NumPy closure.
NUMPY_ROWS = 8
_MIN_IMPROVEMENT = 1e-4  # relative improvement that resets the early-stopping counter
_SMOOTHING_EPOCHS = 5  # window of the validation curve's moving average (refit only)
#: Default training: full-batch AdamW for a fixed number of epochs with cosine annealing
#: and no validation split (the epoch count, lr and weight decay are hyper-parameters,
#: chosen per preset by ``benchmarks/tune.py``; see :func:`nirglucose.models.tuned_params`).
#: These untuned defaults are mid-grid values of that search's space.
DEFAULT_EPOCHS = 300
DEFAULT_LR = 3e-3
DEFAULT_WEIGHT_DECAY = 1e-3


class _UnfittedError(NotFittedError, _SklearnNotFittedError):
    """nirglucose's :class:`~nirglucose.exceptions.NotFittedError`, also recognised by
    scikit-learn tools as theirs (it subclasses both)."""


def nir_pmf_features(
    Xa: np.ndarray, schema: DeviceSchema | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """Decadic absorbances and the physiological vector from a device's raw columns.

    Parameters
    ----------
    Xa : numpy.ndarray
        (n, width) raw columns in ``schema.raw_columns`` order (ADC codes, reference
        codes where the device has them, physiological columns).
    schema : DeviceSchema, optional
        The device (the study's when None).

    Returns
    -------
    absorbance : numpy.ndarray
        :math:`A_\\lambda = \\log_{10}(I_0 / I)`, (n, k); a device without
        reference codes uses the ADC's full scale as :math:`I_0`. [-]
    pmf : numpy.ndarray
        (n, m) physiological columns; one column of zeros when the device records none
        (the networks' physiology branch then sees a constant). [column units]

    Raises
    ------
    DataError
        If any ADC or reference code is not positive (no absorbance exists).
    """
    a, pmf = (schema or DeviceSchema()).split(np.asarray(Xa, dtype=float))
    if pmf.shape[1] == 0:
        pmf = np.zeros((len(a), 1))
    return a, pmf


def _smoothed_argmin(values: list[float], window: int) -> int:
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


def _start_at_mean(module: nn.Module) -> nn.Module:
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


#: State-dict key of the whitening matrix (a buffer, not a trained parameter).
WHITENING_KEY = "whitening"


class _WhitenedInputs(nn.Module):
    """A fixed linear map on ``[x_nir | x_pmf]`` before the network (see ``whiten_inputs``).

    The matrix is a buffer (saved with the weights, never trained, not counted in
    ``n_parameters``); the wrapped network sees the whitened columns split as before.
    """

    def __init__(self, inner: nn.Module, matrix: np.ndarray, n_nir: int) -> None:
        super().__init__()
        self.inner = inner
        self.n_nir = int(n_nir)
        self.register_buffer(WHITENING_KEY, torch.as_tensor(matrix, dtype=torch.float32))

    def forward(self, x_nir: torch.Tensor, x_pmf: torch.Tensor) -> Any:
        z = torch.cat((x_nir, x_pmf), dim=-1) @ getattr(self, WHITENING_KEY)
        return self.inner(z[:, : self.n_nir], z[:, self.n_nir :])

    def numpy_forward(self) -> Any:
        """NumPy closure: the whitening, then the network's own closure (None if none)."""
        inner = getattr(self.inner, "numpy_forward", None)
        if not callable(inner):
            return None
        fn = inner()
        m = getattr(self, WHITENING_KEY).detach().numpy().copy()

        def run(x: np.ndarray):
            return fn(x @ m)

        return run


#: The training keyword arguments every network takes (name -> default), in the
#: constructor's order; documented in :class:`TorchRegressor`.
TRAINING_PARAMS: dict[str, Any] = {
    "max_epochs": DEFAULT_EPOCHS,
    "batch_size": None,
    "lr": DEFAULT_LR,
    "weight_decay": DEFAULT_WEIGHT_DECAY,
    "dropout": 0.0,
    "whiten_inputs": True,
    "patience": None,
    "val_fraction": 0.0,
    "lr_schedule": "cosine",
    "refit": True,
    "random_state": None,
}


def _constructor_defaults(cls: type) -> dict[str, Any]:
    """``cls``'s constructor parameters and defaults: its own (most derived first),
    then :data:`TRAINING_PARAMS` with the hierarchy's ``training_defaults``."""
    own: dict[str, Any] = {}
    training = dict(TRAINING_PARAMS)
    for klass in reversed(cls.__mro__):
        training.update(klass.__dict__.get("training_defaults", {}))
    for klass in cls.__mro__:
        for name, default in klass.__dict__.get("own_params", {}).items():
            own.setdefault(name, default)
    clash = sorted(set(own) & set(training))
    if clash:
        raise TypeError(f"{cls.__name__}.own_params repeats training parameters {clash}")
    return {**own, **training}


def _keyword_init(cls: type) -> Callable[..., None]:
    """A keyword-only ``__init__`` for ``cls`` storing each parameter unchanged.

    scikit-learn reads an estimator's parameters from its ``__init__`` signature
    (``BaseEstimator._get_param_names``), so the generated function carries an explicit
    ``__signature__``: ``get_params``, ``clone`` and ``set_params`` see every
    parameter, and no network re-declares the eleven training ones.
    """
    defaults = _constructor_defaults(cls)

    def __init__(self, **params: Any) -> None:
        unknown = sorted(set(params) - set(defaults))
        if unknown:
            raise TypeError(
                f"{cls.__name__}() got an unexpected keyword argument {unknown[0]!r}; "
                f"parameters: {', '.join(defaults)}"
            )
        for name, default in defaults.items():
            setattr(self, name, params.get(name, default))

    self_param = inspect.Parameter("self", inspect.Parameter.POSITIONAL_OR_KEYWORD)
    __init__.__signature__ = inspect.Signature(
        [self_param]
        + [
            inspect.Parameter(name, inspect.Parameter.KEYWORD_ONLY, default=default)
            for name, default in defaults.items()
        ]
    )
    __init__.__qualname__ = f"{cls.__qualname__}.__init__"
    __init__.__module__ = cls.__module__
    __init__.generated = True  # see test_training_parameters_are_declared_once
    return __init__


class TorchRegressor(RegressorMixin, BaseEstimator):
    """Base of the network estimators: one seeded training loop, save/load, fast predict.

    Subclasses implement :meth:`build_module` and may override :meth:`get_loss`
    (calling the parent), :meth:`_fit_physics` and :meth:`_validate_extra_params`.

    Parameters
    ----------
    max_epochs : int
        Training epochs (an upper bound when early stopping is on). [-]
    batch_size : int or None
        Mini-batch size; None (default) takes one full-batch step per epoch, which on
        the study's few hundred rows is both faster (one Python round trip per epoch)
        and a smoother optimisation than mini-batches. [-]
    lr : float
        AdamW learning rate. [-]
    weight_decay : float
        AdamW decoupled weight decay [3]_. [-]
    dropout : float
        Dropout probability after the hidden activations, in [0, 1). [-]
    whiten_inputs : bool
        Train on ZCA-whitened inputs [4]_ [5]_: a fixed linear map (a buffer of the
        module, from the training rows) decorrelates the standardised absorbances and
        physiological vector before the network. Glucose lives in low-variance
        directions of those inputs (the LEDs' absorbances move together with the
        tissue); without decorrelation gradient descent learns the high-variance
        directions first and memorises the training subjects before it finds them
        (on a quiet regime, 80 subjects x 3, grouped 5-fold: SDNN 39 -> 16 mg/dL, the
        training mean 58; ``benchmarks/tune.py``). False gives the plain study
        network on standardised inputs.
    patience : int or None
        Stop after this many epochs without a relative improvement of 1e-4 in the
        monitored loss (validation MSE, or training loss without a validation set);
        None (default) trains all ``max_epochs``. [-]
    val_fraction : float
        Share of subjects (or rows, without subject ids) held out for early stopping
        when no ``X_val`` is passed to :meth:`fit`; 0 (default) disables the split:
        the epoch count is then a hyper-parameter chosen by cross-validation, not by a
        20 % hold-out of a 192-row training set. [-]
    lr_schedule : {'plateau', 'cosine', 'none'}
        Halve the learning rate when the monitored loss stalls for ``patience // 4``
        epochs (``ReduceLROnPlateau``), cosine annealing over ``max_epochs``, or
        constant.
    refit : bool
        After early stopping on an *internal* validation split, retrain from the same
        initial weights on every training row for the selected number of epochs, at
        the learning rates those epochs had (so the held-out subjects are not lost to
        the final model). Not done with an explicit ``X_val`` (the study's 60/20/20
        protocol trains on the 60 % only) or without a validation split.
    random_state : int, numpy.random.RandomState or None
        Seeds the split, the initialisation, dropout and shuffling. The same integer
        gives identical weights and predictions.

    Attributes
    ----------
    module_ : torch.nn.Module
        The trained network (in eval mode).
    history_ : list of dict
        One dict per epoch: ``epoch``, ``lr``, ``train_loss``, ``val_loss`` and each
        loss term as ``train_<term>`` / ``val_<term>`` (e.g. ``train_mse``,
        ``train_physics``), plus ``val_rmse_mgdl``. Losses are in standardised target
        units; ``val_*`` are None without a validation set.
    best_epoch_ : int
        With a validation set: the epoch with the lowest validation MSE (whose weights
        were kept) or, after a refit, how many epochs the refit ran; 0 when no epoch
        beat the untrained network, which predicts the training mean (its glucose
        output layer starts at zero). Without one: the last epoch (its weights are
        kept).
    start_val_mse_ : float or None
        Validation MSE of the untrained network, i.e. of the training mean (epoch 0
        of early stopping); None without a validation set. [standardised units]
    n_epochs_ : int
        Epochs run before early stopping.
    refit_epochs_ : int
        Epochs of the refit on all rows (0 without one).
    refit_history_ : list of dict
        Per-epoch training losses of the refit.
    scaler_ : dict
        Means and scales of the absorbances, physiology and target (all training rows,
        an internal validation split included; an explicit ``X_val`` excluded).
    physics_ : dict
        Constants of the physics terms (JSON-serialisable), empty for the SDNN.
    n_features_in_ : int
        Width of the device's raw columns (20 for the study's device).
    schema_ : DeviceSchema
        The device fitted on (LEDs, reference codes, ADC bits, physiological columns).
    """

    #: Set by :func:`~nirglucose.models.registry.register`.
    registry_name: ClassVar[str] = ""

    #: A subclass's own constructor parameters (name -> default), placed before the
    #: training ones; collected along the class hierarchy, the subclass's first.
    own_params: ClassVar[dict[str, Any]] = {}
    #: Training defaults a subclass changes (e.g. the Optimized PINN's dropout 0.1).
    training_defaults: ClassVar[dict[str, Any]] = {}

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        if "__init__" not in cls.__dict__:
            cls.__init__ = _keyword_init(cls)

    # ------------------------------------------------------------------ overridables

    def build_module(self) -> nn.Module:
        """Return a freshly initialised network.

        Modules that need data-dependent constants read them from
        :meth:`_physics_or_default`.
        """
        raise NotImplementedError

    def get_loss(
        self, y_pred: Any, y_true: torch.Tensor, batch: dict[str, torch.Tensor]
    ) -> tuple[torch.Tensor, dict[str, torch.Tensor]]:
        """Data loss: mean squared error of the standardised glucose.

        Parameters
        ----------
        y_pred : torch.Tensor or tuple
            The module's output (glucose first when a tuple).
        y_true : torch.Tensor
            Standardised reference glucose, (n,).
        batch : dict of torch.Tensor
            ``nir``, ``pmf`` (scaled inputs), ``absorbance`` (raw decadic, (n, 4)),
            ``y``.

        Returns
        -------
        total : torch.Tensor
            Scalar loss to minimise.
        terms : dict of torch.Tensor
            Its named parts (``mse`` here; subclasses add theirs).
        """
        g = self._glucose(y_pred)
        mse = torch.mean((g - y_true) ** 2)
        return mse, {"mse": mse}

    def train_step(self, batch: dict[str, torch.Tensor]) -> dict[str, torch.Tensor]:
        """One optimiser step on ``batch``; returns the detached loss terms (and ``loss``)."""
        self._optimizer.zero_grad(set_to_none=True)
        out = self.module_(batch["nir"], batch["pmf"])
        total, terms = self.get_loss(out, batch["y"], batch)
        total.backward()
        self._optimizer.step()
        return {"loss": total.detach(), **{k: v.detach() for k, v in terms.items()}}

    def validation_step(self, batch: dict[str, torch.Tensor]) -> dict[str, torch.Tensor]:
        """Loss terms (and ``loss``) on ``batch`` without gradients."""
        with torch.no_grad():
            out = self.module_(batch["nir"], batch["pmf"])
            total, terms = self.get_loss(out, batch["y"], batch)
        return {"loss": total, **terms}

    def _fit_physics(self, source: Any, absorbance: np.ndarray, y: np.ndarray) -> dict:
        """Constants of the physics terms, from the training data and its scenario."""
        return {}

    def _default_physics(self) -> dict:
        """``physics_`` used to build an unfitted module (for ``n_parameters``)."""
        return {}

    def _validate_extra_params(self) -> None:
        """Check subclass hyper-parameters (raise ConfigError)."""

    def _prepare_physics_tensors(self) -> None:
        """Turn ``physics_`` into tensors the loss uses (after fit setup or load)."""

    # ------------------------------------------------------------------ sklearn glue

    def __sklearn_tags__(self):
        tags = super().__sklearn_tags__()
        tags.input_tags.allow_nan = False
        tags.target_tags.required = True
        tags.regressor_tags.poor_score = True
        return tags

    @property
    def n_parameters(self) -> int:
        """Trainable parameters, counted from the module (a fresh one if not fitted)."""
        module = getattr(self, "module_", None)
        if module is None:
            with torch.random.fork_rng(devices=[]):
                module = self.build_module()
        return count_parameters(module)

    def _physics_or_default(self) -> dict:
        """Fitted ``physics_``, or :meth:`_default_physics` before fitting."""
        physics = self.__dict__.get("physics_")
        return physics if physics is not None else self._default_physics()

    def _check_fitted(self) -> None:
        if getattr(self, "module_", None) is None:
            raise _UnfittedError(
                f"this {type(self).__name__} is not fitted yet; call fit(...) first"
            )

    @staticmethod
    def _glucose(out: Any) -> torch.Tensor:
        return out[0] if isinstance(out, tuple) else out

    def _validate_params(self) -> None:
        def need(ok: bool, name: str, rule: str) -> None:
            if not ok:
                raise ConfigError(f"{type(self).__name__}: {name}={getattr(self, name)!r}; {rule}")

        v = self.max_epochs
        need(
            isinstance(v, int | np.integer) and not isinstance(v, bool) and v >= 1,
            "max_epochs",
            "must be an integer >= 1",
        )
        v = self.batch_size
        need(
            v is None or (isinstance(v, int | np.integer) and not isinstance(v, bool) and v >= 1),
            "batch_size",
            "must be None (full batch) or an integer >= 1",
        )
        need(
            self.patience is None
            or (isinstance(self.patience, int | np.integer) and self.patience >= 1),
            "patience",
            "must be None or an integer >= 1",
        )
        need(
            isinstance(self.lr, float | int) and math.isfinite(self.lr) and self.lr > 0,
            "lr",
            "must be a finite number > 0",
        )
        need(
            isinstance(self.weight_decay, float | int) and self.weight_decay >= 0,
            "weight_decay",
            "must be >= 0",
        )
        need(
            isinstance(self.dropout, float | int) and 0 <= self.dropout < 1,
            "dropout",
            "must lie in [0, 1)",
        )
        need(
            isinstance(self.val_fraction, float | int) and 0 <= self.val_fraction < 1,
            "val_fraction",
            "must lie in [0, 1)",
        )
        need(self.lr_schedule in LR_SCHEDULES, "lr_schedule", f"valid: {', '.join(LR_SCHEDULES)}")
        need(isinstance(self.refit, bool | np.bool_), "refit", "must be True or False")
        need(
            isinstance(self.whiten_inputs, bool | np.bool_),
            "whiten_inputs",
            "must be True or False",
        )
        self._validate_extra_params()

    def _measurements(
        self, X: Any, y: Any = None, *, require_target: bool = False, fit: bool = False
    ):
        """``(raw columns, y, groups)`` through the schema boundary.

        ``fit=True`` records the device (``schema_``) from X; otherwise X must carry the
        fitted device's columns (a validation set, or data to predict).
        """
        if fit:
            self.schema_, Xa, y, groups = fit_input(self, X, y)
            return Xa, y, groups
        Xa = predict_input(self, X)
        frame = X.frame if isinstance(X, Dataset) else X
        groups = None
        if isinstance(frame, pd.DataFrame):
            if y is None and "glucose_mgdl" in frame.columns:
                y = frame["glucose_mgdl"]
            if "subject_id" in frame.columns:
                groups = frame["subject_id"].to_numpy()
        if y is not None:
            y = target_of(self, y, len(Xa))
        elif require_target:
            raise DataError("validation data needs reference glucose: glucose_mgdl or y_val")
        return Xa, y, groups

    def _nir_pmf(self, Xa: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return nir_pmf_features(Xa, self.schema_)

    def _input_widths(self) -> dict[str, int]:
        """``n_nir``, ``n_pmf`` of the network: the device's, or the study's before fit."""
        s = self.__dict__.get("schema_")
        if s is None:
            return {"n_nir": 4, "n_pmf": 12}
        return {"n_nir": s.n_channels, "n_pmf": max(len(s.physiology), 1)}

    # ------------------------------------------------------------------ scaling

    def _transform(self, Xa: np.ndarray) -> dict[str, np.ndarray]:
        a, pmf = self._nir_pmf(Xa)
        s = self.scaler_
        return {
            "nir": (a - s["nir_mean"]) / s["nir_scale"],
            "pmf": (pmf - s["pmf_mean"]) / s["pmf_scale"],
            "absorbance": a,
        }

    @staticmethod
    def _tensors(arrays: dict[str, np.ndarray]) -> dict[str, torch.Tensor]:
        return {
            k: torch.as_tensor(np.ascontiguousarray(v), dtype=torch.float32)
            for k, v in arrays.items()
        }

    # ------------------------------------------------------------------ fit

    def fit(self, X: Any, y: Any = None, *, X_val: Any = None, y_val: Any = None):
        """Train the network.

        Parameters
        ----------
        X : Dataset, pandas.DataFrame or array_like (n, 20)
            Training measurements (measured columns only are read).
        y : array_like, optional
            Reference glucose; taken from ``glucose_mgdl`` when omitted. [mg/dL]
        X_val, y_val : optional
            An explicit validation set (e.g. the study's 60/20/20 split) used for
            early stopping instead of an internal subject-grouped split.

        Returns
        -------
        self
        """
        self._validate_params()
        self.__dict__.pop("_fast", None)  # a previous fit's snapshot
        Xa, y, groups = self._measurements(X, y, require_target=True, fit=True)
        if len(Xa) < 2:
            raise DataError(f"fitting needs at least 2 samples, got {len(Xa)}")
        rs = check_random_state(self.random_state)
        split_seed, init_seed, shuffle_seed = (int(s) for s in rs.randint(0, 2**31 - 1, size=3))

        if X_val is not None:
            Xv, yv, _ = self._measurements(X_val, y_val, require_target=True)
            Xt, yt = Xa, y
        else:
            tr, va = self._split(len(Xa), groups, split_seed)
            Xt, yt = Xa[tr], y[tr]
            Xv, yv = (Xa[va], y[va]) if va is not None else (None, None)
        refit = bool(self.refit) and X_val is None and Xv is not None

        # Scaling and physics constants from every row given for training (an internal
        # validation split is part of the training data; an explicit X_val is not).
        a_train, pmf_train = self._nir_pmf(Xa)
        self.scaler_ = {
            "nir_mean": a_train.mean(axis=0),
            "nir_scale": _scale_of(a_train),
            "pmf_mean": pmf_train.mean(axis=0),
            "pmf_scale": _scale_of(pmf_train),
            "y_mean": float(y.mean()),
            "y_scale": float(_scale_of(y[:, None])[0]),
        }
        self.physics_ = self._fit_physics(X, a_train, y)
        self._prepare_physics_tensors()
        self._whitening = None
        if self.whiten_inputs:
            z = self._transform(Xa)
            self._whitening = (zca_whitening(np.hstack((z["nir"], z["pmf"]))), z["nir"].shape[1])
        train = self._tensors({**self._transform(Xt), "y": self._scale_y(yt)})
        val = None
        if Xv is not None and len(Xv):
            val = self._tensors({**self._transform(Xv), "y": self._scale_y(yv)})

        # Subnormal floats (weights, gradients and Adam moments that strong weight decay
        # drives towards 0) are 10-100x slower on x86 CPUs: flush them to 0 while
        # training (RTE PINN at weight_decay=10: 2.8 -> 1.1 s per fit). Restored after.
        flushing = torch.set_flush_denormal(True)
        try:
            with torch.random.fork_rng(devices=[]):
                torch.manual_seed(init_seed)
                self.start_val_mse_ = None
                self.history_, self.best_epoch_ = self._train(train, val, shuffle_seed)
                self.n_epochs_ = len(self.history_)
                self.refit_history_ = []
                if refit:
                    # Same initial weights and shuffling seed, every training row, the
                    # selected number of epochs at the learning rates they had.
                    torch.manual_seed(init_seed)
                    every = self._tensors({**self._transform(Xa), "y": self._scale_y(y)})
                    curve = [self.start_val_mse_]
                    curve += [r["val_mse"] for r in self.history_]
                    self.best_epoch_ = _smoothed_argmin(curve, _SMOOTHING_EPOCHS) - 1
                    plan = [r["lr"] for r in self.history_[: self.best_epoch_]]
                    self.refit_history_, _ = self._train(every, None, shuffle_seed, lr_plan=plan)
        finally:
            if flushing:
                torch.set_flush_denormal(False)  # torch's default
            self.__dict__.pop("_optimizer", None)
            self.__dict__.pop("_whitening", None)
        self.refit_epochs_ = len(self.refit_history_)
        self._build_fast_path()
        return self

    def _wrap_inputs(self, module: nn.Module, whitening: Any) -> nn.Module:
        """``module`` behind the input whitening when ``whiten_inputs`` (else as is).

        ``whitening`` is ``(matrix, n_nir)`` from :meth:`fit`, or a saved matrix tensor
        (:meth:`load`; its NIR width is the module's first input width).
        """
        if not self.whiten_inputs:
            return module
        if isinstance(whitening, tuple):
            matrix, n_nir = whitening
        else:
            matrix = np.zeros((0, 0)) if whitening is None else whitening.numpy()
            n_nir = len(self.scaler_["nir_mean"])
        return _WhitenedInputs(module, matrix, n_nir)

    def _scale_y(self, y: np.ndarray) -> np.ndarray:
        return (y - self.scaler_["y_mean"]) / self.scaler_["y_scale"]

    def _split(self, n: int, groups: np.ndarray | None, seed: int):
        all_rows = np.arange(n)
        if self.val_fraction == 0 or n < 4:
            return all_rows, None
        if groups is not None and len(np.unique(groups)) >= 2:
            splitter = GroupShuffleSplit(n_splits=1, test_size=self.val_fraction, random_state=seed)
            tr, va = next(splitter.split(all_rows, groups=groups))
        else:
            splitter = ShuffleSplit(n_splits=1, test_size=self.val_fraction, random_state=seed)
            tr, va = next(splitter.split(all_rows))
        if len(tr) < 2 or len(va) == 0:
            return all_rows, None
        return tr, va

    @staticmethod
    def _batches(
        tensors: dict[str, torch.Tensor], batch_size: int | None, order: torch.Tensor | None = None
    ) -> Iterator[tuple[int, dict[str, torch.Tensor]]]:
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

    def _evaluate(self, tensors: dict[str, torch.Tensor]) -> dict[str, float]:
        self.module_.eval()
        sums: dict[str, torch.Tensor] = {}
        n = 0
        for size, batch in self._batches(tensors, _PREDICT_CHUNK // 8):
            for k, v in self.validation_step(batch).items():
                sums[k] = sums.get(k, 0.0) + v * size
            n += size
        return {k: float(v) / n for k, v in sums.items()}

    def _train(
        self,
        train: dict,
        val: dict | None,
        shuffle_seed: int,
        *,
        lr_plan: list[float] | None = None,
    ) -> tuple[list[dict], int]:
        """Train a fresh module; return ``(history, best_epoch)``.

        Without ``lr_plan``: up to ``max_epochs`` with the schedule and early stopping,
        keeping the best weights on ``val`` (the last weights without ``val``). With it:
        exactly ``len(lr_plan)`` epochs at those learning rates, keeping the last
        weights (the refit).
        """
        self.module_ = self._wrap_inputs(
            _start_at_mean(self.build_module()), self.__dict__.get("_whitening")
        )
        self._optimizer = torch.optim.AdamW(
            self.module_.parameters(),
            lr=self.lr,
            weight_decay=float(self.weight_decay),
            foreach=True,  # one fused call per step instead of one per tensor
        )
        patience = self.patience if lr_plan is None else None
        max_epochs = int(self.max_epochs) if lr_plan is None else len(lr_plan)
        if lr_plan is not None:
            sched = None
        elif self.lr_schedule == "plateau":
            sched = torch.optim.lr_scheduler.ReduceLROnPlateau(
                self._optimizer,
                mode="min",
                factor=0.5,
                patience=max(1, (patience or 20) // 4),
            )
        elif self.lr_schedule == "cosine":
            sched = torch.optim.lr_scheduler.CosineAnnealingLR(
                self._optimizer, T_max=self.max_epochs
            )
        else:
            sched = None
        gen = torch.Generator().manual_seed(shuffle_seed)
        n_train = len(train["y"])
        batch_size = None if self.batch_size is None else int(self.batch_size)
        full_batch = batch_size is None or batch_size >= n_train
        y_scale = self.scaler_["y_scale"]
        history: list[dict] = []
        best, best_epoch, best_state, stale = math.inf, 0, None, 0
        if val is not None and lr_plan is None:
            # Epoch 0 is a candidate: the untrained network predicts the training mean
            # (its glucose output starts at 0, see _start_at_mean), so early stopping
            # never returns weights worse on the validation subjects than no skill.
            best = self._evaluate(val)["mse"]
            best_state = copy.deepcopy(self.module_.state_dict())
            self.start_val_mse_ = best
        for epoch in range(1, max_epochs + 1):
            self.module_.train()
            if lr_plan is not None:
                for group in self._optimizer.param_groups:
                    group["lr"] = lr_plan[epoch - 1]
            lr_now = self._optimizer.param_groups[0]["lr"]
            order = None if full_batch else torch.randperm(n_train, generator=gen)
            sums: dict[str, torch.Tensor] = {}
            for size, batch in self._batches(train, batch_size, order):
                for k, v in self.train_step(batch).items():
                    sums[k] = sums.get(k, 0.0) + v * size
            record: dict[str, Any] = {"epoch": epoch, "lr": lr_now}
            train_terms = {k: float(v) / n_train for k, v in sums.items()}
            record["train_loss"] = train_terms.pop("loss")
            record.update({f"train_{k}": v for k, v in train_terms.items()})
            if val is not None:
                val_terms = self._evaluate(val)
                record["val_loss"] = val_terms.pop("loss")
                record.update({f"val_{k}": v for k, v in val_terms.items()})
                record["val_rmse_mgdl"] = math.sqrt(max(val_terms["mse"], 0.0)) * y_scale
                monitor = val_terms["mse"]
            else:
                record["val_loss"] = None
                record.update({f"val_{k}": None for k in train_terms})
                record["val_rmse_mgdl"] = None
                monitor = record["train_loss"]
            history.append(record)
            logger.debug("%s epoch %d: %s", type(self).__name__, epoch, record)
            if not math.isfinite(monitor):
                raise DataError(
                    f"{type(self).__name__}: training diverged at epoch {epoch} "
                    f"(loss {monitor}); lower lr (now {self.lr})"
                )
            if monitor < best - _MIN_IMPROVEMENT * abs(best) or (epoch == 1 and val is None):
                best, stale = monitor, 0
                if val is not None and lr_plan is None:
                    # The weights early stopping returns to; without a validation set
                    # the last weights are kept (no copy per epoch).
                    best_epoch = epoch
                    best_state = copy.deepcopy(self.module_.state_dict())
            else:
                stale += 1
            if val is None or lr_plan is not None:
                best_epoch = epoch
            if isinstance(sched, torch.optim.lr_scheduler.ReduceLROnPlateau):
                sched.step(monitor)
            elif sched is not None:
                sched.step()
            if patience is not None and stale >= patience:
                break
        if best_state is not None:
            self.module_.load_state_dict(best_state)
        self.module_.eval()
        return history, best_epoch

    # ------------------------------------------------------------------ predict

    def _inputs32(self, Xa: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Standardised float32 network inputs ``(nir, pmf)`` from measured columns."""
        a, pmf = self._nir_pmf(Xa)
        s = self.scaler_
        nir = ((a - s["nir_mean"]) / s["nir_scale"]).astype(np.float32)
        return nir, ((pmf - s["pmf_mean"]) / s["pmf_scale"]).astype(np.float32)

    def predict(self, X: Any) -> np.ndarray:
        """Glucose estimates.

        Up to :data:`NUMPY_ROWS` rows go through the network's NumPy closure (the
        low-latency path, see :meth:`predict_one`); larger batches through the torch
        module in ``torch.inference_mode`` in chunks of 65,536 rows. The two paths
        agree to float32 rounding.

        Parameters
        ----------
        X : Dataset, pandas.DataFrame or array_like (n, 20)
            Measurements.

        Returns
        -------
        numpy.ndarray
            (n,) glucose. [mg/dL]
        """
        self._check_fitted()
        Xa, _, _ = self._measurements(X)
        fast = self.__dict__.get("_fast")
        if len(Xa) <= NUMPY_ROWS and fast is not None and fast["fn"] is not None:
            x = np.concatenate(self._nir_pmf(Xa), axis=1)
            x -= fast["mu"]
            x *= fast["inv_scale"]
            out = self._glucose(fast["fn"](x.astype(np.float32))).astype(np.float64)
        else:
            nir, pmf = self._inputs32(Xa)
            out = np.empty(len(Xa), dtype=np.float64)
            nir_t, pmf_t = torch.from_numpy(nir), torch.from_numpy(pmf)
            self.module_.eval()
            with torch.inference_mode():
                for start in range(0, len(Xa), _PREDICT_CHUNK):
                    stop = start + _PREDICT_CHUNK
                    g = self._glucose(self.module_(nir_t[start:stop], pmf_t[start:stop]))
                    out[start:stop] = g.numpy()
        return out * self.scaler_["y_scale"] + self.scaler_["y_mean"]

    def predict_one(self, adc: Any, adc_ref: Any, pmf: Any) -> float:
        """Glucose from one snapshot, on the low-latency path.

        No DataFrame handling and no autograd: the inputs are standardised into a
        pre-allocated float32 buffer and run through the network's NumPy closure
        (:meth:`~nirglucose.models.networks.OriginalPINNNet.numpy_forward` and
        siblings), a snapshot of the fitted weights that evaluates the same function
        as the torch module (tested to float32 rounding) without PyTorch's per-module
        dispatch cost. Not thread-safe: the buffers belong to the estimator.

        Parameters
        ----------
        adc : array_like
            The device's ADC codes, one per LED in ``schema_`` order. [code]
        adc_ref : array_like or None
            Its reference codes (None for a device without them). [code]
        pmf : array_like
            Its physiological values in ``schema_.physiology`` order. [column units]

        Returns
        -------
        float
            Glucose. [mg/dL]
        """
        self._check_fitted()
        fast = self._fast
        sch = self.schema_
        k = sch.n_channels
        i = np.asarray(adc, dtype=np.float64)
        r = np.asarray(adc_ref, dtype=np.float64) if sch.reference else float(sch.full_scale)
        p = np.asarray(pmf if pmf is not None else [], dtype=np.float64)
        if i.shape != (k,) or np.shape(r) not in ((k,), ()) or p.shape != (len(sch.physiology),):
            raise DataError(
                f"predict_one takes {k} ADC codes, {k if sch.reference else 'no'} reference "
                f"codes and {len(sch.physiology)} physiological values; got shapes "
                f"{np.shape(adc)}, {np.shape(adc_ref)}, {p.shape}"
            )
        with np.errstate(divide="ignore", invalid="ignore"):
            a = np.log10(r / i)
        if not sch.physiology:
            p = np.zeros(1)
        u = np.concatenate((a, p))
        u -= fast["mu"]
        u *= fast["inv_scale"]
        x = fast["x"]
        x[0] = u
        if not np.isfinite(x).all():
            raise DataError("predict_one: codes must be > 0 and every value finite")
        if fast["fn"] is not None:
            g = self._glucose(fast["fn"](x))
        else:
            with torch.inference_mode():
                t = torch.from_numpy(x)
                g = self._glucose(self.module_(t[:, :k], t[:, k:]))
        return float(g[0]) * fast["y_scale"] + fast["y_mean"]

    def _build_fast_path(self) -> None:
        """Snapshot the fitted weights and scaler for the low-latency path."""
        s = self.scaler_
        self.module_.eval()
        numpy_forward = getattr(self.module_, "numpy_forward", None)
        self._fast = {
            "fn": numpy_forward() if callable(numpy_forward) else None,
            "x": np.zeros((1, len(self._fast_mu())), dtype=np.float32),
            "mu": np.concatenate((s["nir_mean"], s["pmf_mean"])).astype(np.float64),
            "inv_scale": 1.0 / np.concatenate((s["nir_scale"], s["pmf_scale"])).astype(np.float64),
            "y_mean": float(s["y_mean"]),
            "y_scale": float(s["y_scale"]),
        }

    def _fast_mu(self) -> np.ndarray:
        s = self.scaler_
        return np.concatenate((s["nir_mean"], s["pmf_mean"]))

    def __getstate__(self) -> dict:
        state = self.__dict__.copy()
        state.pop("_fast", None)  # closures do not pickle; rebuilt on unpickling
        return state

    def __setstate__(self, state: dict) -> None:
        self.__dict__.update(state)
        if getattr(self, "module_", None) is not None:
            self._build_fast_path()

    # ------------------------------------------------------------------ save / load

    def _json_params(self) -> dict:
        params = self.get_params(deep=False)
        rs = params.get("random_state")
        if not (rs is None or isinstance(rs, int | np.integer)):
            params["random_state"] = None  # a RandomState object has no JSON form
        return {k: (v.item() if isinstance(v, np.generic) else v) for k, v in params.items()}

    def save(self, path: str | Path) -> Path:
        """Write the model: ``path`` (JSON) and ``<stem>.safetensors`` beside it.

        Both files are written atomically (temporary file, then rename); the weights
        first, so a JSON document never names weights that are not there.

        Parameters
        ----------
        path : str or Path
            Destination of the JSON document (e.g. ``model.json``).

        Returns
        -------
        Path
            ``path``.
        """
        from safetensors.torch import save_file

        from .. import __version__

        self._check_fitted()
        path = Path(path)
        weights = path.with_name(path.stem + ".safetensors")
        if weights == path:
            raise DataError(
                f"{str(path)!r}: the model document needs a suffix other than "
                f"'.safetensors' (e.g. 'model.json')"
            )
        tensors = {
            k: v.detach().to("cpu").contiguous() for k, v in self.module_.state_dict().items()
        }
        meta = {"format": "nirglucose-model", "model": self.registry_name}
        atomic_write(weights, lambda tmp: save_file(tensors, tmp, metadata=meta))
        doc = {
            "format": "nirglucose-model",
            "format_version": FORMAT_VERSION,
            "model": self.registry_name,
            "nirglucose_version": __version__,
            "params": self._json_params(),
            "schema": self.schema_.to_json(),
            "scaler": {k: np.asarray(v).tolist() for k, v in self.scaler_.items()},
            "physics": self.physics_,
            "history": self.history_,
            "best_epoch": self.best_epoch_,
            "n_epochs": self.n_epochs_,
            "refit_history": self.refit_history_,
            "start_val_mse": self.start_val_mse_,
            "n_parameters": self.n_parameters,
            "weights_file": weights.name,
        }
        if getattr(self, "conformal_", None) is not None:  # its interval calibration
            doc["conformal"] = self.conformal_
        text = json.dumps(doc, indent=1, allow_nan=False)
        atomic_write(path, lambda tmp: Path(tmp).write_text(text))
        return path

    @classmethod
    def load(cls, path: str | Path):
        """Load a model written by :meth:`save`.

        Reads JSON and safetensors (or a ``.pt`` file through
        ``torch.load(weights_only=True)``); never executes code from the files.

        Raises
        ------
        DataError
            If the document is not a model of this class, or the weights miss keys,
            have extra keys or wrong shapes.
        """
        path = Path(path)
        if not path.exists():
            raise DataError(f"no such model file {str(path)!r}")
        try:
            doc = json.loads(path.read_text())
        except (json.JSONDecodeError, UnicodeDecodeError):
            raise DataError(f"{str(path)!r} is not a nirglucose model (not JSON)") from None
        if not isinstance(doc, dict) or doc.get("format") != "nirglucose-model":
            raise DataError(f"{str(path)!r} is not a nirglucose model file")
        if doc.get("model") != cls.registry_name:
            raise DataError(
                f"{str(path)!r} holds a {doc.get('model')!r} model, not {cls.registry_name!r}"
            )
        if doc.get("format_version") != FORMAT_VERSION:
            raise DataError(
                f"{str(path)!r} has format_version {doc.get('format_version')!r}; "
                f"this nirglucose reads {FORMAT_VERSION}"
            )
        required = ("params", "scaler", "physics", "history", "weights_file")
        missing = [k for k in required if k not in doc]
        if missing:
            raise DataError(f"{str(path)!r} lacks {missing}")
        check_torch_doc(doc, path)  # types, finite values, positive scales (issue 20)
        params = doc["params"]
        valid = cls().get_params(deep=False)
        unknown = sorted(set(params) - set(valid))
        if unknown:
            raise DataError(f"{str(path)!r}: unknown parameters {unknown}; valid: {sorted(valid)}")
        est = cls(**params)
        # Files written before the schema was saved are the study's device.
        est.schema_ = DeviceSchema.from_json(doc["schema"]) if "schema" in doc else DeviceSchema()
        est.scaler_ = {
            k: (float(v) if k.startswith("y_") else np.asarray(v, dtype=np.float64))
            for k, v in doc["scaler"].items()
        }
        est.physics_ = doc["physics"]
        est.history_ = doc["history"]
        est.best_epoch_ = doc.get("best_epoch", len(est.history_))
        est.n_epochs_ = doc.get("n_epochs", len(est.history_))
        est.refit_history_ = doc.get("refit_history", [])
        est.refit_epochs_ = len(est.refit_history_)
        est.start_val_mse_ = doc.get("start_val_mse")
        if "conformal" in doc:  # the interval calibration saved with the model
            from ..evaluation.conformal import check_calibration_doc

            est.conformal_ = check_calibration_doc(doc["conformal"], repr(str(path)))
        est.n_features_in_ = len(est.schema_.raw_columns)
        if not est.schema_.is_plain:
            est.feature_names_in_ = np.asarray(est.schema_.raw_columns, dtype=object)
        state = _read_weights(path, doc["weights_file"])
        module = est._wrap_inputs(est.build_module(), state.get(WHITENING_KEY))
        expected = module.state_dict()
        missing_keys = sorted(set(expected) - set(state))
        extra_keys = sorted(set(state) - set(expected))
        if missing_keys or extra_keys:
            raise DataError(
                f"weights for {cls.registry_name!r} do not match its network: "
                f"missing keys {missing_keys}, unexpected keys {extra_keys}"
            )
        bad = [k for k in expected if tuple(state[k].shape) != tuple(expected[k].shape)]
        if bad:
            k = bad[0]
            raise DataError(
                f"weights for {cls.registry_name!r}: {k} has shape {tuple(state[k].shape)}, "
                f"the network needs {tuple(expected[k].shape)}"
            )
        check_weights(state, path)  # finite, sane magnitudes (issue 20)
        module.load_state_dict(
            {k: state[k].to(dtype=expected[k].dtype) for k in expected}, strict=True
        )
        module.eval()
        est.module_ = module
        est._prepare_physics_tensors()
        est._build_fast_path()
        return est


TorchRegressor.__init__ = _keyword_init(TorchRegressor)  # subclasses: __init_subclass__


def _read_weights(doc_path: Path, name: Any) -> dict[str, torch.Tensor]:
    """Tensors of the weight file ``name`` beside ``doc_path`` (no code execution)."""
    if not isinstance(name, str) or Path(name).name != name or name in ("", ".", ".."):
        raise DataError(f"weights_file must be a plain file name beside the model, got {name!r}")
    wpath = doc_path.with_name(name)
    if not wpath.exists():
        raise DataError(f"weights file {str(wpath)!r} is missing")
    if wpath.suffix == ".safetensors":
        from safetensors import SafetensorError
        from safetensors.torch import load_file

        try:
            return load_file(str(wpath), device="cpu")
        except (SafetensorError, OSError, ValueError) as exc:
            raise DataError(f"{str(wpath)!r} is not a readable safetensors file: {exc}") from None
    if wpath.suffix in (".pt", ".pth"):
        try:
            state = torch.load(wpath, map_location="cpu", weights_only=True)
        except Exception as exc:  # noqa: BLE001 - any unpickling refusal is a data error
            raise DataError(f"{str(wpath)!r} is not a weights-only torch file: {exc}") from None
        if not isinstance(state, dict) or not all(
            isinstance(v, torch.Tensor) for v in state.values()
        ):
            raise DataError(f"{str(wpath)!r} does not hold a state_dict of tensors")
        return state
    raise DataError(f"unknown weights format {wpath.suffix!r}; valid: .safetensors, .pt, .pth")
