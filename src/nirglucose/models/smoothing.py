"""A causal smoother of a worn device's glucose predictions: a Kalman filter with a
physiological rate-of-change limit.

Any registered model predicts one reading at a time; a device worn for days reads every
few minutes, and glucose cannot jump between readings as far as the noise of a single
estimate can. :class:`CausalKalmanSmoother` runs, per subject and in time order, the
constant-velocity (local linear trend) Kalman filter of glucose and its rate of change:
state ``x = [g, dg/dt]``, transition ``[[1, dt], [0, 1]]``, process noise of a
white-noise acceleration with spectral density ``q`` (``Q = q [[dt³/3, dt²/2],
[dt²/2, dt]]``), measurement ``z = g + e`` with ``e ~ N(0, r²)`` (Kalman 1960, J. Basic
Eng. 82:35; the continuous white-noise-acceleration model of Bar-Shalom, Li and
Kirubarajan 2001, *Estimation with Applications to Tracking and Navigation*, §6.2.2).
After each update the rate is clipped to ``± max_rate_mgdl_per_min`` and the
output may move from the previous output by at most that rate times the time between
the readings: the physiological limit. Healthy people exceed ±2 mg/dL/min over 15 min
about 1 % of the time (Normal reference range for glucose rates of change, Diabetes Technol. Ther.
2025, doi:10.1177/15209156251390822) and people with type 1 diabetes spend about 5 %
of the time beyond the healthy 0.1–99.9 % range of −80 … +89 mg/dL/h (J. Diabetes Sci.
Technol. 2024, doi:10.1177/19322968241298248), so the limit is a tuned parameter
(:data:`SMOOTHER_GRID`), never a constant. Only past and present readings enter each
output (causal): what a device can display in real time.

A gap longer than ``reset_after_min`` (the device taken off) restarts the filter at the
next reading.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from itertools import product
from typing import Any, ClassVar

import numpy as np
import pandas as pd

from ..exceptions import DataError
from ._params import Interval, Real, check_parameters

__all__ = ["CausalKalmanSmoother", "INITIAL_RATE_SD_MGDL_PER_MIN", "SMOOTHER_GRID", "tune_smoother"]

#: The prior SD of the rate of change at a (re)start [mg/dL/min]: the normative
#: ±2 mg/dL/min of healthy people (Diabetes Technol. Ther. 2025, module docstring).
INITIAL_RATE_SD_MGDL_PER_MIN = 2.0

#: The tuning grid (12 configurations, the budget of every family): measurement SD
#: [mg/dL] × acceleration spectral density [mg²/dL²/min³] × rate limit [mg/dL/min].
SMOOTHER_GRID: dict[str, tuple[float, ...]] = {
    "measurement_sd_mgdl": (10.0, 30.0),
    "accel_psd": (0.001, 0.01, 0.1),
    "max_rate_mgdl_per_min": (2.0, 4.0),
}


@dataclass(frozen=True)
class CausalKalmanSmoother:
    """Causal Kalman filter of predictions with a rate-of-change limit (module docstring).

    Parameters
    ----------
    measurement_sd_mgdl : float
        SD of one prediction's error, r [mg/dL].
    accel_psd : float
        Spectral density q of the white-noise acceleration of glucose [mg²/dL²/min³].
    max_rate_mgdl_per_min : float
        The physiological limit on |dg/dt| [mg/dL/min]; ``inf`` for none.
    reset_after_min : float
        A gap between readings longer than this restarts the filter [min].

    Examples
    --------
    >>> import numpy as np
    >>> s = CausalKalmanSmoother(measurement_sd_mgdl=20.0, accel_psd=0.01)
    >>> t = np.arange(0.0, 60.0, 5.0)
    >>> out = s.smooth(np.full(12, 100.0), t, np.zeros(12))
    >>> bool(np.allclose(out, 100.0))
    True
    """

    measurement_sd_mgdl: float = 20.0
    accel_psd: float = 0.01
    max_rate_mgdl_per_min: float = 4.0
    reset_after_min: float = 120.0

    #: Finite and > 0, except the rate limit, which may be ``inf`` (no limit).
    _parameter_constraints: ClassVar[dict[str, Any]] = {
        "measurement_sd_mgdl": [Interval(Real, 0, None, closed="neither")],
        "accel_psd": [Interval(Real, 0, None, closed="neither")],
        "max_rate_mgdl_per_min": [Interval(Real, 0, None, closed="right")],
        "reset_after_min": [Interval(Real, 0, None, closed="neither")],
    }

    def __post_init__(self) -> None:
        check_parameters(self._parameter_constraints, asdict(self), type(self).__name__)

    def smooth(self, predicted_mgdl, time_min, subject_id) -> np.ndarray:
        """The filtered glucose of every reading [mg/dL], in the input's order.

        Parameters
        ----------
        predicted_mgdl, time_min, subject_id : array-like, same length
            A model's predictions [mg/dL], each reading's time [min] and its subject.
            Readings of a subject are filtered in time order; times must be distinct
            within a subject.
        """
        z = np.asarray(predicted_mgdl, dtype=float)
        t = np.asarray(time_min, dtype=float)
        sid = np.asarray(subject_id)
        if not (z.shape == t.shape == sid.shape) or z.ndim != 1:
            raise DataError("predicted_mgdl, time_min and subject_id must be 1-D arrays of "
                            "one length")
        if not (np.isfinite(z).all() and np.isfinite(t).all()):
            raise DataError("predicted_mgdl and time_min must be finite; drop or fill the "
                            "missing readings first")
        out = np.empty_like(z)
        order = np.lexsort((t, sid))
        s_sorted, t_sorted = sid[order], t[order]
        starts = np.flatnonzero(np.r_[True, s_sorted[1:] != s_sorted[:-1]])
        ends = np.r_[starts[1:], len(order)]
        for a, b in zip(starts, ends, strict=True):
            idx = order[a:b]
            if np.any(np.diff(t_sorted[a:b]) <= 0):
                who = s_sorted[a:a + 1].tolist()[0]  # a Python value, not np.int64(3)
                raise DataError(f"subject {who!r} has two readings at one time; times must be "
                                "distinct within a subject")
            out[idx] = self._filter(z[idx], t[idx])
        return out

    def _filter(self, z: np.ndarray, t: np.ndarray) -> np.ndarray:
        """One subject's readings in time order (scalar loop: series are short per subject)."""
        r2, q, vmax = self.measurement_sd_mgdl**2, self.accel_psd, self.max_rate_mgdl_per_min
        out = np.empty_like(z)
        g = v = 0.0
        p00 = p01 = p11 = 0.0
        for i in range(len(z)):
            dt = t[i] - t[i - 1] if i else np.inf
            if dt > self.reset_after_min:  # first reading, or the device was put back on
                g, v, p00, p01, p11 = z[i], 0.0, r2, 0.0, INITIAL_RATE_SD_MGDL_PER_MIN**2
                out[i] = g
                continue
            # predict: x = F x, P = F P F' + Q
            g = g + dt * v
            p00, p01, p11 = (p00 + 2 * dt * p01 + dt * dt * p11 + q * dt**3 / 3,
                             p01 + dt * p11 + q * dt**2 / 2,
                             p11 + q * dt)
            # update with the reading
            s = p00 + r2
            k0, k1 = p00 / s, p01 / s
            resid = z[i] - g
            g, v = g + k0 * resid, v + k1 * resid
            p00, p01, p11 = (1 - k0) * p00, (1 - k0) * p01, p11 - k1 * p01
            v = min(max(v, -vmax), vmax)  # the physiological limit, on the rate ...
            g = min(max(g, out[i - 1] - vmax * dt), out[i - 1] + vmax * dt)  # ... and the step
            out[i] = g
        return out


