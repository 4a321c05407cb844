"""The report of a device's twin (``nirglucose report TWIN_DIR``): one HTML page.

Reads ``twin.json`` (:func:`nirglucose.twin.load_twin`) and shows what a device team
asks of it: each parameter's posterior beside the base scenario's value, the presets'
and the published magnitude; what the file does not identify; whether the simulator
reaches the file at all; the posterior predictive checks (the file's summaries and code
distributions against the twin's); and the twin's device bound beside the estimators'
cross-validated errors on the file. Nothing here fits or simulates.
"""

from __future__ import annotations

import base64
import html
from pathlib import Path

import numpy as np
import pandas as pd

from ..dataset import atomic_write
from ..exceptions import DataError
from ..plots.style import figure_bytes
from ..plots.twin import plot_posterior_intervals, plot_ppc
from ..twin import Twin, load_twin
from ..twin.parameters import PRESET_GAINS

__all__ = ["is_twin_dir", "build_twin_report"]

_CSS = ("body{font-family:system-ui,sans-serif;max-width:980px;margin:2em auto;padding:0 1em;"
        "color:#222}table{border-collapse:collapse;font-size:13px}td,th{padding:3px 8px;"
        "border-bottom:1px solid #ddd;text-align:left}.warn{background:#fff4e5;padding:.5em "
        "1em;border-left:4px solid #e69f00}img{max-width:100%}")


def is_twin_dir(directory: str | Path) -> bool:
    """Whether ``directory`` holds a twin (``twin.json``) and no benchmark run."""
    d = Path(directory)
    return (d / "twin.json").is_file() and not (d / "metrics.json").is_file()


def _img(ax, alt: str) -> str:
    data = base64.b64encode(figure_bytes(ax.figure, "png", close=True)).decode("ascii")
    return f'<img src="data:image/png;base64,{data}" alt="{html.escape(alt)}">'


def _table(frame: pd.DataFrame) -> str:
    return frame.to_html(index=False, float_format=_g, border=0, escape=True)


def _g(value) -> str:
    """Three significant digits: a twin's values span 1e-5 (a noise) to 1e3 (a code)."""
    return f"{value:.3g}"


def _parameter_table(twin: Twin) -> pd.DataFrame:
    rows = []
    for e in twin.parameters:
        state = "yes" if e["identified"] else (
            "no: posterior ~ prior" if e["fitted"] else f"held at prior: {e['reason']}")
        rows.append({"scenario key": e["key"], "what": e["label"], "median": _g(e["median"]),
                     "90 % interval": f"{_g(e['lower'])} - "
                                      f"{_g(e['upper'])}",
                     "identified": state, "base value": _g(e["preset"]),
                     "published": "" if e["published"] is None else _g(e["published"]),
                     "prior": f"{_g(e['prior']['low'])} - "
                              f"{_g(e['prior']['high'])} ({e['prior']['scale']})",
                     "unit": e["unit"]})
    return pd.DataFrame(rows)


def _gain_lines(twin: Twin) -> list[str]:
    """One sentence per channel: the glucose signal against the published magnitude."""
    out = []
    presets = ", ".join(f"{k} x{_g(v)}" for k, v in PRESET_GAINS.items())
    for e in twin.parameters:
        if e["kind"] != "glucose signal":
            continue
        size = (f"{_g(e['median'])} x the published magnitude (90 %: "
                f"{_g(e['lower'])} - {_g(e['upper'])})")
        if not e["identified"]:
            size = "not identified by this file (its posterior fills the prior)"
        out.append(f"Glucose signal at {_g(e['channel_nm'])} nm: {size}; "
                   f"the presets assume {presets}.")
    return out


