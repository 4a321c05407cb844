"""Which models a sweep runs when --models is not given."""

from nirglucose.cli.sweep_command import _sweep_models
from nirglucose.evaluation.sweep.studies import STUDY_MODELS
from nirglucose.models.registry import available_models


def test_a_study_with_its_own_models_runs_them():
    assert _sweep_models(None, "mismatch") == [
        m for m in STUDY_MODELS["mismatch"] if m in available_models()]


def test_data_size_runs_every_model_and_models_wins():
    assert _sweep_models(None, "data-size") == available_models()
    assert _sweep_models("ebl,gp", "mismatch") == ["ebl", "gp"]
