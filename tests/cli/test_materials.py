# SPDX-License-Identifier: BSD-3-Clause
"""Materials (issue 37, doc/model.md#materials): a repose angle per cell.

Two half-planes at 30 and 40 degrees relax each to its own angle, with the
boundary between them as the face law says (the larger angle of a face's
two cells); one angle in a raster gives the bits of that angle given as a
number; bad rasters are refused with the file, the cell and the value.
"""
import json
import math
import signal

import numpy as np

from conftest import h5open, run, same_bits
from test_crs import UTM33N_ESRI
from test_relax import read_asc, write_asc
from test_reliability import start_paused

DX = 1.0


def ridge(nx=48, ny=40, height=15.0):
    """A ridge along x: 60 degree flanks on a flat floor, crest at mid y."""
    y = np.arange(ny) - (ny - 1) / 2.0
    profile = np.maximum(0.0, height - math.tan(math.radians(60.0)) * np.abs(y) * DX)
    return np.tile(profile[:, None], (1, nx))


def half_planes(nx=48, ny=40, west=30.0, east=40.0):
    a = np.full((ny, nx), east)
    a[:, : nx // 2] = west
    return a


def relax_ok(args, tmp_path):
    r = run(["relax"] + [str(a) for a in args], cwd=tmp_path, timeout=300)
    assert r.returncode == 0, f"relax {args} exited {r.returncode}:\n{r.stderr}"
    return r


def normal_slopes_deg(h):
    """|g_n| of the x-faces and of the y-faces, in degrees."""
    gx = np.degrees(np.arctan(np.abs(np.diff(h, axis=1)) / DX))
    gy = np.degrees(np.arctan(np.abs(np.diff(h, axis=0)) / DX))
    return gx, gy


def test_half_planes_relax_each_to_its_angle(tmp_path):
    h0, angles = ridge(), half_planes()
    ny, nx = h0.shape
    write_asc(tmp_path / "ridge.asc", h0, cellsize=DX)
    write_asc(tmp_path / "angles.asc", angles, cellsize=DX)
    relax_ok(["ridge.asc", "-o", "out.asc", "--angle", "angles.asc",
              "--report", "report.json"], tmp_path)
    report = json.loads((tmp_path / "report.json").read_text())
    assert report["steady"], f"not steady: {report}"
    _, h = read_asc(tmp_path / "out.asc")
    assert abs(h.sum() - h0.sum()) <= 1e-9 * h0.sum(), (
        f"volume {h0.sum()!r} -> {h.sum()!r} m^3 (x dx dy)")
    gx, gy = normal_slopes_deg(h)
    b = nx // 2        # first column of the 40 degree half
    tol = 1e-3         # degrees: the steady rule's slope tolerance, and more
    # away from the boundary each half lies at its own angle
    west, east = gy[:, : b - 3].max(), gy[:, b + 3:].max()
    assert 29.9 <= west <= 30.0 + tol, f"the 30 degree half's steepest face: {west:.4f} deg"
    assert 39.9 <= east <= 40.0 + tol, f"the 40 degree half's steepest face: {east:.4f} deg"
    # the steep half keeps its angle up to its edge: the column beside the
    # loose half holds at 40 degrees (a face takes the larger angle)
    edge = gy[:, b].max()
    assert 39.9 <= edge <= 40.0 + tol, (
        f"the 40 degree column at the boundary has its steepest face at {edge:.4f} deg")
    # no face is steeper than the larger angle of its two cells
    limit_x = np.maximum(angles[:, 1:], angles[:, :-1])
    limit_y = np.maximum(angles[1:, :], angles[:-1, :])
    over_x, over_y = (gx - limit_x).max(), (gy - limit_y).max()
    assert max(over_x, over_y) <= tol, (
        f"a face steeper than the larger angle of its cells by {max(over_x, over_y):.4g} deg")
    # and the loose half's faces that do not touch the steep one hold at 30
    assert gy[:, : b - 1].max() <= 30.0 + tol and gx[:, : b - 2].max() <= 30.0 + tol, (
        "a face inside the 30 degree half is steeper than 30 degrees")


def test_one_angle_in_a_raster_is_that_angle(tmp_path):
    h0 = ridge(24, 20, 8.0)
    write_asc(tmp_path / "ridge.asc", h0, cellsize=DX)
    write_asc(tmp_path / "angles.asc", np.full(h0.shape, 33.0), cellsize=DX)
    relax_ok(["ridge.asc", "-o", "raster.asc", "--angle", "angles.asc"], tmp_path)
    relax_ok(["ridge.asc", "-o", "number.asc", "--angle", "33"], tmp_path)
    assert (tmp_path / "raster.asc").read_bytes() == (tmp_path / "number.asc").read_bytes(), (
        "an angle raster of one value did not give the bits of --angle 33")


CASE = """[grid]
nx = 24
ny = 20
dx = 1
dy = 1
[model]
closure = coulomb
repose_angle = {angle}
nu = 1
[time]
end = steady
output_every = 50
[initial]
type = file
file = ridge.asc
"""


def test_case_angle_file(tmp_path):
    """[model] repose_angle = FILE, resolved beside the case: one angle gives
    the bits of the number; two halves the half-planes' angles."""
    h0 = ridge(24, 20, 8.0)
    write_asc(tmp_path / "ridge.asc", h0, cellsize=DX)
    write_asc(tmp_path / "one.asc", np.full(h0.shape, 33.0), cellsize=DX)
    write_asc(tmp_path / "two.asc", half_planes(24, 20), cellsize=DX)
    for name, angle in (("number", "33"), ("one", "one.asc"), ("two", "two.asc")):
        (tmp_path / f"{name}.ini").write_text(CASE.format(angle=angle))
        r = run(["run", f"{name}.ini", "-o", f"{name}.h5"], cwd=tmp_path, timeout=300)
        assert r.returncode == 0, f"run {name}.ini exited {r.returncode}:\n{r.stderr}"
    with h5open(tmp_path / "number.h5") as a, h5open(tmp_path / "one.h5") as b:
        ha, hb = a["height"][-1], b["height"][-1]
        assert same_bits(ha, hb), "repose_angle = one.asc (all 33) differs from 33"
    with h5open(tmp_path / "two.h5") as f:
        h = f["height"][-1]
    gx, gy = normal_slopes_deg(h)
    assert gy[:, 12:].max() > 39.0, (
        f"the 40 degree half lies at {gy[:, 12:].max():.3f} deg at most")
    assert gy[:, :10].max() <= 30.001, (
        f"the 30 degree half lies at {gy[:, :10].max():.3f} deg at most")


def test_bad_angle_rasters(tmp_path):
    h0 = ridge(24, 20, 8.0)
    write_asc(tmp_path / "ridge.asc", h0, cellsize=DX)
    write_asc(tmp_path / "small.asc", np.full((10, 24), 33.0), cellsize=DX)
    steep = np.full(h0.shape, 33.0)
    steep[3, 5] = 95.0
    write_asc(tmp_path / "steep.asc", steep, cellsize=DX)
    holes = np.full(h0.shape, 33.0)
    holes[4, 6] = -9999.0
    write_asc(tmp_path / "holes.asc", holes, cellsize=DX, nodata=-9999.0)
    for angle, words in (("small.asc", ["small.asc", "24 x 10", "24 x 20"]),
                         ("steep.asc", ["steep.asc", "95", "(5, 3)", "(0, 90)"]),
                         ("holes.asc", ["holes.asc", "no data", "(6, 4)"]),
                         ("missing.asc", ["missing.asc"])):
        r = run(["relax", "ridge.asc", "-o", "out.asc", "--angle", angle], cwd=tmp_path)
        assert r.returncode == 2, f"--angle {angle}: exit {r.returncode}\n{r.stderr}"
        line = r.stderr.strip()
        assert len(line.splitlines()) == 1, f"--angle {angle}: not one line:\n{r.stderr}"
        for w in words:
            assert w in line, f"--angle {angle}: '{w}' not in the message: {line}"
    # a number out of range is still a number
    r = run(["relax", "ridge.asc", "-o", "out.asc", "--angle", "95"], cwd=tmp_path)
    assert r.returncode == 2 and "(0, 90)" in r.stderr, r.stderr


# What GDAL 3.6 writes as the .prj of EPSG:32633, and the zone west of it.
UTM33N = UTM33N_ESRI
UTM32N = UTM33N.replace("Zone_33N", "Zone_32N").replace('Meridian",15.0', 'Meridian",9.0')


def test_a_raster_beside_the_dem_must_lie_on_its_cells(tmp_path):
    """The angles, classes and bedrock are read on the DEM's cells: another
    cell size, corner or CRS is refused, naming both (doc/dem.md)."""
    h0 = ridge(24, 20, 8.0)
    x0, y0 = 500000.0, 5200000.0
    write_asc(tmp_path / "ridge.asc", h0, cellsize=DX, x0=x0, y0=y0)
    (tmp_path / "ridge.prj").write_text(UTM33N)
    a = np.full(h0.shape, 33.0)
    write_asc(tmp_path / "coarse.asc", a, cellsize=2.0, x0=x0, y0=y0)
    write_asc(tmp_path / "shifted.asc", a, cellsize=DX, x0=x0 + 5.0, y0=y0)
    write_asc(tmp_path / "zone32.asc", a, cellsize=DX, x0=x0, y0=y0)
    (tmp_path / "zone32.prj").write_text(UTM32N)
    write_asc(tmp_path / "same.asc", a, cellsize=DX, x0=x0, y0=y0)
    (tmp_path / "same.prj").write_text(UTM33N)
    write_asc(tmp_path / "bare.asc", a, cellsize=DX, x0=x0, y0=y0)   # no .prj: not compared
    write_asc(tmp_path / "rock.asc", h0 - 1.0, cellsize=DX, x0=x0 + 1.0, y0=y0)
    for args, words in ((["--angle", "coarse.asc"], ["--angle coarse.asc", "2 x 2 m", "1 x 1 m"]),
                        (["--angle", "shifted.asc"], ["shifted.asc", "corner", "500005"]),
                        (["--angle", "zone32.asc"], ["zone32.asc", "32N", "33N", "CRS"]),
                        (["--bedrock", "rock.asc"], ["--bedrock rock.asc", "corner", "500001"])):
        r = run(["relax", "ridge.asc", "-o", "out.asc"] + args, cwd=tmp_path)
        assert r.returncode == 2, f"{args}: exit {r.returncode}\n{r.stderr}"
        line = r.stderr.strip()
        assert len(line.splitlines()) == 1, f"{args}: not one line:\n{r.stderr}"
        for w in words:
            assert w in line, f"{args}: '{w}' not in the message: {line}"
    for angle in ("same.asc", "bare.asc"):
        relax_ok(["ridge.asc", "-o", f"out-{angle}", "--angle", angle, "--max-time", "1"],
                 tmp_path)


# ---- hysteresis (doc/model.md#hysteresis) ----------------------------------

POUR = """[grid]
nx = 41
ny = 41
dx = 0.05
origin = -1.025 -1.025

[model]
closure = coulomb
repose_angle = 30
{static}
nu = 0.1

[time]
end = steady
max_time = 120
output_every = 0.25

[boundary]
west = open
east = open
south = open
north = open

[source pour]
disk = 0 0 0.06
rate = 0.02
stop = 45
"""


def steepest_deg(h, dx=0.05):
    g = max((np.abs(np.diff(h, axis=1)) / dx).max(), (np.abs(np.diff(h, axis=0)) / dx).max())
    return math.degrees(math.atan(g))


def pour(tmp_path, name, static, *args):
    (tmp_path / f"{name}.ini").write_text(POUR.format(static=static))
    r = run(["run", f"{name}.ini", "-o", f"{name}.h5"] + list(args), cwd=tmp_path,
            timeout=300)
    assert r.returncode == 0, f"run {name}.ini exited {r.returncode}:\n{r.stderr}"
    with h5open(tmp_path / f"{name}.h5") as f:
        return f["height"][:], f["time"][:], r.stdout


def test_slow_pour_avalanches_between_the_two_angles(tmp_path):
    """Poured slowly at 30 and 36 degrees, the flank steepens to the static
    angle, an avalanche runs it down to the dynamic one, again and again; it
    stays between the two, and the pile ends at rest."""
    a_d, a_s, tol = 30.0, 36.0, 0.2
    heights, times, out = pour(tmp_path, "pour", "static_angle = 36")
    assert "(steady)" in out, f"the pile did not come to rest:\n{out}"
    steepest = [steepest_deg(h) for h in heights]
    # an avalanche: the steepest face from near a_s down to near a_d
    avalanches = count_avalanches(steepest, a_d, a_s)
    assert avalanches >= 3, f"{avalanches} avalanches: steepest faces {steepest}"
    first = next(k for k, s in enumerate(steepest) if s >= a_s - 1.0)
    after = steepest[first:]
    assert a_d - tol <= min(after) and max(after) <= a_s + tol, (
        f"after the first avalanche the steepest face ran from {min(after):.3f} to "
        f"{max(after):.3f} deg, outside [{a_d}, {a_s}] + {tol}")
    # at rest anywhere between the two: a pile poured no more stays as it is
    assert a_d - tol <= steepest[-1] <= a_s + tol, f"at rest at {steepest[-1]:.4f} deg"
    # the same bits on 1 and 2 threads and another tile size
    other, _, _ = pour(tmp_path, "pour1", "static_angle = 36", "--threads", "1",
                       "--tile", "16x8")
    assert same_bits(heights, other), "hysteresis: another thread count or tile size " \
        "gave other bits"


def test_static_angle_equal_to_repose_is_no_hysteresis(tmp_path):
    plain, _, _ = pour(tmp_path, "plain", "")
    equal, _, _ = pour(tmp_path, "equal", "static_angle = 30")
    assert same_bits(plain, equal), "static_angle = repose_angle differs from no static_angle"


def test_bad_static_angles(tmp_path):
    (tmp_path / "low.ini").write_text(POUR.format(static="static_angle = 25"))
    r = run(["run", "low.ini", "-o", "low.h5"], cwd=tmp_path)
    assert r.returncode == 2 and len(r.stderr.splitlines()) == 1, r.stderr
    for w in ("static_angle", "25", "30"):
        assert w in r.stderr, f"'{w}' not in: {r.stderr}"
    h0 = ridge(24, 20, 8.0)
    write_asc(tmp_path / "ridge.asc", h0, cellsize=DX)
    write_asc(tmp_path / "angles.asc", half_planes(24, 20), cellsize=DX)
    for args, words in ((["--angle", "35", "--static-angle", "30"],
                         ["--static-angle", "30", "35"]),
                        (["--angle", "angles.asc", "--static-angle", "45"],
                         ["--static-angle", "--angle", "[material NAME]"])):
        r = run(["relax", "ridge.asc", "-o", "out.asc"] + args, cwd=tmp_path)
        assert r.returncode == 2 and len(r.stderr.splitlines()) == 1, (args, r.stderr)
        for w in words:
            assert w in r.stderr, f"{args}: '{w}' not in: {r.stderr}"


def count_avalanches(steepest, a_d, a_s):
    """Falls of the steepest face from near a_s to near a_d."""
    avalanches, high = 0, False
    for s in steepest:
        if s >= a_s - 1.0:
            high = True
        elif high and s <= a_d + 1.5:
            avalanches, high = avalanches + 1, False
    return avalanches


def test_a_class_with_a_static_angle_avalanches_beside_one_without(tmp_path):
    """Hysteresis per material ([material NAME] static_angle): sand of 30
    and 36 degrees poured inside a ring of loose sand at 25 without
    hysteresis (so the poured sand's states are materials 2 and 3, not 0
    and 1) avalanches between its two angles and comes to rest; the same bits on
    1 thread and another tile size; a class's static angle below its
    repose angle is refused."""
    c = np.full((41, 41), 7.0)
    c[3:-3, 3:-3] = 3.0
    write_asc(tmp_path / "classes.asc", c, cellsize=0.05, x0=-1.025, y0=-1.025)
    sections = ("[material sand]\nclass = 3\nrepose_angle = 30\nstatic_angle = {a_s}\n\n"
                "[material loose]\nclass = 7\nrepose_angle = 25\n")
    case = POUR.format(static="materials = classes.asc").replace("repose_angle = 30\n", "")
    case += "\n" + sections
    (tmp_path / "c.ini").write_text(case.format(a_s=36))
    runs = []
    for name, args in (("c", []), ("c1", ["--threads", "1", "--tile", "16x8"])):
        r = run(["run", "c.ini", "-o", f"{name}.h5"] + args, cwd=tmp_path, timeout=300)
        assert r.returncode == 0, f"run c.ini exited {r.returncode}:\n{r.stderr}"
        assert "(steady)" in r.stdout, f"the pile did not come to rest:\n{r.stdout}"
        with h5open(tmp_path / f"{name}.h5") as f:
            runs.append((f["height"][:], f["moving"][:]))
    (heights, moving), (other, other_moving) = runs
    steepest = [steepest_deg(h) for h in heights]
    assert count_avalanches(steepest, 30.0, 36.0) >= 3, f"steepest faces {steepest}"
    first = next(k for k, s in enumerate(steepest) if s >= 35.0)
    assert 29.8 <= min(steepest[first:]) and max(steepest[first:]) <= 36.2, (
        f"after the first avalanche the steepest face ran from {min(steepest[first:]):.3f} "
        f"to {max(steepest[first:]):.3f} deg")
    assert moving.max() == 1 and moving[-1].max() == 0, "no sand moved, or some moves at rest"
    assert same_bits(heights, other) and np.array_equal(moving, other_moving), \
        "hysteresis with classes: another thread count or tile size gave other bits"
    (tmp_path / "low.ini").write_text(case.format(a_s=25))
    r = run(["run", "low.ini", "-o", "low.h5"], cwd=tmp_path)
    assert r.returncode == 2 and len(r.stderr.splitlines()) == 1, r.stderr
    for w in ("[material sand]", "static_angle 25", "repose_angle 30"):
        assert w in r.stderr, f"'{w}' not in: {r.stderr}"


def test_restart_mid_avalanche_gives_the_uninterrupted_bits(tmp_path):
    """The snapshots hold which cells move (/moving): a run signalled in the
    middle of an avalanche and continued by run --restart has every
    snapshot of the run never cut."""
    case = POUR.format(static="static_angle = 36").replace(
        "end = steady\nmax_time = 120", "end = 6\nintegrator = euler")
    (tmp_path / "p.ini").write_text(case)
    r = run(["run", "p.ini", "-o", "whole.h5", "-q"], cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    with h5open(tmp_path / "whole.h5") as f:
        steps, slope, moving = f["steps"][:], f["max_slope_deg"][:], f["moving"][:]
    # the first avalanche: the steepest face falls between snapshots k - 1 and k
    k = next(k for k in range(1, len(slope)) if slope[k - 1] >= 33.0 and slope[k] < slope[k - 1] - 1.0)
    assert moving[k].sum() > 0, "test set-up: nothing moves during the avalanche"
    pause = int(steps[k - 1] + steps[k]) // 2
    assert steps[k - 1] < pause < steps[k], f"test set-up: steps {list(steps)}"
    p = start_paused(["run", "p.ini", "-o", "cut.h5", "-q"], tmp_path, pause)
    p.send_signal(signal.SIGTERM)
    _, err = p.communicate(timeout=60)
    assert p.returncode == 143, (p.returncode, err)
    with h5open(tmp_path / "cut.h5") as f:
        assert f["moving"][-1].sum() > 0, "the cut is not in the middle of an avalanche"
    r = run(["run", "--restart", "cut.h5", "-q"], cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    with h5open(tmp_path / "whole.h5") as a, h5open(tmp_path / "cut.h5") as b:
        ta, tb = a["time"][:], b["time"][:]
        for name in ("height", "moving"):
            for t in ta:
                ia, ib = np.flatnonzero(ta == t)[0], np.flatnonzero(tb == t)
                assert len(ib) == 1, f"t = {t} s missing from the continued run"
                assert same_bits(a[name][ia].astype(np.float64),
                                 b[name][ib[0]].astype(np.float64)), (
                    f"/{name} at t = {t} s differs from the uninterrupted run")


# ---- classes and a material table (doc/model.md#materials) -----------------

TABLE = """[material sand]
class = 3
repose_angle = 30

[material gravel]
class = 7
repose_angle = 40
"""


def classes(nx=48, ny=40):
    c = np.full((ny, nx), 7.0)
    c[:, : nx // 2] = 3.0
    return c


def test_classes_and_table_are_the_angle_raster(tmp_path):
    """Two classes of 30 and 40 degrees give the bits of the raster of those
    angles; one class the bits of its angle as a number."""
    write_asc(tmp_path / "ridge.asc", ridge(), cellsize=DX)
    write_asc(tmp_path / "classes.asc", classes(), cellsize=DX)
    write_asc(tmp_path / "angles.asc", half_planes(), cellsize=DX)
    (tmp_path / "table.ini").write_text(TABLE)
    relax_ok(["ridge.asc", "-o", "classes.out.asc", "--materials", "classes.asc",
              "--material-table", "table.ini"], tmp_path)
    relax_ok(["ridge.asc", "-o", "angles.out.asc", "--angle", "angles.asc"], tmp_path)
    assert (tmp_path / "classes.out.asc").read_bytes() == \
        (tmp_path / "angles.out.asc").read_bytes(), \
        "classes 3 and 7 at 30 and 40 degrees differ from the raster of those angles"
    write_asc(tmp_path / "one.asc", np.full((40, 48), 7.0), cellsize=DX)
    relax_ok(["ridge.asc", "-o", "one.out.asc", "--materials", "one.asc",
              "--material-table", "table.ini"], tmp_path)
    relax_ok(["ridge.asc", "-o", "forty.out.asc", "--angle", "40"], tmp_path)
    assert (tmp_path / "one.out.asc").read_bytes() == \
        (tmp_path / "forty.out.asc").read_bytes(), \
        "a class raster of one class (40 degrees) differs from --angle 40"


CLASS_CASE = """[grid]
nx = 48
ny = 40
dx = 1
[model]
closure = coulomb
materials = classes.asc
nu = 1
[time]
end = steady
output_every = 200
[initial]
type = file
file = ridge.asc
""" + TABLE


def test_case_material_sections(tmp_path):
    """[model] materials = FILE with [material NAME] sections; --set changes
    one; the halves lie at their angles."""
    write_asc(tmp_path / "ridge.asc", ridge(), cellsize=DX)
    write_asc(tmp_path / "classes.asc", classes(), cellsize=DX)
    (tmp_path / "case.ini").write_text(CLASS_CASE)
    for name, extra in (("table", []), ("set", ["--set", "material gravel.repose_angle=38"])):
        r = run(["run", "case.ini", "-o", f"{name}.h5", "-q"] + extra, cwd=tmp_path,
                timeout=300)
        assert r.returncode == 0, r.stderr
    for name, steep in (("table", 40.0), ("set", 38.0)):
        with h5open(tmp_path / f"{name}.h5") as f:
            gx, gy = normal_slopes_deg(f["height"][-1])
        assert gy[:, :21].max() <= 30.001 and steep - 0.1 <= gy[:, 27:].max() <= steep + 0.001, (
            f"{name}: the halves lie at {gy[:, :21].max():.3f} and {gy[:, 27:].max():.3f} deg")


def test_bad_classes_and_tables(tmp_path):
    write_asc(tmp_path / "ridge.asc", ridge(), cellsize=DX)
    write_asc(tmp_path / "classes.asc", classes(), cellsize=DX)
    c = classes()
    c[5, 30] = 2.5
    write_asc(tmp_path / "half.asc", c, cellsize=DX)
    (tmp_path / "table.ini").write_text(TABLE)
    (tmp_path / "sand.ini").write_text(TABLE.split("\n\n")[0] + "\n")
    (tmp_path / "twice.ini").write_text(TABLE.replace("class = 7", "class = 3"))
    (tmp_path / "noangle.ini").write_text(TABLE.replace("repose_angle = 40\n", ""))
    (tmp_path / "steep.ini").write_text(TABLE.replace("repose_angle = 40", "repose_angle = 95"))
    bad = [
        (["--materials", "classes.asc", "--material-table", "sand.ini"],
         ["classes.asc", "class 7", "not in the material table", "3"]),
        (["--materials", "half.asc", "--material-table", "table.ini"],
         ["half.asc", "2.5", "(30, 5)", "integer"]),
        (["--materials", "classes.asc", "--material-table", "twice.ini"],
         ["twice.ini", "class 3", "gravel", "sand"]),
        (["--materials", "classes.asc", "--material-table", "noangle.ini"],
         ["gravel", "repose_angle"]),
        (["--materials", "classes.asc", "--material-table", "steep.ini"],
         ["steep.ini", "gravel", "95", "(0, 90)"]),
        (["--materials", "classes.asc"], ["--materials", "--material-table"]),
        (["--materials", "classes.asc", "--material-table", "table.ini", "--angle", "a.asc"],
         ["--angle", "--materials"]),
    ]
    for args, words in bad:
        r = run(["relax", "ridge.asc", "-o", "out.asc"] + args, cwd=tmp_path)
        assert r.returncode == 2 and len(r.stderr.splitlines()) == 1, (args, r.stderr)
        for w in words:
            assert w in r.stderr, f"{args}: '{w}' not in: {r.stderr}"
    # a case: sections without the raster, the raster without sections
    base = CLASS_CASE.replace("materials = classes.asc\n", "repose_angle = 35\n")
    (tmp_path / "a.ini").write_text(base)
    (tmp_path / "b.ini").write_text(CLASS_CASE.split("[material sand]")[0])
    for case, words in (("a.ini", ["[material sand]", "materials = FILE"]),
                        ("b.ini", ["materials = classes.asc", "[material NAME]"])):
        r = run(["run", case, "-o", "out.h5"], cwd=tmp_path)
        assert r.returncode == 2 and len(r.stderr.splitlines()) == 1, (case, r.stderr)
        for w in words:
            assert w in r.stderr, f"{case}: '{w}' not in: {r.stderr}"
