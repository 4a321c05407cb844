"""Permutation importance of each wavelength channel on held-out data.

The same method for every estimator [1]_: the channel of one LED (its ``adc_<nm>``
code *and*, where the device records one, its reference ``adc_ref_<nm>``, permuted together with one
permutation so that the pair stays consistent) is shuffled across the held-out rows,
and the increase of the RMSE over the unshuffled prediction is recorded; the mean over
``n_repeats`` permutations is reported. All permuted copies are predicted in one call.

References
----------
.. [1] Breiman L. Random forests. Mach Learn 45:5-32, 2001. doi:10.1023/A:1010933404324
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
import pandas as pd

from ..dataset import Dataset
from ..exceptions import DataError

__all__ = ["permutation_importance"]


def _wavelengths(data: Dataset) -> list[float]:
    if data.config is not None:
        return [float(w) for w in data.config.leds.wavelengths_nm]
    return [float(c[4:]) for c in data.frame.columns if c.startswith("adc_") and c[4:].isdigit()]


def permutation_importance(
    model: Any,
    data: Dataset,
    *,
    n_repeats: int = 3,
    seed: int = 0,
    wavelengths_nm: Sequence[float] | None = None,
) -> pd.DataFrame:
    """RMSE increase when one wavelength channel is permuted across held-out rows.

    Parameters
    ----------
    model : fitted estimator
        Anything with ``predict(Dataset) -> mg/dL``.
    data : Dataset
        Held-out rows with ``glucose_mgdl``.
    n_repeats : int
        Permutations per channel. [-]
    seed : int
        Seed of the permutations. [-]
    wavelengths_nm : sequence of float, optional
        Channels to permute (default: the dataset's LEDs). [nm]

    Returns
    -------
    pandas.DataFrame
        ``wavelength_nm`` [nm], ``rmse_increase_mgdl`` (mean) [mg/dL],
        ``rmse_increase_sd_mgdl`` [mg/dL], ``baseline_rmse_mgdl`` [mg/dL].
    """
    frame = data.frame.reset_index(drop=True)
    if "glucose_mgdl" not in frame:
        raise DataError("permutation importance needs the reference 'glucose_mgdl'")
    wl = list(wavelengths_nm) if wavelengths_nm is not None else _wavelengths(data)
    y = frame["glucose_mgdl"].to_numpy(float)
    n, n_rep = len(frame), max(int(n_repeats), 1)
    rng = np.random.default_rng(np.random.SeedSequence([0x1A9, int(seed)]))
    n_copies = 1 + len(wl) * n_rep
    # copy 0 is the data as is; copy 1 + i * n_rep + r permutes channel i (repeat r)
    big = frame.iloc[np.tile(np.arange(n), n_copies)].reset_index(drop=True)
    for i, w in enumerate(wl):
        if f"adc_{w:g}" not in frame:
            raise DataError(f"no column 'adc_{w:g}' for wavelength {w:g} nm")
        # A device without reference codes (full scale as I0) has its code alone.
        cols = [c for c in (f"adc_{w:g}", f"adc_ref_{w:g}") if c in frame]
        values = frame[cols].to_numpy()
        block = np.tile(values, (n_copies, 1))
        for r in range(n_rep):
            start = (1 + i * n_rep + r) * n
            block[start : start + n] = values[rng.permutation(n)]
        big[cols] = block
    pred = np.asarray(model.predict(Dataset(big, config=data.config, seed=data.seed)), dtype=float)
    pred = pred.reshape(1 + len(wl) * n_rep, n)
    rmse = np.sqrt(np.mean((pred - y) ** 2, axis=1))
    inc = (rmse[1:] - rmse[0]).reshape(len(wl), n_rep)
    return pd.DataFrame(
        {
            "wavelength_nm": np.asarray(wl, dtype=float),
            "rmse_increase_mgdl": inc.mean(axis=1),
            "rmse_increase_sd_mgdl": inc.std(axis=1, ddof=1) if n_rep > 1 else np.zeros(len(wl)),
            "baseline_rmse_mgdl": np.full(len(wl), rmse[0]),
        }
    )
