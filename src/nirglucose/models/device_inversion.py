"""The deployable forward-model inversion: the device's parts and published tables only.

:class:`DeviceInversion` (``device-inversion``) is the MAP/EM inversion of
:class:`~nirglucose.models.inversion.ForwardModelInversion` -- the same solver, the
same empirical-Bayes updates -- over a forward model built from nothing a real
device's file does not carry. It never reads a generating scenario
(``Dataset.config``), so a Dataset and its CSV give the same model.

What it reads besides the measured columns (``privileged`` is None):

* **The device's declared parts.** LED centres from the ``adc_<nm>`` columns; LED
  widths from ``led_fwhm_nm`` (else :data:`DEFAULT_LED_FWHM_NM`, the parts
  catalogue's typical width); the ADC resolution from the schema (declared by the
  file's metadata or ``--adc-bits``), which sets the quantisation floor of the
  residual variance. The detector does not enter the noise-free log ratio
  ln(adc / adc_ref): its responsivity and area are per-channel factors that the
  reference divides out or the calibration offset absorbs (the package's band integral
  does not weight an LED's band by the detector's curve), so none is asked for; its
  noise is in the learned residual covariance.
* **Published tables at the default geometry** (:func:`device_scenario`): the package's
  chromophore tables (``data/optics/SOURCES.md``: Kou 1993 water, Bosschaart 2014
  blood, van Veen 2004 fat, Jacques 1998 melanosome, Jacques 2013 scattering) mixed as
  :mod:`nirglucose.optics.tissue` does, at the package's default probe geometry and
  reference tissue (:class:`~nirglucose.config.OpticsConfig` defaults), through the
  ``forward_model`` chosen. Their stated uncertainty (water tables within a few %,
  whole blood 2-3 significant digits and up to 25 % between compilations) is not
  propagated per table: each channel's learned gain ``b`` and offset ``a`` absorb a
  proportional error of the tables at that LED, and the learned residual covariance
  ``S`` what remains.

What it learns from the training rows' measured columns and reference glucose:

* **Glucose's response per channel** -- not the scenario's gain. The optics hold
  glucose at the training mean, and glucose enters linearly,

      y_k = a_k + b_k [m_k(theta) + r_k (g - g_mean)],

  with ``r`` (:attr:`DeviceInversion.glucose_response_`) refitted with (a, b) in every
  EM calibration step by least squares at the rows' reference glucose and nuisance
  modes (:func:`calibrate_with_glucose`). Per channel, because neither the size nor the
  spectral shape of glucose's effect on a real device is known well enough to fix
  (the amplified presets scale it 11-12.5 times, DESIGN.md "Regimes"); linear,
  because glucose's optical effects are linear in concentration over the meter's
  range (SOURCES.md, "glucose": absorption, water displacement and scattering per mM).
  No start from the published absorptivity: the first calibration at the prior
  start already fits ``r``, and a published direction would only bias it where the
  device's response differs.
* **The prior means**: the published population values of :data:`POPULATION_PRIOR`
  (or a column that measures the nuisance itself, in its unit, e.g. PPG
  ``blood_volume_pct``), plus the ridge correction linear in the standardised
  physiology that the EM learns -- so hydration -> water, BMI -> fat, skin
  temperature -> LED shift are learned from the rows, not taken from the simulator.
* the prior widths, the calibration, the residual covariance and glucose's prior, as
  the privileged inversion learns them;
* **how far to trust the learned response** (:attr:`DeviceInversion.skill_weight_`):
  the posterior mode's deviation from the training mean is weighted by ``c`` in
  [0, 1], the least-squares weight of the out-of-fold deviations over ``cv``
  subject-grouped folds of the training rows (:func:`skill_weight`; stacking with a
  non-negative weight never above 1, L. Breiman, "Stacked regressions", Machine
  Learning 24, 49-64 (1996), doi:10.1007/BF00117832). The EM learns glucose's
  response at the training rows' known glucose, where the nuisances absorb what the
  response leaves, so nothing inside the fit says whether a small response is
  glucose or noise; held-out subjects do. Where glucose's effect is at its published
  magnitude (``physical``) the weight falls towards 0 and the estimator towards the
  training mean, instead of below it.

Examples
--------
>>> import nirglucose as ng
>>> ds = ng.simulate("paper", 20, 3, seed=0)
>>> m = DeviceInversion(n_em=3).fit(ds.frame)  # a frame: no scenario is read
>>> m.predict(ds).shape, m.glucose_response_.shape
((60,), (4,))
"""

