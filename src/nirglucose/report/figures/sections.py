"""The report's figures section by section: numbering, captions and drawing.

:func:`render_figures` runs each section builder in page order; a builder computes its
figures' inputs (:mod:`.inputs`, :mod:`.descriptive`), writes their captions and hands
a drawing function to :meth:`Page.add`, which numbers, draws and saves the figure.
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Iterable, Mapping, Sequence
from pathlib import Path
from typing import Any, Final

import numpy as np
import pandas as pd

from ...exceptions import DataError
from ...formatting import format_number
from ...models.labels import label
from ...models.registry import is_pinn
from ...models.tuning import lambda_curve
from .descriptive import (
    ARCHITECTURE_MODELS,
    _adc_by_wavelength,
    ebl_feature_table,
    environment_panels,
    feature_categories,
    fitted_architectures,
    noise_states,
    physics_loss_texts,
    physiology_panels,
    pipeline_columns,
)
from .diagnostics import section_residuals, section_scatter, section_spread
from .inputs import (
    PHYSICS_DEPTH_LABELS,
    bland_altman_inputs,
    channel_correlations,
    competitors,
    drop_one_models,
    efficiency_table,
    forest_table,
    is_ablation_row,
    latency_resolution,
    model_order,
    performance_table,
    physics_depth_table,
    radar_scores,
    reference_values,
)
from .page import Page, draw_pending
from .results import RenderedFigure, Results

__all__ = ["render_figures"]

logger = logging.getLogger(__package__)  # the package's name, as before the split


def _section_data(page: Page) -> None:
    """Figures 1a-1c: glucose and the NIR signal, environment, physiology."""
    from ...plots import data

    ds = page.results.dataset
    if ds is None:
        for key, title in (("data", "Glucose and NIR signal"), ("environment", "Environment"),
                           ("physiology", "Physiology")):
            page.add(key, title, "Characteristics of the simulated data.", None,
                     note="No dataset.parquet in the results directory: figure not drawn.")
        return
    what = "measured" if page.user_data else "simulated"
    frame = ds.frame
    adc = _adc_by_wavelength(frame, [float(w) for w in ds.wavelengths_nm])
    g = frame["glucose_mgdl"].to_numpy(float)
    corr = channel_correlations(g, adc)
    corr_txt = ", ".join(
        f"{format_number(w, style='general')} nm r = {format_number(r, 2, sign=True)}"
        for w, r in corr.items()
    )
    by_status = ("by diabetes status (left)" if "diabetes_status" in frame
                 else "(left; the diabetes status is not recorded)")
    page.add("data", "Glucose and NIR signal",
             f"Reference glucose of the {len(frame)} {what} snapshots {by_status} and the "
             f"log ADC code of each LED channel against glucose, with the Pearson "
             f"correlation ({corr_txt}).",
             lambda: data.figure_data_characteristics(
                 g, frame["diabetes_status"].astype(str).to_numpy()
                 if "diabetes_status" in frame else np.full(len(frame), "unknown"),
                 {w: np.log(v) for w, v in adc.items()}, corr))
    env = environment_panels(frame)
    if env:  # a user's data may record no ambient conditions: promise no panels
        page.add("environment", "Environment",
                 f"Distributions of the ambient conditions of the {what} snapshots "
                 "(temperature, humidity, pressure, illuminance and light source, where "
                 "recorded).",
                 lambda: data.figure_distributions(env, ncols=5))
    phys = physiology_panels(frame)
    if phys:
        cfg = page.results.config
        how = ("the exact physiological vector the models see (device.physiology = exact: "
               "it equals the truth)" if cfg is not None and cfg.device.physiology == "exact"
               else "the measured physiological vector the models see"
               if cfg is not None else "the physiological vector the models see")
        page.add("physiology", "Physiology",
                 f"Distributions of {how}, one count per snapshot"
                 + (" (its humidity and pressure entries are shown with the environment)."
                    if env else "."),
                 lambda: data.figure_distributions(phys, ncols=5))


def _section_pipeline(page: Page) -> None:
    """Figure 2: the simulator's layers."""
    from ...plots import pipeline
    from ...plots.style import plot_style

    cfg = page.results.config
    if page.user_data:
        return  # measured, not simulated: there is no simulator pipeline to draw
    if cfg is None:
        page.add("pipeline", "Data-generation pipeline", "The simulator's layers.", None,
                 note="No resolved configuration in the results: diagram not drawn.")
        return
    page.add("pipeline", "Data-generation pipeline", _pipeline_caption(cfg),
             lambda: _figure_pipeline(pipeline, cfg, plot_style))
    for peer in page.peers:  # every preset's device, not only the primary's
        pcfg = peer.config
        if pcfg is not None:
            page.add(f"pipeline_{pcfg.preset}", f"Data-generation pipeline on {pcfg.preset}",
                     _pipeline_caption(pcfg),
                     lambda pcfg=pcfg: _figure_pipeline(pipeline, pcfg, plot_style))