def _drift_lines(twin: Twin) -> list[str]:
    """One sentence per channel: its LED power drift over time, or why it is not known."""
    out = []
    for e in twin.parameters:
        if e["kind"] != "drift":
            continue
        where = (f"LED power drift at {_g(e['channel_nm'])} nm" if e["channel_nm"] is not None
                 else "LED power drift")
        if not e["fitted"]:
            size = f"not identified ({e['reason']}); the twin keeps the base value"
        elif not e["identified"]:
            size = "not identified by this file's reading times (its posterior fills the prior)"
        else:
            size = (f"{_g(100 * e['median'])} % of the power lost per 1000 h (90 %: "
                    f"{_g(100 * e['lower'])} - {_g(100 * e['upper'])})")
        out.append(f"{where}: {size}; the base scenario assumes {_g(100 * e['preset'])} %.")
    return out


#: Summary prefix -> (what it is, its value in natural units from the summary's scale).
_SUMMARY_MEANING = {
    "level": ("mean code [ADC code]", lambda v, fs: 10.0 ** v * fs),
    "between": ("SD of people's mean codes [% of the mean]", lambda v, fs: 100 * 10.0 ** v),
    "within": ("within-person SD after glucose [% of the mean]",
               lambda v, fs: 100 * 10.0 ** v),
    "slope": ("code-glucose slope [% of the mean per 100 mg/dL]",
              lambda v, fs: 100 * 0.002 * np.sinh(v)),
    "hetero": ("corr(log mean, log within-SD) over people [-]", lambda v, fs: v),
    "kurtosis": ("kurtosis of within-person residuals [-]", lambda v, fs: 10.0 ** v),
    "corr": ("within-person residual correlation [-]", lambda v, fs: v),
    "bcorr": ("correlation of people's mean codes [-]", lambda v, fs: v),
    "ref": ("mean reference code [ADC code]", lambda v, fs: 10.0 ** v * fs),
    "ratio": ("within-person SD of log(code / reference) [-]", lambda v, fs: 10.0 ** v),
    "drift": ("loss of code over time [% of the mean per 1000 h]",
              lambda v, fs: 100 * 0.001 * np.sinh(v)),
}


def _meaning(name: str, value: float, full_scale: int) -> tuple[str, str]:
    prefix = name.split("_")[0]
    if name.startswith("within_") and not name.split("_")[1][0].isdigit():
        if name == "within_fitzpatrick_type":
            return "share of readings off a person's usual type [-]", _g(value)
        return "within-person SD of the column [its unit]", _g(10.0 ** value)
    what, natural = _SUMMARY_MEANING.get(prefix, ("", lambda v, fs: v))
    return what, _g(natural(value, full_scale))


def _ppc_tables(twin: Twin) -> str:
    ppc = twin.info.get("ppc") or {}
    fs = twin.device.full_scale
    rows = []
    for k, v in ppc.get("summaries", {}).items():
        what, file_natural = _meaning(k, v["file"], fs)
        twin_natural = _meaning(k, v["twin_median"], fs)[1]
        rows.append({"summary": k, "what": what, "file": file_natural,
                     "twin median": twin_natural, "file (scale)": v["file"],
                     "twin 5 %": v["twin_low"], "twin 95 %": v["twin_high"],
                     "share of twin devices below the file": v["p_below"]})
    q = [f"{100 * x:g} %" for x in ppc.get("quantiles", [])]
    codes = [{"channel": f"adc_{w}", "of": who, **dict(zip(q, vals[who], strict=True))}
             for w, vals in ppc.get("codes", {}).items() for who in ("file", "twin")]
    return (f"{_table(pd.DataFrame(rows))}<h3>Code distributions per channel "
            f"[ADC code]</h3>{_table(pd.DataFrame(codes))}")


