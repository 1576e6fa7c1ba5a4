"""The dashboard in headless Chromium against a live service: submit through the
form and watch the job succeed, its preview and energy plot, cancel a long job,
validation errors next to their fields, the status filter, download and delete,
the lost-connection banner and the polling back-off, a mesh file attached beside the scene."""
from __future__ import annotations

import json
import re
from pathlib import Path

import pytest
from playwright.sync_api import Page, expect

import live_scenes
from mpm_client import JobCancelled, JobFailed

HDF5_SIGNATURE = b"\x89HDF\r\n\x1a\n"


def fill_scene(page: Page, scene: dict) -> None:
    page.goto("/#/new")
    page.get_by_label("scene JSON").fill(json.dumps(scene, indent=2))


def open_job(page: Page, job_id: str) -> None:
    page.goto(f"/#/jobs/{job_id}")
    expect(page.locator("code.id")).to_have_text(job_id)


def screenshot(page: Page, last: str, path: Path) -> None:
    """The page from the top down to a little below the element `last`."""
    viewport = page.viewport_size
    page.set_viewport_size({"width": viewport["width"], "height": 1400})
    box = page.locator(last).bounding_box()
    page.screenshot(path=str(path), clip={"x": 0, "y": 0, "width": viewport["width"],
                                          "height": box["y"] + box["height"] + 28})
    page.set_viewport_size(viewport)


def test_submit_through_the_form_and_watch_it_succeed(page: Page, example, screenshot_dir):
    page.goto("/#/new")
    page.get_by_label("example").select_option(live_scenes.EXAMPLE)
    editor = page.get_by_label("scene JSON")
    expect(editor).to_have_value(re.compile(r'"bodies"'))
    # long enough (about 14 000 steps) to be seen running; a few frames for the slider
    scene = live_scenes.slower(json.loads(editor.input_value()), "Two disks (dashboard)", 4.0, frames=16)
    editor.fill(json.dumps(scene, indent=2))

    page.get_by_role("button", name="Validate").click()
    expect(page.locator(".valid")).to_contain_text("valid")
    expect(page.locator(".summary")).to_contain_text("Particles")

    page.get_by_role("button", name="Submit").click()
    page.wait_for_url(re.compile(r"#/jobs/[0-9a-f-]{36}$"))
    expect(page.locator("h1")).to_have_text("Two disks (dashboard)")

    # running: a progress bar short of 100 % and the viewer on the latest frame
    expect(page.locator(".job-head .badge")).to_have_text("running", timeout=60_000)
    percent = float(page.locator(".job-head .progress-label").inner_text().rstrip("%"))
    assert 0.0 <= percent < 100.0
    expect(page.locator(".viewer-stage[data-ready] canvas")).to_be_visible(timeout=30_000)

    badge = page.locator(".job-head .badge")
    expect(badge).to_have_text(re.compile("succeeded|failed|cancelled"), timeout=120_000)
    assert badge.text_content() == "succeeded", page.locator(".diagnostic").text_content()
    expect(page.locator(".job-head .progress-label")).to_have_text("100.0%")

    # the energy plot: kinetic, strain, total and the balance, each a line of many points, and the balance error
    lines = page.locator("svg.energy-plot polyline.series")
    expect(lines).to_have_count(4)
    for i in range(4):
        assert len(lines.nth(i).get_attribute("points").split()) > 100
    expect(page.locator("p.balance-error")).to_contain_text("Energy balance error now:")

    # frames and fields of the finished job: the slider, its label and the image agree
    slider = page.get_by_label("frame")
    expect(slider).to_have_attribute("max", "15")
    assert slider.input_value() == "15"
    expect(page.locator(".viewer-stage")).to_have_attribute("data-frame", "15")
    slider.fill("0")
    expect(page.locator(".frame-label")).to_have_text("frame 0 / 15 (t = 0)")
    expect(page.locator(".viewer-stage")).to_have_attribute("data-frame", "0")
    page.locator('.tab[data-mode="image"]').click()
    image = page.locator("img.preview-image")
    expect(image).to_have_attribute("data-frame", "0")
    expect(image).to_be_visible()
    page.get_by_label("field").select_option("von_mises")
    page.wait_for_function("document.querySelector('img.preview-image').naturalWidth > 0")
    expect(page.locator(".scene pre.json")).to_contain_text('"Two disks (dashboard)"')

    slider.fill("15")
    page.get_by_label("field").select_option("velocity_magnitude")
    expect(image).to_have_attribute("data-frame", "15")
    expect(image).to_have_attribute("data-field", "velocity_magnitude")
    screenshot(page, "div.columns", screenshot_dir / "dashboard-job.png")


