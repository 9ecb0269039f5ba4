# SPDX-License-Identifier: BSD-3-Clause
"""end = steady (doc/model.md#the-steady-rule): stop when max |dh/dt| < steady_tol, but never
while a source is still to switch on."""
import numpy as np

from conftest import edit, h5open, run_ok


def steady_case(base, extra=""):
    # walls all round: the flat 0.2 m state has no supercritical face
    text = edit(base, "east = open", "east = wall")
    text = edit(text, "end = 1\noutput_every = 0.5\n",
                "end = steady\nsteady_tol = 1e-9\nmax_time = 50\noutput_every = 1\n")
    return text + extra


def test_subcritical_state_is_steady_at_once(tmp_path, base_case):
    case = tmp_path / "case.ini"
    case.write_text(steady_case(base_case))
    out = tmp_path / "run.h5"
    r = run_ok(["run", case, "-o", out])
    with h5open(out) as f:
        times = f["time"][:]
        steps = f["steps"][:]
        h = f["height"][:]
    assert times[-1] == 0.0, f"a flat state should be steady at t = 0, ran to {times}"
    assert steps[-1] == 0, f"a flat state took {steps[-1]} steps"
    # one snapshot: a second at t = 0 would make the time axis non-unique
    assert list(times) == [0.0] and h.shape[0] == 1, \
        f"steady at once: snapshots at t = {list(times)}, expected the one at 0"
    # the projected size comes first (doc/running.md#run), then the summary
    lines = r.stdout.splitlines()
    assert lines[0].startswith(f"writing {out}: at most ") and \
        lines[1].startswith(f"wrote {out}: 1 snapshot to t = 0 s, 0 "), r.stdout


def test_relax_steady_at_once_writes_one_snapshot(tmp_path):
    """relax of a DEM below the repose angle to .h5: steady after 0 steps,
    one snapshot at t = 0 (xarray needs a unique time axis)."""
    (tmp_path / "flat.asc").write_text("ncols 4\nnrows 3\nxllcorner 0\nyllcorner 0\n"
                                       "cellsize 1\n" + "1 1 1 1\n" * 3)
    for extra in ([], ["--output-every", "10"]):
        run_ok(["relax", "flat.asc", "-o", "flat.h5", "-q", "--force"] + extra, cwd=tmp_path)
        with h5open(tmp_path / "flat.h5") as f:
            times, steps = list(f["time"][:]), list(f["steps"][:])
        assert times == [0.0] and steps == [0.0], \
            f"relax {extra}: snapshots at t = {times} after {steps} steps, expected one at 0"


def test_snapshot_times_are_unique(tmp_path, base_case):
    """A run that settles between targets ends with its steady snapshot,
    never a second one at a time already written."""
    case = tmp_path / "case.ini"
    case.write_text(edit(steady_case(base_case), "east = wall", "east = open"))
    run_ok(["run", case, "-o", tmp_path / "run.h5", "-q"])
    with h5open(tmp_path / "run.h5") as f:
        times = f["time"][:]
    assert len(times) > 2 and np.all(np.diff(times) > 0), f"times {list(times)}"


def test_steady_waits_for_a_later_source(tmp_path, base_case):
    source = "\n[source late]\nrect = 0.2 0.2 0.6 0.6\nrate = 1e-3\nstart = 5\nstop = 8\n"
    case = tmp_path / "case.ini"
    case.write_text(steady_case(base_case, source))
    out = tmp_path / "run.h5"
    run_ok(["run", case, "-o", out, "-q"])
    with h5open(out) as f:
        times = f["time"][:]
        inflow = f["inflow"][:]
    # 16 cells of 0.1 m x 0.1 m under the rect get 1e-3 m/s for 3 s
    assert times[-1] >= 8.0, f"the run stopped at t = {times[-1]} before the source ran"
    assert abs(inflow[-1] - 16 * 0.01 * 1e-3 * 3.0) < 1e-15, f"inflow {inflow[-1]}"
