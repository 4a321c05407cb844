"""Export a fitted linear model as C99 source for a microcontroller.

:func:`export_c` writes ``nirglucose_model.h`` and ``nirglucose_model.c``: single
precision, no heap, no library beyond ``<math.h>`` (``log10f``, ``expf``), with the
feature computation and the dot product, behind one function whose signature follows
the device the model was fitted on (:func:`prototype`); for the study's device::

    float nirglucose_predict(const float adc[4], const float adc_ref[4],
                             const float pmf[NIRGLUCOSE_N_PMF]);

``adc`` holds one code per LED in the header's ``NIRGLUCOSE_CHANNELS_NM`` order;
``adc_ref`` the device's reference codes (absent for a device without them: the ADC's
full scale is the reference); ``pmf`` the physiological columns in the order
``NIRGLUCOSE_PMF_COLUMNS`` lists (absent when the device records none). Each input is
centred on its training mean before the dot product, so single precision keeps the
prediction within a few thousandths of a mg/dL of Python's double-precision one.

When the model carries a split-conformal calibration
(:func:`nirglucose.calibration.conformal.split_conformal`, ``nirglucose fit``), whose
interval is the prediction ± a constant half-width, the source also defines
``nirglucose_predict_interval`` (:func:`interval_prototype`): the same inputs, the
90 % interval's bounds written to ``lower_mgdl`` / ``upper_mgdl`` (the lower one not
below 0 mg/dL), the prediction returned.

Only linear models are exportable (:data:`EXPORTABLE_MODELS`): the Enhanced
Beer–Lambert ridge (its features computed in C, 56 at the study's device) and the PLS
baseline (absorbances and physiological entries), fitted on a device's data (a model
fitted on a plain array has no device to describe).
"""

from __future__ import annotations

import math
import os
from pathlib import Path

import numpy as np

from .._version import __version__
from ..dataset import atomic_write
from ..dataset.schema import DeviceSchema
from ..exceptions import ConfigError, DataError
from ..features import _ENV as ENV_SYMBOLS
from ..features import (
    NOMINAL_BLOOD_PCT,
    PERFUSION_COEFFS,
    PRESSURE_CENTER_MBAR,
    SKIN_TEMP_CENTER_C,
    feature_table,
)
from ..models.registry import model_from
from .c_guard import estimate_body, estimate_decl

__all__ = [
    "EXPORTABLE_MODELS",
    "HEADER_NAME",
    "SOURCE_NAME",
    "PROTOTYPE",
    "prototype",
    "interval_prototype",
    "INTERVAL_LEVEL_PCT",
    "generate_c",
    "export_c",
    "c_float",
]

#: Registry names of the models :func:`export_c` accepts.
EXPORTABLE_MODELS = ("ebl", "pls")
HEADER_NAME = "nirglucose_model.h"
SOURCE_NAME = "nirglucose_model.c"
#: The exported function's signature for the study's device (:func:`prototype`).
PROTOTYPE = (
    "float nirglucose_predict(const float adc[4], const float adc_ref[4], "
    "const float pmf[NIRGLUCOSE_N_PMF])"
)


def prototype(schema: DeviceSchema) -> str:
    """The exported function's signature for a device.

    Examples
    --------
    >>> prototype(DeviceSchema((940.0,), reference=False, physiology=()))
    'float nirglucose_predict(const float adc[1])'
    """
    k = schema.n_channels
    args = [f"const float adc[{k}]"]
    if schema.reference:
        args.append(f"const float adc_ref[{k}]")
    if schema.physiology:
        args.append("const float pmf[NIRGLUCOSE_N_PMF]")
    return f"float nirglucose_predict({', '.join(args)})"


#: Coverage of the exported interval [%] (the benchmark's headline level).
INTERVAL_LEVEL_PCT = 90


def _arg_names(schema: DeviceSchema) -> list[str]:
    return ["adc"] + (["adc_ref"] if schema.reference else []) + (
        ["pmf"] if schema.physiology else []
    )


def interval_prototype(schema: DeviceSchema) -> str:
    """The signature of the exported interval function for a device.

    Examples
    --------
    >>> interval_prototype(DeviceSchema((940.0,), reference=False, physiology=()))
    'float nirglucose_predict_interval(const float adc[1], float *lower_mgdl, float *upper_mgdl)'
    """
    args = prototype(schema)[len("float nirglucose_predict(") : -1]
    return (
        f"float nirglucose_predict_interval({args}, float *lower_mgdl, float *upper_mgdl)"
    )


