"""The job page's results in headless Chromium at 1400 px and 800 px: the WebGL particle viewer
(3D turned with the mouse, 2D, axisymmetric r-z, 1D), its colour bar with units, the frame
slider and the play button, the animation, a failed job's real frames, and the narrow
layouts (job table, new-job form). Screenshots go to docs/images with MPM_UPDATE_SCREENSHOTS=1."""
from __future__ import annotations

import json
import re

import h5py
import pytest
from playwright.sync_api import Page, expect

import live_scenes
from mpm_client import JobFailed

WIDE = {"width": 1400, "height": 1000}
NARROW = {"width": 800, "height": 1000}
UNITS = {"length": "m", "time": "s", "mass": "kg", "stress": "Pa"}


@pytest.fixture(scope="module")
def cube(sdk):
    """The 3D example, shortened: a few frames of the cube falling and hitting the floor."""
    scene = sdk.example("elastic_cube_3d")
    scene.update(name="Elastic cube (viewer)", units=UNITS)
    scene["time"]["end"] = 0.4
    scene["output"]["frames"] = 5
    return sdk.submit(scene).wait(timeout=180, poll=0.2, progress=False)


def open_results(page: Page, job_id: str, size: dict) -> None:
    page.set_viewport_size(size)
    page.goto(f"/#/jobs/{job_id}")
    expect(page.locator("code.id")).to_have_text(job_id)
    expect(page.locator(".viewer-stage[data-ready] canvas")).to_be_visible(timeout=30_000)


def canvas_image(page: Page) -> str:
    """The viewer's pixels (the canvas keeps its drawing buffer)."""
    page.wait_for_timeout(100)  # the frame requested by the last change is drawn
    return page.locator(".viewer-canvas").evaluate("canvas => canvas.toDataURL('image/png')")


def coloured_share(page: Page) -> float:
    """The share of the canvas's pixels that are saturated (particles; the box lines are grey)."""
    return page.locator(".viewer-canvas").evaluate("""canvas => {
        const copy = document.createElement("canvas");
        copy.width = canvas.width; copy.height = canvas.height;
        const context = copy.getContext("2d");
        context.drawImage(canvas, 0, 0);
        const data = context.getImageData(0, 0, copy.width, copy.height).data;
        let coloured = 0;
        for (let i = 0; i < data.length; i += 4) {
            const max = Math.max(data[i], data[i + 1], data[i + 2]), min = Math.min(data[i], data[i + 1], data[i + 2]);
            if (max - min > 40) coloured += 1;
        }
        return coloured / (data.length / 4);
    }""")


def test_the_3d_viewer_turns_with_the_mouse_and_colours_by_any_field(page: Page, cube, screenshot_dir):
    open_results(page, cube.id, WIDE)
    stage = page.locator(".viewer-stage")
    expect(stage).to_have_attribute("data-frame", "4")
    # the cube is drawn: a few % of the canvas is particles (the box lines are grey)
    assert coloured_share(page) > 0.01
    axes = page.locator(".viewer-axis").all_inner_texts()
    assert axes == ["x [m]", "y [m]", "z [m]"]
    expect(page.locator(".colour-bar .colour-label")).to_have_text("velocity_magnitude [m/s]")

    before = canvas_image(page)
    box = page.locator(".viewer-canvas").bounding_box()
    centre = (box["x"] + box["width"] / 2, box["y"] + box["height"] / 2)
    page.mouse.move(*centre)
    page.mouse.down()
    page.mouse.move(centre[0] + 120, centre[1] + 40, steps=6)
    page.mouse.up()
    turned = canvas_image(page)
    assert turned != before  # the view turned
    page.locator(".viewer-canvas").dblclick()
    assert canvas_image(page) == before  # double-click: back to the first view

    page.get_by_label("field").select_option("von_mises")
    expect(stage).to_have_attribute("data-field", "von_mises")
    expect(page.locator(".colour-bar .colour-label")).to_have_text("von_mises [Pa]")
    assert canvas_image(page) != before  # other colours
    page.get_by_label("field").select_option("velocity_magnitude")
    expect(stage).to_have_attribute("data-field", "velocity_magnitude")
    page.locator("section.results").screenshot(path=str(screenshot_dir / "dashboard-viewer-3d.png"))


