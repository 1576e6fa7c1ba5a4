"""Fixtures of the dashboard tests: Debian's headless Chromium driven by Playwright,
against the same live service as the SDK tests (`mpm serve`, see
tests/clients/live_service.py). A missing browser fails the tests; it never skips them."""
from __future__ import annotations

import os
import sys
from pathlib import Path
from typing import Iterator

import pytest

# The live service and its scenes are shared with the SDK tests, one service per session.
sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "clients"))

import live_scenes  # noqa: E402
from live_service import LiveService, shared_service  # noqa: E402
from mpm_client import Client  # noqa: E402

CHROMIUM = Path(os.environ.get("MPM_CHROMIUM", "/usr/bin/chromium"))
# --enable-unsafe-swiftshader: WebGL (the results viewer) on the CPU, as there is no GPU here;
# recent Chromium versions no longer fall back to it by themselves.
CHROMIUM_ARGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
                 "--disable-background-networking", "--disable-component-update", "--disable-sync",
                 "--enable-unsafe-swiftshader"]
VIEWPORT = {"width": 1280, "height": 860}
SCREENSHOTS = Path(__file__).resolve().parents[2] / "docs" / "images"


@pytest.fixture(scope="session")
def live(pytestconfig: pytest.Config, tmp_path_factory: pytest.TempPathFactory) -> LiveService:
    return shared_service(pytestconfig, tmp_path_factory)


@pytest.fixture(scope="module")
def sdk(live):
    with Client(live.url, timeout=60) as client:
        yield client


@pytest.fixture(scope="module")
def example(sdk) -> dict:
    return sdk.example(live_scenes.EXAMPLE)


@pytest.fixture(scope="module")
def browser():
    """Module scope: Playwright's sync API keeps an event loop running in this thread
    while it is open, and the SDK's async tests that run later need it closed."""
    try:
        from playwright.sync_api import sync_playwright
    except ImportError:
        pytest.fail("the dashboard tests need Playwright for Python: pip install playwright "
                    "(never `playwright install`: they drive the system's Chromium)")
    if not CHROMIUM.is_file():
        pytest.fail(f"the dashboard tests need Chromium at {CHROMIUM}: apt-get install -y chromium "
                    "(or set MPM_CHROMIUM to another Chromium binary)")
    with sync_playwright() as playwright:
        browser = playwright.chromium.launch(executable_path=str(CHROMIUM), args=CHROMIUM_ARGS)
        yield browser
        browser.close()


@pytest.fixture
def page(browser, live) -> Iterator:
    """A fresh tab on the dashboard; fails the test on any uncaught script error."""
    context = browser.new_context(viewport=VIEWPORT, accept_downloads=True, base_url=live.url)
    page = context.new_page()
    page.set_default_timeout(30_000)
    errors: list[str] = []
    page.on("pageerror", lambda error: errors.append(str(error)))
    yield page
    context.close()
    assert not errors, f"script errors in the dashboard: {errors}"


@pytest.fixture(scope="session")
def screenshot_dir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """docs/images when MPM_UPDATE_SCREENSHOTS=1 (to refresh the README's), else a temp folder."""
    if os.environ.get("MPM_UPDATE_SCREENSHOTS") == "1":
        SCREENSHOTS.mkdir(parents=True, exist_ok=True)
        return SCREENSHOTS
    return tmp_path_factory.mktemp("screenshots")
