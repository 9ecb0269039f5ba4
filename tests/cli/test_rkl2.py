# SPDX-License-Identifier: BSD-3-Clause
"""RKL2 super-steps from the command line: [time] integrator and its keys,
relax --integrator, the output's /stencil_evaluations and integrator
attribute, restarts and threads bit for bit, bad values, and the steady
stop on coarse cells.

Runs use --threads 1 unless the thread count is the point: the machine
that runs the tests may be loaded, and OpenMP on tiny grids then waits.
"""
import json
import math
import os
import subprocess

import numpy as np
import pytest

import conftest
from conftest import SANDSLIDE_NAN, h5open, run, run_ok, same_bits, text_attr

# A small cases/door.ini: sand poured into a walled room leaves through a
# door; the region beyond has open sides.  30 x 20 cells of 5 cm.
DOOR = """\
# small door (tests/cli/test_rkl2.py)
[grid]
nx = 30
ny = 20
dx = 0.05
origin = 0 -0.5

[model]
closure = coulomb
repose_angle = 35
nu = 0.1

[time]
end = 120
output_every = 20

[boundary]
west = wall
south = open
north = open
east = open

[initial]
type = flat
height = 0

[wall room_south]
rect = 0 -0.5 0.55 -0.45
[wall room_north]
rect = 0 0.45 0.55 0.5
[wall jamb_south]
rect = 0.5 -0.45 0.55 -0.1
[wall jamb_north]
rect = 0.5 0.1 0.55 0.45

[source room]
rect = 0 -0.45 0.5 0.45
rate = 1e-3
"""

# A small cases/cone.ini with a source on the apex and an open east side:
# the middle cell (15, 10), where the test hook puts its NaN, is on the
# sliding cone for the whole run.
PILE = """\
# pile (tests/cli/test_rkl2.py)
[grid]
nx = 30
ny = 20
dx = 0.05
origin = 0 0

[model]
closure = coulomb
repose_angle = 35
nu = 0.02

[time]
end = 30
output_every = 3

[boundary]
west = wall
east = open
south = wall
north = wall

[initial]
type = cone
center = 0.75 0.5
radius = 0.4
angle = 50
height = 0

[source top]
disk = 0.75 0.5 0.1
rate = 2e-3
start = 0
stop = 20
"""

SERIES = ["volume", "inflow", "outflow", "max_height", "max_slope_deg", "steps",
          "stencil_evaluations"]


def write(tmp_path, text, name="case.ini"):
    (tmp_path / name).write_text(text)
    return name


def assert_same_snapshots(cut, whole):
    conftest.assert_same_snapshots(cut, whole, SERIES)


# ---- a. the output says which integrator ran and what it cost ---------------------


@pytest.mark.parametrize("integrator", ["rkl2", "euler", "auto"])
def test_output_names_the_integrator_and_counts_evaluations(tmp_path, integrator):
    case = write(tmp_path, DOOR)
    args = ["run", case, "-o", "o.h5", "-q", "--threads", "1"]
    if integrator != "auto":
        args += ["--set", f"time.integrator={integrator}"]
    run_ok(args, cwd=tmp_path)
    with h5open(tmp_path / "o.h5") as f:
        name = text_attr(f, "integrator")
        steps = f["steps"][:]
        ev = f["stencil_evaluations"][:]
        t = f["time"][:]
        inflow = f["inflow"][:]
        assert f["stencil_evaluations"].shape == f["time"].shape
    want = "euler" if integrator == "euler" else "rkl2"   # auto: rkl2 without bedrock
    assert name == want, f"integrator = {integrator}: the file says {name!r}, not {want!r}"
    assert list(t) == [0, 20, 40, 60, 80, 100, 120]
    assert ev[0] == 0 and steps[0] == 0
    assert np.all(np.diff(ev) >= 0) and np.all(np.diff(steps) >= 0), \
        f"counters not monotone: steps {steps}, evaluations {ev}"
    if want == "euler":
        assert np.array_equal(ev, steps), \
            f"euler: every step is one evaluation, yet steps {steps}, evaluations {ev}"
    else:
        assert np.all(ev >= 2 * steps), \
            f"rkl2: a super-step is at least 2 stages, yet steps {steps}, evaluations {ev}"
        assert ev[-1] > 5 * steps[-1], \
            f"rkl2 took {steps[-1]} super-steps of {ev[-1]} stages: hardly super-stepping"
    # 10 x 18 room cells of 5 cm poured at 1 mm/s
    assert inflow[-1] == pytest.approx(10 * 18 * 0.0025 * 1e-3 * 120, rel=1e-12)