def _half_width(model) -> float | None:
    """The model's constant 90 % half-width [mg/dL], or None without a calibration."""
    cal = getattr(model, "conformal_", None)
    if cal is None:
        return None
    if cal.get("method") != "split":
        raise DataError("only a split-conformal (constant-width) interval can be exported to C")
    return float(cal["half_width_mgdl"][str(INTERVAL_LEVEL_PCT)])


def c_float(value: float) -> str:
    """A C float literal: the value rounded to float32, printed with ``%.9g``.

    Nine significant digits identify every float32, so the compiler reads back exactly
    the float32 nearest to ``value``.

    Examples
    --------
    >>> c_float(1.0), c_float(-0.125e-6), c_float(1013.25)
    ('1.0f', '-1.25e-07f', '1013.25f')
    """
    x = float(value)
    if not math.isfinite(x) or not math.isfinite(float(np.float32(x))):
        raise DataError(f"cannot export a non-finite coefficient ({x!r}); refit the model")
    # Round to float32 first: 9 significant digits of a float32 parse back to it exactly.
    text = f"{float(np.float32(x)):.9g}"
    if "e" not in text and "." not in text:
        text += ".0"
    return text + "f"


def _array(name: str, values, per_line: int = 4) -> str:
    vals = [c_float(v) for v in np.asarray(values, dtype=float).ravel()]
    lines = [
        "    " + ", ".join(vals[i : i + per_line]) + ("," if i + per_line < len(vals) else "")
        for i in range(0, len(vals), per_line)
    ]
    return f"static const float {name}[{len(vals)}] = {{\n" + "\n".join(lines) + "\n};\n"


def _interval_decl(schema: DeviceSchema, half: float | None) -> str:
    if half is None:
        return ""
    return f"""
/* {INTERVAL_LEVEL_PCT} % prediction interval (subject-grouped split conformal: the
 * prediction +- a constant half-width, calibrated on held-out people). Writes its
 * bounds [mg/dL] to lower_mgdl (not below 0) and upper_mgdl; returns glucose [mg/dL]. */
#define NIRGLUCOSE_INTERVAL_LEVEL_PCT {INTERVAL_LEVEL_PCT}
#define NIRGLUCOSE_INTERVAL_HALF_WIDTH_MGDL {c_float(half)}
{interval_prototype(schema)};
"""


def _header(
    model_name: str, n_inputs: int, version: str, schema: DeviceSchema, half: float | None = None
) -> str:
    cols = ", ".join(f'"{c}"' for c in schema.physiology)
    k = schema.n_channels
    ref = (
        "adc_ref: the device's reference codes for the same LEDs (positive)"
        if schema.reference
        else f"no reference codes: the ADC's full scale {schema.full_scale} is I0"
    )
    pmf = "pmf: the physiological vector" if schema.physiology else "no physiological vector"
    return f"""/* nirglucose_model.h: generated by nirglucose {version} (model '{model_name}').
 * Glucose [mg/dL] from one snapshot of a {k}-LED NIR sensor with a {schema.adc_bits}-bit
 * ADC. C99, single precision, no heap, no library beyond <math.h>. Do not edit:
 * regenerate with `nirglucose export-c --model model.json --out DIR`.
 */
#ifndef NIRGLUCOSE_MODEL_H
#define NIRGLUCOSE_MODEL_H

/* LED channels, in the order of adc[]{" and adc_ref[]" if schema.reference else ""} [nm]. */
#define NIRGLUCOSE_N_CHANNELS {k}
#define NIRGLUCOSE_CHANNELS_NM {", ".join(schema.labels)}
#define NIRGLUCOSE_ADC_BITS {schema.adc_bits}

/* Measured physiological vector pmf[], in this order (dataset column names; units in
 * docs/user_guide/your_data.md). */
#define NIRGLUCOSE_N_PMF {len(schema.physiology)}
#define NIRGLUCOSE_PMF_COLUMNS {cols}

/* Linear model inputs (features) evaluated per call. */
#define NIRGLUCOSE_N_INPUTS {n_inputs}

#ifdef __cplusplus
extern "C" {{
#endif

/* adc: ADC codes (positive); {ref}; {pmf}.
 * Returns glucose [mg/dL], unchecked: prefer nirglucose_estimate, which checks the
 * codes and the training range and returns a status. */
{prototype(schema)};
{estimate_decl(schema)}{_interval_decl(schema, half)}
#ifdef __cplusplus
}}
#endif

#endif /* NIRGLUCOSE_MODEL_H */
"""


