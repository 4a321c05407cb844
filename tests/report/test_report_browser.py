"""The report in a real browser: every image loads, the console stays clean.

Needs Debian's ``chromium`` and ``chromium-driver`` (``apt-get install -y chromium
chromium-driver``); skipped with the reason when either is missing.
"""

from __future__ import annotations

import os
import shutil
from pathlib import Path

import pytest
from report_fixtures import write_synthetic_results

pytestmark = pytest.mark.browser

CHROMIUM = shutil.which("chromium") or "/usr/bin/chromium"
CHROMEDRIVER = shutil.which("chromedriver") or "/usr/bin/chromedriver"
_MISSING = [p for p in (CHROMIUM, CHROMEDRIVER) if not os.access(p, os.X_OK)]


@pytest.fixture(scope="module")
def driver(tmp_path_factory):
    if _MISSING:
        pytest.skip(f"headless browser test needs {', '.join(_MISSING)} "
                    "(apt-get install -y chromium chromium-driver)")
    webdriver = pytest.importorskip("selenium.webdriver")
    from selenium.webdriver.chrome.service import Service

    opts = webdriver.ChromeOptions()
    opts.binary_location = CHROMIUM
    for flag in ("--headless", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage",
                 "--disable-background-networking", "--disable-component-update",
                 "--disable-sync", "--no-first-run", "--window-size=1400,1000",
                 f"--user-data-dir={tmp_path_factory.mktemp('chromium-profile')}"):
        opts.add_argument(flag)
    opts.set_capability("goog:loggingPrefs", {"browser": "ALL"})
    drv = webdriver.Chrome(options=opts, service=Service(executable_path=CHROMEDRIVER))
    drv.set_page_load_timeout(60)
    yield drv
    drv.quit()


@pytest.fixture(scope="module")
def report(tmp_path_factory) -> Path:
    from nirglucose.report import build_report

    d = tmp_path_factory.mktemp("browser")
    results = write_synthetic_results(d / "results", models=("ebl", "original-pinn"),
                                      networks=("original-pinn",), n_subjects=10, repeats=1)
    return build_report(results, d / "report.html")


def test_every_image_loads_and_console_is_clean(driver, report, tmp_path):
    from selenium.webdriver.common.by import By

    driver.get(report.as_uri())
    assert driver.execute_script("return document.readyState") == "complete"
    assert driver.title == "nirglucose benchmark report"
    images = driver.find_elements(By.TAG_NAME, "img")
    assert len(images) == len(driver.find_elements(By.CSS_SELECTOR, "figure img"))
    assert len(images) >= 14  # every figure of the report
    for img in images:
        loaded = driver.execute_script(
            "return arguments[0].complete && arguments[0].naturalWidth", img)
        assert loaded and loaded > 0, img.get_attribute("alt")
    errors = [e for e in driver.get_log("browser") if e["level"] in ("SEVERE", "ERROR")]
    assert errors == []
    assert driver.find_element(By.ID, "reproduced-table-paper").is_displayed()
    assert driver.find_element(By.ID, "findings").is_displayed()
    # no horizontal overflow: the page is no wider than the window (wide tables scroll
    # inside their own box)
    assert driver.execute_script(
        "return document.documentElement.scrollWidth <= window.innerWidth")
    assert driver.save_screenshot(str(tmp_path / "report.png"))


#: The numbers of the findings that name one row and column of metrics.json, as the page
#: holds them (read in the browser).
_SPANS_JS = """
return Array.from(document.querySelectorAll('#findings span.v')).map(s => ({
  src: s.dataset.src, op: s.dataset.op, value: parseFloat(s.dataset.value),
  digits: parseInt(s.dataset.digits), scale: parseFloat(s.dataset.scale),
  text: s.textContent, visible: s.offsetWidth > 0}));
"""