def test_rkl2_and_euler_pour_the_same_room(tmp_path):
    case = write(tmp_path, DOOR)
    for name in ("euler", "rkl2"):
        run_ok(["run", case, "-o", f"{name}.h5", "-q", "--threads", "1", "--set",
                f"time.integrator={name}"], cwd=tmp_path)
    with h5open(tmp_path / "euler.h5") as e, h5open(tmp_path / "rkl2.h5") as r:
        he, hr = e["height"][-1], r["height"][-1]
        ve, vr = e["volume"][:], r["volume"][:]
        ev_e, ev_r = e["stencil_evaluations"][-1], r["stencil_evaluations"][-1]
    tan35 = math.tan(math.radians(35.0))
    assert np.array_equal(np.isnan(he), np.isnan(hr)), "the walls (NaN) differ"
    diff = np.nanmax(np.abs(he - hr))
    assert diff <= 0.1 * tan35 * 0.05, \
        f"rkl2 ends {diff:.3g} m from euler, more than 0.1 tan a_cr dx"
    assert np.allclose(ve, vr, rtol=1e-12, atol=0), "the volumes differ"
    assert ev_r < ev_e, f"rkl2 took {ev_r} evaluations, euler {ev_e}"


# ---- b. restart ----------------------------------------------------------------


@pytest.mark.skipif(not os.access(SANDSLIDE_NAN, os.X_OK),
                    reason="needs build/tests/sandslide-nan (make test builds it)")