def _bound_section(twin: Twin) -> str:
    b, e = twin.info.get("bound"), twin.info.get("file_errors_mgdl")
    if not b or not e:
        return "<p>Not computed for this twin.</p>"
    rows = [{"what": "twin's device bound (Cramér-Rao, the device's readings)",
             "RMSE [mg/dL]": b["device_mgdl"]},
            {"what": "twin's oracle bound (knows every nuisance; a reference)",
             "RMSE [mg/dL]": b["oracle_mgdl"]}]
    rows += [{"what": f"{m}: subject-grouped 5-fold CV on the file", "RMSE [mg/dL]": v}
             for m, v in e.items() if m != "mean"]
    rows.append({"what": "no skill (the training mean) on the file", "RMSE [mg/dL]": e["mean"]})
    return (_table(pd.DataFrame(rows)) + "<p>The bound holds for the twin's most probable "
            "scenario (its regime: glucose at the fitted gain, not a preset's); an "
            "estimator's error on the file below the bound would say the twin misses a "
            "signal the file has.</p>")


def build_twin_report(twin_dir: str | Path, out_path: str | Path, *,
                      figures_dir: str | Path | None = None) -> Path:
    """Write the HTML report of a twin directory (atomically); its path.

    Raises
    ------
    DataError
        No valid ``twin.json``, or the output directory does not exist.
    """
    twin, out_path = load_twin(twin_dir), Path(out_path)
    dev = twin.device
    figs = {"posterior": plot_posterior_intervals(twin.parameters)}
    if twin.info.get("ppc"):
        figs["ppc"] = plot_ppc(twin.info["ppc"])
    if figures_dir is not None:
        Path(figures_dir).mkdir(parents=True, exist_ok=True)
        for name, ax in figs.items():
            for fmt in ("png", "svg"):
                (Path(figures_dir) / f"twin_{name}.{fmt}").write_bytes(figure_bytes(ax.figure,
                                                                                    fmt))
    warns = "".join(f"<p class='warn'>warning: {html.escape(w)}</p>" for w in twin.warnings)
    gains = "".join(f"<li>{html.escape(t)}</li>" for t in _gain_lines(twin))
    drifts = "".join(f"<li>{html.escape(t)}</li>" for t in _drift_lines(twin))
    t = twin.info.get("timing", {})
    method = html.escape(str(twin.info.get("settings", {}).get("method", "")))
    body = (
        f"<h1>The twin of a device: {', '.join(dev.labels)} nm, {dev.adc_bits}-bit ADC</h1>"
        f"<p>File {html.escape(str(twin.info.get('source', '')))}: {dev.n_subjects} people, "
        f"{dev.per_subject} readings each (median); reference codes: "
        f"{'monitor' if dev.monitor else 'start-up' if dev.reference else 'none'}; "
        f"physiology: {html.escape(', '.join(dev.physiology) or 'none')}. Regime: the "
        f"fitted one, on the physical preset (glucose at the published magnitude x each "
        f"channel's fitted gain). Method: {method}, "
        f"{t.get('n_train')} simulated devices; {t.get('total_s')} s.</p>{warns}"
        f"<h2>Glucose signal</h2><ul>{gains}</ul>"
        f"<h2>Drift over time</h2><ul>{drifts}</ul>"
        f"<h2>Posterior of each parameter</h2>{_img(figs['posterior'], 'posterior intervals')}"
        f"{_table(_parameter_table(twin))}"
        "<h2>Posterior predictive checks</h2>"
        + (_img(figs["ppc"], "posterior predictive check") if "ppc" in figs else "")
        + _ppc_tables(twin)
        + f"<h2>Device bound and the estimators on the file</h2>{_bound_section(twin)}"
    )
    page = ("<!DOCTYPE html>\n<html lang='en'><head><meta charset='utf-8'>"
            "<title>nirglucose: a device's twin</title>"
            f"<style>{_CSS}</style></head><body>{body}</body></html>\n")
    if not out_path.parent.exists():
        raise DataError(f"output directory {str(out_path.parent)!r} does not exist; "
                        "create it first")
    return atomic_write(out_path, lambda tmp: Path(tmp).write_text(page, encoding="utf-8"))