def _dot_block(n: int) -> str:
    """Centred dot product over x[n] with four accumulators (short dependency chains)."""
    return f"""    {{
        float s0 = 0.0f, s1 = 0.0f, s2 = 0.0f, s3 = 0.0f;
        int i;
        for (i = 0; i + 3 < {n}; i += 4) {{
            s0 += COEF[i] * (x[i] - MEAN[i]);
            s1 += COEF[i + 1] * (x[i + 1] - MEAN[i + 1]);
            s2 += COEF[i + 2] * (x[i + 2] - MEAN[i + 2]);
            s3 += COEF[i + 3] * (x[i + 3] - MEAN[i + 3]);
        }}
        for (; i < {n}; ++i) {{
            s0 += COEF[i] * (x[i] - MEAN[i]);
        }}
        return INTERCEPT + ((s0 + s1) + (s2 + s3));
    }}
"""


def _absorbances(schema: DeviceSchema) -> list[str]:
    if schema.reference:
        return [
            f"    const float a{k} = log10f(adc_ref[{k}] / adc[{k}]);"
            for k in range(schema.n_channels)
        ]
    fs = c_float(schema.full_scale)
    return [f"    const float a{k} = log10f({fs} / adc[{k}]);" for k in range(schema.n_channels)]


def _ebl_body(schema: DeviceSchema) -> str:
    """The features of :func:`~nirglucose.features.feature_table` in C, then the dot."""
    table = feature_table(schema)
    pmf = {c: f"pmf[{m}]" for m, c in enumerate(schema.physiology)}
    ops = {f.op[0] for f in table}
    env = {f.op[1] for f in table if f.op[0] == "envA"} | {
        s for f in table if f.op[0] == "env2" for s in f.op[1:]
    }
    lines = _absorbances(schema)
    for sym, (column, center, scale) in ENV_SYMBOLS.items():  # the features' own table
        if sym in env:
            x = f"{pmf[column]} - {c_float(center)}"
            x = x if scale == 1.0 else f"({x}) / {c_float(scale)}"
            lines.append(f"    const float {sym} = {x};")
    if "w" in ops:
        pc = PERFUSION_COEFFS
        p0 = c_float(PRESSURE_CENTER_MBAR)
        lines += [
            f"    const float t = {pmf['skin_thickness_mm']};",
            f"    const float mel = {pmf['melanin_fraction']};",
        ]
        if "blood_volume_pct" in pmf:  # measured perfusion (features.NOMINAL_BLOOD_PCT)
            lines.append(
                f"    const float perf = {pmf['blood_volume_pct']} / {c_float(NOMINAL_BLOOD_PCT)};"
            )
        else:
            lines += [
                f"    const float perf = expf({c_float(pc['temp'])} * ({pmf['skin_temp_c']} - "
                f"{c_float(SKIN_TEMP_CENTER_C)}) + {c_float(pc['sbp'])} * "
                f"({pmf['systolic_bp_mmhg']} - {c_float(pc['sbp_center'])})",
                f"                            + {c_float(pc['pressure'])} * "
                f"({pmf['pressure_mbar']} - {p0}));",
            ]
    lines.append(f"    float x[{len(table)}];")
    for f, spec in enumerate(table):
        op = spec.op
        kind = op[0]
        if kind == "A":
            expr = f"a{op[1]}"
        elif kind == "lin":
            expr = " + ".join(f"{c_float(w)} * a{c}" for c, w in op[1] if w != 0.0)
        elif kind == "AA":
            expr = f"a{op[1]} * a{op[2]}"
        elif kind == "w":
            _, k, a_s, a_p, a_m = op
            expr = f"({c_float(a_s)} * t + {c_float(a_p)} * perf + {c_float(a_m)} * mel) * a{k}"
        elif kind == "envA":
            expr = f"{op[1]} * a{op[2]}"
        elif kind == "pmf":
            expr = f"pmf[{op[1]}]"
        else:  # env2
            expr = f"{op[1]} * {op[2]}"
        lines.append(f"    x[{f}] = {expr};  /* {spec.name} */")
    return "\n".join(lines) + "\n" + _dot_block(len(table))


def _pls_body(schema: DeviceSchema) -> str:
    k, m = schema.n_channels, len(schema.physiology)
    lines = _absorbances(schema)
    lines.append(f"    float x[{k + m}];")
    for i, w in enumerate(schema.labels):
        lines.append(f"    x[{i}] = a{i};  /* A_{w} */")
    for j, col in enumerate(schema.physiology):
        lines.append(f"    x[{k + j}] = pmf[{j}];  /* {col} */")
    return "\n".join(lines) + "\n" + _dot_block(k + m)


