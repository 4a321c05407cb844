"""`nirglucose report` on a benchmark of a user's own measurements (docs/user_guide/your_data.md).

The file holds what a device logs (ADC codes, its references, three physiological
columns, the meter's glucose, subject ids): no scenario, no preset, no ambient
conditions, no diabetes status. The page must word itself for measured data.
"""

from __future__ import annotations

import html
import re
from pathlib import Path

import numpy as np
import pytest

from device_data import simulate_device
from nirglucose.cli import main
from nirglucose.report.figures import forest_table, load_results

#: Columns a user's device file holds (docs/user_guide/your_data.md): a three-LED device.
_PHYSIOLOGY = ("age_yr", "skin_temp_c", "heart_rate_bpm")


@pytest.fixture(scope="module")
def user_run(tmp_path_factory) -> tuple[Path, str]:
    """A benchmark of a user's CSV and its report (the page's HTML)."""
    d = tmp_path_factory.mktemp("user")
    frame = simulate_device(3, 12, n_subjects=10, per_subject=3, seed=4).frame
    cols = ["subject_id", "measurement_id", "glucose_mgdl",
            *[c for c in frame.columns if c.startswith("adc_")], *_PHYSIOLOGY]
    frame[cols].to_csv(d / "mine.csv", index=False)
    argv = ["benchmark", "--data", str(d / "mine.csv"), "--models", "ebl,pls",
            "--no-references", "--folds", "3", "--repeats", "1", "--resamples", "50",
            "--jobs", "1", "--out", str(d / "r")]
    assert main(argv) == 0
    assert main(["report", str(d / "r"), "--out", str(d / "report.html")]) == 0
    return d / "r", (d / "report.html").read_text(encoding="utf-8")


def _visible_text(page: str) -> str:
    """The page's words as read: no tags, no images, no raw-metadata JSON dump."""
    body = page.split("<body>", 1)[1]
    body = re.sub(r"<pre>.*?</pre>", " ", body, flags=re.S)  # raw metadata, verbatim
    body = re.sub(r"<[^>]+>", " ", body)
    return re.sub(r"\s+", " ", html.unescape(body))


def test_user_report_says_no_preset_none(user_run):
    results_dir, page = user_run
    assert load_results(results_dir).meta.get("preset") is None  # the benchmark wrote null
    text = _visible_text(page)
    assert "your data" in text
    assert not re.search(r"preset\W*(None|null)\b", text), re.search(
        r".{60}preset\W*(None|null).{20}", text)
    assert "None" not in text


def test_user_report_does_not_call_the_measurements_simulated(user_run):
    _, page = user_run
    text = _visible_text(page)
    assert "measured snapshots" in text  # figure 1's caption
    assert "simulated" not in text.replace("measured, not simulated", "")
    assert 'id="fig-pipeline"' not in page  # no simulator layers for measured data


def test_user_report_promises_no_environment_it_does_not_draw(user_run):
    _, page = user_run
    assert 'id="fig-environment"' not in page
    assert "environment" not in _visible_text(page).lower()
    assert "diabetes status is not recorded" in _visible_text(page)  # not "by status"


def test_user_report_shows_none_of_the_studys_columns(user_run):
    results_dir, page = user_run
    text = _visible_text(page)
    assert 'class="study"' not in page and "<th>study</th>" not in page
    assert "n = 48" not in text and "48-snapshot" not in text
    assert "Study:" not in text  # the benchmark's protocol sentence about the study
    ft = forest_table(load_results(results_dir).metrics, ["ebl", "pls"], with_study=False)
    assert ft["study_rmse_mgdl"].isna().all()  # no study diamonds on the forest plot
    assert np.isfinite(ft["rmse_mgdl"]).all()


def test_user_report_draws_the_device_s_own_features(user_run):
    """The feature diagram and EBL architecture are drawn for the user's device."""
    _, page = user_run
    for key in ("architecture", "features"):
        fig = re.search(rf'<figure id="fig-{key}">(.*?)</figure>', page, flags=re.S)
        assert fig and "data:image/png;base64," in fig.group(1), key
    caption = re.search(r'<figure id="fig-features">.*?<figcaption>(.*?)</figcaption>',
                        page, flags=re.S).group(1)
    assert "the 3 raw LED intensities" in caption and "3-entry physiological" in caption
