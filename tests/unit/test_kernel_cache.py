"""The versioned kernel cache (solver/kernel_cache.py) and the compile estimate (solver/cost.py)."""
import multiprocessing
import os
import shutil
import time
from pathlib import Path

from numba.core import caching

from solver import cost, kernel_cache
from solver.scene_checks import load_scene

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"


def test_checkouts_of_one_version_share_a_folder_and_a_changed_source_is_a_new_one(tmp_path):
    a, b = tmp_path / "a" / "solver", tmp_path / "b" / "solver"
    for copy in (a, b):
        shutil.copytree(kernel_cache.PACKAGE, copy, ignore=shutil.ignore_patterns("__pycache__"))
    assert kernel_cache.digest(a) == kernel_cache.digest(b)
    fused = b / "fused.py"   # a callee of the generated kernels: numba's own key would not see it
    fused.write_text(fused.read_text() + "\n# changed\n")
    assert kernel_cache.digest(a) != kernel_cache.digest(b)


def test_solver_kernels_are_kept_by_their_place_in_the_package():
    folder = kernel_cache.version_folder()
    assert kernel_cache._kernels_folder(str(kernel_cache.PACKAGE / "materials" / "kernels" / "fluid.py")) == \
        folder / "kernels" / "solver" / "materials" / "kernels"
    generated = kernel_cache.modules_folder("fused") / "fused_2d_x.py"
    assert kernel_cache._kernels_folder(str(generated)) == folder / "kernels" / "generated" / "fused"
    assert kernel_cache._kernels_folder(os.__file__) is None   # not the solver's: numba's own locators


def _save_entries(index_folder: str, worker: int, entries: int, start) -> None:
    kernel_cache.install()
    start.wait()
    cache_file = caching.IndexDataCacheFile(index_folder, "kernel-1.py311", "stamp")
    for entry in range(entries):
        cache_file.save((worker, entry), f"data {worker} {entry}")


def test_processes_saving_at_once_keep_every_entry_with_its_own_data(tmp_path):
    """numba numbers data files after reading the index: savers at once wrote one file and
    dropped each other's index entries. The locked save keeps all of them."""
    kernel_cache.install()
    workers, entries = 6, 15
    context = multiprocessing.get_context("fork")
    start = context.Event()
    processes = [context.Process(target=_save_entries, args=(str(tmp_path), w, entries, start))
                 for w in range(workers)]
    for process in processes:
        process.start()
    start.set()
    for process in processes:
        process.join(60)
        assert process.exitcode == 0
    cache_file = caching.IndexDataCacheFile(str(tmp_path), "kernel-1.py311", "stamp")
    for worker in range(workers):
        for entry in range(entries):
            assert cache_file.load((worker, entry)) == f"data {worker} {entry}"


def test_folders_of_versions_unused_for_a_month_are_pruned(tmp_path):
    old, recent = tmp_path / "v-old", tmp_path / "v-recent"
    for folder, age_days in ((old, 31), (recent, 29)):
        folder.mkdir()
        stamp = folder / ".last-used"
        stamp.touch()
        then = time.time() - age_days * 86400
        os.utime(stamp, (then, then))
    assert kernel_cache.prune(tmp_path) == [old]
    assert recent.exists() and not old.exists()


def test_a_variant_is_the_scenes_structure_not_its_numbers_or_names():
    scene = load_scene(EXAMPLES / "two_disks.json").model_dump(mode="json")
    stiffer = load_scene(EXAMPLES / "two_disks.json").model_dump(mode="json")
    material = next(iter(stiffer["materials"].values()))
    material["youngs_modulus"] *= 2
    stiffer["materials"] = {"renamed": material}
    for body in stiffer["bodies"]:
        body["material"], body["name"] = "renamed", body["name"] + "!"
    assert cost.variant(load_scene(scene), 1) == cost.variant(load_scene(stiffer), 1)
    other = dict(scene, method={**scene["method"], "shape_function": "cubic_bspline"})
    assert cost.variant(load_scene(other), 1) != cost.variant(load_scene(scene), 1)


def test_a_run_on_one_thread_and_a_run_on_several_are_two_variants():
    """They run different forms of the kernels (solver/jit.py); several threads, one form."""
    scene = load_scene(EXAMPLES / "two_disks.json")
    assert cost.variant(scene, 1) != cost.variant(scene, 2) == cost.variant(scene, 4)


def test_the_estimate_counts_compiling_until_a_run_marks_the_variant(tmp_path, monkeypatch):
    monkeypatch.setattr(kernel_cache, "version_folder", lambda: tmp_path)
    scene = load_scene(EXAMPLES / "two_disks.json")
    model = cost.CostModel.model_validate({**cost.load_model().model_dump(), "compile_seconds": {"2/fused": 25.0}})
    assert not cost.is_compiled(scene, 2) and cost.compile_seconds(scene, 2, model) == 25.0
    assert cost.compile_seconds(scene, 1, model) == 25.0 * cost.ONE_THREAD_COMPILE
    cost.mark_compiled(scene, 2, 24.0, 38)
    assert cost.is_compiled(scene, 2) and cost.compile_seconds(scene, 2, model) == 0.0
    assert not cost.is_compiled(scene, 1)