def test_a_long_job_is_cancelled_from_its_page(page: Page, sdk, example):
    job = sdk.submit(live_scenes.long(example, "Long run (cancelled)"))
    open_job(page, job.id)
    expect(page.locator(".job-head .badge")).to_have_text("running", timeout=60_000)
    cancel = page.get_by_role("button", name="Cancel")
    expect(cancel).to_be_enabled()
    cancel.click()
    expect(page.locator(".job-head .badge")).to_have_text("cancelled", timeout=60_000)
    expect(cancel).to_be_disabled()
    expect(page.get_by_role("button", name="Download HDF5")).to_be_enabled()
    assert sdk.job(job.id).record.status == "cancelled"


def test_validation_errors_appear_next_to_their_fields(page: Page, example):
    scene = live_scenes.invalid(example)
    material = next(iter(scene["materials"]))
    fill_scene(page, scene)
    for button in ("Validate", "Submit"):  # the service rejects a submitted scene the same way
        page.get_by_role("button", name=button).click()
        radius = page.locator('.annotated .line[data-path="bodies[0].geometry.radius"]')
        expect(radius.locator(".field-error")).to_contain_text("must be > 0")
        expect(radius).to_contain_text('"radius": -0.2')
        poisson = page.locator(f'.annotated .line[data-path="materials.{material}.poisson_ratio"]')
        expect(poisson.locator(".field-error")).to_contain_text("0.5")
        expect(page.locator(".annotated .field-error")).to_have_count(2)
        expect(page.locator("ul.errors li")).to_have_count(2)
    assert "#/new" in page.url  # nothing was submitted

    page.get_by_label("scene JSON").fill('{"version": 1,,}')
    page.get_by_role("button", name="Validate").click()
    expect(page.locator(".outcome")).to_contain_text("not valid JSON")


def test_a_failed_job_shows_the_solver_diagnostic(page: Page, sdk, example):
    job = sdk.submit(live_scenes.unstable(example, "Time step too large"))
    with pytest.raises(JobFailed):
        job.wait(timeout=120, poll=0.2, progress=False)
    open_job(page, job.id)
    expect(page.locator(".job-head .badge")).to_have_text("failed")
    expect(page.locator(".diagnostic")).to_contain_text(job.record.error)


def test_download_and_delete_a_finished_job(page: Page, sdk, example, tmp_path):
    job = sdk.submit(live_scenes.quick(example, "Downloaded then deleted"))
    job.wait(timeout=120, poll=0.2, progress=False)
    open_job(page, job.id)
    expect(page.locator(".job-head .badge")).to_have_text("succeeded")
    with page.expect_download() as download:
        page.get_by_role("button", name="Download HDF5").click()
    saved = tmp_path / download.value.suggested_filename
    download.value.save_as(saved)
    assert saved.name == "Downloaded then deleted.h5"
    assert saved.read_bytes()[:8] == HDF5_SIGNATURE

    page.once("dialog", lambda dialog: dialog.accept())
    page.get_by_role("button", name="Delete").click()
    page.wait_for_url(re.compile(r"#/jobs$"))
    expect(page.locator(f'tr[data-id="{job.id}"]')).to_have_count(0)