def _pipeline_caption(cfg) -> str:
    """What the pipeline diagram shows, counted from the device's noise states."""
    states = noise_states(cfg)
    n = {k: sum(1 for s, _ in states.values() if s == k) for k in ("on", "neutralised", "off")}
    neut = [src.replace("_", " ") for src, (s, _) in states.items() if s == "neutralised"]
    how = "exact: it equals the truth" if cfg.device.physiology == "exact" else \
        "measured: it carries the instruments' errors"
    return (f"The simulator's layers for preset '{cfg.preset}', left to right in the order "
            f"applied, with the '{cfg.optics.model}' forward model: {n['on']} of "
            f"{len(states)} noise sources act on the readings (✓, with their factor when not "
            f"×1)" + (f", {n['neutralised']} are switched on but removed by the device "
                      f"({', '.join(neut)}; ✗ with the reason)" if neut else "")
            + (f", {n['off']} are off (✗)" if n["off"] else "")
            + f". The physiological vector the models see is {how} "
            f"(device.physiology = {cfg.device.physiology}).")


def _section_architecture(page: Page) -> None:
    """The model architectures, from models fitted for one epoch."""
    from ...plots import architecture

    ds = page.results.dataset
    models = page.models
    arch_models = [m for m in ARCHITECTURE_MODELS if m in models] or list(ARCHITECTURE_MODELS)
    archs: dict[str, Any] = {}
    arch_err: str | None = "No dataset.parquet in the results: diagram not drawn."
    if ds is not None and page.wants("architecture"):
        try:
            archs = fitted_architectures(ds, page.results.meta.get("preset"), arch_models,
                                         fitted=page.fitted)
            arch_err = None
        except (ImportError, ValueError, RuntimeError) as exc:
            archs, arch_err = {}, f"Models could not be built on this dataset: {exc}"
    page.add("architecture", "Model architectures",
             "One block diagram per model family, inputs at the top and glucose at the "
             "bottom; the layer widths (a→b→c: the Linear layers of each block) and parameter "
             "counts are read from each model built with "
             + ("the default parameters" if page.user_data else "this preset's tuned "
                "parameters")
             + " and fitted for one epoch on this run's dataset, so they are the sizes that "
             "ran. The absorbance (nir) and physiology (pmf) branches run in parallel and "
             "are concatenated; a curved arrow is an input that skips a block (the RTE "
             "networks' glucose head reads the trunk besides the optics, the SDNN's stack "
             "the physiology besides the front); the dashed box is each physics-informed "
             "network's training loss with its physics term and the λ it was fitted with "
             "(not part of prediction).",
             (lambda: architecture.figure_architectures(
                 archs, physics=physics_loss_texts(page.fitted))) if archs else None,
             note=arch_err)