from __future__ import annotations

import math
from typing import Any, ClassVar

import numpy as np
from pydantic import ValidationError
from sklearn.base import clone
from sklearn.model_selection import GroupKFold

from ..config import ScenarioConfig
from ..dataset import Dataset
from ..dataset.adc import quantisation_variance_ln
from ..exceptions import DataError
from ._inversion_solver import NUISANCES, ForwardModel
from ._params import Integral, Interval, IntervalArray, Real, StrOptions
from .inversion import ForwardModelInversion
from .registry import register

__all__ = [
    "DeviceInversion",
    "DEFAULT_LED_FWHM_NM",
    "POPULATION_PRIOR",
    "LearnedGlucoseForward",
    "calibrate_with_glucose",
    "device_prior_start",
    "device_scenario",
    "skill_weight",
]

#: LED width assumed where the device declares none: the median FWHM of the parts
#: catalogue's datasheet rows not marked uncertain (``data/parts/leds.csv``: Hamamatsu
#: L8957 45 nm, Super Bright LEDs IR-1W-850 50 nm). [nm]
DEFAULT_LED_FWHM_NM = 47.5
#: Largest LED width accepted (the LED record's bound, :class:`~nirglucose.config.LED`). [nm]
_MAX_FWHM_NM = 150.0

#: Published population value of each nuisance, the prior means' start where the device
#: does not measure it: the middle of the ranges in ``data/optics/SOURCES.md``'s layer
#: table (I. V. Meglinski, S. J. Matcher, Physiol. Meas. 23, 741-753 (2002); S. L.
#: Jacques, "Skin optics", OMLC News (1998)) -- dermal blood volume fraction 0.002-0.05
#: (its geometric middle, 0.01), mixed dermal SO2 0.6-0.8, dermal water 0.6-0.7,
#: subcutis fat 0.7-0.9, epidermal melanosome fraction 0.01-0.43 across skin types
#: (geometric middle), dermis about 1.5 mm; an LED at its datasheet centre (no shift)
#: and unit coupling. Units of :data:`~nirglucose.models._inversion_solver.NUISANCES`.
POPULATION_PRIOR: dict[str, float] = {
    "log_blood_fraction": float(np.log(np.sqrt(0.002 * 0.05))),
    "saturation": 0.7,
    "water_fraction": 0.65,
    "subcutis_fat_fraction": 0.8,
    "melanin_fraction": float(np.sqrt(0.01 * 0.43)),
    "skin_thickness_mm": 1.5,
    "led_shift_nm": 0.0,
    "log_coupling": 0.0,
}
#: Columns that measure a nuisance itself (``columns.COLUMN_UNITS``): column ->
#: (nuisance, factor from the column's unit to the nuisance's).
_MEASURES = {
    "blood_volume_pct": ("log_blood_fraction", 0.01),
    "spo2_pct": ("saturation", 0.01),
    "melanin_fraction": ("melanin_fraction", 1.0),
    "skin_thickness_mm": ("skin_thickness_mm", 1.0),
}
#: LED power and responsivity of the assumed scenario's records: the LED record needs
#: them, the noise-free log ratio never reads them (power and responsivity are
#: per-channel factors the reference reading divides out). [mW, A/W]
_UNREAD_POWER_MW, _UNREAD_RESPONSIVITY_A_PER_W = 1.0, 1.0


