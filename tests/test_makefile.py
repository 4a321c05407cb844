"""``make run`` benchmarks every registered model but the two GP hybrids and the four
forward-model PINNs on ``paper`` and ``wearable``, and a named subset on ``physical``
(Makefile).

The Makefile names the models (those left out would take ``make run`` past its 3-minute
budget on 2 cores); this keeps that list from going stale when a model is registered,
and the physical set inside it with its references.
"""

from __future__ import annotations

import re
from pathlib import Path

from nirglucose.models.registry import MODELS

_MAKEFILE = Path(__file__).resolve().parents[1] / "Makefile"
#: Registered models ``make run`` leaves out, and why (the Makefile says the same).
LEFT_OUT = {
    "ebl+gp": "a GP on EBL's out-of-fold residual: several fits per task",
    "physics-inversion+gp": "a GP on the inversion's out-of-fold residual: 4 inversions a task",
    "original-pinn-fm": "a physics-inversion fit per task besides the network (and its "
                        "no-physics row); studies/pinn_forward.py scores it",
    "optimized-pinn-fm": "the same, on the attention network",
    "rte-pinn-fm": "the same, on the RTE network",
    "selective-rte-pinn-fm": "the same, on the selective RTE network",
}


def test_make_run_benchmarks_every_registered_model_but_those_left_out():
    text = _MAKEFILE.read_text()
    match = re.search(r"^MODELS \?= (.+)$", text, re.M)
    assert match, "the Makefile has no MODELS list"
    listed = match.group(1).strip().split(",")
    assert len(listed) == len(set(listed))
    assert set(listed) == set(MODELS) - set(LEFT_OUT)
    assert "--models $(MODELS)" in text


#: What the physical set must hold: the references the report's verdicts are drawn
#: against (no skill, the oracle) and the deployable forward-model estimator.
PHYSICAL_REQUIRED = {"mean", "oracle", "device-inversion"}


def _make_list(text: str, name: str) -> list[str]:
    match = re.search(rf"^{name} \?= (.+)$", text, re.M)
    assert match, f"the Makefile has no {name} list"
    listed = match.group(1).strip().split(",")
    assert len(listed) == len(set(listed)), f"{name} names a model twice"
    return listed


def test_make_run_benchmarks_three_presets_physical_on_a_subset():
    text = _MAKEFILE.read_text()
    presets = re.search(r"^PRESET \?= (.+)$", text, re.M)
    assert presets and presets.group(1).strip().split(",") == ["paper", "wearable", "physical"]
    physical = _make_list(text, "PHYSICAL_MODELS")
    assert set(physical) <= set(_make_list(text, "MODELS"))
    assert PHYSICAL_REQUIRED <= set(physical)
    assert "--preset-models physical=$(PHYSICAL_MODELS)" in text
    assert "$(PRESET_MODELS)" in text.split("\nrun:", 1)[1].split("\n\n", 1)[0]


def test_make_run_protocol_reduction_is_stated_and_shared():
    """One repeat for every model and preset (one --repeats flag), said in the Makefile."""
    text = _MAKEFILE.read_text()
    run = text.split("\nrun:", 1)[1].split("\n\n", 1)[0]
    assert run.count("--repeats $(REPEATS)") == 1
    assert re.search(r"^REPEATS \?= 1$", text, re.M)
    assert "ONE repeat" in text
