"""The one ADC-resolution policy of ``fit``, ``predict``, ``benchmark`` and ``export-c``.

The resolution (bits) of a device's ADC sets its full scale 2^bits - 1, which plays the
reference intensity I0 of a device without reference codes, so a wrong guess shifts
every absorbance. It is, in order:

1. declared: ``--adc-bits`` / ``adc_bits=`` / a Dataset's ``metadata["adc_bits"]``;
2. the file's metadata (the scenario's ``hardware.adc_bits`` for simulated files);
3. otherwise *assumed* only where the codes leave a single plausible answer: codes
   above 2^10 - 1 = 1023 rule out the 8- and 10-bit ADCs of microcontrollers, and the
   study's 12 bits (:data:`~nirglucose.dataset.DEFAULT_ADC_BITS`) is assumed with a
   warning; codes up to 1023 fit a 10-, 12-, 14- or 16-bit ADC alike and are refused
   until the resolution is declared.

Every output records the resolution it used (the model file's schema, ``meta.json``,
the C header).

A device may mix converters (an analog front end at 10 bits beside a digital PPG
sensor's 18-bit counts): ``adc_bits`` may then be a mapping from channel to bits
(``{"adc_940": 10, "adc_1050": 18}``; ``--adc-bits adc_940=10,adc_1050=18``), with an
optional ``"default"`` for the channels not named, and ``adc_full_scale`` a mapping
from channel to its full-scale code where that is not 2^bits - 1
(:func:`channel_converters`). A channel's reference codes ``adc_ref_<nm>`` share its
converter. A declared converter whose codes never reach a quarter of its full scale is
warned about (:func:`check_headroom`): a 10-bit channel read at 18 bits shifts its
absorbance by log10(2^8) = 2.4. A channel whose every reading sits at mid-scale is warned
about too (:func:`check_dc_level`): an AC-coupled front end (a PPG sensor's, which
removes the DC level and biases the pulse at mid-scale) records the pulse, not the light
level that absorbance reads.

Examples
--------
>>> import pandas as pd
>>> resolve_adc_bits(pd.DataFrame({"adc_940": [512.5, 700.0]}), declared=10)
(10, 'declared')
"""

from __future__ import annotations

import warnings
from collections.abc import Mapping
from typing import Any

import numpy as np
import pandas as pd

from ..exceptions import DataError
from .columns import CODE_COLUMN_RE, DEFAULT_ADC_BITS

__all__ = ["AMBIGUOUS_BELOW_CODE", "HEADROOM_FRACTION", "resolve_adc_bits", "check_adc_bits",
           "check_channel_bits", "parse_channel_spec", "channel_converters",
           "check_headroom", "check_dc_level", "MIDSCALE_TOLERANCE", "AC_SPREAD_FRACTION",
           "quantisation_variance_ln"]

#: Codes at or below this fit a 10-bit ADC and every larger one: the resolution is
#: ambiguous and must be declared. [ADC code]
AMBIGUOUS_BELOW_CODE = 2**10 - 1


#: A declared converter whose codes never exceed this fraction of its full scale is warned
#: about: a quarter is 2 bits unused, more than an analog front end's usual design
#: margin, and what a channel read with another converter's resolution shows. [-]
HEADROOM_FRACTION = 0.25


#: A channel whose median code lies within this fraction of full scale of mid-scale ...
MIDSCALE_TOLERANCE = 0.005
#: ... and whose central 90 % of readings span less than this fraction of full scale is
#: taken for an AC-coupled (DC-removed) channel. A DC-coupled channel reads the light
#: through each person's skin, which moves it far more: on the simulated presets the
#: central 90 % of a channel's codes span 10-44 % of full scale (``lab``, cuvette-like,
#: one nominal subject: about 2 %, but its medians sit 2-10 % off mid-scale), while
#: an AC-coupled reading's mean is its bias point, mid-scale, whoever wears it. [-]
AC_SPREAD_FRACTION = 0.05