def device_scenario(wavelengths_nm, fwhm_nm) -> ScenarioConfig:
    """The optics a device's declared parts and the published tables define.

    The package's defaults (:class:`~nirglucose.config.ScenarioConfig`: chromophore
    tables, probe geometry, reference tissue, glucose at its published magnitude,
    ``glucose.signal_gain`` 1) with the device's LEDs. No preset and no dataset's
    scenario is read.

    Parameters
    ----------
    wavelengths_nm : sequence of float
        LED centres, 700-1700. [nm]
    fwhm_nm : sequence of float
        LED widths, one per LED, (0, 150]. [nm]

    Returns
    -------
    ScenarioConfig
        Its ``preset`` is ``"device"``.

    Raises
    ------
    DataError
        An LED outside the optics tables or a width out of range (one line).

    Examples
    --------
    >>> device_scenario([850.0, 1150.0], [47.5, 47.5]).leds.fwhm_nm
    (47.5, 47.5)
    """
    leds = [
        {"wavelength_nm": float(w), "fwhm_nm": float(f), "power_mw": _UNREAD_POWER_MW,
         "responsivity_a_per_w": _UNREAD_RESPONSIVITY_A_PER_W}
        for w, f in zip(wavelengths_nm, fwhm_nm, strict=True)
    ]
    try:
        return ScenarioConfig(preset="device", leds=leds)
    except ValidationError as exc:
        err = exc.errors()[0]
        where = ".".join(str(p) for p in err["loc"])
        raise DataError(
            f"device-inversion cannot model this device's LEDs: {where}: {err['msg']} "
            f"(got {err.get('input')!r}; the optics tables span 700-1700 nm)"
        ) from None


def device_prior_start(schema, phys: np.ndarray) -> np.ndarray:
    """The prior means' start: a column that measures the nuisance, else its
    published population value (:data:`POPULATION_PRIOR`).

    Parameters
    ----------
    schema : DeviceSchema
        The device (which physiological columns it records, in ``phys``'s order).
    phys : numpy.ndarray
        (n, m) the measured physiology.

    Returns
    -------
    numpy.ndarray
        (n, len(NUISANCES)) in the units of :data:`NUISANCES`.
    """
    out = np.tile([POPULATION_PRIOR[k] for k in NUISANCES], (len(phys), 1))
    for column, (nuisance, factor) in _MEASURES.items():
        if column in schema.physiology:
            value = factor * phys[:, schema.physiology.index(column)]
            if nuisance.startswith("log_"):
                value = np.log(np.maximum(value, 1e-4))
            out[:, NUISANCES.index(nuisance)] = value
    return out


class LearnedGlucoseForward:
    """The device's optics with glucose held at a reference and its response learned.

    ``log_ratio(g, theta) = m(g_ref, theta) + r (g - g_ref)``, per channel: ``m`` the
    optics (:class:`~nirglucose.models._inversion_solver.ForwardModel` over
    :func:`device_scenario`), ``r`` the learned response per mg/dL.

    Parameters
    ----------
    optics : ForwardModel
        The noise-free optics.
    glucose_ref_mgdl : float
        Where the optics hold glucose (the training mean). [mg/dL]
    response_per_mgdl : numpy.ndarray
        (k,) d ln(adc / adc_ref) / d glucose before the channel gain. [1/(mg/dL)]
    """

    def __init__(self, optics: ForwardModel, glucose_ref_mgdl: float,
                 response_per_mgdl: np.ndarray):
        self.optics = optics
        self.glucose_ref_mgdl = float(glucose_ref_mgdl)
        self.response_per_mgdl = np.asarray(response_per_mgdl, dtype=float)

    def log_ratio(self, glucose_mgdl: np.ndarray, theta: np.ndarray) -> np.ndarray:
        """(n, k) ln(adc / adc_ref) at glucose [mg/dL] and ``theta`` ((n, len(NUISANCES)))."""
        dg = np.asarray(glucose_mgdl, dtype=float) - self.glucose_ref_mgdl
        held = np.full(len(theta), self.glucose_ref_mgdl)
        return self.optics.log_ratio(held, theta) + dg[:, None] * self.response_per_mgdl


