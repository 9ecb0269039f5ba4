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
    run_ok(["run", case, "-o", out, "-q"])
    with h5open(out) as f:
        times = f["time"][:]
        steps = f["steps"][:]
        h = f["height"][:]
    assert times[-1] == 0.0, f"a flat state should be steady at t = 0, ran to {times}"
    assert steps[-1] == 0, f"a flat state took {steps[-1]} steps"
    assert np.array_equal(h[0], h[-1])


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
