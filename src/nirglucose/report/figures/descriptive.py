"""Inputs of the figures that describe the run rather than score it.

The data characteristics (glucose, ADC codes, environment, physiology), the
simulator's pipeline diagram, the model architectures and the Enhanced Beer–Lambert
feature engineering, read from the dataset, its configuration and models fitted on it.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, Final

import numpy as np
import pandas as pd

from ...config import NOISE_SOURCES, device_capabilities
from ...formatting import format_number
from ...models import make_model, tuned_params
from ...simulation.measurement import PMF_COLUMNS, PPG_COLUMNS

__all__ = ["NOISE_LAYER", "NEUTRALISED_BY", "REDUCED_BY", "noise_states",
           "ARCHITECTURE_MODELS", "fitted_architectures", "physics_loss_texts",
           "ebl_feature_table",
           "feature_categories", "pipeline_columns", "environment_panels",
           "physiology_panels"]

#: Simulator layer in which each noise source acts (for the pipeline diagram).
NOISE_LAYER: Final[dict[str, str]] = {
    "ambient_light": "environment",
    "humidity_coupling": "environment",
    "pulsation": "physiology",
    # water absorbs at the skin temperature (Röttgers et al. 2014): the tissue's own state
    "water_temperature": "physiology",
    "contact_pressure": "contact",
    "led_thermal_drift": "hardware",
    "led_ageing": "hardware",
    "led_flicker": "hardware",
    "led_wavelength_shift": "hardware",
    "dark_current": "hardware",
    "shot": "hardware",
    "johnson": "hardware",
    "adc_inl": "hardware",
    "adc_offset_drift": "hardware",
    "pmf_measurement": "measurement",
}

#: Noise sources a device capability neutralises although they are switched on:
#: source -> (capability, what the diagram says), from the simulator's layers
#: (simulation/measurement.py, contact.py, hardware.py).
NEUTRALISED_BY: Final[dict[str, tuple[str, str]]] = {
    "pmf_measurement": ("exact_physiology", "exact physiology: device.physiology = exact"),
    "contact_pressure": ("constant_force_probe", "constant-force probe"),
    "led_ageing": ("monitor_photodiode", "cancelled in adc/adc_ref by the monitor photodiode"),
    "led_flicker": ("monitor_photodiode", "cancelled in adc/adc_ref by the monitor "
                    "photodiode"),
}
#: Noise sources a capability reduces but does not remove: source -> (capability, note).
REDUCED_BY: Final[dict[str, tuple[str, str]]] = {
    # its junction-temperature jitter also drives the wavelength shift (simulator.py),
    # which the monitor does not cancel
    "led_thermal_drift": ("monitor_photodiode", "power drift cancelled in adc/adc_ref by "
                          "the monitor photodiode; the junction-temperature jitter still "
                          "shifts the wavelength"),
    "humidity_coupling": ("humidity_compensation", "compensated down to the RH sensor's "
                          "error"),
}


def noise_states(config) -> dict[str, tuple[str, str]]:
    """Each noise source's effect on this device's readings: (state, note).

    ``state`` is ``"on"``, ``"neutralised"`` (switched on, but a device capability of
    the configuration removes it: :data:`NEUTRALISED_BY`) or ``"off"`` (factor 0);
    ``note`` is the factor when not ×1 and the capability's effect.
    """
    caps = set(device_capabilities(config))
    out: dict[str, tuple[str, str]] = {}
    for src in NOISE_SOURCES:
        f = config.noise_factor(src)
        if f <= 0:
            out[src] = ("off", "off")
            continue
        factor = f"×{_g(f)}" if f != 1 else ""
        cap, note = NEUTRALISED_BY.get(src, (None, ""))
        if cap in caps:
            out[src] = ("neutralised", note)
            continue
        cap, note = REDUCED_BY.get(src, (None, ""))
        out[src] = ("on", ", ".join(x for x in (factor, note if cap in caps else "") if x))
    return out


#: Model families of the architecture figure, in the study's order.
ARCHITECTURE_MODELS: Final = ("ebl", "original-pinn", "optimized-pinn", "rte-pinn",
                              "selective-rte-pinn", "sdnn")


def _module_blocks(module) -> list[tuple[str, str]]:
    """Blocks of a fitted torch module: each top-level child with its layer widths."""
    import torch.nn as nn

    inner = getattr(module, "inner", module)
    blocks: list[tuple[str, str]] = []
    for name, child in inner.named_children():
        if isinstance(child, nn.MultiheadAttention):
            blocks.append((name, f"attention {child.embed_dim}-d, {child.num_heads} head(s)"))
            continue
        linears = [m for m in child.modules() if isinstance(m, nn.Linear)]
        if not linears:
            continue  # norms, dropout: no widths to show
        widths = [linears[0].in_features] + [m.out_features for m in linears]
        drop = [m.p for m in child.modules() if isinstance(m, nn.Dropout) and m.p > 0]
        blocks.append((name, "→".join(str(w) for w in widths)
                       + (f", dropout {_g(drop[0])}" if drop else "")))
    return blocks


def fitted_architectures(dataset, preset: str | None,
                         models: Sequence[str] = ARCHITECTURE_MODELS, *,
                         fitted: dict[str, Any] | None = None
                         ) -> dict[str, tuple[list[tuple[str, str]], int]]:
    """Layer sizes of each model family, read from models fitted for one epoch.

    Each model is built with the run's tuned parameters
    (:func:`nirglucose.models.tuned_params`) and fitted on ``dataset`` for one epoch
    (the sizes do not depend on training), so the diagram shows the widths that ran.
    When ``fitted`` is given, each fitted model is also stored there by name (the
    report reuses the EBL fit for :func:`ebl_feature_table`).
    """
    out: dict[str, tuple[list[tuple[str, str]], int]] = {}
    for name in models:
        params = dict(tuned_params(name, preset)) if preset else {}
        if name != "ebl":
            params["max_epochs"] = 1
        m = make_model(name, **params).fit(dataset)
        if fitted is not None:
            fitted[name] = m
        schema = m.schema_
        n_a, n_p = len(schema.labels), len(schema.physiology)
        if name == "ebl":
            blocks = [("inputs", f"{n_a} absorbances + {n_p} physiology"),
                      ("features", f"{len(m.table_)} engineered (Beer–Lambert)"),
                      ("standardise", f"{len(m.table_)}"),
                      ("ridge", f"{len(m.table_)}→1, α = "
                                       f"{format_number(m.alpha_, 0, style='scientific')}"),
                      ("output", "glucose [mg/dL]")]
        else:
            blocks = [("inputs", f"{n_a} absorbances + {n_p} physiology")] \
                + _module_blocks(m.module_) \
                + [("output", "glucose [mg/dL]")]
        out[name] = (blocks, int(m.n_parameters))
    return out


#: The physics term of each PINN family's training loss, in words.
PHYSICS_TERMS: dict[str, str] = {
    "original-pinn": "Beer–Lambert residual A − εcl",
    "optimized-pinn": "Beer–Lambert residual A − εcl",
    "rte-pinn": "diffusion reflectance from μa, μs′ (optics) + μs′ prior",
    "selective-rte-pinn": "diffusion reflectance at 1050, 1150 nm + μs′ prior",
}


def physics_loss_texts(fitted: dict[str, Any]) -> dict[str, str]:
    """Model -> its training loss with the physics term and the λ it was fitted with.

    Only models with a ``lambda_phys`` (the PINNs); λ = 0 is said to switch it off.
    """
    out = {}
    for name, m in fitted.items():
        lam = getattr(m, "lambda_phys", None)
        if lam is None:
            continue
        term = PHYSICS_TERMS.get(name, "physics residual")
        out[name] = (f"MSE + λ·{term}\nλ = {_g(lam)}" + (" (off: tuned to 0)" if lam == 0
                                                         else ""))
    return out


def ebl_feature_table(dataset, preset: str | None, *, model: Any = None
                      ) -> tuple[tuple, int, int]:
    """The Enhanced Beer–Lambert features of ``dataset``'s device, from a fitted model.

    ``model``, when given, is an EBL model already fitted on ``dataset`` with the
    preset's tuned parameters (as :func:`fitted_architectures` fits it); else one is
    fitted here.

    Returns
    -------
    tuple
        (feature table of :func:`nirglucose.features.feature_table`, LED channels,
        physiological entries).
    """
    m = model if model is not None else make_model(
        "ebl", **(tuned_params("ebl", preset) if preset else {})).fit(dataset)
    return tuple(m.table_), len(m.schema_.labels), len(m.schema_.physiology)


#: What each feature operation (:attr:`nirglucose.features.FeatureSpec.op`) reads.
_OP_SOURCE: Final = {"A": "absorbance", "lin": "absorbance", "AA": "absorbance",
                     "w": "both", "envA": "both", "pmf": "physiology", "env2": "physiology"}


def feature_categories(table) -> tuple[dict[str, list[str]], dict[str, str]]:
    """Feature names by category (table order), and what each category is computed from.

    The source is ``"absorbance"``, ``"physiology"`` or ``"both"``, from the operations
    of the category's features (``"both"`` when unknown or mixed).
    """
    cats: dict[str, list[str]] = {}
    src: dict[str, set[str]] = {}
    for spec in table:
        cats.setdefault(spec.category, []).append(spec.name)
        op = spec.op[0] if spec.op else None
        src.setdefault(spec.category, set()).add(_OP_SOURCE.get(op, "both"))
    return cats, {c: next(iter(s)) if len(s) == 1 else "both" for c, s in src.items()}


def _g(v: float) -> str:
    """A configuration value in its shortest form (1050, 0.5, 1e-05)."""
    return format_number(v, style="general")


def _fmt_range(v: Sequence[float], unit: str) -> str:
    return f"{_g(v[0])}–{_g(v[1])} {unit}"


def pipeline_columns(config) -> list[list[dict[str, Any]]]:
    """Boxes of the pipeline diagram (figure 2), from a resolved ScenarioConfig.

    Each box lists settings of its layer and the noise sources acting in it
    (:data:`NOISE_LAYER`), on (with their effective factor, enabled × scale ×
    ``noise_scale``, when not 1) or not acting, with the reason: off, or neutralised by
    a device capability (:func:`noise_states`).
    """
    noise: dict[str, tuple[list[str], list[str]]] = {}
    for src, (state, note) in noise_states(config).items():
        layer = NOISE_LAYER.get(src, "hardware")
        on, off = noise.setdefault(layer, ([], []))
        name = src.replace("_", " ")
        if state == "on":
            on.append(f"{name} ({note})" if note else name)  # note: factor, compensation
        else:
            off.append(f"{name} ({note})")

    def box(title: str, layers: Sequence[str], details: list[str], kind: str) -> dict[str, Any]:
        on = [s for layer in layers for s in noise.get(layer, ([], []))[0]]
        off = [s for layer in layers for s in noise.get(layer, ([], []))[1]]
        return {"title": title, "details": details, "noise_on": on, "noise_off": off,
                "kind": kind}

    env, phys, glu, hw, opt = (config.environment, config.physiology, config.glucose,
                               config.hardware, config.optics)
    wl = ", ".join(_g(w) for w in config.leds.wavelengths_nm)
    status = [f"  {k} {format_number(v, 0, style='percent')}" for k, v in glu.status_probs.items()]
    return [
        [
            box("Environment", ("environment",), [
                f"ambient {_fmt_range(env.temperature_c, '°C')}",
                f"RH {_fmt_range(env.humidity_pct, '%')}",
                f"light {_fmt_range(env.ambient_lux, 'lx')}",
            ], "input"),
            box("Glucose", (), [
                f"signal gain ×{_g(glu.signal_gain)}",
                "diabetes status mix:",
                *status,
            ], "input"),
            box("Physiology + contact", ("physiology", "contact"), [
                f"age {_fmt_range(phys.age_yr, 'yr')}",
                f"variation scale ×{_g(phys.variation_scale)}",
                f"coupling SD {_g(config.contact.coupling_sd)}",
            ], "input"),
        ],
        [
            box(f"Optics: {opt.model}", (), [
                f"LEDs {wl} nm",
                f"source–detector {_g(opt.source_detector_mm)} mm",
                f"water spectrum: {opt.water_source}",
                "μa: water, Hb, HbO2, lipid, melanin, glucose; μs′: power law, "
                "lowered by glucose",
            ], "optics"),
        ],
        [
            box("Hardware", ("hardware",), [
                f"LED power {', '.join(_g(p) for p in config.leds.power_mw)} mW",
                f"TIA gain {format_number(hw.tia_gain_ohm, 0, style='scientific')} Ω",
                f"ADC {hw.adc_bits} bit, {_g(hw.adc_vref_v)} V",
            ], "hardware"),
        ],
        [
            box("Measured outputs", ("measurement",), _measured_lines(config), "output"),
        ],
    ]


def _measured_lines(config) -> list[str]:
    """What the device records and knows, from its capabilities (``device.*``)."""
    caps = device_capabilities(config)
    n_phys = len(PMF_COLUMNS) + (len(PPG_COLUMNS) if "ppg_perfusion_spo2" in caps else 0)
    ref = ("monitor photodiode, per reading" if "monitor_photodiode" in caps
           else "start-up reference")
    how = "exact" if "exact_physiology" in caps else "measured"
    lines = ["adc_<nm>: codes per LED", f"adc_ref_<nm>: {ref}",
             f"physiological vector ({n_phys} {how} values)"]
    if caps:
        lines += ["device capabilities:", *(f"  {c.replace('_', ' ')}" for c in caps)]
    return lines


def _panel(frame: pd.DataFrame, cols: Sequence[str], xlabel: str, log: bool = False
           ) -> dict[str, Any] | None:
    for c in cols:
        if c in frame.columns:
            return {"values": frame[c].to_numpy(float), "xlabel": xlabel, "log": log}
    return None


def environment_panels(frame: pd.DataFrame) -> list[dict[str, Any]]:
    """Panels of the environment figure (true ambient conditions where recorded)."""
    panels = [
        _panel(frame, ["true_ambient_temperature_c"], "ambient temperature [°C]"),
        _panel(frame, ["true_humidity_pct", "humidity_pct"], "relative humidity [%]"),
        _panel(frame, ["true_pressure_mbar", "pressure_mbar"], "barometric pressure [mbar]"),
        _panel(frame, ["true_ambient_lux", "ambient_lux"], "ambient illuminance [lx]", log=True),
    ]
    out = [p for p in panels if p is not None]
    if "true_light_source" in frame.columns:
        counts = frame["true_light_source"].astype(str).value_counts()
        out.append({"counts": counts.sort_index(), "xlabel": "ambient light source"})
    return out


_PHYSIOLOGY: Final = (
    ("age_yr", "age [yr]"),
    ("bmi_kgm2", "BMI [kg/m²]"),
    ("melanin_fraction", "melanin [volume fraction]"),
    ("skin_thickness_mm", "skin thickness [mm]"),
    ("hydration_pct", "hydration [% of nominal]"),
    ("systolic_bp_mmhg", "systolic BP [mmHg]"),
    ("heart_rate_bpm", "heart rate [1/min]"),
    ("resp_rate_bpm", "respiration rate [1/min]"),
    ("skin_temp_c", "skin temperature [°C]"),
)


def physiology_panels(frame: pd.DataFrame) -> list[dict[str, Any]]:
    """Panels of the physiology figure (the measured physiological vector)."""
    out: list[dict[str, Any]] = []
    if "fitzpatrick_type" in frame.columns:
        counts = frame["fitzpatrick_type"].astype(int).value_counts().sort_index()
        out.append({"counts": {f"{k}": int(v) for k, v in counts.items()},
                    "xlabel": "Fitzpatrick skin type [I–VI as 1–6]"})
    for col, label in _PHYSIOLOGY:
        p = _panel(frame, [col], label)
        if p is not None:
            out.append(p)
    return out




def _adc_by_wavelength(frame: pd.DataFrame, wavelengths: Sequence[float]
                       ) -> dict[float, np.ndarray]:
    out = {}
    for w in wavelengths:
        col = f"adc_{w:g}"
        if col in frame.columns:
            out[float(w)] = frame[col].to_numpy(float)
    return out
