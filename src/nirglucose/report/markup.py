"""The report's text pieces: HTML escaping, numbers as the page prints them, the small
Markdown subset of ``table.md``, model labels and a run's preset name (a leaf: the
section modules and the page read them, none of them imports back)."""

from __future__ import annotations

import html
import re
from collections.abc import Mapping
from typing import TYPE_CHECKING, Any

import pandas as pd

from ..formatting import format_number
from ..models.labels import label, row_privilege

if TYPE_CHECKING:
    from .figures import Results

__all__ = ["esc", "num", "pval", "markdown_to_html", "model_label", "physics_off_models",
           "preset_of",
           "user_data_md", "strip_ablation"]


def esc(x: Any) -> str:
    """``x`` as text safe inside HTML (quotes escaped too)."""
    return html.escape(str(x), quote=True)


def num(v: Any, digits: int = 1) -> str:
    """A number as the page prints it: ``digits`` decimals with thousands separators
    (``digits=3``: a latency, 3 significant places below 0.1), ``"–"`` when missing.

    Examples
    --------
    >>> num(1234.56), num(0.01234, 3), num(float("nan"))
    ('1,234.6', '0.012', '–')
    """
    if digits == 3:  # latencies span 0.001-100 ms
        return format_number(v, style="latency", text=esc)
    return format_number(v, digits, thousands=True, text=esc)


def pval(v: Any) -> str:
    """A p-value with 3 significant digits, ``"–"`` when missing."""
    return format_number(v, 3, style="significant")


def _inline_md(text: str) -> str:
    out = esc(text)
    out = re.sub(r"`([^`]+)`", r"<code>\1</code>", out)
    out = re.sub(r"\*\*([^*]+)\*\*", r"<b>\1</b>", out)
    return out


def markdown_to_html(text: str, *, skip_tables: bool = False, skip_h1: bool = False) -> str:
    """Render the small Markdown subset the benchmark writes (headings, tables, lists).

    Everything is HTML-escaped first; only headings, pipe tables, ``-`` lists,
    paragraphs, ``code`` and ``**bold**`` are recognised.

    Examples
    --------
    >>> markdown_to_html("# T\\n\\nA `x` <b>\\n\\n- one")
    '<h3>T</h3>\\n<p>A <code>x</code> &lt;b&gt;</p>\\n<ul><li>one</li></ul>'
    """
    blocks: list[str] = []
    lines = text.splitlines()
    i = 0
    while i < len(lines):
        line = lines[i].rstrip()
        if not line.strip():
            i += 1
            continue
        if line.startswith("#"):
            level = len(line) - len(line.lstrip("#"))
            if not (skip_h1 and level == 1):
                h = min(6, level + 2)
                blocks.append(f"<h{h}>{_inline_md(line.lstrip('#').strip())}</h{h}>")
            i += 1
        elif line.lstrip().startswith("|"):
            rows = []
            while i < len(lines) and lines[i].lstrip().startswith("|"):
                rows.append(lines[i].strip().strip("|").split("|"))
                i += 1
            if skip_tables:
                continue
            body = [r for r in rows if not all(re.fullmatch(r"\s*:?-+:?\s*", c) for c in r)]
            if not body:
                continue
            head = "".join(f"<th>{_inline_md(c.strip())}</th>" for c in body[0])
            trs = "".join("<tr>" + "".join(f"<td>{_inline_md(c.strip())}</td>" for c in r)
                          + "</tr>" for r in body[1:])
            blocks.append(f'<div class="scroll"><table><thead><tr>{head}</tr></thead>'
                          f"<tbody>{trs}</tbody></table></div>")
        elif re.match(r"\s*[-*] ", line):
            items = []
            while i < len(lines) and re.match(r"\s*[-*] ", lines[i]):
                item = re.sub(r"^\s*[-*] ", "", lines[i])
                items.append(f"<li>{_inline_md(item)}</li>")
                i += 1
            blocks.append(f"<ul>{''.join(items)}</ul>")
        else:
            para = []
            while (i < len(lines) and lines[i].strip() and not lines[i].startswith("#")
                   and not lines[i].lstrip().startswith("|")
                   and not re.match(r"\s*[-*] ", lines[i])):
                para.append(lines[i].strip())
                i += 1
            blocks.append(f"<p>{_inline_md(' '.join(para))}</p>")
    return "\n".join(blocks)


def model_label(model: str, metrics_row: pd.Series | None = None,
                physics_off: bool = False) -> str:
    """The model's label: the run's own (``metrics.csv``'s ``label``), else
    :func:`nirglucose.models.labels.label`; a privileged row (it reads the generating
    scenario or the true nuisances, :func:`~nirglucose.models.labels.row_privilege`)
    says it is a reference, a PINN whose tuned physics weight is 0 that its physics is
    off (:func:`physics_off_models`).

    >>> model_label("physics-inversion")
    'Physics inversion (forward model) — reference'
    >>> model_label("rte-pinn", physics_off=True)
    'RTE-inspired PINN (physics off)'
    """
    name = (metrics_row["label"] if metrics_row is not None
            and isinstance(metrics_row.get("label"), str) else label(model))
    if physics_off:
        name += " (physics off)"
    if model != "oracle" and row_privilege(str(model)) is not None:
        name += " — reference"
    return name


def physics_off_models(meta: Mapping[str, Any]) -> set[str]:
    """The run's PINNs whose tuned ``lambda_phys`` is 0 (``meta.json``'s
    ``model_params``): plain networks, whose every row, sentence and figure says
    "physics off" (issue 39).

    >>> sorted(physics_off_models({"model_params": {"rte-pinn": {"lambda_phys": 0},
    ...                                             "original-pinn": {"lambda_phys": 1}}}))
    ['rte-pinn']
    """
    params = meta.get("model_params") or {}
    return {str(m) for m, p in params.items()
            if isinstance(p, dict) and p.get("lambda_phys") == 0 and "/" not in str(m)}


def user_data_md(md: str) -> str:
    """The benchmark's table.md text for a user's data: no preset, no study protocol.

    The benchmark writes one paragraph for every run; on measured data its preset is
    ``None`` and the study it compares against was measured on another device.
    """
    md = re.sub(r",? preset `(None|null)`", "", md)
    return re.sub(r" ?Study: [^.]*?test n = \d+\.", "", md)


#: How the report names the run of a device's own file (no preset, no scenario).
USER_DATA = "your data"


def preset_of(results: Results) -> str:
    """The preset name of a run: ``your data`` for a device's file, else its directory's
    name when none is recorded."""
    p = results.meta.get("preset")
    if p not in (None, "", "None"):
        return str(p)
    return USER_DATA if results.user_data else results.directory.name or "run"


def strip_ablation(table_md: str) -> str:
    """``table.md`` without its ablation section (the report shows it as a table)."""
    return table_md.split("\n## Physics ablation", 1)[0]
