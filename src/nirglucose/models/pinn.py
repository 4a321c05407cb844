r"""The study's four physics-informed networks, each an override of ``get_loss``.

=========================  ========================  ==========================================
estimator                  registry name             physics term added to the MSE
=========================  ========================  ==========================================
:class:`OriginalPINN`      ``original-pinn``         Beer-Lambert residual ``A - eps c l``
:class:`OptimizedPINN`     ``optimized-pinn``        the same, on an attention network
:class:`RTEPINN`           ``rte-pinn``              diffusion-theory reflectance + mus' prior
:class:`SelectiveRTEPINN`  ``selective-rte-pinn``    the same at 1050 and 1150 nm only
=========================  ========================  ==========================================

The Beer-Lambert PINNs choose their term by ``physics_form``
(:data:`PHYSICS_FORMS`): ``'study'`` (the default, alias ``'absolute'``) is the study's
residual, kept so the reproduction stays; ``'forward'`` ties the predicted glucose to
the measured absorbances through the package's own forward model
(:meth:`~nirglucose.models.inversion.PhysicsInversion.glucose_likelihood`,
:func:`~nirglucose.models.physics_losses.forward_likelihood_loss`); the RTE PINNs
likewise (:data:`RTE_PHYSICS_FORMS`). The ``-fm`` names are registered variants of the
four (:func:`~nirglucose.models.registry.register_variant`): each network with
``physics_form='forward'`` and its own ``lambda_phys`` by default, privileged
(:data:`FORWARD_MODEL_KNOWLEDGE`): ``original-pinn-fm`` (:class:`OriginalPINNForward`),
``optimized-pinn-fm``, ``rte-pinn-fm`` and ``selective-rte-pinn-fm``.

All share :class:`~nirglucose.models._torch_base.TorchRegressor`'s one training loop;
each adds its residual in ``get_loss`` by calling the parent (the skorch habit). The
loop measures how hard each term pulls against the data term
(:mod:`~nirglucose.models.physics_effect`).

Notes
-----
**Why the study's Beer-Lambert term does not move the fit.** The residual
:math:`r_{i\lambda} = A_{i\lambda} - \varepsilon_\lambda \hat c_i l` hardly depends on
:math:`\hat c`: on ``paper`` (signal gain 11) :math:`\varepsilon` is
:math:`1.1\times10^{-8}`, :math:`1.7\times10^{-6}`, :math:`1.9\times10^{-7}` and
:math:`2.7\times10^{-5}` per cm per mg/dL at 850, 940, 1050 and 1150 nm, so at 140 mg/dL
:math:`\varepsilon\hat c l` is at most 0.004 against mean absorbances of 0.09, 0.14, 0.08
and 0.28: whatever the network predicts, the term stays at 0.120 (it changes by
:math:`3\times10^{-4}` of its value over 200 epochs). It is not without a gradient:
:math:`\partial P/\partial \hat c_i = -\frac2n\sum_\lambda\varepsilon_\lambda
r_{i\lambda}` pushes every prediction up, towards the :math:`\hat c \approx A/\varepsilon`
(about 10,000 mg/dL) that would zero it, and the push adds up over the rows while the
data term's gradients partly cancel, so its gradient w.r.t. the parameters is 0.03-0.4
of the data term's (0.006-0.5 on ``wearable``; the larger where the network has
memorised its training rows). But the data term pulls back: the two balance where
each prediction has moved by
:math:`\lambda\,\sigma_y^2\sum_\lambda\varepsilon_\lambda r_{i\lambda}`
(:math:`\sigma_y` the training glucose's SD, 58 mg/dL), which at
:math:`\lambda_\mathrm{phys} = 1` is 0.026 mg/dL on ``paper`` and 0.029 mg/dL on
``wearable`` (:math:`4\text{-}5\times10^{-4}` SD; ``studies/pinn_physics_gradient.py``,
40 x 3, seed 0; the record in ``studies/records/pinn_physics_gradient.json``). The
estimate holds: at :math:`\lambda = 1000` it predicts 26 mg/dL and the Original PINN's
held-out predictions rise by 27-33 mg/dL (``random_state`` 0-2). So the study's term is
constant during training and cannot change the fit at the study's weights
(:math:`\lambda \le 1`): its ablation cannot show an effect. What an ablation of it does
show is the training's sensitivity to any change of the loss: :math:`\lambda = 10^{-3}`
instead of 0 moves the Original PINN's held-out predictions by 2.3 mg/dL RMS, as much as
:math:`\lambda = 1` (2.6 mg/dL). The forward-model term of the ``-fm`` variants pulls
each prediction by tens to hundreds of SD on ``paper`` and about 0.6 SD on ``wearable``
at :math:`\lambda = 1`, and the RTE PINNs' study term acts through their optics heads
(its gradient outside the glucose prediction is 3-11 times the data term's): both move
the fit.

Examples
--------
>>> import nirglucose as ng
>>> from nirglucose.models import OriginalPINN
>>> ds = ng.simulate("paper", n_subjects=10, per_subject=2, seed=0)
>>> m = OriginalPINN(max_epochs=2, random_state=0).fit(ds)
>>> m.predict(ds).shape
(20,)

References
----------
.. [1] R. Gani, "Physics-Informed Neural Networks vs. Physics Models for Non-Invasive
   Glucose Monitoring: A Comparative Study Under Noise-Stressed Synthetic Conditions",
   University College London (the reference study).
.. [2] M. Raissi, P. Perdikaris and G. E. Karniadakis, "Physics-informed neural
   networks", J. Comput. Phys. 378, 686-707 (2019). :doi:`10.1016/j.jcp.2018.10.045`
.. [3] T. J. Farrell, M. S. Patterson and B. Wilson, Med. Phys. 19, 879-888 (1992).
   :doi:`10.1118/1.596777`
.. [4] S. L. Jacques, "Optical properties of biological tissues: a review",
   Phys. Med. Biol. 58, R37-R61 (2013). :doi:`10.1088/0031-9155/58/11/R37`
"""