def check_adc_bits(bits: Any) -> int:
    """``bits`` as an int from 1 to 32, else DataError."""
    if isinstance(bits, bool) or not isinstance(bits, int | np.integer) or not 1 <= bits <= 32:
        raise DataError(f"adc_bits must be an integer from 1 to 32, got {bits!r}")
    return int(bits)


def quantisation_variance_ln(adc_bits: Any) -> float:
    """Variance of a mid-scale code's quantisation error in ln(code): LSB^2 / 12.

    A uniform quantiser of step q adds an error uniform on [-q/2, q/2], of variance
    q^2 / 12 [1]_. At mid-scale (code 2^(bits-1)) one step is 1 / 2^(bits-1) of the
    code, so in ln(code) the variance is (1 / 2^(bits-1))^2 / 12; each extra bit --
    or each fourfold of readings averaged with noise that dithers them -- quarters it.

    Parameters
    ----------
    adc_bits : int
        ADC resolution (:func:`check_adc_bits`). [bit]

    Returns
    -------
    float
        The variance. [-] (ln units squared)

    References
    ----------
    .. [1] W. R. Bennett, "Spectra of quantized signals", Bell Syst. Tech. J. 27,
       446-472 (1948); B. Widrow, I. Kollár, "Quantization Noise", Cambridge University
       Press (2008), ch. 4.

    Examples
    --------
    >>> f"{quantisation_variance_ln(12):.4g}"
    '1.987e-08'
    >>> quantisation_variance_ln(12) / quantisation_variance_ln(14)
    16.0
    """
    step = 0.5 ** (check_adc_bits(adc_bits) - 1)  # [1]: q at mid-scale, in ln(code)
    return float(step * step / 12.0)


def _max_code(frame: pd.DataFrame) -> float:
    cols = [c for c in frame.columns if isinstance(c, str) and CODE_COLUMN_RE.match(c)]
    if not cols or not len(frame):
        return float("nan")
    vals = frame[cols].apply(pd.to_numeric, errors="coerce").to_numpy(dtype=float)
    return float(np.nanmax(vals)) if np.isfinite(vals).any() else float("nan")


def resolve_adc_bits(frame: pd.DataFrame, declared: Any = None, metadata_bits: Any = None
                     ) -> tuple[int, str]:
    """``(bits, source)``: the resolution by the policy above and where it came from
    (``"declared"``, ``"metadata"`` or ``"assumed"``); a declared per-channel mapping is
    returned as the checked mapping (:func:`check_channel_bits`).

    Raises
    ------
    DataError
        An invalid resolution, or none declared while every code fits 10 bits.
    """
    if declared is not None:
        return check_channel_bits(declared), "declared"  # type: ignore[return-value]
    if metadata_bits is not None:
        return check_channel_bits(metadata_bits), "metadata"  # type: ignore[return-value]
    top = _max_code(frame)
    if np.isfinite(top) and top <= AMBIGUOUS_BELOW_CODE:
        raise DataError(
            f"ADC codes up to {top:g} fit a 10-, 12-, 14- or 16-bit ADC alike; declare "
            "the device's resolution (--adc-bits N; Python adc_bits=N)"
        )
    if np.isfinite(top):
        warnings.warn(
            f"ADC resolution not declared: assuming {DEFAULT_ADC_BITS} bits (codes reach "
            f"{top:g}); declare it (--adc-bits N; Python adc_bits=N) if the ADC has more",
            UserWarning,
            stacklevel=3,
        )
    return DEFAULT_ADC_BITS, "assumed"


