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
which the tests check (same seed, bit-identical weights). Fits on fewer than
:data:`~nirglucose.models._training.SMALL_FIT_ROWS` rows run on one torch thread
(:func:`~nirglucose.models._training.training_threads`): faster on such small tensors,
and the same arithmetic whatever the machine's core count. Larger fits use the caller's
thread count, and are reproducible for a given torch build and thread count.

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

import logging
import math
from typing import Any, ClassVar

import numpy as np
import pandas as pd
import torch
from sklearn.base import BaseEstimator, RegressorMixin
from sklearn.model_selection import GroupShuffleSplit, ShuffleSplit
from sklearn.utils import check_random_state
from torch import nn

from ..dataset import Dataset
from ..dataset.schema import DeviceSchema
from ..exceptions import DataError
from ..fitted import require_fitted
from ._base import fit_input, predict_input, target_of
from ._constructor import (
    DEFAULT_EPOCHS,
    DEFAULT_LR,
    DEFAULT_WEIGHT_DECAY,
    TRAINING_PARAMS,
    keyword_init,
)
from ._params import (
    Integral,
    Interval,
    ParameterError,
    Real,
    StrOptions,
    ValidatedParamsMixin,
)
from ._torch_io import FORMAT_VERSION, WHITENING_KEY, TorchIOMixin
from ._torch_predict import NUMPY_ROWS, PREDICT_CHUNK, TorchPredictMixin
from ._training import (
    LR_SCHEDULES,
    SMOOTHING_EPOCHS,
    EarlyStopping,
    batches,
    gradient_norms,
    make_scheduler,
    smoothed_argmin,
    start_at_mean,
    step_scheduler,
    training_threads,
)
from ._whitening import scale_of as _scale_of
from ._whitening import zca_whitening
from .networks import count_parameters
from .physics_effect import GRADIENT_KEYS, is_probe_epoch

__all__ = [
    "TorchRegressor",
    "DEFAULT_EPOCHS",
    "DEFAULT_LR",
    "DEFAULT_WEIGHT_DECAY",
    "TRAINING_PARAMS",
    "LR_SCHEDULES",
    "FORMAT_VERSION",
    "NUMPY_ROWS",
    "WHITENING_KEY",
    "nir_pmf_features",
    "zca_whitening",
]

logger = logging.getLogger(__name__)


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