from __future__ import annotations

from typing import Any, ClassVar

import numpy as np
import torch

from ..config import ScenarioConfig
from ..constants import DEFAULT_LED_WAVELENGTHS_NM
from ..exceptions import DataError
from ..optics import forward, tissue
from ..optics.diffusion import farrell_reflectance
from ..optics.forward import FORWARD_MODELS
from ..simulation.simulator import nominal_tissue, scenario_band_spectra
from ._base import predict_input
from ._inversion_solver import NUISANCES
from ._params import Integral, Interval, ParameterError, Real, StrOptions
from ._torch_base import TorchRegressor
from .device_inversion import DEFAULT_LED_FWHM_NM, device_scenario
from .forward_term import BeerLambertForwardTerm, StateForwardTerm
from .inversion import PRIVILEGED_SCENARIO
from .networks import OptimizedPINNNet, OriginalPINNNet, RTEPINNNet
from .physics_losses import (
    beer_lambert_loss,
    diffusion_reflectance_loss,
    glucose_absorptivity_per_cm_per_mgdl,
    scattering_prior_loss,
)
from .registry import register, register_variant

__all__ = [
    "OriginalPINN",
    "OptimizedPINN",
    "RTEPINN",
    "SelectiveRTEPINN",
    "OriginalPINNForward",
    "OptimizedPINNForward",
    "RTEPINNForward",
    "SelectiveRTEPINNForward",
    "PHYSICS_FORMS",
    "RTE_PHYSICS_FORMS",
    "FORWARD_MODEL_KNOWLEDGE",
    "nominal_optics",
]

#: Valid ``physics_form`` values of the Beer-Lambert PINNs: the study's residual
#: (``'study'``, also accepted under its earlier name ``'absolute'``), its differential
#: variant, and the forward model's likelihood.
PHYSICS_FORMS = ("study", "absolute", "relative", "forward")
#: Valid ``physics_form`` values of the RTE PINNs: the study's reflectance tie, and
#: predicted glucose and tissue state through the package's forward model.
RTE_PHYSICS_FORMS = ("study", "forward")


def _device_optics(wavelengths_nm: Any) -> tuple[ScenarioConfig | None, str]:
    """The optics a study PINN's physics term assumes: the device's LEDs (from its
    columns, :data:`~nirglucose.models.device_inversion.DEFAULT_LED_FWHM_NM` wide) over
    the published tables and glucose at its published magnitude
    (:func:`~nirglucose.models.device_inversion.device_scenario`). No dataset's
    scenario and no preset is read, so the study PINNs fit a device file and a simulated
    Dataset alike (they are deployable; the ``-fm`` variants' forward term is not).

    ``(None, why)`` when the LEDs lie outside the optics tables: the physics term is
    then switched off.
    """
    wl = [float(w) for w in wavelengths_nm]
    try:
        cfg = device_scenario(wl, [DEFAULT_LED_FWHM_NM] * len(wl))
    except DataError as exc:
        return None, f"none: {exc}"
    return cfg, "the device's LEDs over the published tables (glucose at gain 1)"


def _with_physics(est: Any, total: torch.Tensor, physics: torch.Tensor) -> torch.Tensor:
    """``total + lambda_phys * physics``; with ``lambda_phys == 0`` exactly ``total``.

    At 0 the physics term is left out of the graph altogether (not multiplied by 0), so
    the loss, its gradients and hence the trained weights are bit-identical to the plain
    network's: the clean ablation the benchmark pairs against the tuned weight.
    """
    if est.lambda_phys == 0:
        return total
    return total + est.lambda_phys * physics


