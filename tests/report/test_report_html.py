"""The HTML report: every figure and table, provenance, self-containment, errors, CLI."""

from __future__ import annotations

import base64
import re
from html.parser import HTMLParser
from pathlib import Path

import pytest
from report_fixtures import REPORT_TEST_MODELS, write_synthetic_results

import nirglucose as ng
from nirglucose.cli import main
from nirglucose.exceptions import DataError
from nirglucose.report import build_report, load_results

#: Every figure of the report: anchor key -> printed number.
#: Numbered in page order: each figure beside the text that cites it (issue 39).
FIGURES = {
    "wavelengths": "1", "forest": "2", "performance": "3", "scatter": "4",
    "bland_altman": "5", "residuals": "6", "fold_spread": "7", "training": "8",
    "physics_weight": "9", "architecture": "10", "radar": "11", "physics_depth": "12",
    "efficiency": "13", "data": "14", "environment": "15", "physiology": "16",
    "pipeline": "17", "features": "18",
}


class _Page(HTMLParser):
    """Collects figures, images, captions, tables and external references."""

    def __init__(self) -> None:
        super().__init__()
        self.figures: dict[str, dict] = {}
        self.tables: dict[str, int] = {}
        self.external: list[str] = []
        self.tags: set[str] = set()
        self._fig: str | None = None
        self._table: str | None = None
        self._caption = False

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        self.tags.add(tag)
        for key in ("src", "href"):
            v = a.get(key) or ""
            if v and not (v.startswith("data:") or v.startswith("#")):
                self.external.append(v)
        if tag == "figure":
            self._fig = a["id"]
            self.figures[self._fig] = {"imgs": [], "caption": ""}
        elif tag == "img" and self._fig:
            self.figures[self._fig]["imgs"].append(a["src"])
        elif tag == "figcaption":
            self._caption = True
        elif tag == "table" and a.get("id"):
            self._table = a["id"]
            self.tables[self._table] = 0
        elif tag == "tr" and self._table:
            self.tables[self._table] += 1

    def handle_endtag(self, tag):
        if tag == "figure":
            self._fig = None
        elif tag == "figcaption":
            self._caption = False
        elif tag == "table":
            self._table = None

    def handle_data(self, data):
        if self._caption and self._fig:
            self.figures[self._fig]["caption"] += data


def _parse(path: Path) -> tuple[str, _Page]:
    text = path.read_text(encoding="utf-8")
    page = _Page()
    page.feed(text)
    return text, page


def test_report_contains_every_figure_as_embedded_png(synthetic_report):
    _, page = _parse(synthetic_report)
    assert set(page.figures) == {f"fig-{k}" for k in FIGURES} | {"fig-headline"}
    for key, number in FIGURES.items():
        fig = page.figures[f"fig-{key}"]
        assert len(fig["imgs"]) == 1, key
        src = fig["imgs"][0]
        assert src.startswith("data:image/png;base64,")
        assert base64.b64decode(src.split(",", 1)[1])[:8] == b"\x89PNG\r\n\x1a\n"
        caption = " ".join(fig["caption"].split())
        assert caption.startswith(f"Figure {number}.") and caption.endswith("."), caption
        assert "could not be drawn" not in caption


def test_report_tables(synthetic_report):
    text, page = _parse(synthetic_report)
    # two header rows + one row per model
    # the essentials and, behind a toggle, every column
    assert page.tables["reproduced-table-paper"] == 2 + len(REPORT_TEST_MODELS)
    assert page.tables["reproduced-table-full-paper"] == 2 + len(REPORT_TEST_MODELS)
    assert page.tables["extra-table-paper"] == 1 + len(REPORT_TEST_MODELS)
    assert "comparisons-paper" in page.tables
    assert "<td class=\"study\">13.6</td>" in text  # the study's EBL RMSE
    assert "<td class=\"study\">14.6</td>" in text  # and Original PINN
    assert re.search(r"<td>\d+\.\d \[\d+\.\d, \d+\.\d\]</td>", text)  # ours with a CI
    assert "not distinguishable from it: PLS" in text  # significance from table.md
    assert "Significant rankings" in text