def _section_features(page: Page) -> None:
    """The Enhanced Beer–Lambert feature engineering."""
    from ...plots import architecture

    ds = page.results.dataset
    feat: dict[str, list[str]] = {}
    feat_src: dict[str, str] = {}
    n_ch = n_phys = 0
    if ds is not None and page.wants("features"):
        try:
            table, n_ch, n_phys = ebl_feature_table(ds, page.results.meta.get("preset"),
                                                    model=page.fitted.get("ebl"))
            feat, feat_src = feature_categories(table)
        except (ImportError, ValueError) as exc:
            logger.warning("feature table not built: %s", exc)
    page.add("features", "Feature engineering",
             f"How the Enhanced Beer–Lambert model turns the {n_ch} raw LED intensities and "
             f"the {n_phys}-entry physiological vector into its "
             f"{sum(len(v) for v in feat.values())} features, by category (count and first "
             "names; the full list is features.feature_table).",
             (lambda: architecture.figure_feature_engineering(
                 n_ch, n_phys, feat, feat_src)) if feat else None,
             note=None if feat else "No dataset.parquet in the results: diagram not drawn.")


def _section_agreement(page: Page) -> None:
    """Bland–Altman (the linearity panels are part of the agreement scatter now)."""
    from ...plots import agreement

    ba = bland_altman_inputs(page.preds, page.pred_models)
    page.add("bland_altman", "Bland–Altman",
             f"Prediction minus reference against their mean for each model ({_points(page)}),"
             f" each panel on its own y range (so that every interval shows), with the bias "
             f"(solid) and 95 % limits of agreement (dashed), their values and 95 % "
             f"confidence intervals (shaded) under each title (Bland & Altman 1986). The "
             f"bias and limits are computed per repeat and averaged over repeats, the "
             f"definition of the further-metrics table's bias and LoA columns, so the "
             f"numbers are the same.",
             lambda: agreement.figure_bland_altman(ba) if ba else None,
             note=None if ba else "Too few predictions: figure not drawn.")


def _points(page: Page) -> str:
    """Which predictions a scatter draws (no claim about the table)."""
    p = page.preds
    n_rep = int(p["repeat"].nunique()) if "repeat" in p.columns else 1
    return (f"every out-of-fold prediction of all {n_rep} repeats pooled" if n_rep > 1
            else "every out-of-fold prediction")


def _section_training(page: Page) -> None:
    """Training dynamics of the networks, one figure per preset that recorded them."""
    _training_figure(page, page.results, "training", "Training dynamics")
    for peer in page.peers:
        preset = str(peer.meta.get("preset") or peer.directory.name)
        _training_figure(page, peer, f"training_{preset}", f"Training dynamics on {preset}")


def _training_figure(page: Page, res: Results, key: str, title: str) -> None:
    from ...plots import training

    histories = res.histories
    where = f" on preset '{res.meta['preset']}'" if res.meta.get("preset") else ""
    if histories is None:
        page.add(key, title, "Training and validation loss per epoch.", None,
                 note="No histories.json in the results directory: figure not drawn.")
        return
    hist = {m: histories[m] for m in model_order(histories) if not is_ablation_row(m)}
    has_val = any("val_loss" in h and h["val_loss"].notna().any() for h in hist.values())
    caption = ((f"Training (solid){' and validation (dashed)' if has_val else ''} loss per "
                f"epoch of each network{where} (the timed fit: first fold of the first "
                "repeat), thick the total and thin each term of the physics-informed ones (a "
                "term equal to another curve is named in that curve's legend entry rather "
                "than drawn under it). Losses are mean squared errors of glucose "
                "standardised on the training rows, so 1 is the training mean's loss; "
                "physics terms are in their own squared residual units. "
                + ("The validation curves are on the rows each fit held out for early "
                   "stopping (val_fraction of its training rows). " if has_val else
                   "These fits recorded no validation loss (no validation split), so there "
                   "are no validation curves. ")
                + "The physics-ablation refits are left out: their physics weight is 0, so "
                "their total is their MSE.") if hist else
               "No networks in this run, so there are no training curves to show.")
    held = _held_out_mse(res, list(hist))
    if held:
        caption += (" The black dash-dot line is each network's held-out error in the same "
                    "units: its cross-validated RMSE over all folds and repeats squared and "
                    "divided by the variance of the cohort's reference glucose "
                    "(approximately the standardisation of one fold's training rows); the "
                    "gap between it and the training curve is how much the fit does not "
                    "carry over to new subjects.")
    page.add(key, title, caption,
             lambda: training.figure_training_dynamics(hist, held_out=held),
             note=None if hist else "No networks in this run.")


