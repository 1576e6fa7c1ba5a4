"""Two result files hold the same run: frames and time series equal bit for bit.

Used where a run was interrupted and resumed (checkpoints, fault tests): the solver is
deterministic and serial, so the resumed run repeats the same floating-point
operations on the same bits; any difference means state was lost on the way."""
import h5py
import numpy as np

from solver.results import list_frames, read_frame, read_series


def assert_same_result(path_a, path_b):
    frames_a, frames_b = list_frames(path_a), list_frames(path_b)
    assert [(f["time"], f["step"]) for f in frames_a] == [(f["time"], f["step"]) for f in frames_b]
    for index in range(len(frames_a)):
        a, b = read_frame(path_a, index)["fields"], read_frame(path_b, index)["fields"]
        assert a.keys() == b.keys()
        for name in a:
            np.testing.assert_array_equal(a[name], b[name], err_msg=f"frame {index} {name}")
    series_a, series_b = read_series(path_a), read_series(path_b)
    assert series_a.keys() == series_b.keys()
    for name in series_a:
        np.testing.assert_array_equal(series_a[name], series_b[name], err_msg=f"series {name}")
    with h5py.File(path_a, "r") as a, h5py.File(path_b, "r") as b:
        assert a.attrs["status"] == b.attrs["status"] == "complete"
        assert a.attrs["scene"] == b.attrs["scene"]
