"""The dashboard's layout at a phone's width (400 px) and a laptop's (1280 px), measured in the
browser: nothing wider than the window, the job page's title, actions, figures and progress bar
inside their card, the job list scrolling sideways with a cue, the energy plots' text the same
size on the job and the sweep page, a sweep's energy columns apart; and a Karamelo input file
opened in the new-job form."""
from __future__ import annotations

import contextlib
import json
import re
from pathlib import Path

import pytest
from playwright.sync_api import Page, expect

import live_scenes
from mpm_client import Conflict
from solver.karamelo import translate_file

PHONE = {"width": 400, "height": 860}
LAPTOP = {"width": 1280, "height": 860}
SIZES = pytest.mark.parametrize("size", [PHONE, LAPTOP], ids=["400px", "1280px"])
LONG_NAME = "A long running job with a name long enough to wrap on a phone"
KARAMELO = Path(__file__).resolve().parents[1] / "data" / "karamelo"
SPEED = "/bodies/0/initial_velocity/0"


@pytest.fixture(scope="module")
def running(sdk, example):
    """A job that runs for minutes (Cancel enabled, a progress bar short of its end); cancelled after."""
    job = sdk.submit(live_scenes.long(example, LONG_NAME))
    yield job
    with contextlib.suppress(Conflict):   # it may have finished
        job.cancel()


@pytest.fixture(scope="module")
def finished_sweep(sdk, example):
    scene = live_scenes.quick(example, "Layout sweep")
    scene["time"]["end"] = 0.3
    sweep = sdk.sweep(scene, {SPEED: [0.05, 0.1]})
    sweep.wait(timeout=240, progress=False)
    return sweep


def box(page: Page, selector: str) -> dict:
    found = page.locator(selector).first.bounding_box()
    assert found is not None, f"{selector} is not displayed"
    return found


def inside(inner: dict, outer: dict, what: str) -> None:
    """`inner` within `outer` (bounding boxes; half a pixel for rounding)."""
    assert inner["x"] >= outer["x"] - 0.5 and inner["x"] + inner["width"] <= outer["x"] + outer["width"] + 0.5, \
        f"{what}: {inner} is not inside {outer}"


def no_page_overflow(page: Page) -> None:
    width = page.evaluate("document.documentElement.scrollWidth")
    assert width <= page.viewport_size["width"], f"the page is {width} px wide in a {page.viewport_size['width']} px window"


@SIZES
def test_the_job_page_fits_the_window(page: Page, running, size, screenshot_dir):
    page.set_viewport_size(size)
    page.goto(f"/#/jobs/{running.id}")
    expect(page.locator(".job-head .badge")).to_have_text("running", timeout=60_000)
    no_page_overflow(page)
    card = box(page, ".job-head")
    inside(card, {"x": 0, "width": size["width"]}, "the job's card")
    # the title beside the buttons on one line, or (when it wraps) the card's whole width, not a
    # column squeezed beside them (a word a line): then its longest line is most of the card's
    content = page.locator(".job-head").evaluate(
        "node => node.clientWidth - parseFloat(getComputedStyle(node).paddingLeft) - parseFloat(getComputedStyle(node).paddingRight)")
    lines = page.locator(".job-head h1").evaluate("""node => {
        const range = document.createRange(); range.selectNodeContents(node);
        const rects = [...range.getClientRects()];
        return [new Set(rects.map(r => Math.round(r.top))).size, Math.max(...rects.map(r => r.width))]; }""")
    if lines[0] > 1:
        assert box(page, ".job-head .job-title")["width"] >= content - 1
        assert lines[1] >= 0.6 * content, f"the title's longest line is {lines[1]} px of {content}"
    for name in ("Cancel", "Download HDF5", "Delete"):
        button = page.locator(".job-head .actions").get_by_role("button", name=name)
        expect(button).to_be_visible()
        inside(button.bounding_box(), card, f"the {name} button")
    for figure in page.locator(".job-head .stats > div").all():
        inside(figure.bounding_box(), card, f"the figure {figure.locator('dt').inner_text()}")
        dd = figure.locator("dd")
        assert dd.evaluate("node => node.scrollWidth <= node.clientWidth"), f"{dd.inner_text()} is clipped"
    progress = box(page, ".job-head .progress")
    inside(progress, card, "the progress bar")
    inside(box(page, ".job-head .progress-label"), card, "the progress label")
    for section in page.locator("main section.card").all():
        inside(section.bounding_box(), {"x": 0, "width": size["width"]}, "a card")
    page.screenshot(path=str(screenshot_dir / f"dashboard-job-{size['width']}.png"), full_page=True)


def test_the_job_list_on_a_phone_scrolls_sideways_with_a_cue(page: Page, running):
    page.set_viewport_size(PHONE)
    page.goto("/#/jobs")
    expect(page.locator(f"tr.job-row[data-id='{running.id}']")).to_be_visible()
    no_page_overflow(page)
    wrap = page.locator(".table-wrap")
    assert wrap.evaluate("node => node.scrollWidth > node.clientWidth"), "the table fits: nothing to test"
    hint = page.locator(".scroll-hint")
    expect(hint).to_be_visible()
    inside(hint.bounding_box(), {"x": 0, "width": PHONE["width"]}, "the hint")
    fade = page.locator(".table-fade.right")
    expect(fade).to_have_css("opacity", "1")
    # scrolled to the end: the last column (Age) in sight and the shadow on the right gone. The
    # column is measured in the same task as the scroll: the list re-renders as the ages grow, and
    # a wider Age column moves the end (measured after, it once stuck out 9 px on a loaded machine)
    ends = wrap.evaluate("""node => {
        node.scrollLeft = node.scrollWidth;
        const age = node.querySelector("table.jobs th:last-child").getBoundingClientRect();
        const wrap = node.getBoundingClientRect();
        return {age: {x: age.x, width: age.width}, wrap: {x: wrap.x, width: wrap.width}};
    }""")
    inside(ends["age"], ends["wrap"], "the Age column")
    expect(fade).to_have_css("opacity", "0")
    expect(page.locator(".table-fade.left")).to_have_css("opacity", "1")