def _held_out_mse(res: Results, models: Sequence[str]) -> dict[str, float]:
    """Each model's cross-validated MSE in the training loss's units (standardised
    glucose: RMSE² / variance of the run's reference glucose, each snapshot once)."""
    p, m = res.predictions, res.metrics.drop_duplicates("model").set_index("model")
    if p is None or not len(p) or "rmse_mgdl" not in m.columns:
        return {}
    if "measurement_id" in p.columns:
        p = p.drop_duplicates("measurement_id")
    var = float(np.nanvar(p["reference_mgdl"].to_numpy(float)))
    return {k: float(m.at[k, "rmse_mgdl"]) ** 2 / var for k in models
            if k in m.index and var > 0 and np.isfinite(m.at[k, "rmse_mgdl"])}


def _reference_text(refs: Mapping[str, float]) -> str:
    """Caption sentence naming the reference rows drawn as horizontal lines."""
    if not refs:
        return ""
    names = [("oracle (a bound, not a competitor)" if r == "oracle" else
              "training mean (no skill)" if r == "mean" else
              f"{label(r)} (a privileged reference: it reads the generating scenario; "
              "dash-dotted)") for r in refs]
    return (" The " + " and ".join(names)
            + (" are drawn as horizontal reference lines." if len(names) > 1 else
               " is drawn as a horizontal reference line."))


def _section_physics_weight(page: Page) -> None:
    """The tuning's validation curve of each PINN against λ, every preset of the run."""
    from ...plots.physics_weight import figure_lambda_curves

    runs = [page.results, *page.peers]
    curves = {}
    for res in runs:
        preset = _preset_name(res)
        got = {m: c for m in page.models if "/" not in m and is_pinn(m)
               and (c := lambda_curve(m, preset)) is not None}
        if got:
            curves[preset] = got
    page.add("physics_weight", "The physics weight's validation curve",
             "Each PINN's cross-validated RMSE on the tuning seeds (1000-1002, never the "
             "reported ones) against its physics weight λ, from the packaged tuning file: "
             "solid, the tuned training parameters refitted at every λ (only λ changes); "
             "dashed, the best of the tuning's own draws at each λ (the other parameters "
             "differ); the ring marks the λ the tuning chose. Where it chose 0 the benchmark "
             "also runs the solid curve's best λ > 0 (the ablation table).",
             lambda: figure_lambda_curves(curves) if curves else None,
             note=None if curves else "No tuned PINN in this run.")


def _section_radar(page: Page) -> None:
    """Figure 8: normalised scores."""
    from ...plots import tradeoffs

    scores = radar_scores(page.results.metrics, competitors(page.models))
    page.add("radar", "Normalised scores",
             "One panel per model (its polygon in colour, the other models' outlines in grey "
             "for comparison): each model's RMSE, MARD, Clarke zone A and share within ±15 % "
             "as a ratio to the best model shown (1 = best), and its parameter count and "
             "multiply-accumulates per prediction scored 1 for the smallest, minus 1/6 per "
             "decade above it. Latency is not an axis (it measures the machine and Python's "
             "call overhead; the multiply-accumulates are the machine-independent cost). No "
             "composite score is given: a mean over these axes weighs accuracy against cost "
             "by the arbitrary 1/6 per decade, and it ranked PLS (25 mg/dL on paper) above "
             "every PINN. The oracle, a bound, the training mean, no skill, and the privileged "
             "estimators (they read the generating scenario) are references rather than "
             "competitors and are left out; so are the ablation rows.",
             lambda: tradeoffs.figure_radar_grid(scores) if len(scores) else None,
             note=None if len(scores) else "No model besides the oracle.")


