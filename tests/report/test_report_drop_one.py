"""The wavelength-utilisation figure is the drop-one-LED refit; LED findings need a CI."""

from __future__ import annotations

import shutil
from html.parser import HTMLParser

import pandas as pd
import pytest

from nirglucose.evaluation.benchmark.drop_one import led_verdicts
from nirglucose.report import build_report, load_results


class _Figure(HTMLParser):
    """The figure ``fig-wavelengths``: its images and caption text."""

    def __init__(self) -> None:
        super().__init__()
        self.imgs: list[str] = []
        self.caption = ""
        self._in = self._cap = False

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        if tag == "figure":
            self._in = a.get("id") == "fig-wavelengths"
        elif tag == "img" and self._in:
            self.imgs.append(a["src"])
        elif tag == "figcaption" and self._in:
            self._cap = True

    def handle_endtag(self, tag):
        if tag == "figcaption":
            self._cap = False
        elif tag == "figure":
            self._in = False

    def handle_data(self, data):
        if self._cap:
            self.caption += data


def _figure(path) -> _Figure:
    page = _Figure()
    page.feed(path.read_text(encoding="utf-8"))
    return page


def test_report_draws_the_drop_one_refits(synthetic_report, synthetic_results):
    fig = _figure(synthetic_report)
    assert len(fig.imgs) == 1 and fig.imgs[0].startswith("data:image/png;base64,")
    cap = " ".join(fig.caption.split())
    assert "refitted without one LED" in cap
    assert "without the LED minus with every LED" in cap and "95 % cluster-bootstrap CI" in cap
    t = pd.read_csv(synthetic_results / "drop_one.csv")
    assert f"({int(t['n_test_subjects'].min())} subjects" in cap
    loaded = load_results(synthetic_results)
    assert loaded.drop_one is not None and len(loaded.drop_one) == len(t)


def test_old_results_with_importance_only_say_so(synthetic_results, tmp_path):
    old = tmp_path / "old"
    shutil.copytree(synthetic_results, old)
    (old / "drop_one.csv").unlink()
    pd.DataFrame({"model": ["ebl"], "wavelength_nm": [850.0],
                  "rmse_increase_mgdl": [4482.0]}).to_csv(old / "importance.csv", index=False)
    out = build_report(old, tmp_path / "r.html")
    fig = _figure(out)
    assert fig.imgs == []
    text = out.read_text(encoding="utf-8")
    assert "No drop_one.csv" in text and "4482" not in text


def _run(rows, n_subjects=20):
    t = pd.DataFrame(rows, columns=["model", "dropped_wavelength_nm", "delta_rmse_mgdl",
                                    "ci_low", "ci_high"])
    t["rmse_all_mgdl"] = 14.0
    t["n_test_subjects"] = n_subjects
    return t


def test_an_led_is_named_only_where_its_ci_lies_above_zero():
    rows = [("ebl", 850.0, 9.0, -1.0, 19.0),  # the largest, but its CI includes 0
            ("ebl", 1050.0, 4.0, 1.0, 7.0),  # smaller, CI above 0: the one named
            ("ebl", 1150.0, 2.0, 0.5, 3.5),
            ("pls", 850.0, 3.0, -0.5, 6.5), ("pls", 940.0, -1.0, -2.0, -0.1)]
    v = {x["model"]: x for x in led_verdicts(_run(rows))}
    assert float(v["ebl"]["row"]["dropped_wavelength_nm"]) == 1050.0
    assert v["pls"]["row"] is None and not v["pls"]["withheld"]


def test_too_few_subjects_name_no_led():
    rows = [("ebl", 1050.0, 40.0, 30.0, 50.0)]
    (v,) = led_verdicts(_run(rows, n_subjects=8))
    assert v["withheld"] and v["row"] is None

# Long-running (whole studies, end-to-end runs, Monte Carlo or every model): `make test-slow`,
# which CI runs beside the fast `make test` (tests/test_slow_marks.py)
pytestmark = pytest.mark.slow