#: Constraint of the physics weight shared by every PINN: finite and >= 0.
_LAMBDA_PHYS = [Interval(Real, 0, None, closed="left")]
#: A physics constant that defaults to the scenario's: None, or finite and > 0.
_POSITIVE_OR_NONE = [None, Interval(Real, 0, None, closed="neither")]
_FORWARD_MODEL = [None, StrOptions(set(FORWARD_MODELS))]


# ============================================================================ Beer-Lambert


class _BeerLambertPINN(BeerLambertForwardTerm, TorchRegressor):
    """Shared physics of the Original and Optimized PINNs (not registered)."""

    privileged: ClassVar[str | None] = None
    own_params: ClassVar[dict[str, Any]] = {
        "lambda_phys": 0.01,
        "physics_form": "study",
        "absorptivity_per_cm_per_mm": None,
        "signal_gain": None,
        "forward_model": None,
        "collocation": 0,
    }

    _parameter_constraints: ClassVar[dict[str, Any]] = {
        **TorchRegressor._parameter_constraints,
        "lambda_phys": _LAMBDA_PHYS,
        "physics_form": [StrOptions(set(PHYSICS_FORMS))],
        "absorptivity_per_cm_per_mm": _POSITIVE_OR_NONE,
        "signal_gain": _POSITIVE_OR_NONE,
        "forward_model": _FORWARD_MODEL,
        "collocation": [Interval(Integral, 0, None, closed="left")],
    }

    def _physics_constants(self, cfg: ScenarioConfig, origin: str) -> dict:
        peak = self.absorptivity_per_cm_per_mm
        gain = self.signal_gain
        schema = self.__dict__.get("schema_")
        enabled = cfg is not None and (schema is None or not schema.is_plain)
        if cfg is None:  # LEDs outside the tables: the constants of the study's device
            cfg = _device_optics(DEFAULT_LED_WAVELENGTHS_NM)[0]
        peak = cfg.glucose.absorptivity_per_cm_per_mm if peak is None else float(peak)
        gain = cfg.glucose.signal_gain if gain is None else float(gain)
        # The physics takes its wavelengths from the data (a plain array has none: off).
        wl = DEFAULT_LED_WAVELENGTHS_NM if schema is None else schema.wavelengths_nm
        k = len(wl) if enabled else schema.n_channels
        eps = glucose_absorptivity_per_cm_per_mgdl(wl, peak, gain) if enabled else np.zeros(k)
        if schema is not None and schema.is_plain:
            origin = "none: a plain array has no wavelengths (physics term off)"
        return {
            "enabled": enabled,
            "wavelengths_nm": [float(w) for w in wl],
            "absorptivity_per_cm_per_mgdl": eps.tolist(),
            "glucose_peak_per_cm_per_mm": peak,
            "signal_gain": gain,
            "pathlength_cm": 1.0,
            "form": self.physics_form,
            "absorbance_ref": [0.0] * k,
            "glucose_ref_mgdl": 0.0,
            "constants_from": origin,
        }

    def _fit_physics(self, source: Any, absorbance: np.ndarray, y: np.ndarray) -> dict:
        schema = self.schema_
        wl = DEFAULT_LED_WAVELENGTHS_NM if schema.is_plain else schema.wavelengths_nm
        cfg, origin = _device_optics(wl)
        phys = self._physics_constants(cfg, origin)
        if self.physics_form == "relative":
            phys["absorbance_ref"] = absorbance.mean(axis=0).tolist()
            phys["glucose_ref_mgdl"] = float(y.mean())
        if self.physics_form == "forward":
            phys.update(self._fit_forward(source, y))
        return phys

    def _prepare_physics_tensors(self) -> None:
        p = self.physics_
        self._phys = {
            "enabled": bool(p.get("enabled", True)),
            "eps": torch.tensor(p["absorptivity_per_cm_per_mgdl"], dtype=torch.float32),
            "a_ref": torch.tensor(p["absorbance_ref"], dtype=torch.float32),
            "c_ref": float(p["glucose_ref_mgdl"]),
            "l": float(p["pathlength_cm"]),
            "y_mean": float(self.scaler_["y_mean"]),
            "y_scale": float(self.scaler_["y_scale"]),
        }

    def get_loss(self, y_pred, y_true, batch):
        """MSE plus ``lambda_phys`` times the Beer-Lambert residual (see class notes)."""
        total, terms = super().get_loss(y_pred, y_true, batch)
        ph = self._phys
        if not ph["enabled"]:
            terms["physics"] = torch.zeros(())
            return total, terms
        c_hat = self._glucose(y_pred) * ph["y_scale"] + ph["y_mean"]
        if self.physics_form == "forward":
            terms.update(self._forward_loss(c_hat, batch))
            return _with_physics(self, total, terms["physics"]), terms
        physics = beer_lambert_loss(
            batch["absorbance"],
            c_hat,
            ph["eps"],
            ph["l"],
            absorbance_ref=ph["a_ref"],
            glucose_ref_mgdl=ph["c_ref"],
        )
        terms["physics"] = physics
        return _with_physics(self, total, physics), terms