def _model_arrays(model) -> tuple[str, np.ndarray, np.ndarray, float, str]:
    """(registry name, coefficients, input means, centred intercept, body)."""
    name = getattr(type(model), "registry_name", type(model).__name__)
    if name not in EXPORTABLE_MODELS:
        raise ConfigError(
            f"model {name!r} cannot be exported to C: only the linear models "
            f"({', '.join(EXPORTABLE_MODELS)}) can"
        )
    if not hasattr(model, "coef_"):
        raise DataError(f"the {name!r} model is not fitted; fit it before exporting")
    schema = model.schema_
    if schema.is_plain:
        raise DataError(
            f"the {name!r} model was fitted on a plain array, which names no device; fit it "
            "on a device's data (adc_<nm> columns) to export C"
        )
    if schema.per_channel:
        raise DataError(f"the {name!r} model's device has a converter per channel "
                        f"({schema.describe()}); the C export takes one ADC resolution "
                        "for every channel")
    coef = np.asarray(model.coef_, dtype=float)
    if name == "ebl":
        mean, body = np.asarray(model.scaler_mean_, dtype=float), _ebl_body(schema)
    else:
        mean, body = np.asarray(model.x_mean_, dtype=float), _pls_body(schema)
    # prediction = intercept + coef . x = (intercept + coef . mean) + coef . (x - mean)
    intercept = float(model.intercept_) + float(coef @ mean)
    return name, coef, mean, intercept, body


def generate_c(model) -> dict[str, str]:
    """The header and source text of a fitted linear model.

    Parameters
    ----------
    model : EnhancedBeerLambert or PLSBaseline
        A fitted model.

    Returns
    -------
    dict
        ``{"nirglucose_model.h": text, "nirglucose_model.c": text}``.

    Raises
    ------
    ConfigError
        The model is not linear.
    DataError
        The model is not fitted, or has non-finite coefficients.
    """
    name, coef, mean, intercept, body = _model_arrays(model)
    half = _half_width(model)
    n = len(coef)
    source = (
        f"/* nirglucose_model.c: generated by nirglucose {__version__} (model '{name}'). */\n"
        "#include <math.h>\n"
        f'#include "{HEADER_NAME}"\n\n'
        "/* Coefficients on the centred inputs [mg/dL per input unit], the inputs' training\n"
        " * means, and the prediction at the means [mg/dL]. */\n"
        + _array("COEF", coef)
        + _array("MEAN", mean)
        + f"static const float INTERCEPT = {c_float(intercept)};\n\n"
        f"{prototype(model.schema_)}\n{{\n" + body + "}\n"
        + estimate_body(model.schema_, _array)
        + _interval_body(model.schema_, half)
    )
    return {
        HEADER_NAME: _header(name, n, __version__, model.schema_, half),
        SOURCE_NAME: source,
    }


def _interval_body(schema: DeviceSchema, half: float | None) -> str:
    if half is None:
        return ""
    call = ", ".join(_arg_names(schema))
    return f"""
{interval_prototype(schema)}
{{
    const float g = nirglucose_predict({call});
    const float lo = g - NIRGLUCOSE_INTERVAL_HALF_WIDTH_MGDL;
    *lower_mgdl = lo > 0.0f ? lo : 0.0f;
    *upper_mgdl = g + NIRGLUCOSE_INTERVAL_HALF_WIDTH_MGDL;
    return g;
}}
"""


def export_c(model, out_dir: str | os.PathLike) -> tuple[Path, Path]:
    """Write ``nirglucose_model.h`` and ``nirglucose_model.c`` into ``out_dir``.

    Parameters
    ----------
    model : EnhancedBeerLambert, PLSBaseline or path
        A fitted model, or the path of its model file.
    out_dir : str or path-like
        Output directory; created if its parent exists. Files are written atomically.

    Returns
    -------
    tuple of pathlib.Path
        The header and source paths.

    Examples
    --------
    >>> import tempfile, nirglucose as ng
    >>> from nirglucose.models import EnhancedBeerLambert
    >>> m = EnhancedBeerLambert().fit(ng.simulate("paper", 20, 3, seed=0))
    >>> h, c = export_c(m, tempfile.mkdtemp())
    >>> h.name, c.name
    ('nirglucose_model.h', 'nirglucose_model.c')
    """
    if not isinstance(out_dir, str | os.PathLike):
        raise DataError(f"out_dir must be a directory path, got {type(out_dir).__name__}")
    texts = generate_c(model_from(model))
    out = Path(out_dir)
    if not out.parent.exists():
        raise DataError(f"parent directory {str(out.parent)!r} of --out does not exist")
    if out.exists() and not out.is_dir():
        raise DataError(f"{str(out)!r} exists and is not a directory")
    out.mkdir(exist_ok=True)
    paths = []
    for fname in (HEADER_NAME, SOURCE_NAME):
        text = texts[fname]
        paths.append(atomic_write(out / fname, lambda tmp, text=text: Path(tmp).write_text(text)))
    return paths[0], paths[1]
