"""The report of the "what it takes" study (``nirglucose report REQUIREMENTS_DIR``).

Reads what ``nirglucose sweep --study requirements`` wrote
(:meth:`~nirglucose.evaluation.sweep.requirements.RequirementsResult.from_dir`) and shows,
in this order: the one-line answer per detector, the error against the averaging window
of the study's device and the named designs, the minimal-designs table, the
confirmation by simulation (the privileged oracle and physics-inversion drawn as
references beside the bounds, never as competitors), what each lever group is worth,
and the study's limits. Nothing here searches, bounds or simulates.
"""

from __future__ import annotations

import base64
import html
from pathlib import Path

import pandas as pd

from ..dataset import atomic_write
from ..evaluation.sweep.requirements import REQUIREMENTS_FILES, RequirementsResult
from ..exceptions import DataError
from ..models.registry import available_models, privileged_knowledge

__all__ = ["is_requirements_dir", "save_requirements_figures", "build_requirements_report",
           "REQUIREMENTS_FIGURES"]

#: Figure stems written by :func:`save_requirements_figures`.
REQUIREMENTS_FIGURES = ("requirements_averaging", "requirements_designs")

_CSS = ("body{font-family:system-ui,sans-serif;max-width:1040px;margin:2em auto;padding:0 1em;"
        "color:#222}table{border-collapse:collapse;font-size:13px}td,th{padding:3px 8px;"
        "border-bottom:1px solid #ddd;text-align:left}.answer{background:#eef6fb;padding:.5em "
        "1em;border-left:4px solid #0072b2}.ref{color:#555;font-style:italic}img{max-width:100%}")


def is_requirements_dir(directory: str | Path) -> bool:
    """Whether ``directory`` holds a requirements study (``requirements.json`` and
    ``minimal_designs.csv``) and no benchmark run."""
    d = Path(directory)
    return ((d / "requirements.json").is_file() and (d / "minimal_designs.csv").is_file()
            and not (d / "metrics.json").is_file())


def _figures(result: RequirementsResult) -> dict:
    from ..plots.requirements import plot_averaging_curve, plot_minimal_designs

    meta = result.meta
    regime = f"{meta['preset']} (glucose signal gain {meta['glucose_signal_gain']:g})"
    extra = ", ".join(f"{k}={v}" for k, v in sorted(meta.get("overrides", {}).items()))
    if extra:  # the regime's own overrides, on a second line
        regime += f"\n{extra}"
    return {
        "requirements_averaging": plot_averaging_curve(
            result.averaging_curve, target_rmse_mgdl=meta["target_rmse_mgdl"],
            title=f"error vs averaging window, {regime}"),
        "requirements_designs": plot_minimal_designs(
            result.minimal_designs, title=f"least designs, {regime}"),
    }


def save_requirements_figures(result: RequirementsResult, directory: str | Path,
                              formats: tuple[str, ...] = ("png", "svg")) -> list[Path]:
    """Write the study's two figures (:data:`REQUIREMENTS_FIGURES`) into ``directory``
    (created if missing); the paths written."""
    from ..plots.style import save_figure

    out = Path(directory)
    out.mkdir(parents=True, exist_ok=True)
    paths: list[Path] = []
    for stem, ax in _figures(result).items():
        paths += save_figure(ax.figure, out / stem, formats)
    return paths


def _img(ax, alt: str) -> str:
    from ..plots.style import figure_bytes

    data = base64.b64encode(figure_bytes(ax.figure, "png", close=True)).decode("ascii")
    return f'<img src="data:image/png;base64,{data}" alt="{html.escape(alt)}">'


def _table(frame: pd.DataFrame) -> str:
    return frame.to_html(index=False, float_format=lambda v: f"{v:.3g}", border=0,
                         escape=True, na_rep="")


def _confirmation_table(result: RequirementsResult) -> str:
    conf = result.confirmation
    if conf.empty:
        return "<p>Not simulated (the study ran without its confirmation).</p>"
    known = set(available_models())

    def role(m: str) -> str:
        if m in known and privileged_knowledge(m) is not None:
            return "privileged reference"
        return "deployable"

    rows = []
    for _, r in conf.iterrows():
        rows.append({
            "design": r["design"], "model": r["model"], "role": role(str(r["model"])),
            "RMSE [mg/dL]": f"{r['rmse_mgdl']:.3g} [{r['rmse_ci_low']:.3g}, "
                            f"{r['rmse_ci_high']:.3g}]",
            "MARD [%]": r["mard_pct"],
            "per-state bound with lag [mg/dL]": r.get("bound_total_rmse_mgdl"),
            "oracle-conditioned bound [mg/dL]": r.get("bound_oracle_bound_rmse_mgdl"),
            "readings averaged": r.get("n_readings_emulated"),
        })
    return (_table(pd.DataFrame(rows)) + "<p class='ref'>The oracle (it knows every "
            "nuisance) and physics-inversion (it reads the generating scenario) are "
            "references, like the bounds: no device has their knowledge. Set the oracle "
            "beside the oracle-conditioned bound, physics-inversion beside the per-state "
            "bound; the deployable estimators say what a device reaches today.</p>")