@register("original-pinn")
class OriginalPINN(_BeerLambertPINN):
    r"""The study's Original PINN: two-branch MLP with a Beer-Lambert residual.

    Network: NIR branch 4 -> 32 -> 64 -> 32 and physiology branch 12 -> 16 -> 32 -> 16
    (ReLU), concatenated, 48 -> 128 -> 64 -> 1
    (:class:`~nirglucose.models.networks.OriginalPINNNet`, 20,225 parameters).

    Loss (study's form [1]_):

    .. math::

        L = \mathrm{MSE} + \lambda_\mathrm{phys}\,\frac1n\sum_i\sum_\lambda
            \big|\log_{10}(I_0/I_{i\lambda}) - \varepsilon(\lambda)\,\hat c_i\,l\big|^2,
        \qquad l = 1\ \mathrm{cm},

    with :math:`\varepsilon(\lambda)` the decadic glucose absorptivity per mg/dL at the
    four LEDs from the shared optics tables
    (:func:`~nirglucose.models.physics_losses.glucose_absorptivity_per_cm_per_mgdl`:
    the simulator's glucose band model times the scenario's ``signal_gain``, divided by
    ln 10 and 18.016 mg/dL per mM). The MSE is on the standardised target (unit
    variance); :math:`\hat c` enters the residual in mg/dL.

    Parameters
    ----------
    lambda_phys : float
        Weight of the physics term, ``<< 1`` in the study; a tuned hyper-parameter
        (grid includes 0). 0 trains exactly the plain network (same initialisation,
        same data path, bit-identical weights): the physics ablation. [-]
    physics_form : {'study', 'absolute', 'relative', 'forward'}
        'study' (default; 'absolute' is the same, its earlier name) is the study's
        residual above. 'relative' subtracts the training means from both sides,
        :math:`(A - \bar A) - \varepsilon(\hat c - \bar c)l` (differential
        Beer-Lambert), which removes the tissue's constant background. 'forward' is the
        negative log-likelihood of each training reading's measured log ratios at the
        predicted glucose under the package's forward model, the nuisances (blood,
        water, fat, melanin, thickness, LED shift, coupling) marginalised by Laplace
        (:func:`~nirglucose.models.physics_losses.forward_likelihood_loss`; the model
        is a :class:`~nirglucose.models.inversion.PhysicsInversion` fitted on the
        training rows' measured columns and reference glucose, never ``true_*``). Off
        (recorded in ``physics_``) where the data has no optics: a plain array, or
        LEDs the scenario does not describe. Prediction is the same for every form.
    absorptivity_per_cm_per_mm, signal_gain : float or None
        Glucose peak absorption [1/(cm mM)] and signal gain [-] for
        :math:`\varepsilon`; None takes the published values (the package's glucose
        table, gain 1): never the training data's scenario, whose gain a device file
        does not have.
    forward_model : {None, 'beer-lambert', 'diffusion', 'rte-lut'}
        The forward model of the 'forward' form; None takes the training Dataset's
        (``optics.model``; 'beer-lambert' for data without a scenario). Unused by the
        other forms.
    collocation : int
        'forward' form only: readings the fitted forward model generates per training
        row (the row's measured physiology, nuisances drawn from their learned prior,
        glucose drawn from the training rows', the model's noise), on which the
        network's squared error (standardised units) joins the physics term: PINN
        collocation points where no reference exists. 0 (default): none. [-]
    max_epochs, batch_size, lr, weight_decay, dropout, whiten_inputs, patience,
    val_fraction, lr_schedule, refit, random_state
        Training, see :class:`~nirglucose.models._torch_base.TorchRegressor`.

    Notes
    -----
    The study's relation is crude: the measured absorbance (about 0.1-0.3) is
    dominated by water, blood, melanin and the instrument, while
    :math:`\varepsilon\hat c` is of order 0.005 even at the paper preset's gain, so
    the residual stays large whatever the network predicts, and its gradient with
    respect to :math:`\hat c`, :math:`2\lambda\sum_\lambda\varepsilon(\varepsilon\hat c - A)`
    per mg/dL, pushes every prediction up by the same tiny amount: against the MSE it
    displaces them by 0.03 mg/dL at :math:`\lambda_\mathrm{phys} = 1` (module notes,
    ``studies/pinn_physics_gradient.py``). The term is constant during training
    and does not move the fit at the study's weights; the history's gradient probes
    say so (:func:`~nirglucose.models.physics_effect.physics_verdict`). The 'relative' form
    is the physically sensible variant; it is not the default because it is not the
    study's model. The absorbance is decadic (DESIGN.md) where the study writes
    ``log``; the choice only rescales :math:`\varepsilon` consistently.

    References
    ----------
    See the module references.
    """

    def build_module(self) -> OriginalPINNNet:
        """:class:`~nirglucose.models.networks.OriginalPINNNet`."""
        return OriginalPINNNet(**self._input_widths(), dropout=float(self.dropout))