def test_findings_numbers_equal_metrics_json(driver, preset_report, preset_results):
    import json

    driver.set_window_size(1400, 1000)
    driver.get(preset_report.as_uri())
    spans = driver.execute_script(_SPANS_JS)
    assert spans and all(s["visible"] for s in spans)
    checked = 0
    for s in spans:
        shown = s["value"] * s["scale"]
        assert s["text"].lstrip("+") == (f"{shown:,.0f}" if s["digits"] == 0
                                         else f"{shown:.{s['digits']}f}").lstrip("+"), s
        preset, rest = s["src"].split("/", 1)
        if s["op"] == "" and rest.startswith("metrics.json:"):
            model, col = rest[len("metrics.json:"):].rsplit(":", 1)
            doc = json.loads((preset_results / preset / "metrics.json").read_text())
            row = next(r for r in doc["metrics"] if r["model"] == model)
            assert abs(row[col] - s["value"]) <= 1e-9 * max(1.0, abs(row[col])), s
            checked += 1
    assert checked >= 20


def test_no_overflow_at_1400px_and_unique_ids(driver, preset_report):
    driver.set_window_size(1400, 1000)
    driver.get(preset_report.as_uri())
    assert driver.execute_script(
        "return document.documentElement.scrollWidth <= window.innerWidth")
    # the main table fits without its own scroll bar
    assert driver.execute_script(
        "const t = document.getElementById('reproduced-table-paper');"
        "return t.parentElement.scrollWidth <= t.parentElement.clientWidth")
    dup = driver.execute_script(
        "const ids = Array.from(document.querySelectorAll('[id]')).map(e => e.id);"
        "return ids.filter((x, i) => ids.indexOf(x) !== i)")
    assert dup == []


def test_print_keeps_every_column(driver, preset_report):
    """In print media the collapsed full table opens and every column is laid out."""
    import base64

    driver.set_window_size(1400, 1000)
    driver.get(preset_report.as_uri())
    driver.execute_cdp_cmd("Emulation.setEmulatedMedia", {"media": "print"})
    try:
        cols = driver.execute_script(
            "const t = document.getElementById('reproduced-table-full-paper');"
            "const body = document.body.getBoundingClientRect();"
            "return Array.from(t.querySelectorAll('thead th')).map(th => {"
            "  const r = th.getBoundingClientRect();"
            "  return [th.textContent, r.width > 0 && th.checkVisibility(),"
            "          r.right <= body.right + 1]; })")
    finally:
        driver.execute_cdp_cmd("Emulation.setEmulatedMedia", {"media": ""})
    assert len(cols) >= 10
    assert all(shown and inside for _, shown, inside in cols), cols
    pdf = driver.execute_cdp_cmd("Page.printToPDF", {"paperWidth": 8.27, "paperHeight": 11.69})
    assert base64.b64decode(pdf["data"])[:5] == b"%PDF-"


def test_figures_open_full_size_on_a_phone(driver, report):
    """At 400 px a figure is shown at its natural width in its own scroll box; the page
    itself does not scroll sideways."""
    driver.set_window_size(400, 900)
    try:
        driver.get(report.as_uri())
        widths = driver.execute_script(
            "return Array.from(document.querySelectorAll('figure .zoom img')).map(i => ["
            "  i.getBoundingClientRect().width, i.naturalWidth,"
            "  i.parentElement.clientWidth, getComputedStyle(i.parentElement).overflowX])")
        assert widths and all(abs(w - nat) < 1 and box < nat and ov == "auto"
                              for w, nat, box, ov in widths), widths
        assert driver.execute_script(
            "return document.documentElement.scrollWidth <= window.innerWidth")
        assert driver.execute_script(
            "return getComputedStyle(document.querySelector('.zoom-hint')).display") == "block"
    finally:
        driver.set_window_size(1400, 1000)
    driver.get(report.as_uri())
    assert driver.execute_script(  # on a wide screen the figures fit the column again
        "const i = document.querySelector('figure .zoom img');"
        "return i.getBoundingClientRect().width <= i.parentElement.clientWidth + 1")

# Long-running (whole studies, end-to-end runs, Monte Carlo or every model): `make test-slow`,
# which CI runs beside the fast `make test` (tests/test_slow_marks.py)
pytestmark = [pytestmark, pytest.mark.slow]