def _channel_key(key: Any) -> str:
    """``'adc_940'``, ``'940'`` or ``940`` as ``'adc_940'``; ``'default'`` kept."""
    text = str(key).strip()
    if text.casefold() == "default":
        return "default"
    if not text.casefold().startswith("adc_"):
        text = f"adc_{text}"
    m = CODE_COLUMN_RE.match(text.casefold())
    if not m or m.group(1):
        raise DataError(f"per-channel converter key {key!r}: name an LED's column, e.g. "
                        "adc_940 (its adc_ref_940 shares the converter), or 'default'")
    return f"adc_{float(m.group(2)):g}"


def check_channel_bits(bits: Any) -> int | dict[str, int]:
    """``bits`` checked: an int from 1 to 32, or a mapping from channel (``adc_940``) to
    such an int (``'default'`` for the channels not named). DataError otherwise.

    Examples
    --------
    >>> check_channel_bits({"adc_940": 10, "1050": 18})
    {'adc_940': 10, 'adc_1050': 18}
    """
    if isinstance(bits, Mapping):
        if not bits:
            raise DataError("adc_bits names no channel; give e.g. {'adc_940': 10}")
        return {_channel_key(k): check_adc_bits(v) for k, v in bits.items()}
    return check_adc_bits(bits)


def parse_channel_spec(text: str, what: str = "--adc-bits") -> int | dict[str, float]:
    """A command line's ``N`` or ``adc_940=10,adc_1050=18`` (``default=N`` or a bare
    ``N`` among them for the rest), as an int or a mapping. DataError naming ``what``.

    Examples
    --------
    >>> parse_channel_spec("adc_940=10,adc_1050=18")
    {'adc_940': 10, 'adc_1050': 18}
    >>> parse_channel_spec("12")
    12
    """
    def number(v: str) -> Any:
        try:
            f = float(v)
        except ValueError:
            raise DataError(f"{what} {text!r}: {v!r} is not a number; give N or "
                            "adc_940=10,adc_1050=18") from None
        return int(f) if f.is_integer() else f

    parts = [p.strip() for p in str(text).split(",") if p.strip()]
    if not parts:
        raise DataError(f"{what} {text!r} names nothing; give N or adc_940=10,adc_1050=18")
    if len(parts) == 1 and "=" not in parts[0]:
        return number(parts[0])
    out: dict[str, Any] = {}
    for p in parts:
        key, _, val = p.partition("=") if "=" in p else ("default", "", p)
        key = _channel_key(key)
        if key in out:
            raise DataError(f"{what} {text!r} names {key} twice; keep one")
        out[key] = number(val.strip())
    return out


def channel_converters(labels: tuple[str, ...], bits: int | Mapping[str, int],
                       full_scale: Mapping[str, Any] | None = None
                       ) -> tuple[tuple[int, ...], tuple[float, ...]]:
    """Per LED label (``'940'``), its bits and full-scale code: ``bits`` an int for every
    channel or a mapping (:func:`check_channel_bits`); ``full_scale`` overrides 2^bits - 1
    per channel. DataError for a channel the mapping leaves out (without a default), a
    key naming no channel of the device, or a full scale above 2^bits - 1.
    """
    cols = [f"adc_{w}" for w in labels]
    bits = check_channel_bits(bits)
    if isinstance(bits, int):
        per = dict.fromkeys(cols, bits)
    else:
        unknown = [k for k in bits if k != "default" and k not in cols]
        if unknown:
            raise DataError(f"adc_bits names {', '.join(unknown)}, not a channel of this "
                            f"device ({', '.join(cols)})")
        missing = [c for c in cols if c not in bits and "default" not in bits]
        if missing:
            raise DataError(f"adc_bits declares no resolution for {', '.join(missing)}; "
                            "give every channel (adc_940=10,adc_1050=18) or a default "
                            "(default=12)")
        per = {c: bits.get(c, bits.get("default")) for c in cols}
    fs = {c: float(2 ** per[c] - 1) for c in cols}
    for k, v in (full_scale or {}).items():
        key = _channel_key(k)
        if key not in cols:
            raise DataError(f"adc_full_scale names {key}, not a channel of this device "
                            f"({', '.join(cols)})")
        if isinstance(v, bool) or not isinstance(v, int | float | np.number) or not (
                1 <= float(v) <= fs[key]):
            raise DataError(f"adc_full_scale of {key} must be a code from 1 to "
                            f"{fs[key]:.0f} (its {per[key]}-bit converter), got {v!r}")
        fs[key] = float(v)
    return tuple(int(per[c]) for c in cols), tuple(fs[c] for c in cols)