@register("optimized-pinn")
class OptimizedPINN(_BeerLambertPINN):
    """The study's Optimized PINN: attention fusion, dropout, weight decay.

    Network: :class:`~nirglucose.models.networks.OptimizedPINNNet` (deeper branches,
    one multi-head self-attention block over the NIR and physiology tokens; 76,225
    parameters at the defaults against the study's 89,000). Loss: the same
    Beer-Lambert physics term as :class:`OriginalPINN`.

    Parameters
    ----------
    d_model : int
        Token width. [-]
    n_heads : int
        Attention heads (divides ``d_model``). [-]
    dropout : float
        Dropout probability (0.1 by default: with weight decay, part of the study's
        "optimisation"). [-]
    lambda_phys, physics_form, absorptivity_per_cm_per_mm, signal_gain, forward_model
        As in :class:`OriginalPINN`.
    max_epochs, batch_size, lr, weight_decay, dropout, whiten_inputs, patience,
    val_fraction, lr_schedule, refit, random_state
        Training, see :class:`~nirglucose.models._torch_base.TorchRegressor`.
    """

    own_params: ClassVar[dict[str, Any]] = {"d_model": 64, "n_heads": 4}
    training_defaults: ClassVar[dict[str, Any]] = {"dropout": 0.1}

    _parameter_constraints: ClassVar[dict[str, Any]] = {
        **_BeerLambertPINN._parameter_constraints,
        "d_model": [Interval(Integral, 1, None, closed="left")],
        "n_heads": [Interval(Integral, 1, None, closed="left")],
    }

    def _check_param_relations(self) -> None:
        if self.d_model % self.n_heads:
            raise ParameterError(
                f"{type(self).__name__}: n_heads={self.n_heads!r} must divide "
                f"d_model={self.d_model!r}"
            )

    def build_module(self) -> OptimizedPINNNet:
        """:class:`~nirglucose.models.networks.OptimizedPINNNet`."""
        return OptimizedPINNNet(
            int(self.d_model), int(self.n_heads), float(self.dropout), **self._input_widths()
        )


_FORWARD_NOTES = """
    Notes
    -----
    The term per training reading i is :math:`w_i(\\hat c_i - \\hat g_i)^2`,
    :math:`-2\\ln p(y_i \\mid \\hat c_i)` less its minimum: :math:`\\hat g_i` and
    :math:`w_i` are the mode and curvature of the reading's glucose likelihood
    (:meth:`~nirglucose.models.inversion.PhysicsInversion.glucose_likelihood`,
    linearised at its reference glucose and nuisance mode), computed once per fit. The
    weight :math:`\\lambda_\\mathrm{phys}` multiplies it in the MSE's standardised
    units, so 1 puts one standard deviation of the likelihood on a par with one of the
    training glucose; a device whose nuisances swamp glucose's signal gets small
    :math:`w_i` and hence a weak term. Its grid is the study PINNs'
    (:data:`~nirglucose.models.tuning.LAMBDA_PHYS_GRID`, 0 included); the training
    parameters are its study twin's until ``tools/tune.py`` has tuned it.
    """


#: What the ``-fm`` variants know beyond the measured data (their ``privileged``): the
#: forward term is a :class:`~nirglucose.models.inversion.PhysicsInversion` of the
#: training Dataset's scenario, i.e. the simulator's own forward model.
FORWARD_MODEL_KNOWLEDGE = PRIVILEGED_SCENARIO

#: The ``-fm`` variants' changed defaults: the Beer-Lambert networks', the RTE ones'.
_FM_DEFAULTS = {"physics_form": "forward", "lambda_phys": 0.1}
_RTE_FM_DEFAULTS = {"physics_form": "forward", "lambda_phys": 1.0}

OriginalPINNForward = register_variant(
    "original-pinn-fm", OriginalPINN, defaults=_FM_DEFAULTS, class_name="OriginalPINNForward",
    summary="the forward-model likelihood as its physics term.",
    privileged=FORWARD_MODEL_KNOWLEDGE, notes=_FORWARD_NOTES)
OptimizedPINNForward = register_variant(
    "optimized-pinn-fm", OptimizedPINN, defaults=_FM_DEFAULTS,
    class_name="OptimizedPINNForward",
    summary="the forward-model likelihood as its physics term.",
    privileged=FORWARD_MODEL_KNOWLEDGE, notes=_FORWARD_NOTES)


# ============================================================================ RTE


