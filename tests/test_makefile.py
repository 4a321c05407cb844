"""``make run`` benchmarks every registered model but the two GP hybrids and the four
forward-model PINNs (Makefile).

The Makefile names the models (those left out would take ``make run`` past its 3-minute
budget on 2 cores); this keeps that list from going stale when a model is registered.
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