def test_the_job_table_filters_by_status_and_backs_off_when_idle(page: Page, sdk, example):
    for name in ("bar_vibration", "column_under_gravity_2d"):
        sdk.submit(sdk.example(name)).wait(timeout=180, poll=0.2, progress=False)
    with pytest.raises(JobCancelled):
        sdk.submit(live_scenes.long(example, "Cancelled at once")).cancel().wait(timeout=60, progress=False)
    page.goto("/#/jobs")
    expect(page.locator("tr.job-row").first).to_be_visible()
    statuses = page.locator("tr.job-row").evaluate_all("rows => rows.map(r => r.dataset.status)")
    assert {"succeeded", "cancelled"} <= set(statuses)

    page.locator('.chip[data-status="cancelled"]').click()
    expect(page.locator(".chip.active")).to_have_text("cancelled")
    rows = page.locator("tr.job-row")
    expect(rows.first).to_be_visible()
    assert set(rows.evaluate_all("rows => rows.map(r => r.dataset.status)")) == {"cancelled"}

    # nothing runs: the poll interval doubles from 1 s towards 15 s
    page.wait_for_function("Number(document.body.dataset.pollDelay) >= 4000", timeout=20_000)
    # a hidden tab polls at most every 30 s
    page.evaluate("""() => {
        Object.defineProperty(document, "hidden", {value: true, configurable: true});
        document.dispatchEvent(new Event("visibilitychange"));
    }""")
    page.wait_for_function("Number(document.body.dataset.pollDelay) >= 30000", timeout=20_000)


def test_a_lost_connection_shows_a_banner_and_recovers(page: Page):
    page.goto("/#/jobs")
    expect(page.locator("tr.job-row").first).to_be_visible()
    page.route("**/v1/**", lambda route: route.abort("connectionrefused"))
    banner = page.locator("#banner")
    expect(banner).to_contain_text("Lost the connection", timeout=30_000)
    page.unroute("**/v1/**")
    page.get_by_role("button", name="Retry now").click()
    expect(banner).to_contain_text("Connection restored")
    expect(banner).to_be_hidden(timeout=10_000)
    expect(page.locator("tr.job-row").first).to_be_visible()


def test_the_job_table_while_a_job_runs(page: Page, sdk, example, screenshot_dir):
    job = sdk.submit(live_scenes.long(example, "Two disks, long run"))
    page.goto("/#/jobs")
    row = page.locator(f'tr[data-id="{job.id}"]')
    expect(row.locator(".badge")).to_have_text("running", timeout=60_000)
    expect(row.locator(".progress-label")).not_to_have_text("0.0%", timeout=30_000)
    # something runs: the table polls every second (it backs off after a slow or failed request)
    page.wait_for_function("document.body.dataset.pollDelay === '1000'", timeout=20_000)
    expect(row.locator("td").nth(4)).not_to_have_text("–")  # steps/s
    screenshot(page, "main section.card", screenshot_dir / "dashboard-jobs.png")
    job.cancel()
    expect(row.locator(".badge")).to_have_text("cancelled", timeout=60_000)


SPEED = "/bodies/0/initial_velocity/0"  # the first disk's x velocity: each job its own kinetic energy