def test_the_job_list_on_a_laptop_has_no_scroll_cue(page: Page, running):
    page.set_viewport_size(LAPTOP)
    page.goto("/#/jobs")
    expect(page.locator(f"tr.job-row[data-id='{running.id}']")).to_be_visible()
    expect(page.locator(".scroll-hint")).to_be_hidden()
    expect(page.locator(".table-fade.right")).to_have_css("opacity", "0")


def tick_font_height(page: Page) -> float:
    """The drawn height of the energy plot's tick labels (their size after the SVG is scaled)."""
    text = page.locator("svg.energy-plot .tick text").first
    expect(text).to_be_visible()
    return text.evaluate("node => node.getBoundingClientRect().height")


@SIZES
def test_the_plots_text_is_the_same_size_on_the_job_and_the_sweep_page(page: Page, finished_sweep, size):
    page.set_viewport_size(size)
    page.goto(f"/#/sweeps/{finished_sweep.id}")
    expect(page.locator("svg.energy-plot polyline.series")).to_have_count(2, timeout=60_000)
    no_page_overflow(page)
    on_sweep = tick_font_height(page)
    page.goto(f"/#/jobs/{finished_sweep.jobs[0]['id']}")
    expect(page.locator("svg.energy-plot polyline.series")).not_to_have_count(0, timeout=60_000)
    on_job = tick_font_height(page)
    # and on the job page the frame slider clear of its label ("frame 5 / 5 (t = 0.3)")
    expect(page.locator(".frame-label")).to_contain_text("frame")
    slider, label = box(page, ".frame-row input[type=range]"), box(page, ".frame-label")
    assert (slider["x"] + slider["width"] <= label["x"] or slider["y"] + slider["height"] <= label["y"]), (slider, label)
    # the same 11 px text on both: a tenth of a pixel for the renderer's rounding
    assert abs(on_sweep - on_job) <= 0.1, (on_sweep, on_job)


def test_a_sweeps_energy_columns_are_apart(page: Page, finished_sweep):
    page.set_viewport_size(LAPTOP)
    page.goto(f"/#/sweeps/{finished_sweep.id}")
    expect(page.locator("tr.sweep-job .badge").first).to_have_text("succeeded", timeout=60_000)
    for row in page.locator("tr.sweep-job").all():
        # the printed numbers (not their cells): each ends at least 12 px before the next begins
        spans = row.locator("td.energy").evaluate_all("""cells => cells.map(cell => {
            const range = document.createRange(); range.selectNodeContents(cell);
            const r = range.getBoundingClientRect(); return [r.left, r.right]; })""")
        for (_, right), (left, _) in zip(spans, spans[1:]):
            assert left - right >= 12, spans


def test_the_new_job_form_on_a_phone(page: Page):
    page.set_viewport_size(PHONE)
    page.goto("/#/new")
    no_page_overflow(page)
    card = box(page, "section.card")
    menu = page.get_by_label("example")
    expect(menu.locator("option")).not_to_have_count(1)  # the examples have arrived
    # the menu readable (its own line, not squeezed beside the buttons), everything in the card
    assert menu.bounding_box()["width"] >= 0.8 * card["width"] - 40
    for control in (menu, page.get_by_role("button", name="Open file…"), page.get_by_role("button", name="Mesh file…"),
                    page.get_by_label("scene JSON"), page.get_by_role("button", name="Submit")):
        inside(control.bounding_box(), card, control.evaluate("node => node.outerHTML.slice(0, 60)"))


def test_a_karamelo_file_opens_in_the_form_as_its_scene(page: Page, tmp_path):
    source = KARAMELO / "Cantilever__2D__cantilever_force_tip.mpm"
    expected = translate_file(source)
    assert expected.untranslated or expected.notes, "a file with lines to report: the test shows them"
    page.goto("/#/new")
    page.get_by_label("scene file").set_input_files(str(source))
    expect(page.locator(".imported")).to_contain_text("Imported Cantilever__2D__cantilever_force_tip.mpm")
    editor = page.get_by_label("scene JSON")
    expect(editor).to_have_value(re.compile('"bodies"'))
    assert json.loads(editor.input_value()) == json.loads(json.dumps(expected.scene))
    reported = page.locator("ul.import-lines li")
    expect(reported).to_have_count(len(expected.untranslated) + len(expected.notes))
    first = (expected.untranslated or expected.notes)[0]
    expect(reported.first).to_contain_text(f"line {first.line}")
    page.get_by_role("button", name="Validate").click()
    expect(page.locator(".valid")).to_contain_text("The scene is valid")


def test_a_karamelo_file_that_cannot_be_imported_says_which_line(page: Page):
    page.goto("/#/new")
    page.get_by_label("scene file").set_input_files(str(KARAMELO / "Vertical_bar__ULMPM__vertical_bar.mpm"))
    expect(page.locator(".errors-head")).to_contain_text("Vertical_bar__ULMPM__vertical_bar.mpm")
    expect(page.locator("ul.errors")).to_contain_text("line 34")
