"""Shared helpers of the verification cases."""
from solver.results import list_frames, read_frame, read_series


class Case:
    """A finished run and easy access to its result file."""

    def __init__(self, result):
        self.result = result
        self.path = result.result_path

    def series(self):
        return read_series(self.path)

    def frames(self):
        return [read_frame(self.path, f["index"]) for f in list_frames(self.path)]

    def frame(self, index=-1):
        return read_frame(self.path, index)


def run_scene(scene, folder) -> Case:
    """Run `scene` into `folder` (the solver imported at the first run, not when tests are collected)."""
    from solver import run
    return Case(run(scene, folder))


def centre_of_mass_velocity(frame):
    f = frame["fields"]
    return (f["mass"][:, None] * f["velocity"]).sum(axis=0) / f["mass"].sum()
