"""The exported C's checked entry point: ``nirglucose_estimate`` returns a status.

``nirglucose_predict`` evaluates the model on whatever it is given (code 0 gives NaN,
code 1 on a 10-bit device tens of thousands of mg/dL). ``nirglucose_estimate`` checks
its inputs first and returns a status bit mask, writing the glucose through a pointer:

* ``NIRGLUCOSE_CODE_INVALID``: an ADC or reference code outside (0, full scale] or not
  a number; no estimate (``*glucose_mgdl`` is 0);
* ``NIRGLUCOSE_EXTRAPOLATED``: an input outside the range the model was fitted on
  (per channel and physiological entry, when the model file records it);
* ``NIRGLUCOSE_OUT_OF_METER_RANGE``: the estimate lies outside 20-600 mg/dL, what a
  meter would show as LO/HI.

``NIRGLUCOSE_OK`` (0) is none of these.

Examples
--------
>>> from nirglucose.dataset.schema import DeviceSchema
>>> estimate_prototype(DeviceSchema((940.0,), reference=False, physiology=()))
'int nirglucose_estimate(const float adc[1], float *glucose_mgdl)'
"""

from __future__ import annotations

from ..dataset import GLUCOSE_REPORTING_RANGE_MGDL
from ..dataset.schema import DeviceSchema

__all__ = ["STATUS_BITS", "estimate_prototype", "estimate_decl", "estimate_body"]

#: Status bits of ``nirglucose_estimate``.
STATUS_BITS = {"NIRGLUCOSE_OK": 0, "NIRGLUCOSE_CODE_INVALID": 1,
               "NIRGLUCOSE_EXTRAPOLATED": 2, "NIRGLUCOSE_OUT_OF_METER_RANGE": 4}


def _args(schema: DeviceSchema) -> tuple[list[str], list[str]]:
    k = schema.n_channels
    decl = [f"const float adc[{k}]"] + ([f"const float adc_ref[{k}]"] if schema.reference
                                         else [])
    names = ["adc"] + (["adc_ref"] if schema.reference else [])
    if schema.physiology:
        decl.append("const float pmf[NIRGLUCOSE_N_PMF]")
        names.append("pmf")
    return decl, names


def estimate_prototype(schema: DeviceSchema) -> str:
    """The signature of the checked function for a device."""
    return f"int nirglucose_estimate({', '.join(_args(schema)[0])}, float *glucose_mgdl)"


def estimate_decl(schema: DeviceSchema) -> str:
    """The header's status codes and declaration."""
    codes = "\n".join(f"#define {n} {v}" for n, v in STATUS_BITS.items())
    rng = "recorded" if schema.train_min else "not recorded in this model file: never set"
    return f"""
/* Checked estimate: returns a status bit mask and writes glucose [mg/dL] to
 * *glucose_mgdl. CODE_INVALID: a code outside (0, NIRGLUCOSE_FULL_SCALE] or not a
 * number, no estimate (0 written). EXTRAPOLATED: an input outside the training range
 * ({rng}). OUT_OF_METER_RANGE: the estimate lies outside 20-600 mg/dL. */
{codes}
#define NIRGLUCOSE_FULL_SCALE {schema.full_scale}
{estimate_prototype(schema)};
"""


def _range_checks(schema: DeviceSchema) -> list[str]:
    """C lines that set EXTRAPOLATED for inputs outside TRAIN_MIN/TRAIN_MAX."""
    if not schema.train_min:
        return []
    k, off, lines = schema.n_channels, 0, []
    groups = [("adc", k)] + ([("adc_ref", k)] if schema.reference else [])
    groups += [("pmf", len(schema.physiology))] if schema.physiology else []
    for name, n in groups:
        lines += [f"    for (i = 0; i < {n}; ++i) {{",
                  f"        if ({name}[i] < TRAIN_MIN[{off} + i] || "
                  f"{name}[i] > TRAIN_MAX[{off} + i]) {{",
                  "            status |= NIRGLUCOSE_EXTRAPOLATED;",
                  "        }", "    }"]
        off += n
    return lines


def estimate_body(schema: DeviceSchema, array) -> str:
    """The source of ``nirglucose_estimate`` (``array(name, values)`` writes a table)."""
    _, names = _args(schema)
    codes = [n for n in names if n != "pmf"]
    lo, hi = GLUCOSE_REPORTING_RANGE_MGDL
    tables = (array("TRAIN_MIN", schema.train_min) + array("TRAIN_MAX", schema.train_max)
              if schema.train_min else "")
    code_checks = []
    for n in codes:  # a NaN fails both comparisons, so it is invalid too
        code_checks += ["    for (i = 0; i < NIRGLUCOSE_N_CHANNELS; ++i) {",
                        f"        if (!({n}[i] > 0.0f && {n}[i] <= (float)NIRGLUCOSE_FULL_SCALE)) "
                        "{", "            return NIRGLUCOSE_CODE_INVALID;", "        }", "    }"]
    body = "\n".join([
        "    int status = NIRGLUCOSE_OK;", "    int i;", "    float g;",
        "    *glucose_mgdl = 0.0f;", *code_checks, *_range_checks(schema),
        f"    g = nirglucose_predict({', '.join(names)});",
        f"    if (!(g >= {lo:.1f}f && g <= {hi:.1f}f)) {{",
        "        status |= NIRGLUCOSE_OUT_OF_METER_RANGE;", "    }",
        "    *glucose_mgdl = g;", "    return status;"])
    return f"\n{tables}\n{estimate_prototype(schema)}\n{{\n{body}\n}}\n"
