"""Open the built site in headless Chromium, offline, as a reader would.

The site is served from a loopback HTTP server (127.0.0.1, an ephemeral port) and read by
Debian's ``chromium`` through ``chromium-driver`` and Selenium; nothing else is contacted. The
test asserts that the start page, an API page and a gallery page render with their images, that
the gallery's cards show their thumbnails and .ipynb downloads, that the live ROS 2 page's topic
tables fit a 1280 px window, and that the search page finds "Golombek".
``MARSSCENE_SITE_SHOTS=DIR`` also saves screenshots.
"""

from __future__ import annotations

import functools
import os
import shutil
import threading
from collections.abc import Iterator
from http.server import SimpleHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path
from typing import Any

import pytest

CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
CHROMEDRIVER = shutil.which("chromedriver")


def _need(condition: bool, why: str) -> None:
    if not condition:
        if os.environ.get("MARSSCENE_REQUIRE_SITE") == "1":
            pytest.fail(why)
        pytest.skip(why)


class _Quiet(SimpleHTTPRequestHandler):
    def log_message(self, format: str, *args: Any) -> None:
        pass


@pytest.fixture(scope="module")
def base_url(site_dir: Path) -> Iterator[str]:
    handler = functools.partial(_Quiet, directory=str(site_dir))
    server = ThreadingHTTPServer(("127.0.0.1", 0), handler)
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    try:
        yield f"http://127.0.0.1:{server.server_address[1]}"
    finally:
        server.shutdown()
        server.server_close()


@pytest.fixture(scope="module")
def browser() -> Iterator[Any]:
    try:
        from selenium import webdriver
        from selenium.webdriver.chrome.service import Service
    except ImportError:
        _need(False, "selenium is not installed (pip install -e '.[docs]')")
    _need(CHROMIUM is not None and CHROMEDRIVER is not None,
          "chromium and chromium-driver are not installed "
          "(apt-get install chromium chromium-driver)")
    opts = webdriver.ChromeOptions()
    opts.binary_location = str(CHROMIUM)
    for flag in ("--headless=new", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage",
                 "--disable-background-networking", "--disable-extensions", "--disable-sync",
                 "--no-first-run", "--disable-default-apps", "--window-size=1400,1000"):
        opts.add_argument(flag)
    driver = webdriver.Chrome(service=Service(executable_path=str(CHROMEDRIVER)), options=opts)
    driver.set_page_load_timeout(60)
    try:
        yield driver
    finally:
        driver.quit()


def _open(browser: Any, url: str, shot: str) -> None:
    browser.get(url)
    browser.execute_script("window.scrollTo(0, document.body.scrollHeight); window.scrollTo(0, 0);")
    folder = os.environ.get("MARSSCENE_SITE_SHOTS")
    if folder:
        Path(folder).mkdir(parents=True, exist_ok=True)
        browser.save_screenshot(str(Path(folder) / f"{shot}.png"))


def _images(browser: Any) -> list[dict[str, Any]]:
    """The article's images: source, whether loaded, natural width (lazy ones forced to load)."""
    return browser.execute_async_script("""
        const done = arguments[arguments.length - 1];
        const imgs = Array.from(document.querySelectorAll('article img'));
        imgs.forEach(i => { i.loading = 'eager'; });
        Promise.all(imgs.map(i => i.complete ? Promise.resolve() : new Promise(r => {
            i.addEventListener('load', r); i.addEventListener('error', r); })))
          .then(() => done(imgs.map(i => ({src: i.currentSrc, complete: i.complete,
                                            width: i.naturalWidth}))));
    """)


def _assert_images_render(browser: Any, at_least: int) -> None:
    imgs = _images(browser)
    assert len(imgs) >= at_least, imgs
    bad = [i["src"] for i in imgs if not i["complete"] or i["width"] == 0]
    assert not bad, f"images that did not render: {bad}"


def test_start_page_renders_with_its_image(browser: Any, base_url: str) -> None:
    _open(browser, f"{base_url}/index.html", "start")
    assert "marsscene" in browser.title
    _assert_images_render(browser, 1)
    text = browser.find_element("css selector", "article").text
    for card in ("Getting started", "User guide", "Gallery", "Science", "API reference"):
        assert card in text


def test_api_page_renders_the_docstring(browser: Any, base_url: str) -> None:
    _open(browser, f"{base_url}/api/generated/marsscene.drive.html", "api_drive")
    assert browser.find_element("css selector", "article h1").text.startswith("marsscene.drive")
    sig = browser.find_element("css selector", "dl.py.function dt.sig")
    assert "drive(" in sig.text.replace(" ", "")
    body = browser.find_element("css selector", "dl.py.function dd").text
    assert "Parameters" in body and "waypoints" in body and "Returns" in body


def test_gallery_pages_render_their_figures(browser: Any, base_url: str) -> None:
    _open(browser, f"{base_url}/gallery.html", "gallery")
    links = browser.find_elements("css selector", "article a[href*='notebooks/']")
    assert len({a.get_attribute("href") for a in links}) >= 11
    _open(browser, f"{base_url}/notebooks/02_craters.html", "gallery_craters")
    _assert_images_render(browser, 3)
    _open(browser, f"{base_url}/getting_started.html", "getting_started")
    _assert_images_render(browser, 2)


def test_gallery_cards_have_thumbnails_and_downloads(browser: Any, base_url: str) -> None:
    _open(browser, f"{base_url}/gallery.html", "gallery_cards")
    thumbs = browser.find_elements("css selector", "article .sd-card img.gallery-thumb")
    assert len(thumbs) >= 11
    _assert_images_render(browser, 11)
    downloads = browser.find_elements("css selector", "article .sd-card a.download")
    assert len(downloads) == len(thumbs)
    assert all(a.get_attribute("href").endswith(".ipynb") for a in downloads)


def test_ros2_topic_tables_fit_at_1280_px(browser: Any, base_url: str) -> None:
    browser.set_window_size(1280, 1000)
    try:
        _open(browser, f"{base_url}/ros2_live.html", "ros2_live_1280")
        widths = browser.execute_script(
            "return Array.from(document.querySelectorAll('#topics table'))"
            ".map(t => [t.scrollWidth, t.clientWidth]);")
    finally:
        browser.set_window_size(1400, 1000)
    assert len(widths) >= 2
    assert all(scroll <= client + 1 for scroll, client in widths), widths


def test_search_finds_golombek(browser: Any, base_url: str) -> None:
    from selenium.webdriver.support.ui import WebDriverWait

    _open(browser, f"{base_url}/search.html?q=Golombek", "search")

    def results(driver: Any) -> list[Any]:
        return driver.find_elements("css selector", "#search-results li a")

    found = WebDriverWait(browser, 30).until(results)
    hrefs = [a.get_attribute("href") for a in found]
    assert any("science/rocks.html" in h for h in hrefs), hrefs