def nominal_optics(cfg: ScenarioConfig) -> tuple[np.ndarray, np.ndarray]:
    """Nominal-skin absorption and reduced scattering at each LED, as the simulator sees it.

    The scenario's reference skin (``optics.reference_tissue``, where the simulator
    fixes its geometry factor), dermis and subcutis mixed by the path share at the
    probe's separation, and averaged over each LED's emission band. Scattering follows
    the Jacques (2013) power laws for skin and fat [4]_.

    Parameters
    ----------
    cfg : ScenarioConfig
        Scenario (LEDs, optics, glucose tables).

    Returns
    -------
    mua_per_cm, musp_per_cm : numpy.ndarray
        (n_led,) each. [1/cm]
    """
    ref = cfg.optics.reference_tissue
    spectra = scenario_band_spectra(cfg)
    optics = tissue.tissue_optics(
        spectra,
        nominal_tissue(1, ref),
        water_displacement_per_mm=cfg.glucose.water_displacement_per_mm,
        scattering_rel_per_mm=cfg.glucose.scattering_rel_per_mm,
    )
    mua, musp, _ = forward.mixed_optics(
        optics,
        np.array([ref.skin_thickness_mm / 10.0]),
        cfg.optics.source_detector_mm / 10.0,
    )
    w = spectra.weights
    return (mua[0] * w).sum(axis=-1), (musp[0] * w).sum(axis=-1)