# the whole run takes 20 super-steps: one cut while the source pours (its
# super-steps sized by rkl2_pouring_tol), one after it stopped at t = 20 s
@pytest.mark.parametrize("nan_step", [9, 17])
def test_restart_of_a_cut_rkl2_run_matches_an_uninterrupted_run(tmp_path, nan_step):
    """The run is cut by the non-finite guard (the test hook of
    test_reliability.py puts a NaN into the middle cell after super-step
    nan_step): exit 1 with the good snapshots kept; run --restart continues
    it, and every snapshot is that of the run never cut, bit for bit."""
    case = write(tmp_path, PILE)
    env = dict(os.environ, SANDSLIDE_TEST_NAN_STEP=str(nan_step))
    p = subprocess.run([SANDSLIDE_NAN, "run", case, "-o", "cut.h5", "-q", "--threads", "1",
                        "--set", "time.integrator=rkl2"], cwd=tmp_path, capture_output=True,
                       text=True, env=env, timeout=120)
    assert p.returncode == 1, (p.returncode, p.stderr)
    assert "non-finite" in p.stderr, p.stderr
    with h5open(tmp_path / "cut.h5") as f:
        t_cut = f["time"][:].copy()
        assert text_attr(f, "integrator") == "rkl2"
    assert 0.0 < t_cut[-1] < 30.0, f"the cut run's snapshots end at {t_cut[-1]}"
    r = run(["run", "--restart", "cut.h5", "-q", "--threads", "1"], cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    run_ok(["run", case, "-o", "whole.h5", "-q", "--threads", "1", "--set",
            "time.integrator=rkl2"], cwd=tmp_path)
    with h5open(tmp_path / "whole.h5") as f:
        steps = f["steps"][:]
    assert steps[-1] > nan_step, f"test set-up: the whole run took only {steps[-1]} super-steps"
    assert_same_snapshots(tmp_path / "cut.h5", tmp_path / "whole.h5")


def test_restart_of_a_finished_rkl2_run_adds_nothing(tmp_path):
    case = write(tmp_path, PILE)
    run_ok(["run", case, "-o", "o.h5", "-q", "--threads", "1", "--set",
            "time.integrator=rkl2"], cwd=tmp_path)
    with h5open(tmp_path / "o.h5") as f:
        n = len(f["time"])
        h_end = f["height"][-1]
    # --set may not change a run being continued: the integrator it ran with is kept
    r = run(["run", "--restart", "o.h5", "-q", "--set", "time.integrator=euler"],
            cwd=tmp_path)
    assert r.returncode == 2 and "--set" in r.stderr, r.stderr
    run_ok(["run", "--restart", "o.h5", "-q", "--threads", "1"], cwd=tmp_path)
    with h5open(tmp_path / "o.h5") as f:
        assert len(f["time"]) == n and text_attr(f, "integrator") == "rkl2"
        assert same_bits(f["height"][-1], h_end)


# ---- c. threads ------------------------------------------------------------------


def test_one_and_two_threads_give_the_same_bits(tmp_path):
    case = write(tmp_path, PILE.replace("end = 30\n", "end = 6\n"))
    for n in (1, 2):
        run_ok(["run", case, "-o", f"t{n}.h5", "-q", "--threads", str(n), "--set",
                "time.integrator=rkl2"], cwd=tmp_path)
    assert_same_snapshots(tmp_path / "t1.h5", tmp_path / "t2.h5")
    run_ok(["run", case, "-o", "ref.h5", "-q", "--threads", "1", "--reference-kernel",
            "--set", "time.integrator=rkl2", "--tile", "8x8"], cwd=tmp_path)
    assert_same_snapshots(tmp_path / "t1.h5", tmp_path / "ref.h5")


# ---- d. bad values -----------------------------------------------------------------


@pytest.mark.parametrize("setting, words", [
    ("time.integrator=foo", ["integrator", "foo", "auto, euler or rkl2"]),
    ("time.integrator=RKL2", ["integrator", "auto, euler or rkl2"]),
    ("time.rkl2_max_stages=1", ["rkl2_max_stages", "from 2 to"]),
    ("time.rkl2_max_stages=2.5", ["rkl2_max_stages", "integer"]),
    ("time.rkl2_tol=0", ["rkl2_tol", "> 0"]),
    ("time.rkl2_tol=-0.3", ["rkl2_tol", "> 0"]),
    ("time.rkl2_tol=nan", ["rkl2_tol", "> 0"]),
    ("time.steady_slope_tol=0", ["steady_slope_tol", "> 0"]),
])
def test_bad_rkl2_values_exit_2_naming_the_key(tmp_path, setting, words):
    case = write(tmp_path, DOOR)
    r = run(["run", case, "-o", "o.h5", "-q", "--set", setting], cwd=tmp_path)
    assert r.returncode == 2, (r.returncode, r.stderr)
    for w in words:
        assert w in r.stderr, f"{setting}: {w!r} not in the message {r.stderr!r}"
    assert r.stderr.count("\n") == 1, r.stderr
    assert not (tmp_path / "o.h5").exists(), "an output was written for a bad case"


def test_good_rkl2_values_are_accepted(tmp_path):
    case = write(tmp_path, DOOR.replace("end = 120\n", "end = 20\n"))
    run_ok(["run", case, "-o", "o.h5", "-q", "--threads", "1", "--set",
            "time.integrator=rkl2", "--set", "time.rkl2_max_stages=2", "--set",
            "time.rkl2_tol=0.05", "--set", "time.steady_slope_tol=1e-4"], cwd=tmp_path)
    with h5open(tmp_path / "o.h5") as f:
        steps, ev = f["steps"][-1], f["stencil_evaluations"][-1]
    # s stages and the error estimate: s + 1 evaluations a super-step
    assert ev == 3 * steps, f"rkl2_max_stages = 2: {steps} super-steps took {ev} evaluations"


def bedrock_case(tmp_path, integrator=None):
    """A 1 cm layer on a 45 degree bedrock, open at the low east end."""
    ny, nx, dx = 8, 30, 0.05
    x = (np.arange(nx) + 0.5) * dx
    rock = np.tile(-1.0 * x, (ny, 1))
    for name, h in (("rock.asc", rock), ("sand.asc", rock + 0.01)):
        head = (f"ncols {nx}\nnrows {ny}\nxllcorner 0.0\nyllcorner 0.0\n"
                f"cellsize {dx!r}\n")
        rows = [" ".join(repr(float(v)) for v in h[j]) for j in range(ny - 1, -1, -1)]
        (tmp_path / name).write_text(head + "\n".join(rows) + "\n")
    line = f"integrator = {integrator}\n" if integrator else ""
    return write(tmp_path, f"""\
[grid]
nx = {nx}
ny = {ny}
dx = {dx}
origin = 0 0
[model]
closure = coulomb
repose_angle = 35
nu = 0.05
[time]
end = 0.4
output_every = 0.1
{line}[boundary]
west = wall
east = open
south = wall
north = wall
open_level = -2
[initial]
type = file
file = sand.asc
bedrock = rock.asc
""", "rock.ini")


def test_rkl2_with_a_bedrock_is_refused(tmp_path):
    case = bedrock_case(tmp_path, "rkl2")
    r = run(["run", case, "-o", "o.h5", "-q"], cwd=tmp_path)
    assert r.returncode == 2, (r.returncode, r.stderr)
    assert "rkl2" in r.stderr and "bedrock" in r.stderr, r.stderr
    assert not (tmp_path / "o.h5").exists()
    # the same through --set on a case that does not name an integrator
    case = bedrock_case(tmp_path)
    r = run(["run", case, "-o", "o.h5", "-q", "--set", "time.integrator=rkl2"], cwd=tmp_path)
    assert r.returncode == 2 and "rkl2" in r.stderr and "bedrock" in r.stderr, r.stderr
    r = run(["relax", "sand.asc", "--bedrock", "rock.asc", "--integrator", "rkl2", "-o",
             "out.asc"], cwd=tmp_path)
    assert r.returncode == 2, (r.returncode, r.stderr)
    assert "rkl2" in r.stderr and "bedrock" in r.stderr, r.stderr
    assert not (tmp_path / "out.asc").exists()


@pytest.mark.parametrize("integrator", [None, "auto", "euler"])
def test_auto_with_a_bedrock_runs_euler(tmp_path, integrator):
    case = bedrock_case(tmp_path, integrator)
    run_ok(["run", case, "-o", "o.h5", "-q", "--threads", "1"], cwd=tmp_path)
    with h5open(tmp_path / "o.h5") as f:
        assert text_attr(f, "integrator") == "euler"
        assert np.array_equal(f["steps"][:], f["stencil_evaluations"][:])
        assert f["steps"][-1] > 0
    r = run(["relax", "sand.asc", "--bedrock", "rock.asc", "-o", "out.asc", "-q",
             "--threads", "1", "--report", "r.json"] +
            (["--integrator", integrator] if integrator else []), cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    rep = json.loads((tmp_path / "r.json").read_text())
    assert rep["integrator"] == "euler" and rep["stencil_evaluations"] == rep["steps"], rep


@pytest.mark.parametrize("args, words", [
    (["--integrator", "foo"], ["--integrator", "auto, euler or rkl2"]),
    (["--rkl2-max-stages", "1"], ["--rkl2-max-stages", "from 2 to"]),
    (["--rkl2-tol", "0"], ["--rkl2-tol", "> 0"]),
    (["--slope-tol", "-1"], ["--slope-tol"]),
])
def test_relax_bad_rkl2_options_exit_2(tmp_path, args, words):
    (tmp_path / "d.asc").write_text("ncols 3\nnrows 2\nxllcorner 0\nyllcorner 0\n"
                                    "cellsize 1\n0 0 0\n0 0 9\n")
    r = run(["relax", "d.asc", "-o", "out.asc"] + args, cwd=tmp_path)
    assert r.returncode == 2, (r.returncode, r.stderr)
    for w in words:
        assert w in r.stderr, f"{args}: {w!r} not in {r.stderr!r}"
    assert not (tmp_path / "out.asc").exists()


# ---- e. the steady stop on coarse cells ---------------------------------------------

TAN30 = math.tan(math.radians(30.0))


def write_asc(path, h, cellsize):
    """h: (ny, nx), row 0 = south (written north row first)."""
    ny, nx = h.shape
    head = (f"ncols {nx}\nnrows {ny}\nxllcorner 0.0\nyllcorner 0.0\n"
            f"cellsize {cellsize!r}\n")
    rows = [" ".join(repr(float(v)) for v in h[j]) for j in range(ny - 1, -1, -1)]
    path.write_text(head + "\n".join(rows) + "\n")


def read_asc(path):
    tokens = path.read_text().split()
    head, k = {}, 0
    while True:
        try:
            float(tokens[k])
            break
        except ValueError:
            head[tokens[k].lower()] = tokens[k + 1]
            k += 2
    nx, ny = int(head["ncols"]), int(head["nrows"])
    return np.array([float(t) for t in tokens[k:k + nx * ny]]).reshape(ny, nx)[::-1]


def face_slopes(h, dx):
    """Steepest face of doc/model.md#face-flux (wall sides mirrored): g_n across the
    face, g_t the mean of the two cells' central differences along it."""
    p = np.pad(h, 1, mode="edge")
    cy = (p[2:, 1:-1] - p[:-2, 1:-1]) / (2 * dx)
    cx = (p[1:-1, 2:] - p[1:-1, :-2]) / (2 * dx)
    gn_x = (h[:, 1:] - h[:, :-1]) / dx
    gt_x = 0.5 * (cy[:, 1:] + cy[:, :-1])
    gn_y = (h[1:, :] - h[:-1, :]) / dx
    gt_y = 0.5 * (cx[1:, :] + cx[:-1, :])
    return max(np.sqrt(gn_x ** 2 + gt_x ** 2).max(), np.sqrt(gn_y ** 2 + gt_y ** 2).max())


def synthetic_dem(shape, cellsize):
    ny, nx = 40, 60
    y, x = (np.mgrid[0:ny, 0:nx] + 0.5) * cellsize
    if shape == "pyramid":      # 40 degree faces down to the four sides
        d = np.minimum(np.minimum(x, nx * cellsize - x), np.minimum(y, ny * cellsize - y))
        return math.tan(math.radians(40.0)) * d
    return math.tan(math.radians(31.0)) * x      # a long slope just above 30 degrees


@pytest.mark.parametrize("integrator", ["euler", "rkl2"])
@pytest.mark.parametrize("cellsize", [1.0, 50.0, 200.0])
@pytest.mark.parametrize("shape", ["pyramid", "slope"])
def test_steady_means_no_face_above_the_angle_on_coarse_cells(tmp_path, shape, cellsize,
                                                              integrator):
    if integrator == "euler" and cellsize != 50.0 and \
            float(os.environ.get("SANDSLIDE_TEST_SCALE") or 1) < 1:
        pytest.skip("SANDSLIDE_TEST_SCALE < 1 (the sanitizers): Euler's thousands of "
                    "steps on 50 m cells only; `make test` runs every cell size")
    h0 = synthetic_dem(shape, cellsize)
    write_asc(tmp_path / "dem.asc", h0, cellsize)
    r = run(["relax", "dem.asc", "-o", "out.asc", "--angle", "30", "--report", "r.json",
             "--integrator", integrator, "--threads", "1", "-q"], cwd=tmp_path, timeout=120)
    assert r.returncode == 0, r.stderr
    rep = json.loads((tmp_path / "r.json").read_text())
    h = read_asc(tmp_path / "out.asc")
    bound_deg = math.degrees(math.atan(TAN30 + 1e-6))
    assert rep["steady"] is True, rep
    assert rep["integrator"] == integrator, rep
    assert rep["max_slope_after_deg"] <= bound_deg + 1e-9, (
        f"{shape}, {cellsize} m cells, {integrator}: steady with a face at "
        f"{rep['max_slope_after_deg']!r} deg, above atan(tan 30 + 1e-6) = {bound_deg!r}")
    s = face_slopes(h, cellsize)
    assert s <= TAN30 + 1e-6 + 1e-12, (
        f"{shape}, {cellsize} m cells, {integrator}: the output has a face at slope "
        f"{s!r}, above tan 30 + 1e-6 = {TAN30 + 1e-6!r}")
    assert rep["max_slope_before_deg"] > 30.9, rep
    assert h.sum() == pytest.approx(h0.sum(), rel=1e-12), "volume changed inside wall sides"
