"""One label for every model, beside the registry (issue 42): tables, figures, findings
and the report call :func:`nirglucose.models.labels.label`."""

from __future__ import annotations

import pytest

from nirglucose.models import MODEL_LABELS, label
from nirglucose.models.labels import ablation_base, describe, lambda_row, plain_text
from nirglucose.models.registry import MODELS, available_models


def test_every_registered_model_has_a_label():
    assert set(MODELS) <= set(MODEL_LABELS)
    assert all(label(m) == MODEL_LABELS[m] != m for m in MODELS)


@pytest.mark.parametrize(("row", "want"), [
    ("ebl", "Enhanced Beer–Lambert"),
    ("rte-pinn/no-physics", "RTE-inspired PINN (no physics)"),
    ("original-pinn/lambda=0.1", "Original PINN (λ = 0.1)"),
    ("my-ridge", "my-ridge"),  # an estimator object's label stays as given
])
def test_label_of_models_and_ablation_rows(row, want):
    assert label(row) == want


def test_row_names_round_trip():
    assert ablation_base(lambda_row("rte-pinn", 10.0)) == "rte-pinn"
    assert ablation_base("rte-pinn/no-physics") == "rte-pinn"
    assert ablation_base("rte-pinn") is None


def test_the_plots_the_report_and_the_findings_use_the_one_label():
    from nirglucose.plots.style import model_label
    from nirglucose.report.markup import model_label as report_label

    for row in ("ebl", "sdnn/no-physics", "someone-else"):
        assert model_label(row) == report_label(row) == label(row)


def test_the_models_command_prints_plain_text():
    assert plain_text("A GP (:class:`_ResidualHybrid`).") == "A GP."
    assert plain_text("see :func:`~nirglucose.models.make_model` and ``x``") == \
        "see make_model and x"
    for name in available_models():
        text = describe(name)
        assert ":class:" not in text and "``" not in text and "`_" not in text, (name, text)
