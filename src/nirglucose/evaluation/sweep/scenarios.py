"""One simulated condition of a sweep (a leaf: the built-in studies and the wavelengths
study build them, the sweep runs them; :mod:`.studies` re-exports the class)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

__all__ = ["Scenario"]


@dataclass(frozen=True)
class Scenario:
    """One simulated condition of a sweep.

    Attributes
    ----------
    name : str
        Unique, readable name (``"noise_scale=0.5"``, ``"off:shot"``).
    labels : dict
        Columns identifying the scenario in ``sweep.csv`` (the varied values).
    overrides : dict
        Dotted config overrides on top of the sweep's preset and base overrides.
    test_overrides : dict or None
        Overrides of a separately simulated test cohort; None for cross-validation on
        one dataset.
    train_filter, test_filter : dict or None
        ``{"column": name, "values": [...]}``: keep only rows whose measured column
        takes one of the values.
    preset : str or None
        Preset of this scenario (None: the sweep's).
    n_subjects, n_test_subjects : int or None
        Subjects of the training and of the test draw (None: the sweep's).
    model_params : dict or None
        Model name -> constructor arguments of this scenario only, over the sweep's
        (the ``mismatch`` study's assumed forward model).
    fleet : dict or None
        A ``fleet`` study task's tolerance scale, variant and fleet layout
        (:func:`~nirglucose.evaluation.sweep.fleet.fleet_metrics`); None otherwise.
    """

    name: str
    labels: dict[str, Any] = field(default_factory=dict)
    overrides: dict[str, Any] = field(default_factory=dict)
    test_overrides: dict[str, Any] | None = None
    train_filter: dict[str, Any] | None = None
    test_filter: dict[str, Any] | None = None
    preset: str | None = None
    n_subjects: int | None = None
    n_test_subjects: int | None = None
    model_params: dict[str, dict[str, Any]] | None = None
    fleet: dict[str, Any] | None = None

    @property
    def kind(self) -> str:
        """``"cv"`` (cross-validation on one dataset), ``"shift"`` (train -> test) or
        ``"fleet"`` (train on some units, test on others)."""
        if self.fleet is not None:
            return "fleet"
        return "cv" if self.test_overrides is None else "shift"
