"""The tuned hyper-parameters of every model, one column per preset (not a JSON block).

Read from each run's ``meta.json`` (``model_params``). The physics weight
``lambda_phys`` comes first and is marked where tuning switched the physics off (0);
ablation rows (``<pinn>/no-physics``) are left out (their λ is 0 by construction).
"""

from __future__ import annotations

import html
from collections.abc import Sequence
from typing import Any

from ..formatting import format_number
from .figures import Results, model_order

__all__ = ["hyperparameter_rows", "hyperparameter_section"]

#: Parameters shown first, in this order (the rest follow alphabetically).
FIRST: tuple[str, ...] = ("lambda_phys", "lr", "weight_decay", "dropout", "max_epochs",
                          "val_fraction")


def _fmt(v: Any) -> str:
    if isinstance(v, bool) or v is None:
        return str(v)
    if isinstance(v, (list, tuple)):
        return ", ".join(_fmt(x) for x in v)
    if isinstance(v, float):
        if v == 0 or 1e-3 <= abs(v) < 1e4:  # readable as 3 significant digits
            return format_number(v, 3, style="significant")
        return format_number(v, 0, style="scientific")  # lr 1e-05, weight decay 1e+04
    return str(v)


def hyperparameter_rows(runs: Sequence[Results]) -> list[tuple[str, str, list[str]]]:
    """(model, parameter, one formatted value per run) for every tuned parameter.

    A parameter a run did not record reads ``–``.

    Examples
    --------
    >>> from types import SimpleNamespace as N
    >>> a = N(meta={"model_params": {"pinn": {"lr": 0.003, "lambda_phys": 0.0}}})
    >>> b = N(meta={"model_params": {"pinn": {"lr": 0.01, "lambda_phys": 0.01}}})
    >>> hyperparameter_rows([a, b])
    [('pinn', 'lambda_phys', ['0', '0.01']), ('pinn', 'lr', ['0.003', '0.01'])]
    """
    params = [r.meta.get("model_params") or {} for r in runs]
    models = model_order(m for p in params for m in p if "/" not in str(m))
    rows = []
    for m in models:
        names = {k for p in params for k in (p.get(m) or {})}
        ordered = [k for k in FIRST if k in names] + sorted(names - set(FIRST))
        for k in ordered:
            rows.append((m, k, [_fmt((p.get(m) or {}).get(k)) if k in (p.get(m) or {})
                                else "–" for p in params]))
    return rows


def hyperparameter_section(runs: Sequence[Results]) -> str:
    """HTML table of the tuned hyper-parameters, λ first; '' when none is recorded."""
    from ..plots.style import model_label

    rows = hyperparameter_rows(runs)
    if not rows:
        return ""
    presets = [str(r.meta.get("preset") or ("your data" if getattr(r, "user_data", False)
                                            else r.directory.name)) for r in runs]
    esc = html.escape
    head = "<th>Model</th><th>Parameter</th>" + "".join(f"<th>{esc(p)}</th>" for p in presets)
    body = []
    last = None
    for model, name, values in rows:
        label = esc(model_label(model)) if model != last else ""
        last = model
        cells = "".join(
            '<td class="off">0 (physics off)</td>' if name == "lambda_phys" and v == "0"
            else f"<td>{esc(v)}</td>" for v in values)
        pname = "λ (lambda_phys)" if name == "lambda_phys" else name
        body.append(f"<tr><td>{label}</td><td><code>{esc(pname)}</code></td>{cells}</tr>")
    if all(getattr(r, "user_data", False) for r in runs):  # nothing was tuned there
        return ('<h2 id="hyperparameters">Hyper-parameters</h2>'
                "<p>Nothing was tuned on this data: each network held out a fifth of the "
                "training subjects for early stopping "
                "(<code>nirglucose.models.tuning.untuned_params</code>); every model absent "
                "here ran on its defaults.</p>"
                f'<div class="scroll"><table id="hyperparameter-table"><thead><tr>{head}</tr>'
                f"</thead><tbody>{''.join(body)}</tbody></table></div>")
    return ('<h2 id="hyperparameters">Tuned hyper-parameters</h2>'
            "<p>What each model was fitted with on each preset (chosen by "
            "<code>tools/tune.py</code> and recorded in <code>meta.json</code>; a model "
            "absent here ran on its defaults), the physics weight λ first. A λ of 0 means "
            "tuning switched the physics term off: "
            "that network is trained as a plain one, and its physics is not tested.</p>"
            f'<div class="scroll"><table id="hyperparameter-table"><thead><tr>{head}</tr>'
            f"</thead><tbody>{''.join(body)}</tbody></table></div>")