def tune_smoother(frame: pd.DataFrame, *, prediction: str = "predicted_glucose_mgdl",
                  reference: str = "glucose_mgdl", time: str = "time_min",
                  subject: str = "subject_id") -> tuple[CausalKalmanSmoother, pd.DataFrame]:
    """The configuration of :data:`SMOOTHER_GRID` with the lowest RMSE against the reference.

    Call it on predictions of *tuning* data only (other seeds than the reported ones, the
    budget of every family: 12 configurations), then apply the returned smoother to the
    reported runs.

    Returns
    -------
    smoother : CausalKalmanSmoother
    scores : DataFrame
        One row per configuration with its ``rmse_mgdl``, best first.
    """
    missing = [c for c in (prediction, reference, time, subject) if c not in frame.columns]
    if missing:
        raise DataError(f"tune_smoother needs the columns {missing}; got {list(frame.columns)}")
    y = frame[reference].to_numpy(float)
    rows = []
    for values in product(*SMOOTHER_GRID.values()):
        params = dict(zip(SMOOTHER_GRID, values, strict=True))
        out = CausalKalmanSmoother(**params).smooth(frame[prediction], frame[time],
                                                     frame[subject])
        rows.append({**params, "rmse_mgdl": float(np.sqrt(np.mean((out - y) ** 2)))})
    scores = pd.DataFrame(rows).sort_values("rmse_mgdl", kind="stable").reset_index(drop=True)
    best = {k: float(scores.loc[0, k]) for k in SMOOTHER_GRID}
    return CausalKalmanSmoother(**best), scores
