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
    assert driver.find_element(By.ID, "reproduced-table").is_displayed()
    # no horizontal overflow: the page is no wider than the window (wide tables scroll
    # inside their own box)
    assert driver.execute_script(
        "return document.documentElement.scrollWidth <= window.innerWidth")
    assert driver.save_screenshot(str(tmp_path / "report.png"))
