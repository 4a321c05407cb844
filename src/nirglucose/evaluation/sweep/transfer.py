"""Calibration transfer: map a unit's readings onto a master unit's, per channel.

Each unit measures the same few transfer standards as the master (the factory's golden
unit). Per channel j, with absorbance A_j = log10(adc_ref_j / adc_j), a straight line
A_master = b_j + s_j A_unit is fitted over the standards' readings and then applied to
every later reading of the unit, whose code becomes adc' = adc_ref 10^(-A'). This is
piecewise direct standardisation (PDS) with a one-channel window [1]_, the per-channel
slope/bias standardisation of the transfer literature [2]_; ``"bias"`` fits the offset
alone (s_j = 1), which a few standards determine more robustly.

References
----------
.. [1] Y. Wang, D. J. Veltkamp, B. R. Kowalski, "Multivariate instrument
   standardization", Anal. Chem. 63 (1991) 2750-2756, doi:10.1021/ac00023a016 (DS and
   PDS).
.. [2] R. N. Feudale, N. A. Woody, H. Tan, A. J. Myles, S. D. Brown, J. Ferre,
   "Transfer of multivariate calibration models: a review", Chemom. Intell. Lab. Syst.
   64 (2002) 181-192, doi:10.1016/S0169-7439(02)00085-0 (slope/bias and univariate
   standardisation).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd

from ...exceptions import ConfigError, DataError, unknown_name

__all__ = ["TRANSFER_METHODS", "ChannelTransfer", "absorbance", "fit_transfer"]

#: Transfer methods by name: offset per channel, or slope and offset per channel.
TRANSFER_METHODS = ("bias", "slope-bias")


def _labels(frame: pd.DataFrame) -> list[str]:
    return [c[4:] for c in frame.columns if isinstance(c, str) and c.startswith("adc_")
            and not c.startswith("adc_ref_")]


def absorbance(frame: pd.DataFrame) -> pd.DataFrame:
    """A = log10(adc_ref / adc) per channel (columns named by the channel's label).

    Examples
    --------
    >>> f = pd.DataFrame({"adc_850": [100.0], "adc_ref_850": [1000.0]})
    >>> absorbance(f)["850"].tolist()
    [1.0]
    """
    labels = _labels(frame)
    missing = [f"adc_ref_{w}" for w in labels if f"adc_ref_{w}" not in frame]
    if not labels or missing:
        raise DataError(
            "calibration transfer needs adc_<nm> and adc_ref_<nm> codes for every LED; "
            f"missing {missing or ['adc_<nm>']}"
        )
    return pd.DataFrame(
        {w: np.log10(frame[f"adc_ref_{w}"].to_numpy(float) / frame[f"adc_{w}"].to_numpy(float))
         for w in labels},
        index=frame.index,
    )


@dataclass(frozen=True)
class ChannelTransfer:
    """A fitted per-channel transfer: A_master = bias + slope A_unit.

    Attributes
    ----------
    labels : tuple of str
        Channel labels (the ``<nm>`` of ``adc_<nm>``).
    bias, slope : numpy.ndarray
        Per channel. [-, -]
    """

    labels: tuple[str, ...]
    bias: np.ndarray
    slope: np.ndarray

    def apply(self, frame: pd.DataFrame, adc_bits: int) -> pd.DataFrame:
        """The frame with each ``adc_<nm>`` replaced by the master-equivalent code.

        Codes become floats, clipped to 1 .. 2^bits - 1 (the schema's valid range).
        """
        a = absorbance(frame)
        out = frame.copy()
        full = float(2 ** int(adc_bits) - 1)
        for j, w in enumerate(self.labels):
            a_master = self.bias[j] + self.slope[j] * a[w].to_numpy()
            code = frame[f"adc_ref_{w}"].to_numpy(float) * np.power(10.0, -a_master)
            out[f"adc_{w}"] = np.clip(code, 1.0, full)
        return out


def fit_transfer(unit: pd.DataFrame, master: pd.DataFrame, method: str = "slope-bias"):
    """Fit a per-channel transfer from paired readings of the transfer standards.

    Parameters
    ----------
    unit, master : pandas.DataFrame
        The same standards' readings by the unit and by the master, row by row.
    method : str
        One of :data:`TRANSFER_METHODS`.

    Returns
    -------
    ChannelTransfer

    Raises
    ------
    ConfigError
        Unknown method.
    DataError
        Frames of different lengths or channels, or fewer than two readings.

    Examples
    --------
    >>> m = pd.DataFrame({"adc_850": [100.0, 200.0], "adc_ref_850": [1000.0, 1000.0]})
    >>> u = m.assign(adc_850=m["adc_850"] * 2)
    >>> t = fit_transfer(u, m, "bias")
    >>> round(float(t.bias[0]), 4)
    0.301
    """
    if method not in TRANSFER_METHODS:
        raise ConfigError(unknown_name("transfer method", method, TRANSFER_METHODS))
    au, am = absorbance(unit), absorbance(master)
    if list(au.columns) != list(am.columns) or len(au) != len(am):
        raise DataError(
            "the unit's and the master's transfer readings must pair row by row with the "
            f"same channels; got {len(au)} x {list(au.columns)} and {len(am)} x {list(am.columns)}"
        )
    if len(au) < 2:
        raise DataError("calibration transfer needs at least two readings of the standards")
    bias, slope = [], []
    for w in au.columns:
        x, y = au[w].to_numpy(), am[w].to_numpy()
        if method == "bias" or np.ptp(x) == 0:
            s = 1.0
        else:
            s = float(np.polyfit(x, y, 1)[0])
        slope.append(s)
        bias.append(float(np.mean(y - s * x)))
    return ChannelTransfer(tuple(au.columns), np.array(bias), np.array(slope))