def test_play_runs_through_every_frame_and_stops_at_the_last(page: Page, cube):
    open_results(page, cube.id, WIDE)
    slider = page.get_by_label("frame")
    expect(slider).to_have_attribute("max", "4")
    seen = []
    page.expose_function("frameShown", lambda frame: seen.append(frame))
    page.evaluate("""() => new MutationObserver(() => window.frameShown(document.querySelector('.viewer-stage').dataset.frame))
                     .observe(document.querySelector('.viewer-stage'), {attributes: true, attributeFilter: ['data-frame']})""")
    page.get_by_role("button", name="play").click()  # at the last frame: starts from the first
    expect(page.get_by_role("button", name="play")).to_be_visible(timeout=30_000)  # "pause" again "play" at the end
    expect(page.locator(".viewer-stage")).to_have_attribute("data-frame", "4")
    page.wait_for_timeout(300)  # the exposed function's calls arrive asynchronously
    assert seen == ["0", "1", "2", "3", "4"]
    assert slider.input_value() == "4"


def test_2d_results_show_frames_the_slider_names_and_units(page: Page, sdk, example):
    scene = live_scenes.quick(example, "Two disks (viewer)", frames=4)
    scene["units"] = UNITS
    job = sdk.submit(scene).wait(timeout=120, poll=0.2, progress=False)
    open_results(page, job.id, WIDE)
    times = [f["time"] for f in json.loads(page.evaluate("() => fetch('v1/jobs/%s/frames').then(r => r.text())" % job.id))["frames"]]
    slider = page.get_by_label("frame")
    for frame in (0, 2):
        slider.fill(str(frame))
        # the label rounds to 4 significant digits
        expect(page.locator(".frame-label")).to_have_text(f"frame {frame} / 3 (t = {times[frame]:.4g} s)")
        expect(page.locator(".viewer-stage")).to_have_attribute("data-frame", str(frame))
    assert page.locator(".viewer-axis").all_inner_texts() == ["x [m]", "y [m]"]
    assert coloured_share(page) > 0.03  # two disks of squares


def test_axisymmetric_results_are_drawn_in_r_and_z(page: Page, sdk):
    scene = {
        "name": "Axisymmetric block (viewer)", "dimension": 2, "axisymmetric": True,
        "grid": {"lower": [0, 0], "upper": [1, 1], "cell_size": 0.1},
        "materials": {"m": {"model": "linear_elastic", "density": 1000, "youngs_modulus": 1e5, "poisson_ratio": 0.3}},
        "bodies": [{"name": "block", "material": "m", "geometry": {"type": "box", "lower": [0, 0.2], "upper": [0.4, 0.6]},
                    "initial_velocity": [0, -0.1]}],
        "time": {"end": 0.02, "dt": 0.001}, "output": {"frames": 3}, "units": {"length": "mm", "time": "ms", "mass": "g"},
    }
    job = sdk.submit(scene).wait(timeout=120, poll=0.2, progress=False)
    open_results(page, job.id, WIDE)
    assert page.locator(".viewer-axis").all_inner_texts() == ["r [mm]", "z [mm]"]
    expect(page.locator(".colour-bar .colour-label")).to_have_text("velocity_magnitude [mm/ms]")


def test_a_scene_without_a_grid_box_is_framed_by_its_particles(page: Page, sdk):
    """TLMPM may leave the grid's box out: the viewer frames the particles' box instead."""
    scene = {
        "name": "TLMPM without a grid box (viewer)", "dimension": 2, "method": {"formulation": "tlmpm"},
        "grid": {"cell_size": 0.1},
        "materials": {"m": {"model": "neo_hookean", "density": 1000, "youngs_modulus": 1e5, "poisson_ratio": 0.3}},
        "bodies": [{"name": "block", "material": "m", "geometry": {"type": "box", "lower": [0, 0], "upper": [1, 0.5]},
                    "initial_velocity": ["0.1 * y", 0]}],
        "time": {"end": 0.02, "dt": 0.001}, "output": {"frames": 2},
    }
    job = sdk.submit(scene).wait(timeout=120, poll=0.2, progress=False)
    open_results(page, job.id, WIDE)
    # the block fills the frame's width (the particles' box): squares over a good part of the canvas
    assert coloured_share(page) > 0.2


def test_a_1d_result_is_drawn_as_its_profile(page: Page, sdk):
    scene = sdk.example("bar_vibration")
    scene["name"] = "Bar (viewer)"
    scene["time"]["end"] = scene["time"]["end"] / 20
    scene["output"]["frames"] = 3
    job = sdk.submit(scene).wait(timeout=120, poll=0.2, progress=False)
    open_results(page, job.id, WIDE)
    assert page.locator(".viewer-axis").count() == 1
    assert coloured_share(page) > 0.001  # a row of round points


