# SPDX-License-Identifier: BSD-3-Clause
"""The Python module `sandslide` (python/sandslide) over libsandslide.so.0.

Run from the top of the repository after `make`:

    PYTHONPATH=python /usr/bin/python3 -m pytest -q tests/python

It compares the module with the program build/sandslide (SANDSLIDE names
another): relax gives the CLI's bits on the same DEM, read back both
through .asc (%.17g-exact) and through the .h5 series (rows south first),
on DEMs that are not symmetric north-south so that a flipped row order
fails; then physics (steady, the repose angle, volume, nodata, bedrock),
errors with the library's messages (the CLI's for the same bad value),
run with --set overrides, open with xarray, and finding the library.
"""
import json
import math
import os
import re
import shutil
import subprocess
import sys

import numpy as np
import pytest

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
import sandslide  # conftest.py: this checkout's when not installed
SANDSLIDE = os.environ.get("SANDSLIDE", os.path.join(ROOT, "build", "sandslide"))
TAN35 = math.tan(math.radians(35.0))
SLOPE_TOL = 1e-6          # relax's default --slope-tol


def cli(args, cwd, expect=0):
    r = subprocess.run([SANDSLIDE] + [str(a) for a in args], cwd=cwd, capture_output=True,
                       text=True, timeout=60)
    assert r.returncode == expect, \
        f"sandslide {' '.join(map(str, args))} exited {r.returncode}, expected {expect}\n" \
        f"{r.stdout}\n{r.stderr}"
    return r


def write_asc(path, h, dx=1.0, dy=None, nodata=None):
    """h [row, column] with row 0 north, as the file lists it; %.17g."""
    ny, nx = h.shape
    head = f"ncols {nx}\nnrows {ny}\nxllcorner 0\nyllcorner 0\n"
    head += f"cellsize {dx:.17g}\n" if dy is None else f"dx {dx:.17g}\ndy {dy:.17g}\n"
    if nodata is not None:
        head += f"NODATA_value {nodata:.17g}\n"
    with open(path, "w") as f:
        f.write(head + "\n".join(" ".join(f"{v:.17g}" for v in row) for row in h) + "\n")


def read_asc(path):
    """(header, values [row, column] row 0 north) of an .asc file."""
    with open(path) as f:
        words = f.read().split()
    head = {}
    k = 0
    while words[k][0].isalpha():
        head[words[k].lower()] = words[k + 1]
        k += 2
    nx, ny = int(head["ncols"]), int(head["nrows"])
    return head, np.array([float(w) for w in words[k:k + nx * ny]]).reshape(ny, nx)


def same_bits(a, b):
    return a.shape == b.shape and np.array_equal(a.view(np.uint64), b.view(np.uint64))


def pile_on_ramp(ny=36, nx=44, dx=1.0, dy=1.0):
    """A 60 deg pile north of the centre on a ramp rising to the north
    (row 0 the north edge): nothing about it is symmetric north-south."""
    r, c = np.mgrid[0:ny, 0:nx]
    ramp = 0.15 * (ny - 1 - r) * dy
    d = np.hypot((c - 0.6 * nx) * dx, (r - 0.3 * ny) * dy)
    return ramp + np.maximum(0.0, 12.0 - math.tan(math.radians(60)) * d)


def steepest_normal_gradient(h, dx, dy):
    """The largest |dh| / spacing across any face with data on both sides:
    a lower bound of the face slope of doc/model.md#face-flux (which adds the
    tangential part), so it too must not exceed tan(angle)."""
    gx = np.abs(np.diff(h, axis=1)) / dx
    gy = np.abs(np.diff(h, axis=0)) / dy
    return max(np.nanmax(gx), np.nanmax(gy))


# ---- the CLI's bits --------------------------------------------------------

@pytest.mark.parametrize("dx, dy, bedrock", [(1.0, None, False), (0.5, 0.8, False),
                                             (1.0, None, True)],
                         ids=["square", "rectangular", "bedrock"])