def test_a_sweep_page_shows_its_jobs_side_by_side_and_overlays_their_energies(page: Page, sdk, example,
                                                                               screenshot_dir):
    scene = live_scenes.quick(example, "Speed sweep")
    scene["time"]["end"] = 0.3
    sweep = sdk.sweep(scene, {SPEED: [0.05, 0.1, 0.2]})
    page.goto("/#/sweeps")
    expect(page.locator(f"tr.sweep-row[data-id='{sweep.id}']")).to_contain_text("Speed sweep")
    page.locator(f"tr.sweep-row[data-id='{sweep.id}'] a").click()
    expect(page.locator("code.id")).to_have_text(sweep.id)
    rows = page.locator("tr.sweep-job")
    expect(rows).to_have_count(3)
    expect(page.locator(".job-head .badge")).to_have_text("finished", timeout=120_000)
    for k, (job, speed) in enumerate(zip(sweep.jobs, ["0.05", "0.1", "0.2"])):
        expect(rows.nth(k)).to_contain_text(job["id"][:8])
        expect(rows.nth(k).locator("td").nth(1)).to_have_text(speed)
        expect(rows.nth(k).locator(".badge")).to_have_text("succeeded")
    lines = page.locator("svg.energy-plot polyline.series")
    expect(lines).to_have_count(3)
    labels = [lines.nth(k).get_attribute("data-label") for k in range(3)]
    assert labels == [f"{SPEED} = {v}" for v in (0.05, 0.1, 0.2)]
    assert len({lines.nth(k).get_attribute("points") for k in range(3)}) == 3  # three different curves
    screenshot(page, "svg.energy-plot", screenshot_dir / "dashboard-sweep.png")
    rows.nth(0).locator("a").click()
    expect(page.locator("code.id")).to_have_text(sweep.jobs[0]["id"])


def test_the_job_page_shows_the_solver_log(page: Page, sdk, example):
    job = sdk.submit(live_scenes.unstable(example, "Blows up (log)"))
    open_job(page, job.id)
    expect(page.locator(".job-head .badge")).to_have_text("failed", timeout=120_000)
    text, _ = job.log()
    assert "ended early" in text
    log = page.get_by_label("solver log")
    expect(log).to_contain_text("ended early")
    assert log.text_content() == text  # every line once


def test_a_mesh_file_beside_the_scene_is_sent_as_data(page: Page, sdk, tmp_path):
    """A scene naming a mesh file: the form asks for the file, then sends its bytes inlined
    (the service refuses a path), and the job runs the part."""
    corner = [(i, j, k) for k in (0, 1) for j in (0, 1) for i in (0, 1)]   # the unit cube's 8 corners
    faces = [(0, 2, 3), (0, 3, 1), (4, 5, 7), (4, 7, 6), (0, 1, 5), (0, 5, 4),
             (1, 3, 7), (1, 7, 5), (3, 2, 6), (3, 6, 7), (2, 0, 4), (2, 4, 6)]
    facets = "".join("facet normal 0 0 0\nouter loop\n" + "".join("vertex %d %d %d\n" % corner[v] for v in face)
                     + "endloop\nendfacet\n" for face in faces)
    (tmp_path / "cube.stl").write_text(f"solid cube\n{facets}endsolid cube\n")
    scene = {"name": "Mesh cube (dashboard)", "dimension": 3,
             "grid": {"lower": [0, 0, 0], "upper": [1, 1, 1], "cell_size": 0.25},
             "materials": {"m": {"model": "linear_elastic", "density": 1000, "youngs_modulus": 1e6,
                                 "poisson_ratio": 0.3}},
             "bodies": [{"name": "cube", "material": "m", "initial_velocity": [0.1, 0, 0],
                         "geometry": {"type": "mesh", "file": "cube.stl", "scale": 0.5, "translate": [0.25, 0.25, 0.25]}}],
             "time": {"end": 0.01}, "output": {"frames": 2}}
    fill_scene(page, scene)
    page.get_by_role("button", name="Validate").click()
    expect(page.locator(".outcome")).to_contain_text("cube.stl is not attached")

    page.get_by_label("mesh file").set_input_files(str(tmp_path / "cube.stl"))
    expect(page.locator(".attached")).to_contain_text("Mesh: cube.stl")
    page.get_by_role("button", name="Validate").click()
    expect(page.locator(".outcome")).to_contain_text("The scene is valid")
    expect(page.locator(".outcome")).to_contain_text("64")   # a 0.5 m cube, 0.25 m cells, 2 x 2 x 2 per cell
    page.get_by_role("button", name="Submit").click()
    expect(page).to_have_url(re.compile(r"#/jobs/"))
    job = sdk.job(page.url.rsplit("/", 1)[-1]).wait(timeout=120, progress=False)
    assert job.record.status == "succeeded"