def _section_costs(page: Page) -> None:
    """Figures 9-10: accuracy against physics depth and against cost."""
    from ...plots import tradeoffs
    from ...plots.style import plot_style

    metrics, models = page.results.metrics, page.models
    depth, left_out = physics_depth_table(metrics, models, lambdas=_tuned_lambdas(page.results))
    refs = reference_values(metrics, models)
    ref_txt = _reference_text(refs)
    lo_txt = f" ({', '.join(left_out)} left out: no physics depth or metrics)" if left_out else ""
    page.add("physics_depth", "Accuracy vs physics depth",
             f"RMSE against how much of the forward model each method uses, from the most "
             f"physics on the left to none on the right, the study's direction (the RMSE axis "
             f"starts at 0), bubble area proportional to the trainable parameter count; a "
             f"black ring marks the bubbles on the parameters–RMSE Pareto front. A PINN "
             f"whose tuned physics weight λ is 0 is marked physics off and drawn at no "
             f"physics: it trained without its physics term. Privileged estimators (they "
             f"read the generating scenario) are not competitors: like the oracle they are "
             f"reference lines."
             f"{ref_txt}{lo_txt}",
             lambda: _figure_one(lambda ax: tradeoffs.plot_physics_depth(
                 depth, depth_labels=PHYSICS_DEPTH_LABELS, references=refs, ax=ax),
                 (11.0, 5.2), plot_style)
             if len(depth) else None,
             note=None if len(depth) else "No model with a known physics depth.")
    timed = _latency_ok(page)
    eff = efficiency_table(metrics, models, latency=timed)
    page.add("efficiency", "Efficiency landscape",
             "RMSE (axis from 0) against three costs, each with its own Pareto front (no "
             "other model both cheaper and more accurate; black edge, dashed line): "
             "trainable parameters; multiply-accumulates per prediction, counted from the "
             "fitted model, the same on every machine; and the median single-sample "
             "latency with a grey whisker to its 90th percentile, measured on the machine "
             "recorded under Configuration and provenance (timing machine). Each label "
             "sits nearest its own marker. No combined index: how size, arithmetic and "
             f"time weigh against each other depends on the device.{ref_txt}"
             + ("" if timed else " The latencies differ by less than their timing noise (see "
                "the note under the main table), so they count as equal: the speed panel "
                "marks only the most accurate model."),
             lambda: tradeoffs.figure_efficiency_landscape(eff, refs))


def _tuned_lambdas(res: Results) -> dict[str, float]:
    """Each model's tuned physics weight ``lambda_phys`` (``meta.json``'s model_params)."""
    params = res.meta.get("model_params") or {}
    return {str(m): float(p["lambda_phys"]) for m, p in params.items()
            if isinstance(p, dict) and p.get("lambda_phys") is not None}


def _latency_ok(page: Page) -> bool:
    """Whether latencies differ by more than their timing noise (True when unknown)."""
    res = latency_resolution(page.results.metrics, [p.metrics for p in page.peers])
    return res is None or bool(res["resolved"])


