"""Adding a model is one new module plus one registry line (issue 22)."""

from __future__ import annotations

import sys
import textwrap

import pytest

import nirglucose as ng
from nirglucose.evaluation import Protocol, run_benchmark
from nirglucose.models import registry
from nirglucose.models.tuning import search_space

#: A new module, as a contributor would write it: a linear model on the device's
#: absorbances and physiology, and a new PINN variant.
TOY_MODULE = textwrap.dedent(
    '''
    from sklearn.base import BaseEstimator, RegressorMixin
    from sklearn.linear_model import Ridge

    from nirglucose.models._base import fit_input, predict_input
    from nirglucose.models.pinn import OriginalPINN
    from nirglucose.models.registry import register


    @register("toy-ridge")
    class ToyRidge(RegressorMixin, BaseEstimator):
        def __init__(self, alpha=1.0):
            self.alpha = alpha

        def fit(self, X, y=None, groups=None):
            self.schema_, Xa, y, _ = fit_input(self, X, y, groups)
            self.ridge_ = Ridge(alpha=self.alpha).fit(self.schema_.stacked(Xa), y)
            return self

        def predict(self, X):
            return self.ridge_.predict(self.schema_.stacked(predict_input(self, X)))


    @register("toy-pinn")
    class ToyPINN(OriginalPINN):
        training_defaults = {"max_epochs": 5}
    '''
)


@pytest.fixture
def toy_models(tmp_path, monkeypatch):
    (tmp_path / "toy_models.py").write_text(TOY_MODULE)
    monkeypatch.syspath_prepend(str(tmp_path))
    # The one registry line per model:
    monkeypatch.setitem(registry.MODELS, "toy-ridge", "toy_models")
    monkeypatch.setitem(registry.MODELS, "toy-pinn", "toy_models")
    yield
    for name in ("toy-ridge", "toy-pinn"):
        registry._REGISTRY.pop(name, None)
    sys.modules.pop("toy_models", None)


def test_a_new_module_and_one_registry_line_make_a_benchmarked_model(toy_models):
    assert registry.is_pinn("toy-pinn") and not registry.is_network("toy-ridge")
    assert "lambda_phys" in search_space("toy-pinn")  # the shared network grid + physics
    ds = ng.simulate("wearable", n_subjects=12, per_subject=2, seed=0)
    res = run_benchmark(
        ds,
        ["toy-ridge", "toy-pinn", "mean"],
        protocol=Protocol(n_splits=3, repeats=1, resamples=50),
        ablation=True,
        drop_one_models="none",
        oracle_reference=False,
        timing={"n_single": 5, "min_single": 2, "batch_rows": 100, "batch_repeats": 1},
    )
    rows = set(res.metrics["model"])
    assert {"toy-ridge", "toy-pinn", "toy-pinn/no-physics", "mean"} <= rows
    assert res.metrics.set_index("model").loc["toy-ridge", "rmse_mgdl"] > 0
