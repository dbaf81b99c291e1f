"""The live view in a real headless browser (Debian's chromium via selenium): the page shows the picture and follows it.

CI installs the browser with ``apt-get install chromium chromium-driver`` (see ``.ci/run``); without it these
tests skip, naming what is missing.
"""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from pixelpen.sim.view import ViewServer
from tests.sim.test_view import StubSource, pattern

CHROMIUM = Path("/usr/bin/chromium")
CHROMEDRIVER = Path("/usr/bin/chromedriver")
WAIT_S = 10.0

webdriver = pytest.importorskip("selenium.webdriver", reason="selenium is not installed (pip install selenium)")
if not (CHROMIUM.exists() and CHROMEDRIVER.exists()):
    pytest.skip(f"needs {CHROMIUM} and {CHROMEDRIVER} (Debian: apt-get install chromium chromium-driver)",
                allow_module_level=True)

from selenium.webdriver.chrome.service import Service  # noqa: E402 - only once the browser is known to exist
from selenium.webdriver.support.ui import WebDriverWait  # noqa: E402

READ_PIXELS = """
const img = document.getElementById("frame");
if (!img.complete || img.naturalWidth === 0) return null;
const canvas = document.createElement("canvas");
canvas.width = img.naturalWidth; canvas.height = img.naturalHeight;
const context = canvas.getContext("2d");
context.drawImage(img, 0, 0);
const data = context.getImageData(0, 0, canvas.width, canvas.height).data;
return {frame: Number(img.dataset.frame), width: canvas.width, height: canvas.height, rgba: Array.from(data)};
"""
"""The pixels the page's <img> shows now, at its natural size (the page scales small panels up for the eye)."""


@pytest.fixture
def browser(tmp_path):
    options = webdriver.ChromeOptions()
    options.binary_location = str(CHROMIUM)
    for flag in ("--headless=new", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage", "--no-first-run",
                 "--disable-background-networking", "--disable-component-update", "--disable-sync",
                 f"--user-data-dir={tmp_path / 'profile'}"):
        options.add_argument(flag)
    driver = webdriver.Chrome(service=Service(str(CHROMEDRIVER)), options=options)
    driver.set_page_load_timeout(WAIT_S)
    try:
        yield driver
    finally:
        driver.quit()
        shutil.rmtree(tmp_path / "profile", ignore_errors=True)


def shows(picture: Image.Image):
    """A wait condition: the page's image holds exactly ``picture`` (its frame number then)."""
    want = np.asarray(picture.convert("RGBA"))

    def check(driver) -> int | bool:
        got = driver.execute_script(READ_PIXELS)
        if got is None or (got["width"], got["height"]) != picture.size:
            return False
        rgba = np.array(got["rgba"], dtype=np.uint8).reshape(got["height"], got["width"], 4)
        return got["frame"] if np.array_equal(rgba, want) else False

    return check


def test_the_page_shows_the_picture_and_follows_it_without_reload(browser):
    source = StubSource(pattern(11, (40, 30)))
    source.counters.update(bytes=172808, transfers=43, bus_seconds=0.022)
    with ViewServer(source, max_fps=20) as view:
        browser.get(view.url)
        first = WebDriverWait(browser, WAIT_S).until(shows(pattern(11, (40, 30))))
        assert first == 1
        WebDriverWait(browser, WAIT_S).until(lambda d: "172808" in d.find_element("id", "stats").text)
        text = browser.find_element("id", "stats").text
        assert "bytes 172808" in text and "transfers 43" in text and "bus_seconds 0.022" in text
        assert browser.find_element("id", "status").text == "live"

        browser.execute_script("window.notReloaded = true;")
        source.counters.update(bytes=173000, transfers=44)
        source.show(pattern(12, (40, 30)))
        second = WebDriverWait(browser, WAIT_S).until(shows(pattern(12, (40, 30))))
        assert second == 2
        WebDriverWait(browser, WAIT_S).until(lambda d: "bytes 173000" in d.find_element("id", "stats").text)
        assert browser.execute_script("return window.notReloaded === true;")
        assert browser.find_element("tag name", "title").get_attribute("textContent").startswith("stub <glass>")
