"""The reference study's headline numbers, kept as data.

R. Gani (UCL), *Physics-Informed Neural Networks vs. Physics Models for Non-Invasive
Glucose Monitoring: A Comparative Study Under Noise-Stressed Synthetic Conditions*,
Table 1: one 60/20/20 split by subject of 80 subjects x 3 measurements, so the test set
holds 48 snapshots of 16 subjects.
"""

from __future__ import annotations

from .._renamed import moved_name

__all__ = ["STUDY_TABLE", "STUDY_PROTOCOL", "STUDY_COLUMNS", "STUDY_ORDER"]

#: Columns of :data:`STUDY_TABLE` (besides ``model``), with their units.
STUDY_COLUMNS: dict[str, str] = {
    "rmse_mgdl": "RMSE [mg/dL]",
    "mard_pct": "MARD [%]",
    "clarke_a_pct": "Clarke zone A [%]",
    "within15_pct": "within ±15 % of reference [%]",
    "n_parameters": "trainable parameters [-]",
    "latency_single_ms": "inference time per sample [ms]",
}

#: Study Table 1, one dict per model; ``model`` is this package's registry name.
STUDY_TABLE: tuple[dict[str, float | int | str], ...] = (
    {
        "model": "ebl",
        "rmse_mgdl": 13.6,
        "mard_pct": 9.7,
        "clarke_a_pct": 95.8,
        "within15_pct": 93.8,
        "n_parameters": 56,
        "latency_single_ms": 0.01,
    },
    {
        "model": "original-pinn",
        "rmse_mgdl": 14.6,
        "mard_pct": 10.8,
        "clarke_a_pct": 94.2,
        "within15_pct": 91.5,
        "n_parameters": 163_000,
        "latency_single_ms": 3.8,
    },
    {
        "model": "optimized-pinn",
        "rmse_mgdl": 28.7,
        "mard_pct": 19.2,
        "clarke_a_pct": 87.3,
        "within15_pct": 78.4,
        "n_parameters": 89_000,
        "latency_single_ms": 2.1,
    },
    {
        "model": "rte-pinn",
        "rmse_mgdl": 24.3,
        "mard_pct": 16.8,
        "clarke_a_pct": 89.7,
        "within15_pct": 82.1,
        "n_parameters": 1_340_000,
        "latency_single_ms": 15.2,
    },
    {
        "model": "selective-rte-pinn",
        "rmse_mgdl": 24.9,
        "mard_pct": 17.1,
        "clarke_a_pct": 89.2,
        "within15_pct": 81.6,
        "n_parameters": 566_000,
        "latency_single_ms": 6.1,
    },
    {
        "model": "sdnn",
        "rmse_mgdl": 35.1,
        "mard_pct": 23.4,
        "clarke_a_pct": 78.9,
        "within15_pct": 68.2,
        "n_parameters": 3_713,
        "latency_single_ms": 0.8,
    },
)

#: The study's protocol (for the record in every result).
STUDY_PROTOCOL: dict[str, object] = {
    "split": "single 60/20/20 train/validation/test split by subject",
    "n_subjects": 80,
    "per_subject": 3,
    "n_test": 48,
}

#: The study's ranking by RMSE, best first.
STUDY_ORDER: tuple[str, ...] = tuple(
    row["model"] for row in sorted(STUDY_TABLE, key=lambda r: float(r["rmse_mgdl"]))
)


def __getattr__(name: str):
    """``MODEL_LABELS`` moved to :mod:`nirglucose.models.labels` (a warning until 0.3)."""
    return moved_name(__name__, name)
