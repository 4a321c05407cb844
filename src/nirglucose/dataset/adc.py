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

Examples
--------
>>> import pandas as pd
>>> resolve_adc_bits(pd.DataFrame({"adc_940": [512.5, 700.0]}), declared=10)
(10, 'declared')
"""

from __future__ import annotations

import warnings
from typing import Any

import numpy as np
import pandas as pd

from ..exceptions import DataError
from .columns import CODE_COLUMN_RE, DEFAULT_ADC_BITS

__all__ = ["AMBIGUOUS_BELOW_CODE", "resolve_adc_bits", "check_adc_bits",
           "quantisation_variance_ln"]

#: Codes at or below this fit a 10-bit ADC and every larger one: the resolution is
#: ambiguous and must be declared. [ADC code]
AMBIGUOUS_BELOW_CODE = 2**10 - 1


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
    (``"declared"``, ``"metadata"`` or ``"assumed"``).

    Raises
    ------
    DataError
        An invalid resolution, or none declared while every code fits 10 bits.
    """
    if declared is not None:
        return check_adc_bits(declared), "declared"
    if metadata_bits is not None:
        return check_adc_bits(metadata_bits), "metadata"
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