def test_report_provenance(synthetic_report, synthetic_results):
    text, _ = _parse(synthetic_report)
    res = load_results(synthetic_results)
    assert res.meta["dataset_hash"] in text
    assert f"<dt>seed</dt><dd>{res.meta['seed']}</dd>" in text
    assert ng.__version__ in text
    assert 'id="config"' in text and "&quot;noise_scale&quot;" in text
    # the run line says the protocol with its folds and repeats (make run runs one repeat)
    sub = re.search(r'<p class="sub">([^<]*)</p>', text).group(1)
    assert f"protocol {res.meta['protocol']} (5 folds × 2 repeats)" in sub


def test_report_is_self_contained(synthetic_report):
    text, page = _parse(synthetic_report)
    assert page.external == []
    assert "script" not in page.tags
    assert not re.search(r"https?://", text.split("<body>", 1)[0])
    assert not re.search(r"""(src|href)=["']https?:""", text)


@pytest.fixture(scope="module")
def minimal_results(tmp_path_factory) -> Path:
    """Only the required files, one model."""
    return write_synthetic_results(tmp_path_factory.mktemp("minimal"), models=("ebl",),
                                   networks=(), n_subjects=8, repeats=1,
                                   with_optional=False)


def test_cli_report_with_missing_optional_inputs(minimal_results, tmp_path, capsys):
    out = tmp_path / "report.html"
    assert main(["report", str(minimal_results), "--out", str(out)]) == 0
    text, page = _parse(out)
    assert set(page.figures) == {f"fig-{k}" for k in FIGURES} | {"fig-headline"}
    for name in ("histories.json", "drop_one.csv", "dataset.parquet", "comparisons.csv"):
        assert f"No {name}" in text
    assert page.figures["fig-training"]["imgs"] == []
    assert page.figures["fig-scatter"]["imgs"]  # required inputs still give figures
    assert page.figures["fig-pipeline"]["imgs"]  # config from metrics.json meta
    assert str(out) in capsys.readouterr().out


def test_figures_written_as_png_and_svg(minimal_results, tmp_path):
    from nirglucose.report.figures import render_figures

    figs = render_figures(load_results(minimal_results), tmp_path / "figs",
                          include=["forest", "training"])
    assert [f.key for f in figs] == ["forest", "training"]  # page order
    assert figs[1].files == []  # not drawn: no histories.json
    stem = f"fig{figs[0].number}_forest"
    assert [p.name for p in figs[0].files] == [f"{stem}.png", f"{stem}.svg"]
    assert all(p.stat().st_size > 0 for p in figs[0].files)


def test_figures_drawn_on_two_processes_are_the_same(minimal_results, tmp_path):
    """Figures drawn by forked processes: the same PNG bytes, notes, files and order."""
    import sys

    from nirglucose.report.figures import render_figures

    keys = ["forest", "training", "scatter", "bland_altman"]
    res = load_results(minimal_results)
    one = render_figures(res, tmp_path / "one", include=keys, formats=("png",))
    two = render_figures(res, tmp_path / "two", include=keys, formats=("png",), jobs=2)
    assert [f.key for f in one] == [f.key for f in two]
    assert sum(bool(f.png) for f in one) >= 2  # something was drawn
    for a, b in zip(one, two, strict=True):
        assert (a.number, a.note, a.png) == (b.number, b.note, b.png)
        assert [p.name for p in a.files] == [p.name for p in b.files]
        assert [p.read_bytes() for p in a.files] == [p.read_bytes() for p in b.files]
    if sys.platform.startswith("linux"):  # drawn in children: nothing left pending
        from nirglucose.report.figures import page as page_mod

        assert page_mod._FORKED == []


