"""What each registered estimator knows beyond the measured columns (issue 39): one
declaration per class, read by ``privileged_knowledge``; privileged estimators refuse
data without a scenario instead of reading it as a preset."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest
from sklearn.linear_model import Ridge

import nirglucose as ng
from nirglucose.config import resolve_config
from nirglucose.dataset import load_dataset
from nirglucose.exceptions import ConfigError, DataError
from nirglucose.models import get_model_class, make_model, privileged_knowledge
from nirglucose.models.inversion import PRIVILEGED_SCENARIO
from nirglucose.models.registry import MODELS

FORWARD_PINNS = ("original-pinn-fm", "optimized-pinn-fm", "rte-pinn-fm",
                 "selective-rte-pinn-fm")
#: The privileged set: the oracle (truth) and everything built on the simulator's own
#: forward model read from the scenario. The study PINNs read the device's LEDs and the
#: published tables only (their physics at glucose's published magnitude).
PRIVILEGED = {"oracle", "physics-inversion", "physics-inversion+gp", *FORWARD_PINNS}
NET = {"max_epochs": 2, "batch_size": 16, "random_state": 0}


def test_every_registered_model_declares_what_it_knows():
    for name in MODELS:
        cls = get_model_class(name)
        assert any("privileged" in vars(c) for c in cls.__mro__), f"{name} declares nothing"
        value = cls.privileged
        assert value is None or (isinstance(value, str) and value.strip()), name
    known = {n for n in MODELS if privileged_knowledge(n) is not None}
    assert known == PRIVILEGED
    for name in ("physics-inversion", "physics-inversion+gp", *FORWARD_PINNS):
        assert privileged_knowledge(name) == PRIVILEGED_SCENARIO, name
    assert "true_*" in privileged_knowledge("oracle")
    assert privileged_knowledge("original-pinn") is None


def test_names_classes_instances_and_a_users_own_estimator():
    cls = get_model_class("physics-inversion")
    assert privileged_knowledge(cls) == privileged_knowledge(cls()) == PRIVILEGED_SCENARIO
    assert privileged_knowledge(make_model("ebl")) is None
    assert privileged_knowledge(Ridge()) is None  # declares nothing: deployable
    assert privileged_knowledge(Ridge) is None
    with pytest.raises(ConfigError, match="unknown model 'nope'"):
        privileged_knowledge("nope")


def test_asking_about_linear_models_does_not_import_torch():
    code = (
        "import sys\n"
        "from nirglucose.models import privileged_knowledge as p\n"
        "assert p('ebl') is None and p('device-inversion') is None\n"
        "assert p('physics-inversion') and p('oracle')\n"
        "assert 'torch' not in sys.modules, 'torch imported'\n"
    )
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert run.returncode == 0, run.stderr[-1500:]


@pytest.fixture(scope="module")
def paper():
    return ng.simulate("paper", 12, 3, seed=5)


@pytest.mark.parametrize(
    ("name", "params"),
    [("physics-inversion", {"n_em": 1}),
     ("physics-inversion+gp", {"backbone_params": {"n_em": 1}, "cv": 0}),
     ("original-pinn-fm", NET), ("rte-pinn-fm", NET)],
)
def test_privileged_models_refuse_data_without_a_scenario(name, params, paper, tmp_path):
    """A CSV (``Dataset.save`` writes no config into it) or a frame: one line that says
    what is missing and names the deployable estimator -- never the paper preset."""
    csv = load_dataset(paper.save(tmp_path / "x.csv"))
    assert csv.config is None
    for data in (csv, paper.frame):
        with pytest.raises(DataError, match="generating scenario.*'device-inversion'") as exc:
            make_model(name, **params).fit(data)
        assert "\n" not in str(exc.value)
    make_model(name, **params).fit(paper)  # the simulated Dataset carries its scenario


@pytest.mark.parametrize(
    ("name", "params"),
    [("ebl", {}), ("pls", {}), ("mean", {}), ("gbr", {"n_estimators": 10, "random_state": 0}),
     ("device-inversion", {"n_em": 1, "cv": 0}), ("ebl+gp", {"cv": 0, "random_state": 0}),
     ("rte-pinn", NET), ("sdnn", NET),
     ("physics-inversion", {"n_em": 1}), ("original-pinn", NET), ("optimized-pinn", NET)],
)
def test_the_declaration_matches_what_a_fit_reads(name, params, paper):
    """The same rows under another scenario (``physical``: same device, glucose gain 1
    instead of 11): a deployable model fits the same predictions, a privileged one
    does not (it read the scenario)."""
    other = ng.Dataset(paper.frame, config=resolve_config("physical"))
    a = make_model(name, **params).fit(paper).predict(paper.frame)
    b = make_model(name, **params).fit(other).predict(paper.frame)
    if privileged_knowledge(name) is None:
        np.testing.assert_array_equal(a, b, err_msg=name)
    else:
        assert not np.array_equal(a, b), name