def calibrate_with_glucose(obs: np.ndarray, model: np.ndarray, dg: np.ndarray):
    """Per channel, least squares ``obs = a + b model + beta dg``.

    Parameters
    ----------
    obs : numpy.ndarray
        (n, k) measured ln(adc / adc_ref). [-]
    model : numpy.ndarray
        (n, k) the optics at the rows' nuisances, glucose held. [-]
    dg : numpy.ndarray
        (n,) reference glucose minus the training mean. [mg/dL]

    Returns
    -------
    a, b, beta, residual : numpy.ndarray
        (k,) each but ``residual`` (n, k). Where the model does not vary independently
        of glucose on a channel (a singular 2 x 2 system), ``b`` is 1 and ``beta`` the
        slope of ``obs - model`` on ``dg``. [-, -, 1/(mg/dL), -]

    Examples
    --------
    >>> g = np.array([-20.0, 0.0, 20.0, 10.0])
    >>> m = np.array([[0.1], [0.3], [0.2], [0.0]])
    >>> a, b, beta, r = calibrate_with_glucose(0.5 + 2.0 * m + 0.01 * g[:, None], m, g)
    >>> np.round([a[0], b[0], beta[0], np.abs(r).max()], 12).tolist()
    [0.5, 2.0, 0.01, 0.0]
    """
    oc = obs - obs.mean(axis=0)
    mc = model - model.mean(axis=0)
    gc = dg - dg.mean()
    smm, sgg = (mc**2).mean(axis=0), float((gc**2).mean())
    smg = (mc * gc[:, None]).mean(axis=0)
    smy, sgy = (mc * oc).mean(axis=0), (gc[:, None] * oc).mean(axis=0)
    det = smm * sgg - smg**2
    ok = det > 1e-12 * smm * sgg
    safe = np.where(ok, det, 1.0)
    b = np.where(ok, (smy * sgg - smg * sgy) / safe, 1.0)
    beta_fallback = (sgy - smg) / sgg if sgg > 0 else np.zeros_like(sgy)
    beta = np.where(ok, (smm * sgy - smg * smy) / safe, beta_fallback)
    a = obs.mean(axis=0) - b * model.mean(axis=0) - beta * dg.mean()
    return a, b, beta, obs - a - b * model - beta * dg[:, None]


def skill_weight(y: np.ndarray, oof: np.ndarray, train_mean: np.ndarray) -> float:
    """The least-squares weight in [0, 1] of out-of-fold deviations from the mean.

    ``c = clip(<y - m, p - m> / <p - m, p - m>, 0, 1)``, ``p`` the out-of-fold
    predictions and ``m`` each row's fold's training mean: the stacking weight of one
    predictor against the training mean (L. Breiman, "Stacked regressions", Machine
    Learning 24, 49-64 (1996); non-negative, never amplifying). Sums are exactly
    rounded (:func:`math.fsum`).

    Parameters
    ----------
    y, oof, train_mean : numpy.ndarray
        (n,) reference glucose, out-of-fold predictions and the training mean of the
        fold each row was held out of. [mg/dL]

    Returns
    -------
    float
        ``c``; 0 where the predictions never leave the mean. [-]

    Examples
    --------
    >>> skill_weight(np.array([90.0, 110.0]), np.array([80.0, 120.0]), np.full(2, 100.0))
    0.5
    """
    d, z = oof - train_mean, y - train_mean
    den = math.fsum(d * d)
    return 0.0 if den <= 0.0 else float(np.clip(math.fsum(z * d) / den, 0.0, 1.0))