def _section_performance(page: Page) -> None:
    """The performance panel: the presets on shared axes."""
    from ...plots import architecture

    res = page.results
    by_preset = dict(page.compare) if page.compare else {
        str(res.meta.get("preset") or "this run"): res.metrics}
    perf_models = competitors(page.models)  # privileged rows are references: not here
    perf = performance_table(by_preset, perf_models)
    page.add("performance", "Performance comparison",
             "Error metrics as bars from zero (RMSE with its 95 % CI, MARD) and two "
             "machine-independent costs as dots on log axes (trainable parameters, "
             "multiply-accumulates per prediction counted from the fitted model)"
             + (f", one row per preset ({', '.join(by_preset)}: marker and bar shade) on "
                "shared axes" if len(by_preset) > 1 else "")
             + ". Colour is the model's, as in every figure. Latency is left out: it "
             "measures the machine (see the main table's median and p90 and the efficiency "
             "landscape).",
             (lambda: architecture.figure_performance_panel(perf)) if len(perf) else None,
             note=None if len(perf) else "No competitor models in this run.")


def _section_wavelengths(page: Page) -> None:
    """Wavelength utilisation: each model refitted without each LED (``drop_one.csv``)."""
    from ...plots import wavelengths as wl_plots

    table = page.results.drop_one
    title = "Wavelength utilisation: what each LED adds"
    if table is None or not len(table):
        page.add("wavelengths", title, "Drop-one-LED refits.", None,
                 note="No drop-one-LED refits in the results directory (drop_one.csv absent "
                      "or empty: the benchmark ran with --drop-one none): figure not drawn.")
        return
    models = drop_one_models(table, page.models)
    reps = int(table["n_repeats"].max()) if "n_repeats" in table else 1
    n_sub = int(table["n_test_subjects"].min()) if "n_test_subjects" in table else None
    page.add("wavelengths", title,
             "Each model refitted without one LED (its ADC code and reference columns "
             "removed: a device with one LED fewer), on the same folds with the same seeds, "
             "and scored on the same held-out subjects"
             + (f" ({n_sub} subjects" if n_sub else " (")
             + (f", the first {reps} repeats" if reps > 1 else ", the first repeat")
             + " of the protocol). Each "
             "dot is the paired RMSE difference, without the LED minus with every LED, in "
             "mg/dL, with its 95 % cluster-bootstrap CI over subjects: above 0, leaving the "
             "LED out costs accuracy (the LED carries information the others do not); at "
             "or below 0, the other LEDs make up for it. Filled: the CI excludes 0. Each "
             "panel has its own scale. This replaces permuting one channel at a time: the "
             "channels correlate at 0.95–0.999, so a permuted channel is an input no "
             "device produces and measures extrapolation, not what an LED is worth.",
             lambda: wl_plots.figure_drop_one(table, models))


def _section_forest(page: Page) -> None:
    """Figure 12: RMSE with its confidence interval, the study's values beside it."""
    from ...plots import forest
    from ...plots.style import plot_style

    ft = forest_table(page.results.metrics, [m for m in page.models if not is_ablation_row(m)],
                      with_study=not page.user_data)
    page.add("forest", "RMSE with 95 % CI",
             "Each model's RMSE with its 95 % cluster-bootstrap confidence interval"
             + ("." if page.user_data else ", next to the value the study reported from its "
                "single 48-snapshot test set (open diamonds)."),
             lambda: _figure_one(lambda ax: forest.plot_rmse_forest(ft, ax=ax),
                                 (7.0, 0.5 * len(ft) + 1.5), plot_style))


#: The report's figures, section by section in page order (each builder adds its figures).
#: The order is the page's (:data:`nirglucose.report.html.FIGURE_SLOTS`: each figure
#: sits beside the text that cites it), so the numbers run down the page.
_SECTIONS: Final[tuple[Callable[[Page], None], ...]] = (
    _section_wavelengths,
    _section_forest, _section_performance, section_scatter, _section_agreement,
    section_residuals, section_spread,
    _section_training, _section_physics_weight, _section_architecture,
    _section_radar, _section_costs,
    _section_data, _section_pipeline, _section_features,
)