class _RTEPINNBase(StateForwardTerm, TorchRegressor):
    """Shared physics of the RTE-inspired PINNs (not registered)."""

    privileged: ClassVar[str | None] = None
    own_params: ClassVar[dict[str, Any]] = {
        "lambda_phys": 0.1,
        "stability_weight": 0.1,
        "physics_form": "study",
        "forward_model": None,
    }

    #: Wavelengths the optical heads predict and the regulariser covers. [nm]
    REGULARISED_NM: ClassVar[tuple[float, ...]] = DEFAULT_LED_WAVELENGTHS_NM

    _parameter_constraints: ClassVar[dict[str, Any]] = {
        **TorchRegressor._parameter_constraints,
        "lambda_phys": _LAMBDA_PHYS,
        "stability_weight": [Interval(Real, 0, None, closed="left")],
        "physics_form": [StrOptions(set(RTE_PHYSICS_FORMS))],
        "forward_model": _FORWARD_MODEL,
    }

    def _regularised(self, wavelengths_nm: tuple[float, ...]) -> list[int]:
        """Indices of the data's LEDs the optical heads cover (all of them here)."""
        return list(range(len(wavelengths_nm)))

    def _physics_from(
        self,
        cfg: ScenarioConfig | None,
        origin: str,
        absorbance: np.ndarray | None,
        wavelengths_nm: tuple[float, ...] = DEFAULT_LED_WAVELENGTHS_NM,
        n_channels: int | None = None,
    ) -> dict:
        enabled = cfg is not None
        if enabled:
            wl = tuple(float(w) for w in wavelengths_nm)
            idx = self._regularised(wl)
            mua0, musp0 = (v[idx] for v in nominal_optics(cfg))
        else:
            # No optics for these channels (a plain array, or LEDs outside the tables):
            # the heads start at the study device's mean nominal skin, the term is off.
            cfg = _device_optics(DEFAULT_LED_WAVELENGTHS_NM)[0]
            idx = list(range(n_channels or len(wavelengths_nm)))
            mua_p, musp_p = nominal_optics(cfg)
            mua0 = np.full(len(idx), float(mua_p.mean()))
            musp0 = np.full(len(idx), float(musp_p.mean()))
        rho = cfg.optics.source_detector_mm / 10.0
        area = cfg.optics.detector_area_mm2 / 100.0
        n_t = cfg.optics.tissue_refractive_index
        a_nominal = -np.log10(farrell_reflectance(rho, mua0, musp0, n_t) * area)
        if absorbance is None:
            a_mean, a_scale = np.zeros(len(idx)), np.full(len(idx), 0.05)
        else:
            a = absorbance[:, idx]
            a_mean, a_scale = a.mean(axis=0), np.maximum(a.std(axis=0), 1e-3)
        return {
            "enabled": enabled,
            "wavelengths_nm": [wl[i] for i in idx] if enabled else list(wavelengths_nm),
            "led_index": idx,
            "rho_cm": rho,
            "detector_area_cm2": area,
            "n_tissue": n_t,
            "nominal_mua_per_cm": mua0.tolist(),
            "nominal_musp_per_cm": musp0.tolist(),
            "prior_musp_per_cm": musp0.tolist(),
            # b = mean measured A minus the nominal optics' A: the nominal skin then
            # reproduces the mean absorbance exactly.
            "absorbance_offset": (a_mean - a_nominal).tolist(),
            "absorbance_scale": np.asarray(a_scale).tolist(),
            "constants_from": origin,
        }

    def _fit_physics(self, source: Any, absorbance: np.ndarray, y: np.ndarray) -> dict:
        schema = self.schema_
        if schema.is_plain:
            why = "none: a plain array has no wavelengths (physics term off)"
            return self._physics_from(None, why, absorbance, (), schema.n_channels)
        cfg, origin = _device_optics(schema.wavelengths_nm)
        phys = self._physics_from(cfg, origin, absorbance, schema.wavelengths_nm)
        if self.physics_form == "forward":  # replaces the reflectance tie
            phys.update({"form": "forward", **self._fit_forward(source, y)})
        return phys

    def _default_physics(self) -> dict:
        cfg, origin = _device_optics(DEFAULT_LED_WAVELENGTHS_NM)
        return self._physics_from(cfg, origin, None, DEFAULT_LED_WAVELENGTHS_NM)

    def _prepare_physics_tensors(self) -> None:
        p = self.physics_
        self._phys = {
            "enabled": bool(p.get("enabled", True)),
            "idx": torch.tensor(p["led_index"], dtype=torch.long),
            "offset": torch.tensor(p["absorbance_offset"], dtype=torch.float32),
            "scale": torch.tensor(p["absorbance_scale"], dtype=torch.float32),
            "prior": torch.tensor(p["prior_musp_per_cm"], dtype=torch.float32),
            "rho": float(p["rho_cm"]),
            "area": float(p["detector_area_cm2"]),
            "n": float(p["n_tissue"]),
            "y_mean": float(self.scaler_["y_mean"]),
            "y_scale": float(self.scaler_["y_scale"]),
            **self._state_tensors(),
        }

    def build_module(self) -> RTEPINNNet:
        """:class:`~nirglucose.models.networks.RTEPINNNet` started at nominal optics
        (with a state head for the 'forward' form)."""
        p = self._physics_or_default()
        return RTEPINNNet(
            p["nominal_mua_per_cm"],
            p["nominal_musp_per_cm"],
            **self._input_widths(),
            dropout=float(self.dropout),
            n_state=len(NUISANCES) if self.physics_form == "forward" else 0,
        )

    def get_loss(self, y_pred, y_true, batch):
        """MSE plus ``lambda_phys`` (reflectance residual + stability x scattering prior,
        or the 'forward' form's state likelihood)."""
        total, terms = super().get_loss(y_pred, y_true, batch)
        mua, musp = y_pred[1], y_pred[2]
        ph = self._phys
        if not ph["enabled"]:
            zero = torch.zeros(())
            names = ("likelihood", "state") if self.physics_form == "forward" else (
                "reflectance", "scattering_prior")
            terms.update({**dict.fromkeys(names, zero), "physics": zero})
            return total, terms
        if self.physics_form == "forward":
            c_hat = y_pred[0] * ph["y_scale"] + ph["y_mean"]
            terms.update(self._state_loss(c_hat, y_pred[3], batch))
            return _with_physics(self, total, terms["physics"]), terms
        absorbance = batch["absorbance"].index_select(1, ph["idx"])
        reflectance = diffusion_reflectance_loss(
            absorbance,
            mua,
            musp,
            ph["offset"],
            rho_cm=ph["rho"],
            detector_area_cm2=ph["area"],
            n_tissue=ph["n"],
            scale=ph["scale"],
        )
        prior = scattering_prior_loss(musp, ph["prior"])
        physics = reflectance + self.stability_weight * prior
        terms.update({"reflectance": reflectance, "scattering_prior": prior, "physics": physics})
        return _with_physics(self, total, physics), terms

    def predict_optics(self, X: Any) -> tuple[np.ndarray, np.ndarray]:
        """The optical-property heads: ``(mua, musp)``, each (n, k). [1/cm]"""
        self._check_fitted()
        Xa = predict_input(self, X)
        t = self._tensors({k: v for k, v in self._transform(Xa).items() if k != "absorbance"})
        with torch.inference_mode():
            out = self.module_(t["nir"], t["pmf"])
        return out[1].numpy().astype(np.float64), out[2].numpy().astype(np.float64)


_RTE_DOC_PARAMS = """
    Parameters
    ----------
    lambda_phys : float
        Weight of the physics term; a tuned hyper-parameter (grid includes 0). 0 trains
        exactly the plain network (bit-identical weights): the physics ablation. [-]
    stability_weight : float
        Weight of the scattering prior inside the physics term. [-]
    physics_form : {'study', 'forward'}
        'study' (default): the reflectance tie and scattering prior below. 'forward':
        the forward model's glucose likelihood and a state head tied to each training
        reading's posterior mode (see :class:`RTEPINNForward`); off (recorded in
        ``physics_``) where the data has no optics.
    forward_model : {None, 'beer-lambert', 'diffusion', 'rte-lut'}
        The 'forward' form's model; None takes the training Dataset's.
    max_epochs, batch_size, lr, weight_decay, dropout, whiten_inputs, patience,
    val_fraction, lr_schedule, refit, random_state
        Training, see :class:`~nirglucose.models._torch_base.TorchRegressor`.
"""


