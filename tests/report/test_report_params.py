"""The tuned hyper-parameters as a table: every preset a column, λ first."""

from __future__ import annotations

import re
from types import SimpleNamespace

from nirglucose.report.params import hyperparameter_rows


def _run(params):
    return SimpleNamespace(meta={"model_params": params})


def test_rows_put_lambda_first_and_leave_out_ablation_rows():
    a = _run({"sdnn": {"lr": 0.003, "dropout": 0.1},
              "original-pinn": {"weight_decay": 10.0, "lambda_phys": 0.0, "lr": 0.003},
              "original-pinn/no-physics": {"lambda_phys": 0.0}})
    b = _run({"original-pinn": {"weight_decay": 0.03, "lambda_phys": 0.01, "lr": 0.003,
                                "zeta": 2}})
    rows = hyperparameter_rows([a, b])
    assert all("/" not in m for m, _, _ in rows)
    pinn = [(k, v) for m, k, v in rows if m == "original-pinn"]
    assert pinn[0] == ("lambda_phys", ["0", "0.01"])
    assert ("zeta", ["–", "2"]) in pinn  # not recorded on one preset
    assert [k for k, _ in pinn] == ["lambda_phys", "lr", "weight_decay", "zeta"]
    assert [m for m, _, _ in rows][0] == "original-pinn"  # the study's model order
    assert ("sdnn", "dropout", ["0.1", "–"]) in rows


def test_the_report_shows_them_per_preset(preset_report):
    text = preset_report.read_text(encoding="utf-8")
    assert '<a href="#hyperparameters">' in text
    table = text[text.index('id="hyperparameter-table"'):]
    table = table[:table.index("</table>")]
    head = re.findall(r"<th>([^<]+)</th>", table)
    assert head == ["Model", "Parameter", "paper", "wearable"]
    row = re.search(r"<tr><td>Original PINN</td><td><code>λ \(lambda_phys\)</code></td>"
                    r"(.*?)</tr>", table).group(1)
    assert row == '<td class="off">0 (physics off)</td><td>0.01</td>'