#: Sections drawn once per preset of a multi-preset run (each preset's figure right
#: after the primary's, its key and title suffixed with the preset).
_PER_PRESET: Final[tuple[Callable[[Page], None], ...]] = (
    _section_data, _section_features, section_scatter, _section_agreement,
    section_residuals, section_spread, _section_radar, _section_costs, _section_wavelengths,
    _section_architecture, _section_forest,
)


def _preset_name(res: Results) -> str:
    return str(res.meta.get("preset") or res.directory.name)


def _run_sections(page: Page) -> None:
    """Every section in page order; the per-preset ones once more for each peer.

    With peers, the primary's per-preset figures say their preset in the title too.
    """
    from dataclasses import replace

    for section in _SECTIONS:
        if not (page.peers and section in _PER_PRESET):
            section(page)
            continue
        own = replace(page, title_suffix=f" on {_preset_name(page.results)}")
        subs = [own] + [replace(page, results=peer, peers=(page.results,), compare=None,
                                fitted={}, key_suffix=f"_{_preset_name(peer)}",
                                title_suffix=f" on {_preset_name(peer)}")
                        for peer in page.peers]
        for sub in subs:  # they share the figure list; the count runs on
            sub.rendered, sub.count = page.rendered, page.count
            section(sub)
            page.count = sub.count


def render_figures(results: Results, figures_dir: str | Path | None = None,
                   formats: Sequence[str] = ("png", "svg"), *,
                   include: Iterable[str] | None = None,
                   compare: Mapping[str, pd.DataFrame] | None = None,
                   peers: Sequence[Results] = (), jobs: int = 1) -> list[RenderedFigure]:
    """Build every figure of the report from loaded results.

    Parameters
    ----------
    results : Results
        From :func:`load_results`.
    figures_dir : str or path, optional
        If given, also write each figure there as ``<number>_<key>.<fmt>``; the
        directory is created if its parent exists.
    formats : sequence of str
        File formats written to ``figures_dir``. [-]
    include : iterable of str, optional
        Keys of the figures to render (``"clarke"``, ``"training"``, ...); all by default.
    compare : mapping of str to pandas.DataFrame, optional
        Metrics of each preset of a multi-preset run (the primary first): the
        performance panel then shows every preset on shared axes.
    peers : sequence of Results, optional
        The other presets' runs: the training dynamics are drawn for each, and their
        timings measure the latencies' noise.
    jobs : int
        Processes drawing the figures (forked, on Linux; elsewhere one); the figures are
        the same for any number. [-]

    Returns
    -------
    list of RenderedFigure
        In page order; a figure whose inputs are missing has no PNG and a ``note``.
    """
    out_dir = None
    if figures_dir is not None:
        out_dir = Path(figures_dir)
        if not out_dir.parent.exists():
            raise DataError(f"figure directory's parent {str(out_dir.parent)!r} does not exist")
        out_dir.mkdir(exist_ok=True)
    page = Page(results=results, out_dir=out_dir, formats=formats,
                 wanted=None if include is None else set(include), compare=compare,
                 peers=tuple(peers))
    _run_sections(page)
    draw_pending(page, jobs)
    return page.rendered


def _figure_one(draw: Callable, figsize: tuple[float, float], plot_style):
    from matplotlib.figure import Figure

    from ...plots.labels import place_labels

    with plot_style():
        fig = Figure(figsize=figsize, layout="constrained")
        ax = fig.add_subplot()
        draw(ax)
        place_labels(fig)
    return fig


def _figure_pipeline(pipeline_mod, cfg, plot_style):
    from matplotlib.figure import Figure

    cols = pipeline_columns(cfg)
    with plot_style():
        fig = Figure(figsize=(12.0, pipeline_mod.pipeline_height_in(cols)),
                     layout="constrained")
        pipeline_mod.plot_pipeline(
            cols, ax=fig.add_subplot(),
            title=f"Simulator layers: preset '{cfg.preset}', global noise scale "
                  f"×{format_number(cfg.noise_scale, style='general')}")
    return fig