@register("rte-pinn")
class RTEPINN(_RTEPINNBase):
    __doc__ = (
        r"""The study's RTE-inspired PINN: optical-property heads tied to the absorbance.

    Network: :class:`~nirglucose.models.networks.RTEPINNNet` with heads for
    :math:`\mu_a(\lambda)` and :math:`\mu_s'(\lambda)` at the four LEDs (softplus,
    started at the simulator's nominal skin) besides glucose, which reads the trunk and
    the log optical properties.

    Loss:

    .. math::

        L = \mathrm{MSE} + \lambda_\mathrm{phys}\Big[\frac1n\sum_{i,\lambda}
            \Big(\frac{A_{i\lambda} + \log_{10}[R(\rho;\hat\mu_{a,i\lambda},
            \hat\mu'_{s,i\lambda})A_\mathrm{det}] - b_\lambda}{s_\lambda}\Big)^2
            + w_\mathrm{stab}\frac1n\sum_{i,\lambda}\big(\ln\hat\mu'_{s,i\lambda}
            - \ln\mu'_{s,\mathrm{prior},\lambda}\big)^2\Big]

    with :math:`R` the Farrell dipole reflectance [3]_
    (:func:`~nirglucose.optics.diffusion.farrell_reflectance`, the simulator's own
    function, on tensors) at the probe's separation :math:`\rho` and detector area,
    :math:`b_\lambda` the per-wavelength instrument offset (fixed so that the nominal
    skin reproduces the mean training absorbance), :math:`s_\lambda` the training
    spread of the absorbance (so the term is O(1) and each LED weighs alike), and
    the prior the Jacques (2013) power laws [4]_ for skin and fat mixed as at nominal
    skin.
    """
        + _RTE_DOC_PARAMS
        + r"""
    Notes
    -----
    Departures from the study: its RTE network has 1.34 M parameters; this one has
    187,849 (layers in :class:`~nirglucose.models.networks.RTEPINNNet`) so that it
    trains on 100,000 snapshots in minutes on two cores. Diffusion theory stands in
    for the RTE (the study also calls its model "RTE-inspired"); the optical
    properties are effective ones (the epidermis and coupling losses fold into them).
    """
    )


@register("selective-rte-pinn")
class SelectiveRTEPINN(_RTEPINNBase):
    __doc__ = (
        r"""The study's Selective RTE PINN: the RTE regulariser at 1050 and 1150 nm only.

    As :class:`RTEPINN`, but the optical heads predict :math:`\mu_a` and
    :math:`\mu_s'` at 1050 and 1150 nm only (the glucose-sensitive LEDs) and the
    reflectance and stability terms cover those two. 187,333 parameters (the study:
    566,000).
    """
        + _RTE_DOC_PARAMS
    )

    REGULARISED_NM = (1050.0, 1150.0)

    def _regularised(self, wavelengths_nm: tuple[float, ...]) -> list[int]:
        """The glucose-sensitive LEDs: 1050 and 1150 nm where the device has them, else
        those at or beyond 1000 nm, else its longest wavelength."""
        for keep in (
            lambda w: w in self.REGULARISED_NM,
            lambda w: w >= 1000.0,
        ):
            idx = [i for i, w in enumerate(wavelengths_nm) if keep(w)]
            if idx:
                return idx
        return [int(np.argmax(wavelengths_nm))]


_RTE_FORWARD_NOTES = """
    Notes
    -----
    The term: the glucose likelihood of the Beer-Lambert PINNs' 'forward' form
    (:class:`OriginalPINNForward`) plus a state head that predicts the nuisances of
    :data:`~nirglucose.models._inversion_solver.NUISANCES`, tied to each training
    reading's posterior mode under the forward model at its reference glucose
    (:func:`~nirglucose.models.physics_losses.state_mode_loss`); it replaces the
    study's reflectance tie (the optics heads stay, as features of the glucose head).
    ``estimate_state`` returns the state head's blood, saturation, water, fat, melanin,
    thickness, LED shift and coupling (the benchmark's inverse table). Training
    parameters: its study twin's until ``tools/tune.py`` has tuned it.
    """


RTEPINNForward = register_variant(
    "rte-pinn-fm", RTEPINN, defaults=_RTE_FM_DEFAULTS, class_name="RTEPINNForward",
    summary="the forward model as its physics term, and a state head.",
    privileged=FORWARD_MODEL_KNOWLEDGE, notes=_RTE_FORWARD_NOTES)
SelectiveRTEPINNForward = register_variant(
    "selective-rte-pinn-fm", SelectiveRTEPINN, defaults=_RTE_FM_DEFAULTS,
    class_name="SelectiveRTEPINNForward",
    summary="the forward model as its physics term, and a state head.",
    privileged=FORWARD_MODEL_KNOWLEDGE, notes=_RTE_FORWARD_NOTES)
