"""The inverse-task section: how well each state-predicting estimator recovers the tissue.

The numbers are computed by :mod:`nirglucose.evaluation.benchmark.inverse` (``inverse.csv`` of
each preset's results directory); this module only renders them.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

import pandas as pd

from ..formatting import format_ci, format_number
from .markup import esc as _esc
from .markup import model_label as _model_label
from .markup import preset_of

if TYPE_CHECKING:
    from .figures import Results

__all__ = ["inverse_section"]

#: Readable names of the quantities of ``inverse.csv``.
_LABELS = {
    "blood_fraction": "blood volume fraction (detected)",
    "water_fraction": "water fraction",
    "melanin_fraction": "melanin fraction",
    "skin_thickness_mm": "skin thickness under the probe",
    "saturation": "blood saturation",
    "subcutis_fat_fraction": "subcutis fat fraction",
    "led_shift_nm": "LED thermal peak shift",
    "coupling": "optical coupling",
}


def _read(res: Results) -> pd.DataFrame | None:
    path = res.directory / "inverse.csv"
    if not path.is_file():
        return None
    t = pd.read_csv(path)
    return t if len(t) else None


def _table(t: pd.DataFrame, preset: str) -> str:
    def sig(value, low, high) -> str:  # three significant digits: errors span units
        return format_ci(value, low, high, 3, style="significant")

    rows = []
    for _, r in t.iterrows():
        unit = "" if r["unit"] == "-" else f" {r['unit']}"
        rows.append(
            f"<tr><td>{_esc(_model_label(str(r['model'])))}</td>"
            f"<td>{_esc(_LABELS.get(r['quantity'], r['quantity']))}</td>"
            f"<td>{sig(r['rmse'], r['rmse_ci_low'], r['rmse_ci_high'])}{unit}</td>"
            f"<td>{format_number(r['bias'], 2, style='significant', sign=True)}</td>"
            f"<td>{format_number(r['pearson_r'], 2)}</td>"
            f"<td>{format_number(r['truth_sd'], 3, style='significant')}{unit}</td></tr>"
        )
    return (f'<div class="scroll"><table id="inverse-{_esc(preset)}"><thead><tr>'
            "<th>Model</th><th>Quantity</th><th>RMSE [95 % CI]</th><th>Bias</th>"
            "<th>r</th><th>SD of the truth</th></tr></thead>"
            f"<tbody>{''.join(rows)}</tbody></table></div>")


def inverse_section(runs: Sequence[Results]) -> str:
    """HTML of the inverse-task section ("" when no run has an ``inverse.csv`` row)."""
    tables = [(preset_of(r), t) for r in runs if (t := _read(r)) is not None]
    if not tables:
        return ""
    parts = ['<h2 id="inverse">The inverse task: recovered tissue state</h2><p>Each '
             "estimator that predicts the tissue state (the forward-model estimator and its "
             "hybrid) against the simulator's true values on the held-out readings; the "
             "true values are read for this scoring only. RMSE with a 95 % subject-cluster "
             "bootstrap interval; an estimate that always says the population mean has an "
             "RMSE about the truth's SD. The RTE PINNs predict optical properties "
             "(absorption and scattering at the LEDs), not these tissue fractions, and have "
             "no row.</p>"]
    for p, t in tables:
        parts.append(f"<h3>On <code>{_esc(p)}</code></h3>{_table(t, p)}")
    return "\n".join(parts)