def _settings(meta: dict) -> str:
    t = meta.get("timings_s", {})
    return (f"<p>Preset {html.escape(str(meta['preset']))} (glucose signal gain "
            f"{meta['glucose_signal_gain']:g}: published magnitudes where 1); targets "
            f"{meta['target_rmse_mgdl']:g} mg/dL RMSE and MARD {meta['target_mard_pct']:g} %; "
            f"{meta['n_states']} pilot states per bound; confirmation "
            f"{meta['confirm_subjects']} subjects x {meta['confirm_per_subject']}, "
            f"{meta.get('confirm_folds', 5)}-fold subject-grouped CV, seed {meta['seed']}; "
            f"models {html.escape(', '.join(meta['confirm_models']))}. Took "
            f"{t.get('total_s', float('nan')):.0f} s (search {t.get('search_s', float('nan')):.0f}"
            f" s, confirmation {t.get('confirm_s', float('nan')):.0f} s). nirglucose "
            f"{html.escape(str(meta.get('package_version', '')))}.</p>")


def build_requirements_report(directory: str | Path, out_path: str | Path, *,
                              figures_dir: str | Path | None = None) -> Path:
    """Write the HTML page of a requirements study's directory (atomically); its path.

    Raises
    ------
    DataError
        The directory lacks a file of
        :data:`~nirglucose.evaluation.sweep.requirements.REQUIREMENTS_FILES`, or the
        output directory does not exist.
    """
    result, out_path = RequirementsResult.from_dir(directory), Path(out_path)
    if not out_path.parent.exists():
        raise DataError(f"output directory {str(out_path.parent)!r} does not exist; "
                        "create it first")
    if figures_dir is not None:
        save_requirements_figures(result, figures_dir)
    figs = _figures(result)
    meta = result.meta
    answers = "".join(f"<li>{html.escape(a)}</li>" for a in result.answer_lines())
    limits = "".join(f"<li>{html.escape(str(n))}</li>" for n in meta.get("notes", []))
    gains = result.lever_gains.rename(columns={
        "ceiling_rmse_mgdl": "ceiling [mg/dL]",
        "ceiling_without_rmse_mgdl": "ceiling without it [mg/dL]",
        "worth_at_ceiling_mgdl": "worth at the ceiling [mg/dL]",
        "study_rmse_mgdl": "study's design [mg/dL]",
        "study_with_rmse_mgdl": "study's design with it [mg/dL]",
        "gain_from_study_mgdl": "gain from the study's design [mg/dL]"})
    body = (
        "<h1>What would a device need to read glucose?</h1>"
        f"<div class='answer'><p>One line per detector: the least design whose error "
        f"reaches the targets, or how far the best falls short and which lever buys most."
        f"</p><ul>{answers}</ul></div>{_settings(meta)}"
        "<h2>Error against averaging time</h2>"
        + _img(figs["requirements_averaging"], "error against the averaging window")
        + "<p>Solid: the per-state bound with the averaging lag in quadrature (the "
        "criterion); dotted: the bound alone; dashed: the target.</p>"
        "<h2>Minimal designs</h2>"
        + _img(figs["requirements_designs"], "the least design per detector")
        + "<h2>Confirmation by simulation</h2>" + _confirmation_table(result)
        + "<h2>What each lever group is worth</h2>" + _table(gains)
        + f"<h2>Limits</h2><ul>{limits}</ul>"
        + "<p>Files: " + ", ".join(html.escape(f) for f in REQUIREMENTS_FILES) + ".</p>"
    )
    page = ("<!DOCTYPE html>\n<html lang='en'><head><meta charset='utf-8'>"
            "<title>nirglucose: what it takes</title>"
            f"<style>{_CSS}</style></head><body>{body}</body></html>\n")
    return atomic_write(out_path, lambda tmp: Path(tmp).write_text(page, encoding="utf-8"))