def test_relax_gives_the_cli_bits(tmp_path, dx, dy, bedrock):
    h0 = pile_on_ramp(dx=dx, dy=dy or dx)
    write_asc(tmp_path / "dem.asc", h0, dx, dy)
    args = ["relax", "dem.asc", "--threads", "1", "-q", "--report", "r.json"]
    rock = None
    if bedrock:
        rock = h0 - 3.0 + 0.02 * np.arange(h0.shape[1])   # under all of it
        rock[:, :10] = h0[:, :10]                          # bare in the west
        write_asc(tmp_path / "rock.asc", rock, dx, dy)
        args += ["--bedrock", "rock.asc"]
    cli(args + ["-o", "out.asc"], tmp_path)
    cli(args + ["-o", "out.h5"], tmp_path)
    _, want = read_asc(tmp_path / "out.asc")
    import h5py
    with h5py.File(tmp_path / "out.h5", "r") as f:
        series = f["height"][-1][::-1]                     # stored south row first
    want_report = json.loads((tmp_path / "r.json").read_text())

    got, report = sandslide.relax(h0, dx, dy, bedrock=rock, threads=1)

    assert not same_bits(want, want[::-1]), \
        "the relaxed DEM is symmetric north-south: the test could not see flipped rows"
    assert same_bits(got, want), \
        f"relax differs from `sandslide relax` (out.asc) in {np.sum(got != want)} cells " \
        f"of {got.size}; flipped rows would match: {same_bits(got[::-1], want)}"
    assert same_bits(got, series), "relax differs from the last snapshot of `relax -o out.h5`"
    assert set(report) == set(want_report), \
        f"report keys {sorted(set(report) ^ set(want_report))} differ from --report's"
    # measured, not computed: times and the process's peak memory
    measured = {"wall_seconds", "read_seconds", "write_seconds", "memory_peak_bytes"}
    for key in set(want_report) - {"input", "output"} - measured:
        assert report[key] == want_report[key], \
            f"report[{key!r}] = {report[key]!r}, --report says {want_report[key]!r}"
    assert report["input"] == "heights" and report["output"] == "(array)", report