def check_headroom(frame: pd.DataFrame, columns: tuple[str, ...],
                   full_scales: tuple[float, ...], bits: tuple[int, ...]) -> None:
    """One UserWarning per declared channel whose codes never reach
    :data:`HEADROOM_FRACTION` of its full scale (another converter's resolution?)."""
    for col, fs, b in zip(columns, full_scales, bits, strict=True):
        if col not in frame.columns:
            continue
        top = float(pd.to_numeric(frame[col], errors="coerce").max())
        if np.isfinite(top) and top < HEADROOM_FRACTION * fs:
            need = max(1, int(np.ceil(np.log2(top + 1))))
            warnings.warn(
                f"column {col!r}: codes never exceed {top:g}, under a quarter of its declared "
                f"full scale {fs:.0f} ({b} bits): if its converter has {need} bits, declare "
                f"it per channel (--adc-bits {col}={need},...; Python adc_bits={{'{col}': "
                f"{need}, ...}}); read at {b} bits its absorbance is off by "
                f"{np.log10((fs + 1) / 2 ** need):.1f}",
                UserWarning, stacklevel=3)


def check_dc_level(frame: pd.DataFrame, columns: tuple[str, ...],
                   full_scales: tuple[float, ...]) -> list[str]:
    """The channels whose every reading sits at mid-scale, one UserWarning each.

    An AC-coupled front end (a PPG sensor that subtracts the DC level and biases the
    pulsatile part at mid-scale) gives codes whose mean is the converter's bias point
    whatever the tissue; their logarithm is not an absorbance, so a model of light
    attenuation (and any model) can read no glucose from it. Flagged: the median within
    :data:`MIDSCALE_TOLERANCE` of full scale of mid-scale and the central 90 % of the
    readings within :data:`AC_SPREAD_FRACTION` of full scale.

    Returns
    -------
    list of str
        The flagged columns.

    Examples
    --------
    >>> import warnings
    >>> frame = pd.DataFrame({"adc_940": [2046.0, 2049.0, 2047.0, 2050.0],
    ...                       "adc_1050": [1500.0, 2600.0, 1900.0, 3100.0]})
    >>> with warnings.catch_warnings(record=True):
    ...     warnings.simplefilter("always")
    ...     check_dc_level(frame, ("adc_940", "adc_1050"), (4095.0, 4095.0))
    ['adc_940']
    """
    flagged = []
    for col, fs in zip(columns, full_scales, strict=True):
        if col not in frame.columns:
            continue
        v = pd.to_numeric(frame[col], errors="coerce").to_numpy(float)
        v = v[np.isfinite(v)]
        if len(v) < 2 or not fs > 0:
            continue
        p5, median, p95 = np.percentile(v, [5.0, 50.0, 95.0])
        if (abs(median / fs - 0.5) <= MIDSCALE_TOLERANCE
                and (p95 - p5) / fs <= AC_SPREAD_FRACTION):
            flagged.append(col)
            warnings.warn(
                f"column {col!r}: every reading sits at mid-scale (median {median:,.0f} of "
                f"{fs:,.0f}; 90 % within {100 * (p95 - p5) / fs:.1f} % of full scale): an "
                "AC-coupled front end, which removes the light level? Its codes are not an "
                "absorbance and no model can read glucose from them; give the DC-coupled "
                f"reading (the front end's DC or ambient-cancelled output) as {col}",
                UserWarning, stacklevel=3)
    return flagged