def test_the_animation_plays_in_the_page_and_downloads(page: Page, cube, tmp_path, screenshot_dir):
    open_results(page, cube.id, WIDE)
    page.locator('.tab[data-mode="animation"]').click()
    animation = page.locator("img.animation-image")
    expect(animation).to_be_visible(timeout=180_000)  # drawn on first request
    assert page.evaluate("document.querySelector('img.animation-image').naturalWidth") == 700
    with page.expect_download() as download:
        page.get_by_role("button", name="Download GIF").click()
    saved = tmp_path / download.value.suggested_filename
    download.value.save_as(saved)
    assert saved.name == "Elastic cube (viewer).gif" and saved.read_bytes()[:6] == b"GIF89a"
    from PIL import Image
    assert Image.open(saved).n_frames == 5
    page.locator("section.results").screenshot(path=str(screenshot_dir / "dashboard-animation.png"))


def test_a_failed_job_shows_the_frames_it_wrote(page: Page, sdk, example, tmp_path):
    job = sdk.submit(live_scenes.unstable(example, "Blows up (frames)"))
    with pytest.raises(JobFailed):
        job.wait(timeout=120, poll=0.2, progress=False)
    with h5py.File(job.download(tmp_path / "failed.h5"), "r") as h5:
        times = sorted(float(group.attrs["time"]) for group in h5["frames"].values())
    open_results(page, job.id, WIDE)
    last = len(times) - 1
    expect(page.get_by_label("frame")).to_have_attribute("max", str(last))
    expect(page.locator(".frame-label")).to_have_text(f"frame {last} / {last} (t = {times[-1]:.4g})")
    assert times[-1] < 100.0  # not the end time the scene asked for


def no_sideways_overflow(page: Page, selector: str) -> None:
    overflow = page.locator(selector).evaluate("node => node.scrollWidth - node.clientWidth")
    assert overflow <= 0, f"{selector} is {overflow} px wider than its box"


def test_the_job_table_at_800_px_keeps_every_column_and_short_names(page: Page, sdk, example, cube,
                                                                    screenshot_dir):
    long_name = "A rather long job name that goes on and on to see how the table wraps it at 800 px"
    sdk.submit(live_scenes.quick(example, long_name)).wait(timeout=120, poll=0.2, progress=False)
    page.set_viewport_size(NARROW)
    page.goto("/#/jobs")
    row = page.locator("tr.job-row").filter(has_text=re.compile("A rather long"))
    expect(row).to_be_visible()
    no_sideways_overflow(page, ".table-wrap")
    card = page.locator("main section.card").bounding_box()
    for header in page.locator("table.jobs th").all():
        box = header.bounding_box()
        assert box["x"] + box["width"] <= card["x"] + card["width"], header.inner_text()
    name = row.locator("td.name a")
    font = float(name.evaluate("a => parseFloat(getComputedStyle(a).fontSize)"))
    # two lines at most: a "normal" line is 1.1 to 1.3 font sizes, so two take at most 2.6 and three at least 3.3
    assert name.bounding_box()["height"] <= 2.6 * font
    assert name.get_attribute("title") == long_name  # the whole name on hover
    page.screenshot(path=str(screenshot_dir / "dashboard-jobs-800.png"), full_page=False)

    open_results(page, cube.id, NARROW)
    no_sideways_overflow(page, "main")
    page.screenshot(path=str(screenshot_dir / "dashboard-job-800.png"), full_page=True)


@pytest.mark.parametrize("size", [WIDE, NARROW], ids=["1400px", "800px"])
def test_the_example_menu_fits_its_card(page: Page, size):
    page.set_viewport_size(size)
    page.goto("/#/new")
    menu = page.get_by_label("example")
    expect(menu.locator("option")).not_to_have_count(1)  # the examples have arrived
    longest = max(menu.locator("option").all_inner_texts(), key=len)
    menu.select_option(label=longest)
    expect(page.get_by_label("scene JSON")).to_have_value(re.compile('"bodies"'))
    card = page.locator("section.card").first.bounding_box()
    box = menu.bounding_box()
    assert card["x"] <= box["x"] and box["x"] + box["width"] <= card["x"] + card["width"]
    button = page.get_by_role("button", name="Open file…").bounding_box()
    assert button["x"] + button["width"] <= card["x"] + card["width"]