@register("device-inversion")
class DeviceInversion(ForwardModelInversion):
    """Physics inversion (device parts only): optics from published tables, glucose learned.

    The deployable twin of ``physics-inversion``
    (:class:`~nirglucose.models.inversion.PhysicsInversion`): the same MAP/EM machinery
    (:class:`~nirglucose.models.inversion.ForwardModelInversion`) over the device's
    declared parts and the published tables; glucose's response per channel, the
    prior means and the calibration learned from the training rows (module docstring).
    Fits a Dataset and its CSV alike (no scenario is read).

    Parameters
    ----------
    forward_model : {'beer-lambert', 'diffusion', 'rte-lut'}
        The light-transport model assumed over the published tables. [-]
    prior_scale : float
        Multiplies every nuisance's learned prior width at prediction. [-]
    n_em : int
        Empirical-Bayes rounds in ``fit`` (10: with the ``cv`` refits, about the cost
        of the privileged inversion's 30). [-]
    max_iter : int
        Levenberg-Marquardt iterations at most per solve. [-]
    led_fwhm_nm : float or sequence of float, optional
        The device's LED widths (one for all, or one per LED in ascending wavelength);
        :data:`DEFAULT_LED_FWHM_NM` (47.5 nm) when None. [nm]
    cv : int
        Subject-grouped folds of the training rows that learn :attr:`skill_weight_`
        (rows are the groups where no subject ids are given); 0 or 1: weight 1 (the
        posterior mode as it is). [-]
    lut_solver : {'monte-carlo', 'diffusion'}
        What fills the ``rte-lut`` model's table (``optics.lut_solver``: Monte Carlo,
        about 2 CPU-hours per probe geometry and cached, or three-layer diffusion, about
        40 s); read only with ``forward_model="rte-lut"``.

    Attributes
    ----------
    led_fwhm_nm_ : numpy.ndarray
        (k,) the LED widths assumed. [nm]
    glucose_response_ : numpy.ndarray
        (k,) learned d ln(adc / adc_ref) / d glucose before the channel gain
        (``gain_ * glucose_response_`` is the measured response). [1/(mg/dL)]
    skill_weight_ : float
        Weight of the posterior mode's deviation from ``glucose_mean_`` in
        :meth:`predict` (:func:`skill_weight`). [-]
    offset_, gain_, noise_cov_, prior_coef_, prior_sd_, x_mean_, x_scale_, \
glucose_mean_, glucose_var_
        As :class:`~nirglucose.models.inversion.ForwardModelInversion`.
    """

    privileged: ClassVar[str | None] = None

    _parameter_constraints: ClassVar[dict[str, Any]] = {
        **ForwardModelInversion._parameter_constraints,
        "led_fwhm_nm": [
            None,
            Interval(Real, 0, _MAX_FWHM_NM, closed="right"),
            IntervalArray(Real, 0, _MAX_FWHM_NM, closed="right"),
        ],
        "cv": [Interval(Integral, 0, None, closed="left")],
        "lut_solver": [StrOptions({"monte-carlo", "diffusion"})],
    }
    _STATE: ClassVar[dict[str, Any]] = {
        **ForwardModelInversion._STATE,
        "led_fwhm_nm_": (-1,),
        "glucose_response_": (-1,),
        "skill_weight_": None,
    }

    def __init__(
        self,
        forward_model: str = "beer-lambert",
        prior_scale: float = 1.0,
        n_em: int = 10,
        max_iter: int = 30,
        led_fwhm_nm: Any = None,
        cv: int = 3,
        lut_solver: str = "monte-carlo",
    ):
        super().__init__(forward_model, prior_scale, n_em, max_iter)
        self.led_fwhm_nm = led_fwhm_nm
        self.cv = cv
        self.lut_solver = lut_solver

    def _assume(self, X) -> None:  # X is not read: the device's parts only
        wl = self.schema_.wavelengths_nm
        width = DEFAULT_LED_FWHM_NM if self.led_fwhm_nm is None else self.led_fwhm_nm
        width = np.asarray(width, dtype=float)
        if width.ndim == 1 and len(width) != len(wl):
            raise DataError(
                f"led_fwhm_nm gives {len(width)} widths for {len(wl)} LEDs "
                f"({', '.join(f'{w:g}' for w in wl)} nm): give one for all or one per LED"
            )
        self.led_fwhm_nm_ = np.broadcast_to(width, (len(wl),)).astype(float)
        self.glucose_response_ = np.zeros(len(wl))

    def _build_forward(self) -> LearnedGlucoseForward:
        cfg = device_scenario(self.schema_.wavelengths_nm, self.led_fwhm_nm_)
        if self.forward_model == "rte-lut":
            optics = cfg.optics.model_copy(update={"lut_solver": self.lut_solver})
            cfg = cfg.model_copy(update={"optics": optics})
        return LearnedGlucoseForward(
            ForwardModel(cfg, self.forward_model), self.glucose_mean_, self.glucose_response_
        )

    def _prior_start(self, phys: np.ndarray) -> np.ndarray:
        return device_prior_start(self.schema_, phys)

    def _var_floor(self) -> float:
        """A code's quantisation variance at mid-scale of the device's ADC, in
        ln(code): (1 / 2^(bits - 1))^2 / 12. [-]"""
        bits = min(self.schema_.channel_bits or (self.schema_.adc_bits,))  # the coarsest
        return quantisation_variance_ln(bits)

    def _calibrate(self, obs: np.ndarray, model: np.ndarray, y: np.ndarray,
                   edf: float = 0.0) -> None:
        """(a, b) and glucose's response r together (:func:`calibrate_with_glucose`,
        on the optics with glucose held), then S with three coefficients per channel."""
        dg = np.asarray(y, dtype=float) - self.glucose_mean_
        held = model - dg[:, None] * self.glucose_response_
        a, b, beta, resid = calibrate_with_glucose(obs, held, dg)
        self.offset_, self.gain_ = a, b
        # a channel the nuisances' optics do not explain (b = 0) carries no glucose term
        self.glucose_response_ = np.divide(beta, b, out=np.zeros_like(beta), where=b != 0)
        self.forward_.response_per_mgdl = self.glucose_response_
        self._set_noise(resid, edf, 3)

    def _after_fit(self, X, y: np.ndarray, groups) -> None:
        """:attr:`skill_weight_` from out-of-fold predictions of this model (``cv``
        subject-grouped folds, each fitted with ``cv=0`` on the other folds' rows)."""
        self.skill_weight_ = 1.0
        groups = np.arange(len(y)) if groups is None else np.asarray(groups)
        n_splits = int(self.cv)
        if n_splits < 2 or len(np.unique(groups)) < n_splits:
            return
        frame = X.frame if isinstance(X, Dataset) else X
        meta = self.schema_.converter_metadata()  # the fitted device, declared
        oof, train_mean = np.empty(len(y)), np.empty(len(y))
        for tr, te in GroupKFold(n_splits=n_splits).split(y, y, groups):
            part = clone(self).set_params(cv=0).fit(
                Dataset(frame.iloc[tr].reset_index(drop=True), metadata=meta), y[tr], groups[tr]
            )
            oof[te] = part.predict(Dataset(frame.iloc[te].reset_index(drop=True), metadata=meta))
            train_mean[te] = part.glucose_mean_
        self.skill_weight_ = skill_weight(y, oof, train_mean)

    def _restore(self) -> None:
        super()._restore()
        self.skill_weight_ = float(self.skill_weight_)
        if not 0.0 <= self.skill_weight_ <= 1.0:
            raise DataError(f"the saved skill_weight_ {self.skill_weight_!r} is outside "
                            "[0, 1]; refit the model")

    def estimate_state(self, X):
        """Each reading's glucose -- ``glucose_mean_ + skill_weight_ * (mode -
        glucose_mean_)`` [mg/dL] -- and nuisances (their posterior mode), as
        :meth:`~nirglucose.models.inversion.ForwardModelInversion.estimate_state`."""
        state = super().estimate_state(X)
        mean = self.glucose_mean_
        state["glucose_mgdl"] = mean + self.skill_weight_ * (state["glucose_mgdl"] - mean)
        return state

    @property
    def n_parameters(self) -> int:
        """The inversion's learned numbers plus glucose's response per channel and the
        skill weight."""
        return super().n_parameters + int(self.glucose_response_.size) + 1