def test_an_angle_array_gives_the_cli_bits_of_its_raster(tmp_path):
    """angle= an array is --angle FILE (doc/model.md#materials): 30 degrees
    in the north half, 40 in the south, so flipped rows would differ."""
    h0 = pile_on_ramp()
    angles = np.where(np.arange(h0.shape[0])[:, None] < h0.shape[0] // 2, 30.0, 40.0)
    angles = np.broadcast_to(angles, h0.shape).copy()
    write_asc(tmp_path / "dem.asc", h0, 1.0, None)
    write_asc(tmp_path / "angles.asc", angles, 1.0, None)
    cli(["relax", "dem.asc", "--angle", "angles.asc", "--threads", "1", "-q", "-o", "out.asc"],
        tmp_path)
    _, want = read_asc(tmp_path / "out.asc")
    got, report = sandslide.relax(h0, 1.0, angle=angles, threads=1)
    flipped, _ = sandslide.relax(h0, 1.0, angle=angles[::-1].copy(), threads=1)
    assert same_bits(got, want), \
        f"angle=array differs from --angle angles.asc in {np.sum(got != want)} cells"
    assert not same_bits(flipped, want), "the angles' rows flipped give the same bits"
    assert report["materials"] == 2 and report["steady"], report
    uniform, _ = sandslide.relax(h0, 1.0, angle=33, threads=1)
    same, _ = sandslide.relax(h0, 1.0, angle=np.full(h0.shape, 33.0), threads=1)
    assert same_bits(same, uniform), "an array of one angle differs from the number"
    bad = angles.copy()
    bad[3, 4] = 95.0
    with pytest.raises(sandslide.InputError, match=r"angle.*95.*expected degrees in \(0, 90\)"):
        sandslide.relax(h0, 1.0, angle=bad)
    with pytest.raises(sandslide.InputError, match="angle: shape"):
        sandslide.relax(h0, 1.0, angle=angles[1:])


def test_threads_give_the_same_bits():
    h0 = pile_on_ramp(20, 24)
    one, _ = sandslide.relax(h0, 1.0, threads=1)
    two, _ = sandslide.relax(h0, 1.0, threads=2)
    assert same_bits(one, two), "2 threads differ from 1 (doc/model.md#same-bits)"
    tiled, _ = sandslide.relax(h0, 1.0, threads=2, tile=(8, 4))
    named, _ = sandslide.relax(h0, 1.0, threads=2, tile="5x3")
    assert same_bits(one, tiled) and same_bits(one, named), \
        "tiles of 8x4 or 5x3 cells differ from the default tiles"


# ---- physics ---------------------------------------------------------------

def test_relaxed_surface_is_steady_at_the_repose_angle_with_volume_conserved():
    h0 = pile_on_ramp(dx=0.5, dy=0.8)
    before = h0.copy()
    h, rep = sandslide.relax(h0, 0.5, 0.8, threads=1)
    assert same_bits(h0, before), "relax modified its input"
    assert h.shape == h0.shape and h.dtype == np.float64, (h.shape, h.dtype)
    assert rep["steady"] is True, f"not steady: {rep}"
    assert rep["max_slope_before_deg"] > 55, f"the DEM should start at 60 deg: {rep}"
    assert math.tan(math.radians(rep["max_slope_after_deg"])) <= TAN35 + SLOPE_TOL, \
        f"steepest face {rep['max_slope_after_deg']!r} deg after, above 35 deg"
    g = steepest_normal_gradient(h, 0.5, 0.8)
    assert g <= TAN35 + SLOPE_TOL, f"a face of slope {g!r} > tan 35 deg = {TAN35!r} remains"
    v0, v1 = h0.sum(), h.sum()
    assert abs(v1 - v0) <= 1e-12 * v0, f"volume {v0!r} -> {v1!r} with wall sides"
    assert rep["volume_before"] == pytest.approx(v0 * 0.4, rel=1e-12), rep
    assert abs(rep["volume_after"] - rep["volume_before"]) <= 1e-12 * rep["volume_before"], \
        f"report's volume not conserved: {rep}"
    assert rep["outflow"] == 0 and rep["inflow"] == 0, rep


def test_nodata_cells_stay_nan():
    h0 = pile_on_ramp()
    h0[20:24, 5:9] = np.nan          # a hole south-west of the pile
    h0[0, :] = np.nan                # and the north row
    for nodata in ("open", "wall"):
        h, rep = sandslide.relax(h0, 1.0, nodata=nodata, threads=1)
        assert np.array_equal(np.isnan(h), np.isnan(h0)), \
            f"nodata={nodata}: NaN cells moved: {np.argwhere(np.isnan(h) != np.isnan(h0))}"
        assert rep["steady"], rep
        if nodata == "wall":
            v0, v1 = np.nansum(h0), np.nansum(h)
            assert abs(v1 - v0) <= 1e-12 * v0, f"walls: volume {v0!r} -> {v1!r}"
        else:
            assert rep["outflow"] >= 0, rep


def test_subcritical_dem_with_nan_round_it_comes_back_bit_for_bit():
    """The default nodata treatment (walls): a gentle DEM clipped to an
    irregular outline, NaN all round it, is not touched; nodata="open"
    drains its edges (the check that this can fail)."""
    ny, nx = 30, 38
    r, c = np.mgrid[0:ny, 0:nx]
    bump = np.exp(-((c - 25) ** 2 + (r - 9) ** 2) / 30.0)
    h0 = 40.0 + 0.3 * c + 0.15 * (ny - r) + 1.0 * bump
    th = np.arctan2(r - 15.0, c - 19.0)
    outline = 13.0 + 2.0 * np.sin(3 * th + 0.5) + np.cos(5 * th)
    h0[np.hypot(c - 19.0, (r - 15.0) / 0.8) > outline] = np.nan
    h0[12, 20] = np.nan                                    # a void
    assert np.isnan(h0[[0, -1], :]).all() and np.isnan(h0[:, [0, -1]]).all()
    assert steepest_normal_gradient(h0, 1.0, 1.0) < 0.5
    h, rep = sandslide.relax(h0, 1.0, threads=1)
    assert rep["steps"] == 0 and rep["cells_moved"] == 0 and rep["outflow"] == 0, rep
    assert same_bits(h, h0), f"heights changed: {np.argwhere(~(h == h0) & ~np.isnan(h0))}"
    h, rep = sandslide.relax(h0, 1.0, nodata="open", threads=1)
    assert rep["outflow"] > 0 and rep["cells_moved"] > 0, rep


def test_bedrock_is_respected():
    ny, nx = 30, 40
    r, c = np.mgrid[0:ny, 0:nx]
    rock = 0.2 * c + 0.1 * (ny - r)                        # tilted, steeper than nothing
    rock[:, 30:] += 8.0                                    # and a rock cliff
    h0 = rock + np.where(np.hypot(c - 12, r - 9) < 6, 5.0, 0.0)   # a block of sand
    h, rep = sandslide.relax(h0, 1.0, bedrock=rock, sides="open", threads=1)
    assert rep["steady"], rep
    below = rock - h
    assert below.max() <= 1e-12 * np.abs(rock).max(), \
        f"sand went {below.max()!r} m below the bedrock at {np.unravel_index(below.argmax(), h.shape)}"
    assert np.array_equal(h[:, 31:], rock[:, 31:]) or np.all(h[:, 31:] >= rock[:, 31:]), \
        "the bare rock cliff changed"


# ---- errors ----------------------------------------------------------------

@pytest.mark.parametrize("option, value", [("angle", 95), ("closure", "bogus"),
                                           ("sides", "periodic"), ("tol", -1),
                                           ("threads", 0), ("max_time", "soon")])
def test_bad_option_raises_the_cli_message(tmp_path, option, value):
    h0 = pile_on_ramp(8, 8)
    write_asc(tmp_path / "dem.asc", h0)
    r = cli(["relax", "dem.asc", "--" + option.replace("_", "-"), str(value)], tmp_path,
            expect=2)
    # the CLI's usage error ends with where its options are listed
    said = re.sub(r" \(see 'sandslide relax --help'\)$", "", r.stderr.splitlines()[0])
    with pytest.raises(sandslide.InputError) as e:
        sandslide.relax(h0, 1.0, **{option: value})
    assert isinstance(e.value, ValueError) and isinstance(e.value, sandslide.Error)
    # the CLI's message, its flag named as Python's keyword: --max-time 'x' is max_time='x'
    flag = "sandslide: --" + option.replace("_", "-") + " "
    assert said.startswith(flag) and str(e.value) == option + "=" + said[len(flag):], \
        f"{option}={value!r}: Python says {str(e.value)!r}, the CLI {said!r}"


@pytest.mark.parametrize("heights, words", [
    (np.zeros(5), "2-D array"),
    (np.zeros((2, 3, 4)), "2-D array"),
    (np.zeros((0, 4)), "at least one row"),
    (np.array([["a", "b"], ["c", "d"]]), "real numbers"),
    (np.ones((3, 3), dtype=complex), "real numbers"),
    ([[1.0, np.inf], [0.0, 0.0]], "heights[0, 1] is inf"),
])
def test_bad_arrays_raise_input_errors(heights, words):
    with pytest.raises(sandslide.InputError, match=words.replace("[", r"\[")):
        sandslide.relax(heights, 1.0)


def test_bad_cell_size_and_bedrock_raise_input_errors():
    h0 = pile_on_ramp(8, 8)
    with pytest.raises(sandslide.InputError, match=r"dx='-1': expected m > 0"):
        sandslide.relax(h0, -1.0)
    with pytest.raises(sandslide.InputError, match="shape"):
        sandslide.relax(h0, 1.0, bedrock=np.zeros((8, 7)))
    # the library's checks (the module repeats none): cells named by column
    # and row from the south, and by x and y in m; row 2 from the north of
    # 8 rows is row 5 from the south
    rock = h0 - 1.0
    rock[2, 3] = np.nan
    with pytest.raises(sandslide.InputError,
                       match=r"bedrock of cell \(3, 5\) at x = 3.5 m, y = 5.5 m is nan"):
        sandslide.relax(h0, 1.0, bedrock=rock)
    rock = h0 - 1.0
    rock[1, 6] += 2.0
    with pytest.raises(sandslide.InputError,
                       match=r"bedrock of cell \(6, 6\) at x = 6.5 m, y = 6.5 m is .* above"):
        sandslide.relax(h0, 1.0, bedrock=rock)
    with pytest.raises(sandslide.InputError, match="heights: every cell is nodata"):
        sandslide.relax(np.full((3, 4), np.nan), 1.0)


def test_the_defaults_are_the_librarys():
    """The module repeats no default: every keyword of relax is None, an
    option of the library's table, and the docstring gives the library's
    default; sandslide.options reads the table."""
    import inspect
    table = {o["name"].replace("-", "_"): o for o in sandslide.options("relax")}
    assert table["angle"]["default"] == "35" and table["closure"]["default"] == "coulomb", \
        "relax's table lost its defaults"
    assert table["angle"]["case_key"] == "model.repose_angle", table["angle"]
    params = inspect.signature(sandslide.relax).parameters
    doc = " ".join(sandslide.relax.__doc__.split())
    for name, p in params.items():
        if name in ("heights", "dx"):
            continue
        if name == "progress":   # the module's own, not an option of the library
            assert p.default is False, f"relax(progress={p.default!r}): expected off"
            continue
        assert p.default is None, f"relax({name}={p.default!r}): a default of its own"
        assert f"{name} : " in doc, f"the docstring has no numpydoc entry for {name}"
        if name not in ("dy", "bedrock", "threads"):
            assert name in table and table[name]["by_name"], \
                f"relax's keyword {name} is not an option of the library"
            default = table[name]["default"]
            if default is not None:
                entry = doc[doc.index(f"{name} : "):]
                entry = entry[:entry.index(" : ", len(name) + 3)]
                assert f"(library default: {default})" in entry, \
                    f"the docstring does not give {name}'s default {default}: {entry!r}"
    settable = {n for n, o in table.items() if o["by_name"] and o["kind"] not in ("text",)}
    # what only a file has: its output, the PNG range, the cell size (dx
    # is relax()'s own argument), the series' snapshots
    files_only = {"force", "output_every", "zscale", "zoffset", "dx"}
    missing = settable - set(params) - files_only
    assert not missing, f"options of the library relax() does not take: {sorted(missing)}"
    run_table = {o["name"] for o in sandslide.options("run")}
    assert {"set", "unset", "threads", "force"} <= run_table, run_table
    with pytest.raises(ValueError, match="no options of a command"):
        sandslide.options("nosuch")


def test_pouring_sand_by_name():
    h0 = np.zeros((20, 20))
    h, rep = sandslide.relax(h0, 1.0, add_sand="disk=10,10,3", sand_rate=0.01,
                             sand_duration=20, threads=1)
    assert rep["inflow"] > 0 and abs(np.nansum(h) - rep["inflow"]) < 1e-9 * rep["inflow"], rep
    with pytest.raises(sandslide.InputError, match="go together"):
        sandslide.relax(h0, 1.0, add_sand="disk=10,10,3")


def test_error_classes():
    assert issubclass(sandslide.InputError, (sandslide.Error, ValueError))
    assert issubclass(sandslide.RunError, sandslide.Error)
    assert issubclass(sandslide.RunError, RuntimeError)


def test_errors_print_their_public_names():
    """A traceback names the class the user catches, sandslide.InputError,
    not the private module that defines it."""
    import traceback
    for cls in (sandslide.Error, sandslide.InputError, sandslide.RunError):
        assert f"{cls.__module__}.{cls.__qualname__}" == "sandslide." + cls.__name__
    with pytest.raises(sandslide.InputError) as e:
        sandslide.relax(np.zeros((3, 3)), -1.0)
    last = traceback.format_exception_only(e.type, e.value)[-1]
    assert last == "sandslide.InputError: dx='-1': expected m > 0\n", last


def test_other_inputs_are_converted():
    h0 = pile_on_ramp(12, 14)
    want, _ = sandslide.relax(h0, 1.0, threads=1)
    got, _ = sandslide.relax(h0.tolist(), 1.0, threads=1)
    assert same_bits(got, want), "a list of lists must relax as its array"
    masked = np.ma.masked_array(h0, mask=np.zeros_like(h0, dtype=bool))
    masked.mask[3, 4] = True
    got, _ = sandslide.relax(masked, 1.0, threads=1)
    assert np.isnan(got[3, 4]) and np.isfinite(np.delete(got.ravel(), 3 * 14 + 4)).all(), \
        "a masked cell must be no data (NaN) in the result"
    f32, _ = sandslide.relax(h0.astype(np.float32), 1.0, threads=1)
    assert f32.dtype == np.float64
    row = np.array([[0.0, 0.0, 9.0, 0.0, 0.0]])
    kept = row.copy()
    got, _ = sandslide.relax(row, 1.0, threads=1)
    assert same_bits(row, kept) and not same_bits(got, kept), \
        "a one-row DEM must relax into a new array, its input untouched"


# ---- run and open ----------------------------------------------------------

# the small case of the CLI tests (tests/cli/conftest.py's BASE)
with open(os.path.join(ROOT, "tests", "base.ini")) as _f:
    CASE = _f.read()


@pytest.fixture
def case(tmp_path):
    (tmp_path / "tiny.ini").write_text(CASE)
    return tmp_path / "tiny.ini"


def test_run_writes_the_series_with_overrides(tmp_path, case):
    h5py = pytest.importorskip("h5py", reason="python3-h5py is not installed")
    out = tmp_path / "tiny.h5"
    s = sandslide.run(case, out, set={"time.end": 0.75, "time.output_every": 0.25,
                                      "model.repose_angle": 30}, threads=1)
    assert s["output"] == str(out) and s["end"] == "done", s
    assert s["time"] == 0.75 and s["snapshots"] == 4 and s["steps"] > 0, s
    with h5py.File(out, "r") as f:
        height = f["height"][...]
        time = f["time"][...]
        angle = f.attrs["repose_angle_deg"]
        overrides = f.attrs["case_overrides"]
    assert height.shape == (4, 16, 20), f"/height is {height.shape}"
    assert list(time) == [0.0, 0.25, 0.5, 0.75], f"/time {time}: the overrides not applied"
    assert angle == 30.0, f"repose_angle_deg {angle}: model.repose_angle=30 not applied"
    assert "model.repose_angle=30" in str(overrides), overrides
    assert height[-1, :, -1].max() < 0.2, "no sand left through the open east side"

    with pytest.raises(sandslide.InputError, match="exists"):
        sandslide.run(case, out)                   # refused without force
    s = sandslide.run(case, out, set=["time.end=0.5"], force=True, threads=1)
    assert s["snapshots"] == 2 and s["threads"] == 1, s
    with pytest.raises(sandslide.InputError, match="nonsense"):
        sandslide.run(case, tmp_path / "bad.h5", set={"model.nonsense": 1})
    # an override wins; what it makes redundant is dropped, and said
    s = sandslide.run(case, tmp_path / "layer.h5", set={"model.closure": "bingham",
                      "model.delta": 0.01, "model.density": 1600, "model.viscosity": 5},
                      threads=1)
    assert any("[model] nu" in n and "dropped" in n for n in s["notes"]), s["notes"]
    s = sandslide.run(case, tmp_path / "unset.h5", unset="time.cfl",
                      set={"time.end": 0.5}, threads=1)
    assert s["end"] == "done" and s["notes"] == [], s


def test_fit_finds_nu_and_returns_the_clis_report(tmp_path):
    """sandslide.fit on a twin of the cone (nu = 0.2): the report is the
    command line's (timings aside), and bad words raise the CLI's message."""
    cone = open(os.path.join(ROOT, "cases", "cone.ini")).read()
    for old, new in [("nx = 81", "nx = 41"), ("ny = 81", "ny = 41"), ("dx = 0.03 ", "dx = 0.06 "),
                     ("origin = -1.215 -1.215", "origin = -1.23 -1.23"),
                     ("end = steady", "end = 4 ;"), ("max_time = 300", ""),
                     ("steady_tol = 1e-7", "")]:
        cone = cone.replace(old, new)
    (tmp_path / "cone.ini").write_text(cone)
    sandslide.run(tmp_path / "cone.ini", tmp_path / "twin.h5", set={"model.nu": 0.2}, threads=1)
    report = sandslide.fit(tmp_path / "cone.ini", tmp_path / "twin.h5",
                           {"nu": (0.01, 1, "log")}, closures=["coulomb", "casson"],
                           out=tmp_path / "fit.json", threads=1, profile_points=5)
    assert report["best"]["closure"] == "coulomb", report["verdict"]
    assert abs(report["best"]["params"]["nu"] / 0.2 - 1) < 0.02, report["best"]
    assert [c["closure"] for c in report["closures"]] == ["coulomb", "casson"]
    assert len(report["closures"][0]["profile"]["nu"]["values"]) == 5, "profile_points=5"
    out = cli(["fit", "cone.ini", "twin.h5", "--param", "nu=0.01:1:log", "--closures",
               "coulomb,casson", "--threads", "1", "--profile-points", "5", "--json"],
              tmp_path)
    want = json.loads(out.stdout)
    for r in (report, want):   # the paths as given, and the timings, differ
        for key in ("seconds", "seconds_per_run", "case"):
            r.pop(key)
        r["observations"].pop("path")
    assert report == want, "sandslide.fit's report is not the command line's"
    with pytest.raises(sandslide.InputError, match="nux"):
        sandslide.fit(tmp_path / "cone.ini", tmp_path / "twin.h5", {"nux": "1:2"})
    with pytest.raises(sandslide.InputError, match="grid.points|grid_points"):
        sandslide.fit(tmp_path / "cone.ini", tmp_path / "twin.h5", {"nu": "0.1:1"},
                      grid_points=-3)


# Debian's netCDF4 warns that it was built against another numpy
@pytest.mark.filterwarnings("ignore:numpy.ndarray size changed")
def test_open_gives_a_dataset(tmp_path, case):
    pytest.importorskip("xarray", reason="python3-xarray is not installed")
    out = tmp_path / "tiny.h5"
    sandslide.run(case, out, threads=1)
    with sandslide.open(out) as ds:
        assert ds["height"].dims == ("time", "y", "x"), ds["height"].dims
        # /time in "seconds": float seconds by default, so plots read seconds
        t = ds["time"].values
        assert t.dtype == np.float64 and list(t) == [0.0, 0.5, 1.0], \
            f"time is {t!r} ({t.dtype}): expected float seconds 0, 0.5, 1"
        assert ds.sizes["x"] == 20 and ds.sizes["y"] == 16, dict(ds.sizes)
    with sandslide.open(out, timedelta=True) as ds:
        secs = ds["time"].values / np.timedelta64(1, "s")
        assert ds["time"].dtype.kind == "m" and list(secs) == [0.0, 0.5, 1.0], \
            f"timedelta=True gives {ds['time'].values!r}: expected timedelta64 of 0, 0.5, 1 s"


@pytest.mark.filterwarnings("ignore:numpy.ndarray size changed")
def test_open_of_a_damaged_file_says_what_info_says(tmp_path, case):
    """netCDF says "[Errno -101] NetCDF: HDF error"; open says what
    `sandslide info` says of the same file."""
    pytest.importorskip("xarray", reason="python3-xarray is not installed")
    out = tmp_path / "tiny.h5"
    sandslide.run(case, out, threads=1)
    data = out.read_bytes()
    (tmp_path / "cut.h5").write_bytes(data[:len(data) // 2])
    (tmp_path / "text.h5").write_text("height,time\n")
    for name, why in (("cut.h5", "is damaged: HDF5 cannot open it (truncated file"),
                      ("text.h5", "is not an HDF5 file")):
        r = subprocess.run([SANDSLIDE, "info", name], cwd=tmp_path, capture_output=True,
                           text=True)
        assert r.returncode == 2 and r.stderr.startswith("sandslide: '"), r.stderr
        with pytest.raises(sandslide.InputError) as e:
            sandslide.open(tmp_path / name)
        said = r.stderr.strip()[len("sandslide: "):].replace(f"'{name}'",
                                                             f"'{tmp_path / name}'")
        assert str(e.value) == said and why in said, (str(e.value), said)


def test_version():
    assert sandslide.version() == sandslide.__version__
    out = cli(["--version"], ROOT).stdout
    assert out.startswith(f"sandslide {sandslide.__version__} "), out


# ---- finding the library ---------------------------------------------------

def import_in(pythonpath, env_library, code="import sandslide"):
    env = dict(os.environ, PYTHONPATH=str(pythonpath))
    env.pop("SANDSLIDE_LIBRARY", None)
    if env_library is not None:
        env["SANDSLIDE_LIBRARY"] = str(env_library)
    return subprocess.run([sys.executable, "-c", code], env=env, capture_output=True,
                          text=True, timeout=60)


def package_copy(tmp_path):
    """The module's files alone, away from the build tree."""
    dest = tmp_path / "site" / "sandslide"
    shutil.copytree(os.path.dirname(sandslide.__file__), dest,
                    ignore=shutil.ignore_patterns("__pycache__", "_library.py"))
    return dest.parent


BUILD_LIB = os.environ.get("SANDSLIDE_LIBRARY") or os.path.join(ROOT, "build",
                                                                 "libsandslide.so.0")


def test_missing_library_says_what_was_tried(tmp_path):
    r = import_in(package_copy(tmp_path), tmp_path / "nowhere" / "libsandslide.so.0")
    assert r.returncode != 0 and "ImportError" in r.stderr, r.stderr
    assert "SANDSLIDE_LIBRARY" in r.stderr and "nowhere" in r.stderr, r.stderr
    import ctypes.util
    if ctypes.util.find_library("sandslide"):
        pytest.skip("a libsandslide is installed where the loader looks (make uninstall): "
                    "the search without SANDSLIDE_LIBRARY cannot be shown to fail")
    r = import_in(package_copy(tmp_path / "b"), None)
    assert r.returncode != 0 and "ImportError" in r.stderr, r.stderr
    for tried in ("SANDSLIDE_LIBRARY", "_library.PATH", "build tree", "find_library"):
        assert tried in r.stderr, f"the message does not say it tried {tried}: {r.stderr}"


def test_library_from_the_environment_or_the_installed_path(tmp_path):
    code = "import sandslide; print(sandslide._native.lib._name, sandslide.version())"
    r = import_in(package_copy(tmp_path), BUILD_LIB, code)
    assert r.returncode == 0 and r.stdout.split() == [BUILD_LIB, sandslide.__version__], \
        r.stdout + r.stderr
    site = package_copy(tmp_path / "installed")
    (site / "sandslide" / "_library.py").write_text(f"PATH = {BUILD_LIB!r}\n")
    r = import_in(site, None, code)
    assert r.returncode == 0 and r.stdout.split()[0] == BUILD_LIB, r.stdout + r.stderr
