"""The dashboard on a service with API tokens: it asks for the token when the API
answers 401, keeps it in the tab's session storage (not in local storage, not in the
URL) and then lists only that owner's jobs."""
from __future__ import annotations

import sys
from pathlib import Path

import httpx
import pytest
from playwright.sync_api import expect

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "security"))
sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "integration"))

from secure_service import TOKENS, bearer, shared_secure_service  # noqa: E402
from service_support import two_disks  # noqa: E402

VIEWPORT = {"width": 1280, "height": 860}


@pytest.fixture(scope="module")
def secure(pytestconfig, tmp_path_factory):
    return shared_secure_service(pytestconfig, tmp_path_factory)


def _submit(url: str, owner: str, name: str) -> str:
    with httpx.Client(base_url=url, timeout=60, headers=bearer(owner)) as client:
        answer = client.post("/v1/jobs", json={"scene": two_disks(name, end=0.01)})
        assert answer.status_code == 202, answer.text
        return answer.json()["id"]


def test_the_dashboard_asks_for_the_token_and_shows_only_the_owners_jobs(browser, secure):
    _submit(secure.url, "alice", "alice-in-the-browser")
    _submit(secure.url, "bob", "bob-in-the-browser")
    context = browser.new_context(viewport=VIEWPORT, base_url=secure.url)
    page = context.new_page()
    page.set_default_timeout(30_000)
    errors: list[str] = []
    page.on("pageerror", lambda error: errors.append(str(error)))
    try:
        page.goto("/#/jobs")
        expect(page.locator("#banner")).to_contain_text("needs an API token")
        page.get_by_label("API token").fill(TOKENS["alice"])
        page.get_by_role("button", name="Save").click()

        expect(page.locator("tr.job-row", has_text="alice-in-the-browser")).to_be_visible()
        expect(page.locator("tr.job-row", has_text="bob-in-the-browser")).to_have_count(0)
        names = page.locator("tr.job-row").all_inner_texts()
        assert names and not any("bob" in text for text in names)

        assert page.evaluate("sessionStorage.getItem('mpm.token')") == TOKENS["alice"]
        assert page.evaluate("localStorage.getItem('mpm.token')") is None
        assert TOKENS["alice"] not in page.url
    finally:
        context.close()
    assert not errors, f"script errors in the dashboard: {errors}"