class TorchRegressor(
    ValidatedParamsMixin, TorchIOMixin, TorchPredictMixin, RegressorMixin, BaseEstimator
):
    """Base of the network estimators: one seeded training loop, save/load, fast predict.

    Subclasses implement :meth:`build_module` and may override :meth:`get_loss`
    (calling the parent) and :meth:`_fit_physics`, and extend ``_parameter_constraints``
    (:mod:`~nirglucose.models._params`) with their own parameters.

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
        training mean 58; ``tools/tune.py``). False gives the plain study
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
        units; ``val_*`` are None without a validation set. A network with a physics
        term adds the gradient probes of
        :data:`~nirglucose.models.physics_effect.GRADIENT_KEYS` (norms of the data and
        physics terms' gradients on a few epochs, None on the others), which
        :func:`~nirglucose.models.physics_effect.physics_verdict` reads (the refit's
        rows hold None: it repeats these epochs on every row).
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
    #: Constraints of the training parameters; a subclass adds its ``own_params``'.
    _parameter_constraints: ClassVar[dict[str, Any]] = {
        "max_epochs": [Interval(Integral, 1, None, closed="left")],
        "batch_size": [None, Interval(Integral, 1, None, closed="left")],
        "lr": [Interval(Real, 0, None, closed="neither")],
        "weight_decay": [Interval(Real, 0, None, closed="left")],
        "dropout": [Interval(Real, 0, 1, closed="left")],
        "whiten_inputs": ["boolean"],
        "patience": [None, Interval(Integral, 1, None, closed="left")],
        "val_fraction": [Interval(Real, 0, 1, closed="left")],
        "lr_schedule": [StrOptions(set(LR_SCHEDULES))],
        "refit": ["boolean"],
        "random_state": ["random_state"],
    }

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        if "__init__" not in cls.__dict__:
            cls.__init__ = keyword_init(cls)

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
        if self.__dict__.pop("_probe_next_step", False) and "physics" in terms:
            self._gradient_probe = gradient_norms(
                self.module_.parameters(), terms["mse"], terms["physics"],
                getattr(self, "lambda_phys", 0.0), self._glucose(out))
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

    def _training_rows(self, Xa: np.ndarray, y: np.ndarray) -> dict[str, np.ndarray]:
        """Per-row arrays of a training or validation batch: the scaled inputs
        (:meth:`_transform`) plus any per-row constants a physics term needs (a
        subclass adds them, keyed by name; they are batched with their rows).
        Prediction never calls this."""
        return self._transform(Xa)

    def _default_physics(self) -> dict:
        """``physics_`` used to build an unfitted module (for ``n_parameters``)."""
        return {}

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
        require_fitted(self, "module_")

    @staticmethod
    def _glucose(out: Any) -> torch.Tensor:
        return out[0] if isinstance(out, tuple) else out

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
        rs = check_random_state(self.random_state)
        split_seed, init_seed, shuffle_seed = (int(s) for s in rs.randint(0, 2**31 - 1, size=3))
        (Xt, yt), (Xv, yv) = self._train_val_rows(Xa, y, groups, X_val, y_val, split_seed)
        refit = bool(self.refit) and X_val is None and Xv is not None
        self._fit_scaling(X, Xa, y)
        train = self._tensors({**self._training_rows(Xt, yt), "y": self._scale_y(yt)})
        val = None
        if Xv is not None and len(Xv):
            val = self._tensors({**self._training_rows(Xv, yv), "y": self._scale_y(yv)})
        every = None
        if refit:
            every = self._tensors({**self._training_rows(Xa, y), "y": self._scale_y(y)})
        # Subnormal floats (weights, gradients and Adam moments that strong weight decay
        # drives towards 0) are 10-100x slower on x86 CPUs: flush them to 0 while
        # training (RTE PINN at weight_decay=10: 2.8 -> 1.1 s per fit). Restored after.
        flushing = torch.set_flush_denormal(True)
        try:
            with training_threads(len(Xa)), torch.random.fork_rng(devices=[]):
                self._select_and_refit(train, val, every, init_seed, shuffle_seed)
        finally:
            if flushing:
                torch.set_flush_denormal(False)  # torch's default
            for key in ("_optimizer", "_whitening", "_probe_next_step", "_gradient_probe"):
                self.__dict__.pop(key, None)
        self.refit_epochs_ = len(self.refit_history_)
        self._build_fast_path()
        return self

    def _train_val_rows(self, Xa, y, groups, X_val, y_val, split_seed: int):
        """``((X_train, y_train), (X_val, y_val))``: an explicit validation set, or an
        internal subject split of ``val_fraction`` (``(None, None)`` without one)."""
        if X_val is not None:
            Xv, yv, _ = self._measurements(X_val, y_val, require_target=True)
            return (Xa, y), (Xv, yv)
        tr, va = self._split(len(Xa), groups, split_seed)
        return (Xa[tr], y[tr]), ((Xa[va], y[va]) if va is not None else (None, None))

    def _fit_scaling(self, X: Any, Xa: np.ndarray, y: np.ndarray) -> None:
        """Scaler, physics constants and input whitening from every row given for
        training (an internal validation split is part of the training data; an
        explicit ``X_val`` is not)."""
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

    def _select_and_refit(
        self, train: dict, val: dict | None, every: dict | None, init_seed: int, shuffle_seed: int
    ) -> None:
        """Train on ``train`` (early stopping on ``val``); with ``every``, refit on every
        row from the same initial weights and shuffling seed for the selected number of
        epochs at the learning rates they had (the smoothed validation minimum, epoch 0
        included)."""
        torch.manual_seed(init_seed)
        self.start_val_mse_ = None
        self.history_, self.best_epoch_ = self._train(train, val, shuffle_seed)
        self.n_epochs_ = len(self.history_)
        self.refit_history_ = []
        if every is not None:
            torch.manual_seed(init_seed)
            curve = [self.start_val_mse_] + [r["val_mse"] for r in self.history_]
            self.best_epoch_ = smoothed_argmin(curve, SMOOTHING_EPOCHS) - 1
            plan = [r["lr"] for r in self.history_[: self.best_epoch_]]
            self.refit_history_, _ = self._train(every, None, shuffle_seed, lr_plan=plan)

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
        n_groups = 0 if groups is None else len(np.unique(groups))
        grouped = n_groups >= 2
        splitter = (GroupShuffleSplit if grouped else ShuffleSplit)(
            n_splits=1, test_size=self.val_fraction, random_state=seed)
        try:
            tr, va = next(splitter.split(all_rows, groups=groups if grouped else None))
        except ValueError:  # scikit-learn: the split leaves an empty training set
            units = f"{n_groups} subjects" if grouped else f"{n} rows"
            raise ParameterError(f"val_fraction={self.val_fraction:g} leaves nothing to train "
                                 f"on out of {units}; lower it") from None
        if len(tr) < 2 or len(va) == 0:
            return all_rows, None
        return tr, va

    def _evaluate(self, tensors: dict[str, torch.Tensor]) -> dict[str, float]:
        self.module_.eval()
        sums: dict[str, torch.Tensor] = {}
        n = 0
        for size, batch in batches(tensors, PREDICT_CHUNK // 8):
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
        keeping the best weights on ``val``, the untrained network (the training mean)
        included as epoch 0 (the last weights without ``val``). With it: exactly
        ``len(lr_plan)`` epochs at those learning rates, keeping the last weights (the
        refit).
        """
        self.module_ = self._wrap_inputs(
            start_at_mean(self.build_module()), self.__dict__.get("_whitening")
        )
        self._optimizer = torch.optim.AdamW(
            self.module_.parameters(),
            lr=self.lr,
            weight_decay=float(self.weight_decay),
            foreach=True,  # one fused call per step instead of one per tensor
        )
        max_epochs = int(self.max_epochs) if lr_plan is None else len(lr_plan)
        sched = None
        if lr_plan is None:
            sched = make_scheduler(
                self._optimizer, self.lr_schedule, patience=self.patience, max_epochs=max_epochs
            )
        keep_best = val is not None and lr_plan is None
        stopper = EarlyStopping(self.patience if lr_plan is None else None, keep_best)
        if keep_best:
            self.start_val_mse_ = stopper.start(self._evaluate(val)["mse"], self.module_)
        gen = torch.Generator().manual_seed(shuffle_seed)
        history: list[dict] = []
        for epoch in range(1, max_epochs + 1):
            if lr_plan is not None:
                for group in self._optimizer.param_groups:
                    group["lr"] = lr_plan[epoch - 1]
            # the refit repeats the selection run's epochs: only that run is probed
            probe = lr_plan is None and is_probe_epoch(epoch, max_epochs)
            record, monitor = self._epoch(train, val, epoch, gen, probe)
            history.append(record)
            logger.debug("%s epoch %d: %s", type(self).__name__, epoch, record)
            if not math.isfinite(monitor):
                raise DataError(
                    f"{type(self).__name__}: training diverged at epoch {epoch} "
                    f"(loss {monitor}); lower lr (now {self.lr})"
                )
            stop = stopper.update(monitor, epoch, self.module_)
            step_scheduler(sched, monitor)
            if stop:
                break
        stopper.restore(self.module_)
        self.module_.eval()
        return history, stopper.best_epoch

    def _epoch(
        self, train: dict, val: dict | None, epoch: int, gen: torch.Generator,
        probe: bool = False,
    ) -> tuple[dict[str, Any], float]:
        """One epoch of training steps; ``(history record, monitored loss)``.

        The monitored loss is the validation MSE, or the training loss without ``val``.
        With ``probe`` (and a physics term) the record holds the gradient norms of
        :data:`~nirglucose.models.physics_effect.GRADIENT_KEYS` on the epoch's first
        batch (None otherwise).
        """
        self.module_.train()
        n_train = len(train["y"])
        batch_size = None if self.batch_size is None else int(self.batch_size)
        full_batch = batch_size is None or batch_size >= n_train
        record: dict[str, Any] = {"epoch": epoch, "lr": self._optimizer.param_groups[0]["lr"]}
        order = None if full_batch else torch.randperm(n_train, generator=gen)
        sums: dict[str, torch.Tensor] = {}
        # the epoch's first step measures the physics term's gradient (physics_effect)
        self._probe_next_step = probe
        for size, batch in batches(train, batch_size, order):
            for k, v in self.train_step(batch).items():
                sums[k] = sums.get(k, 0.0) + v * size
        self.__dict__.pop("_probe_next_step", None)
        train_terms = {k: float(v) / n_train for k, v in sums.items()}
        record["train_loss"] = train_terms.pop("loss")
        record.update({f"train_{k}": v for k, v in train_terms.items()})
        if "physics" in train_terms:
            record.update(self.__dict__.pop("_gradient_probe", dict.fromkeys(GRADIENT_KEYS)))
        if val is None:
            record["val_loss"] = None
            record.update({f"val_{k}": None for k in train_terms})
            record["val_rmse_mgdl"] = None
            return record, record["train_loss"]
        val_terms = self._evaluate(val)
        record["val_loss"] = val_terms.pop("loss")
        record.update({f"val_{k}": v for k, v in val_terms.items()})
        record["val_rmse_mgdl"] = math.sqrt(max(val_terms["mse"], 0.0)) * self.scaler_["y_scale"]
        return record, val_terms["mse"]


TorchRegressor.__init__ = keyword_init(TorchRegressor)  # subclasses: __init_subclass__
