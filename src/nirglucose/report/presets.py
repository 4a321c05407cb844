"""Report sections for the physics ablation and for runs on several presets.

``nirglucose benchmark --preset paper,wearable --out results`` writes
``results/<preset>/``; :func:`preset_dirs` finds those sub-directories, the full
report is built from the first (``paper`` when present) and :func:`presets_section`
adds the comparison table, every other preset's reproduced table, each preset's
ablation table and a plain statement of what separates the presets (the simulation
settings that differ, and how the results differ).
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any, Final

import pandas as pd

from ..config import PRESETS
from ..evaluation.benchmark.findings import RunData, physics_verdicts
from ..evaluation.reference import STUDY_TABLE
from ..exceptions import DataError
from ..formatting import as_number, format_number
from ..models.labels import row_privilege
from .markup import esc as _esc
from .markup import model_label as _model_label
from .tables import extra_table, hypo_note, main_table, significance

if TYPE_CHECKING:
    from .figures import Results

__all__ = ["preset_dirs", "ablation_section", "presets_section"]

#: The preset whose run carries the full report (the study's own setting).
PRIMARY_PRESET = "paper"


def _is_results(d: Path) -> bool:
    return (d / "metrics.csv").is_file() or (d / "metrics.json").is_file()


def preset_dirs(results_dir: str | Path) -> list[Path]:
    """Sub-directories of ``results_dir`` that hold a benchmark run, primary first, then
    the built-in presets in their order (``wearable``, ``physical``, ...), then the rest
    by name.

    Empty when ``results_dir`` itself holds a run (a one-preset layout).
    """
    d = Path(results_dir)
    if not d.is_dir() or _is_results(d):
        return []
    order = {name: i for i, name in enumerate(PRESETS)}
    subs = sorted((s for s in d.iterdir() if s.is_dir() and _is_results(s)), key=lambda s: s.name)
    return sorted(subs, key=lambda s: (s.name != PRIMARY_PRESET, order.get(s.name, len(order))))


def _num(v: Any, digits: int = 1, sign: bool = False) -> str:
    """A fixed-point number (``"–"`` when missing); unlike the page's ``markup.num`` no
    thousands separator and no latency rounding (p-values keep 3 decimals), and a sign."""
    return format_number(v, digits, sign=sign)


def _read_ablation(d: Path) -> pd.DataFrame | None:
    path = d / "ablation.csv"
    if not path.is_file():
        return None
    try:
        return pd.read_csv(path)
    except (OSError, ValueError, pd.errors.EmptyDataError):
        return None


def _tuned_lambdas(d: Path) -> dict[str, float]:
    """Each model's tuned physics weight ``lambda_phys`` from ``meta.json`` (if recorded)."""
    try:
        meta = json.loads((d / "meta.json").read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return {}
    params = meta.get("model_params") if isinstance(meta, dict) else None
    return {str(m): float(p["lambda_phys"]) for m, p in (params or {}).items()
            if isinstance(p, dict) and p.get("lambda_phys") is not None}


def ablation_section(results_dir: str | Path, heading: str = "Physics ablation", *,
                     preset: str | None = None) -> str:
    """HTML of ``ablation.csv``: each PINN with physics against without (empty if none).

    Where tuning set the physics weight to 0 (``lambda_phys`` of ``meta.json``), or the
    two fits are identical, no question was asked: the row says so and shows no Δ, p
    or verdict (:func:`nirglucose.evaluation.benchmark.findings.physics_verdicts`).
    """
    d = Path(results_dir)
    a = _read_ablation(d)
    if a is None or a.empty:
        return ""
    preset = preset or d.name
    lam = _tuned_lambdas(d)
    run = RunData(preset, pd.DataFrame({"model": []}),
                  {"model_params": {m: {"lambda_phys": v} for m, v in lam.items()}},
                  pd.DataFrame(), ablation=a)
    rows = []
    for v in physics_verdicts(run):
        r = v["row"]
        lam_txt = format_number(v["lambda"], style="general")
        if v["tested"]:
            diff = (f"<td>{_num(r['rmse_diff_mgdl'], 2, True)} [{_num(r['ci_low'], 2, True)}, "
                    f"{_num(r['ci_high'], 2, True)}]</td><td>{_num(r['p_holm'], 3)}</td>")
        else:
            diff = '<td colspan=2 class="untested">not tested</td>'
        rows.append(
            f"<tr><td>{_esc(_model_label(r['model']))}</td><td>{lam_txt}</td>"
            f"<td>{_num(r['rmse_mgdl'])}</td><td>{_num(r['ablated_rmse_mgdl'])}</td>"
            f"{diff}<td>{_esc(v['verdict'])}</td></tr>"
        )
    return (
        f'<h3 id="ablation-{_esc(preset)}">{_esc(heading)}</h3><p>Each PINN refitted with '
        "its physics term off (<code>lambda_phys = 0</code>), everything else identical "
        "(same splits, seeds and parameters). Δ RMSE = with physics − without (negative: "
        "the physics term helps); paired cluster bootstrap over subjects, Holm-adjusted "
        "over the PINNs. Where tuning chose λ = 0 both fits are the same model: the "
        "question is not asked and no verdict is given.</p>"
        '<div class="scroll"><table class="ablation"><thead><tr><th>PINN</th>'
        "<th>tuned λ</th><th>RMSE with physics [mg/dL]</th><th>RMSE without [mg/dL]</th>"
        "<th>Δ RMSE [95 % CI]</th><th>p (Holm)</th><th>verdict</th></tr></thead>"
        f"<tbody>{''.join(rows)}</tbody></table></div>"
    )


def _flat(d: Any, prefix: str = "") -> dict[str, Any]:
    if isinstance(d, dict):
        out: dict[str, Any] = {}
        for k, v in d.items():
            out.update(_flat(v, f"{prefix}{k}."))
        return out
    return {prefix[:-1]: d}


def _config_differences(a: dict[str, Any], b: dict[str, Any]) -> list[tuple[str, Any, Any]]:
    fa, fb = _flat(a or {}), _flat(b or {})
    return [
        (k, fa.get(k), fb.get(k))
        for k in sorted(set(fa) | set(fb))
        if k != "preset" and fa.get(k) != fb.get(k)
    ]


def _meta_metrics(res: Results) -> tuple[dict[str, Any], pd.DataFrame]:
    return res.meta, res.metrics.drop_duplicates("model").set_index("model")


def presets_section(runs: Sequence[Results]) -> str:
    """HTML comparing the loaded ``runs`` (the first is the primary, shown in full).

    Parameters
    ----------
    runs : sequence of Results
        One loaded run per preset directory (:func:`nirglucose.report.figures.load_results`
        of each of :func:`preset_dirs`), primary first; loaded once by the caller.

    Raises
    ------
    DataError
        Fewer than two runs.
    """
    if len(runs) < 2:
        raise DataError("a preset comparison needs at least two results directories")
    dirs = [r.directory for r in runs]
    loaded = [_meta_metrics(r) for r in runs]
    names = [m.get("preset") or d.name for d, (m, _) in zip(dirs, loaded, strict=True)]
    models = list(dict.fromkeys(m for _, met in loaded for m in met.index))
    label = _model_labels(models, loaded)
    parts = [
        '<h2 id="presets">Presets compared</h2>',
        f"<p>The same benchmark on {len(names)} presets: "
        + ", ".join(f"<code>{_esc(n)}</code>" for n in names)
        + f". The sections above are the <code>{_esc(names[0])}</code> run; below, the key "
        "metrics of every preset next to each other (each metric's presets in adjacent "
        "columns), and the performance-comparison figure draws all presets on shared "
        "axes.</p>",
        _comparison_table(names, loaded, models, label),
        '<h3 id="separation">What separates the presets</h3>',
        _separation(names, loaded, label),
        _ablations_side_by_side(dirs, names),
        *_preset_details(runs[1:], names[1:]),
    ]
    return "\n".join(p for p in parts if p)


#: Columns of the comparison table: (metrics column, heading, stem of its CI columns).
_COMPARED: Final = (("rmse_mgdl", "RMSE [mg/dL, 95 % CI]", "rmse"),
                    ("mard_pct", "MARD [%]", None), ("clarke_a_pct", "Clarke A [%]", None))


def _model_labels(models: list[str], loaded: list[tuple[dict[str, Any], pd.DataFrame]]
                  ) -> dict[str, str]:
    """Display label of each model: a run's ``label`` column, else the study's, else its name."""
    label = {m: _model_label(m) for m in models}
    for _, met in loaded:
        if "label" in met.columns:
            label.update({m: str(v) for m, v in met["label"].items() if isinstance(v, str)})
    return label


def _comparison_table(names: list[str], loaded: list[tuple[dict[str, Any], pd.DataFrame]],
                      models: list[str], label: dict[str, str]) -> str:
    """The key metrics of every preset, metric-major (each metric's presets side by side)."""
    study = {str(r["model"]): r for r in STUDY_TABLE}
    head1 = "<th rowspan=2>Model</th>" + "".join(
        f"<th colspan={len(names)}>{_esc(h)}</th>" for _, h, _ in _COMPARED
    ) + f"<th rowspan=2>Δ RMSE {_esc(names[1])} − {_esc(names[0])} [mg/dL]</th>" \
        "<th rowspan=2>study RMSE [mg/dL]</th>"
    head2 = "".join(f"<th>{_esc(n)}</th>" for _ in _COMPARED for n in names)
    rows = []
    for model in models:
        cells = [f"<td>{_esc(label[model])}</td>"]
        for col, _, ci in _COMPARED:
            cells += [_metric_cell(met, model, col, ci) for _, met in loaded]
        a, b = loaded[0][1], loaded[1][1]
        diff = (float(b.loc[model, "rmse_mgdl"]) - float(a.loc[model, "rmse_mgdl"])
                if model in a.index and model in b.index else float("nan"))
        cells.append(f"<td>{_num(diff, 1, True)}</td>")
        cells.append(f'<td class="study">{_num(study.get(model, {}).get("rmse_mgdl"))}</td>')
        rows.append("<tr>" + "".join(cells) + "</tr>")
    head = f"{head1}</tr><tr>{head2}"
    return ('<div class="scroll"><table id="presets-table"><thead><tr>'
            f"{head}</tr></thead><tbody>{''.join(rows)}</tbody></table></div>")


def _metric_cell(met: pd.DataFrame, model: str, col: str, ci: str | None) -> str:
    """One preset's value of ``col`` for ``model``, with its CI when ``ci`` names one."""
    if model not in met.index or col not in met.columns:
        return "<td>–</td>"
    r = met.loc[model]
    txt = _num(r.get(col))
    if ci and as_number(r.get(f"{ci}_ci_low")) is not None:
        txt += f" [{_num(r.get(f'{ci}_ci_low'))}, {_num(r.get(f'{ci}_ci_high'))}]"
    return f"<td>{txt}</td>"


def _ablations_side_by_side(dirs: list[Path], names: list[str]) -> str:
    """Each preset's ablation table next to the others ("" when no run has one)."""
    ablations = [(n, ablation_section(d, f"Physics ablation on {n}", preset=n))
                 for d, n in zip(dirs, names, strict=True)]
    ablations = [(n, a) for n, a in ablations if a]
    if not ablations:
        return ""
    return ('<h3 id="ablations">Physics ablation, presets side by side</h3><div class="side">'
            + "".join(f"<div>{a}</div>" for _, a in ablations) + "</div>")


def _preset_details(runs: Sequence[Results], names: list[str]) -> list[str]:
    """A collapsed block per preset with its reproduced table and significance statements."""
    out = []
    for res, n in zip(runs, names, strict=True):
        inner = [main_table(res), hypo_note(res), "<h4>Further metrics</h4>", extra_table(res),
                 significance(res)]
        out.append(f'<details id="preset-{_esc(n)}"><summary>Full reproduced table and '
                   f"significance statements on <code>{_esc(n)}</code></summary>"
                   + "\n".join(inner) + "</details>")
    return out


def _separation(
    names: list[str], loaded: list[tuple[dict[str, Any], pd.DataFrame]], label: dict[str, str]
) -> str:
    base_meta, _ = loaded[0]
    items = []
    for n, (meta, _) in zip(names[1:], loaded[1:], strict=True):
        diffs = _config_differences(base_meta.get("config") or {}, meta.get("config") or {})
        if diffs:
            shown = "; ".join(
                f"<code>{_esc(k)}</code> {_esc(json.dumps(a))} → {_esc(json.dumps(b))}"
                for k, a, b in diffs[:12]
            )
            more = f" (and {len(diffs) - 12} more)" if len(diffs) > 12 else ""
            items.append(
                f"<li>Simulation: {len(diffs)} settings differ between "
                f"<code>{_esc(names[0])}</code> and <code>{_esc(n)}</code>: {shown}{more}.</li>"
            )
        else:
            items.append(
                f"<li>Simulation: no recorded setting differs between <code>{_esc(names[0])}"
                f"</code> and <code>{_esc(n)}</code>.</li>"
            )
    for n, (meta, met) in zip(names, loaded, strict=True):
        # the best deployable row: the oracle, no skill, privileged rows and ablations out
        ranked = met.drop(index=[m for m in met.index if m in ("oracle", "mean") or "/" in m
                                 or row_privilege(str(m)) is not None], errors="ignore")
        if ranked.empty:
            continue
        best = ranked["rmse_mgdl"].astype(float).idxmin()
        mean = (
            f"; no skill (training mean) {_num(met.loc['mean', 'rmse_mgdl'])} mg/dL"
            if "mean" in met.index
            else ""
        )
        oracle = meta.get("oracle_rmse_mgdl")
        bound = f"; oracle bound {_num(oracle)} mg/dL" if oracle is not None else ""
        items.append(
            f"<li>Results on <code>{_esc(n)}</code>: best deployable (lowest RMSE) "
            f"{_esc(label.get(best, best))} "
            f"at {_num(met.loc[best, 'rmse_mgdl'])} mg/dL{mean}{bound} (which models are "
            'not distinguishable from it: <a href="#findings">Findings</a>).</li>'
        )
    return "<ul>" + "".join(items) + "</ul>"