def test_cli_report_on_two_processes_ends_quietly(minimal_results, tmp_path, capfd):
    """`report --jobs 2`: the drawing children end without a word (they inherit the
    CLI's signal handlers: a pool ended by SIGTERM printed a KeyboardInterrupt each)."""
    out = tmp_path / "report.html"
    assert main(["report", str(minimal_results), "--out", str(out), "--jobs", "2"]) == 0
    captured = capfd.readouterr()
    assert "Traceback" not in captured.err and "KeyboardInterrupt" not in captured.err
    assert str(out) in captured.out and out.stat().st_size > 0


def test_no_networks_says_so(tmp_path):
    res_dir = write_synthetic_results(tmp_path / "r", models=("ebl",), networks=(),
                                      n_subjects=6, repeats=1)
    from nirglucose.report.figures import render_figures

    figs = {f.key: f for f in render_figures(load_results(res_dir), include=["training"])}
    assert list(figs) == ["training"]
    assert figs["training"].note == "No networks in this run."
    assert figs["training"].png  # a panel that says so, not an empty one
    assert "No networks in this run" in figs["training"].caption


def test_missing_results_dir_is_a_data_error(tmp_path, capsys):
    with pytest.raises(DataError, match="does not exist"):
        build_report(tmp_path / "nope", tmp_path / "r.html")
    assert main(["report", str(tmp_path / "nope"), "--out", str(tmp_path / "r.html")]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("error:") and "\n" not in err and "Traceback" not in err


@pytest.mark.parametrize("remove", ["predictions.parquet", "metrics"])
def test_incomplete_results_dir(minimal_results, tmp_path, remove):
    import shutil

    d = tmp_path / "r"
    shutil.copytree(minimal_results, d)
    for name in (["metrics.csv", "metrics.json"] if remove == "metrics" else [remove]):
        (d / name).unlink()
    with pytest.raises(DataError, match="incomplete"):
        load_results(d)


def test_metrics_without_required_column(minimal_results, tmp_path):
    import shutil

    import pandas as pd

    d = tmp_path / "r"
    shutil.copytree(minimal_results, d)
    pd.read_csv(d / "metrics.csv").drop(columns="rmse_mgdl").to_csv(d / "metrics.csv")
    with pytest.raises(DataError, match="rmse_mgdl"):
        load_results(d)


def test_output_directory_must_exist(minimal_results, tmp_path):
    with pytest.raises(DataError, match="does not exist"):
        build_report(minimal_results, tmp_path / "missing" / "r.html")


def test_hypoglycaemia_caveat_sits_beside_the_error_grid_columns(tmp_path):
    from nirglucose.report.html import glucose_coverage

    d = write_synthetic_results(tmp_path / "r", models=("ebl",), networks=(), n_subjects=8,
                                repeats=1, with_optional=False)
    res = load_results(d)
    lo, hi, n, n_hypo = glucose_coverage(res)
    ref = res.predictions.drop_duplicates("measurement_id")["reference_mgdl"]
    assert (lo, hi, n, n_hypo) == (ref.min(), ref.max(), len(ref), int((ref < 70).sum()))
    text = build_report(d, tmp_path / "r.html").read_text(encoding="utf-8")
    table = text[text.index('id="reproduced-table-paper"'):]
    table = table[:table.index("</thead>")]
    assert re.search(r"Clarke A \[%\]<a class=\"mark\" href=\"#hypo-note-paper\"", table)
    assert "MARD [%]<a" not in table  # only the error-grid columns carry it
    note = re.search(r'<p class="note" id="hypo-note-paper">([^<]+)</p>', text).group(1)
    assert f"{lo:.0f}–{hi:.0f} mg/dL" in note
    if n_hypo == 0:
        assert "no reading of this run is below 70 mg/dL" in note
    else:
        assert f"{n_hypo:,} of the {n:,} readings are below 70 mg/dL" in note
    # the note follows the main table directly
    assert text.index('id="hypo-note-paper"') < text.index('id="further"')
