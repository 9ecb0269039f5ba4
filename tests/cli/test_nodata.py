# SPDX-License-Identifier: BSD-3-Clause
"""`sandslide relax` of a DEM with cells without data (issue 16, item 6).

A real DEM is mostly a clipped region: nodata all round an irregular
outline, with voids inside.  By default (--nodata wall) the nodata cells
are walls: sand never enters them, so a DEM that is below the repose angle
everywhere comes back bit for bit (.asc and GeoTIFF), and a pile against
the nodata edge relaxes with its volume kept.  --nodata open, which lets
sand leave at --open-level (the DEM's lowest height), drains the same
subcritical DEM at its edges: the check that the first test can fail.
"""
import json
import math
import os
import subprocess

import numpy as np
import pytest

from conftest import h5open, run, run_ok, same_bits

TAN35 = math.tan(math.radians(35.0))
NODATA = -9999.0
DX = 0.1


def write_asc(path, h, nodata_mask, cellsize=DX, x0=0.0, y0=0.0):
    """h (ny, nx), row 0 = south; nodata_mask True where there is no data."""
    ny, nx = h.shape
    v = np.where(nodata_mask, NODATA, h)
    head = (f"ncols {nx}\nnrows {ny}\nxllcorner {x0!r}\nyllcorner {y0!r}\n"
            f"cellsize {cellsize!r}\nNODATA_value {NODATA!r}\n")
    rows = [" ".join(repr(float(x)) for x in v[j]) for j in range(ny - 1, -1, -1)]
    with open(path, "w") as f:
        f.write(head + "\n".join(rows) + "\n")


def read_asc(path):
    """(header dict, values (ny, nx) south row first)."""
    with open(path) as f:
        tokens = f.read().split()
    head, k = {}, 0
    while tokens[k][0].isalpha():
        head[tokens[k].lower()] = tokens[k + 1]
        k += 2
    nx, ny = int(head["ncols"]), int(head["nrows"])
    v = np.array([float(t) for t in tokens[k:k + nx * ny]]).reshape(ny, nx)
    return head, v[::-1]


def clipped_dem(ny=36, nx=44):
    """(heights, nodata mask), row 0 south: a tilted plane with a bump, not
    symmetric along either axis, at most ~27 deg anywhere; data inside a
    wobbly outline (a staircase of concave and convex corners), nodata all
    round it, a one-cell void and a 2 x 3 void inside."""
    y, x = (np.mgrid[0:ny, 0:nx] + 0.5) * DX
    h = (5.0 + 0.30 * x + 0.12 * y + 0.08 * np.exp(-((x - 2.7) ** 2 + (y - 1.5) ** 2) / 0.15)
         + 0.01 * np.sin(3.1 * x) * np.cos(2.2 * y))
    th = np.arctan2(y - 1.8, x - 2.2)
    radius = 1.7 + 0.18 * np.sin(3 * th + 0.4) + 0.1 * np.cos(5 * th)
    nodata = np.hypot(x - 2.2, (y - 1.8) / 0.85) > radius
    nodata[17, 14] = True
    nodata[10:12, 25:28] = True
    return h, nodata


def face_slopes(h, wall, dx=DX):
    """Largest face slope of doc/model.md#face-flux with walls where `wall` is True
    (and round the grid): faces touching a wall carry nothing, a wall
    neighbour along a face is replaced by the cell itself."""
    hp = np.pad(np.where(wall, 0.0, h), 1)
    wp = np.pad(wall, 1, constant_values=True)
    c = hp[1:-1, 1:-1]

    def along(dj, di):
        j0, i0 = 1 + dj, 1 + di
        n = hp[j0:j0 + h.shape[0], i0:i0 + h.shape[1]]
        return np.where(wp[j0:j0 + h.shape[0], i0:i0 + h.shape[1]], c, n)

    cy = (along(1, 0) - along(-1, 0)) / (2 * dx)
    cx = (along(0, 1) - along(0, -1)) / (2 * dx)
    s = []
    gn, gt = (c[:, 1:] - c[:, :-1]) / dx, 0.5 * (cy[:, 1:] + cy[:, :-1])
    s.append(np.where(wall[:, 1:] | wall[:, :-1], 0.0, np.hypot(gn, gt)).max())
    gn, gt = (c[1:, :] - c[:-1, :]) / dx, 0.5 * (cx[1:, :] + cx[:-1, :])
    s.append(np.where(wall[1:, :] | wall[:-1, :], 0.0, np.hypot(gn, gt)).max())
    return max(s)


def relax(args, cwd, expect=0):
    r = run(["relax"] + [str(a) for a in args] + ["-q", "--threads", "1"], cwd=cwd)
    assert r.returncode == expect, (
        f"relax {args} exited {r.returncode}, expected {expect}\n{r.stdout}\n{r.stderr}")
    return r


def test_the_clipped_dem_is_what_the_tests_say():
    h, nodata = clipped_dem()
    assert nodata[0].all() and nodata[-1].all() and nodata[:, 0].all() and nodata[:, -1].all()
    assert 0.4 < (~nodata).mean() < 0.85
    s = face_slopes(h, nodata)
    assert s < math.tan(math.radians(30.0)), f"steepest face {math.degrees(math.atan(s))} deg"
    # a staircase outline: nodata cells with data on two or more sides
    inside = np.pad(~nodata, 1).astype(int)
    sides = inside[:-2, 1:-1] + inside[2:, 1:-1] + inside[1:-1, :-2] + inside[1:-1, 2:]
    assert (nodata & (sides >= 2)).sum() >= 10


def test_subcritical_dem_with_nodata_round_it_comes_back_bit_for_bit(tmp_path):
    h0, nodata = clipped_dem()
    write_asc(tmp_path / "dem.asc", h0, nodata, x0=512000.5, y0=4100000.25)
    relax(["dem.asc", "-o", "out.asc", "--report", "r.json"], tmp_path)
    head, h = read_asc(tmp_path / "out.asc")
    rep = json.loads((tmp_path / "r.json").read_text())
    assert rep["steps"] == 0 and rep["cells_moved"] == 0, rep
    assert rep["outflow"] == 0 and rep["volume_after"] == rep["volume_before"], rep
    assert float(head["nodata_value"]) == NODATA
    assert np.all(h[nodata] == NODATA), "a nodata cell lost its marker"
    assert np.all(h[~nodata] != NODATA), "a cell with data became nodata"
    assert same_bits(np.where(nodata, 0.0, h), np.where(nodata, 0.0, h0)), (
        f"heights changed: {np.argwhere(h != np.where(nodata, NODATA, h0))[:10]}")


def test_nodata_open_drains_the_same_dem(tmp_path):
    """--nodata open (nodata cells held at the DEM's lowest height): the
    edges of the same DEM drain, so the test above can fail."""
    h0, nodata = clipped_dem()
    write_asc(tmp_path / "dem.asc", h0, nodata)
    relax(["dem.asc", "--nodata", "open", "-o", "out.asc", "--report", "r.json"], tmp_path)
    _, h = read_asc(tmp_path / "out.asc")
    rep = json.loads((tmp_path / "r.json").read_text())
    assert rep["cells_moved"] > 20 and rep["outflow"] > 0, rep
    assert np.all(h[nodata] == NODATA)
    lost = (h0[~nodata].sum() - h[~nodata].sum()) * DX * DX
    assert lost == pytest.approx(rep["outflow"], rel=1e-9), rep


def gdal():
    if "GDAL: on" not in run(["--version"]).stdout:
        pytest.skip("this build has no GDAL (made with GDAL=0 or MPI=1, or without Debian package libgdal-dev)")
    g = pytest.importorskip("osgeo.gdal", reason="GDAL's Python bindings (python3-gdal) "
                            "are not installed")
    g.UseExceptions()
    return g


def test_subcritical_geotiff_with_nodata_round_it_comes_back_bit_for_bit(tmp_path):
    g = gdal()
    h0, nodata = clipped_dem()
    ny, nx = h0.shape
    ds = g.GetDriverByName("GTiff").Create(str(tmp_path / "dem.tif"), nx, ny, 1,
                                           g.GDT_Float64)
    ds.SetGeoTransform((512000.0, DX, 0.0, 4100000.0 + ny * DX, 0.0, -DX))
    band = ds.GetRasterBand(1)
    band.SetNoDataValue(NODATA)
    band.WriteArray(np.where(nodata, NODATA, h0)[::-1])   # north row first
    ds = band = None
    relax(["dem.tif", "-o", "out.tif", "--report", "r.json"], tmp_path)
    rep = json.loads((tmp_path / "r.json").read_text())
    assert rep["steps"] == 0 and rep["cells_moved"] == 0 and rep["outflow"] == 0, rep
    out = g.Open(str(tmp_path / "out.tif"))
    band = out.GetRasterBand(1)
    h = band.ReadAsArray().astype(np.float64)[::-1]
    marker = band.GetNoDataValue()
    assert marker is not None and np.all(h[nodata] == marker), "nodata lost"
    assert same_bits(np.where(nodata, 0.0, h), np.where(nodata, 0.0, h0)), "heights changed"


def test_pile_against_the_nodata_edge_keeps_its_volume(tmp_path):
    """A 60 deg pile whose foot is cut by the outline: by default its sand
    stays in the DEM (the nodata edge is a wall), every face in sand ends
    at the repose angle, and the nodata cells stay nodata."""
    h0, nodata = clipped_dem()
    y, x = (np.mgrid[0:h0.shape[0], 0:h0.shape[1]] + 0.5) * DX
    pile = np.maximum(0.0, math.tan(math.radians(60)) * (0.6 - np.hypot(x - 3.6, y - 1.6)))
    assert (pile[nodata] > 0.2).any() and (pile[~nodata] > 0.5).any(), "test bug"
    h0 = h0 + pile
    write_asc(tmp_path / "pile.asc", h0, nodata)
    relax(["pile.asc", "-o", "out.asc", "--report", "r.json"], tmp_path)
    _, h = read_asc(tmp_path / "out.asc")
    rep = json.loads((tmp_path / "r.json").read_text())
    assert rep["steady"] is True and rep["steps"] > 0 and rep["outflow"] == 0, rep
    assert np.all(h[nodata] == NODATA), "a nodata cell lost its marker"
    v0, v1 = h0[~nodata].sum(), h[~nodata].sum()
    assert abs(v1 - v0) <= 1e-12 * v0, f"volume {v0!r} -> {v1!r} with nodata walls"
    assert rep["volume_after"] == pytest.approx(rep["volume_before"], rel=1e-12), rep
    assert math.tan(math.radians(rep["max_slope_after_deg"])) <= TAN35 + 1e-6, rep
    s = face_slopes(np.where(nodata, 0.0, h), nodata)
    assert s <= TAN35 + 1e-6, f"steepest face {s!r} above tan 35 = {TAN35!r}"


# ---- the cells without data in the HDF5 output (issue 23) --------------------------

def test_h5_output_marks_the_cells_without_data(tmp_path):
    """relax to .h5: /cell_type is 3 ("nodata", a fourth flag) exactly on the
    DEM's nodata cells and /height NaN there, whether the solver held them
    as walls or as open cells; `info` counts them; read back as a DEM
    (.h5 in, .asc out) they are nodata again, the other cells their
    heights bit for bit."""
    h0, nodata = clipped_dem()
    write_asc(tmp_path / "dem.asc", h0, nodata, x0=512000.5, y0=4100000.25)
    for how in ("wall", "open"):
        relax(["dem.asc", "--nodata", how, "-o", f"{how}.h5"], tmp_path)
        with h5open(tmp_path / f"{how}.h5") as f:
            ct = f["cell_type"]
            assert list(ct.attrs["flag_values"]) == [0, 1, 2, 3], ct.attrs["flag_values"]
            meanings = ct.attrs["flag_meanings"]
            meanings = meanings.decode() if isinstance(meanings, bytes) else meanings
            assert meanings == "flow wall open nodata", meanings
            types = ct[()]
            assert np.array_equal(types == 3, nodata), \
                f"--nodata {how}: cell_type 3 at {np.argwhere((types == 3) != nodata)[:5]}, " \
                "not exactly the nodata cells"
            assert set(np.unique(types[~nodata])) == {0}, "the cells with data are flow cells"
            heights = f["height"][()]
            assert np.isnan(heights[:, nodata]).all(), f"--nodata {how}: a height where no data"
            assert np.isfinite(heights[:, ~nodata]).all()
        r = run_ok(["info", f"{how}.h5"], cwd=tmp_path)
        line = [l for l in r.stdout.splitlines() if l.startswith("cells")][0]
        assert line.split(None, 1)[1] == (f"{(~nodata).sum()} flow, 0 wall, 0 open, "
                                          f"{nodata.sum()} without data"), line
    # the .h5 as a DEM: the nodata cells come back as nodata
    relax(["wall.h5", "-o", "back.asc"], tmp_path)
    head, h = read_asc(tmp_path / "back.asc")
    assert np.array_equal(h == float(head["nodata_value"]), nodata), \
        "nodata cells of the .h5 did not come back as the .asc's nodata"
    assert same_bits(np.where(nodata, 0.0, h), np.where(nodata, 0.0, h0)), "heights changed"


def test_a_run_keeps_three_cell_types(tmp_path):
    """Without cells without data (a run, a DEM without nodata), /cell_type
    keeps its three flags, as before."""
    h0, _ = clipped_dem()
    write_asc(tmp_path / "dem.asc", h0, np.zeros_like(h0, dtype=bool))
    relax(["dem.asc", "-o", "out.h5"], tmp_path)
    with h5open(tmp_path / "out.h5") as f:
        assert list(f["cell_type"].attrs["flag_values"]) == [0, 1, 2]
        assert "without data" not in run_ok(["info", "out.h5"], cwd=tmp_path).stdout


def test_render_draws_the_cells_without_data_as_absent(tmp_path):
    """One pixel per cell: shaded draws the nodata cells white (the
    background), not the wall colour, and no wall border round a grid whose
    edge has no data; gray16 makes them 0 (transparent), like walls."""
    from test_render import read_png
    h0, nodata = clipped_dem()
    write_asc(tmp_path / "dem.asc", h0, nodata)
    relax(["dem.asc", "-o", "out.h5"], tmp_path)
    run_ok(["render", "out.h5", "-o", "shaded", "--scale", "1", "--frames", "-1", "-q"],
           cwd=tmp_path)
    run_ok(["render", "out.h5", "-o", "gray", "--style", "gray16", "--frames", "-1", "-q"],
           cwd=tmp_path)
    ny, nx = nodata.shape
    shaded = read_png(tmp_path / "shaded" / "frame_00000.png", pixels=True)
    px = shaded["pixels"][::-1]      # row 0 south, as the cells
    assert px.shape == (ny, nx, 3), \
        f"{px.shape}: one pixel per cell and no wall border (every edge cell lacks data)"
    white = (px == 255).all(axis=2)
    assert np.array_equal(white, nodata), \
        f"white pixels at {np.argwhere(white != nodata)[:5]} differ from the nodata cells"
    gray = read_png(tmp_path / "gray" / "frame_00000.png", pixels=True)["pixels"][::-1]
    assert np.array_equal(gray == 0, nodata), "gray16: 0 exactly on the nodata cells"


def test_the_guards_snapshot_keeps_the_cells_without_data(tmp_path):
    """relax to .h5 with --nodata open (the solver's open cells, at the open
    level), a NaN put into a height after step 40 (tests/hooks/nan_step.c):
    the guard reopens the series and appends the last good state, which has
    NaN on the nodata cells and nowhere else, like every snapshot before it:
    the reopened series knows its cells without data."""
    from conftest import SANDSLIDE_NAN
    if not os.access(SANDSLIDE_NAN, os.X_OK):
        pytest.fail(f"{SANDSLIDE_NAN} is missing: `make test-hooks` builds it")
    h0, nodata = clipped_dem()
    y, x = (np.mgrid[0:h0.shape[0], 0:h0.shape[1]] + 0.5) * DX
    h0 = h0 + np.maximum(0.0, math.tan(math.radians(60)) * (0.6 - np.hypot(x - 2.2, y - 1.8)))
    assert not nodata[h0.shape[0] // 2, h0.shape[1] // 2], "test bug: the NaN cell has no data"
    write_asc(tmp_path / "pile.asc", h0, nodata)
    p = subprocess.run([SANDSLIDE_NAN, "relax", "pile.asc", "-o", "out.h5", "-q",
                        "--nodata", "open", "--output-every", "0.01", "--threads", "1"],
                       cwd=tmp_path,
                       capture_output=True, text=True, timeout=300,
                       env=dict(os.environ, SANDSLIDE_TEST_NAN_STEP="40"))
    assert p.returncode == 1 and "last good state" in p.stderr, (p.returncode, p.stderr)
    with h5open(tmp_path / "out.h5") as f:
        steps = f["steps"][()]
        heights = f["height"][()]
        types = f["cell_type"][()]
    # the NaN comes after step 40 and is met by step 41, where the state
    # after step 40 taken again is the last good one (39: had step 40
    # ended on a snapshot, which would have met it)
    assert steps[-1] == 40 and len(steps) >= 3, f"snapshots after steps {list(steps)}"
    assert np.array_equal(types == 3, nodata), "cell_type 3 is the nodata cells"
    for k, h in enumerate(heights):
        assert np.array_equal(np.isnan(h), nodata), \
            f"snapshot {k} (step {steps[k]}): NaN at {np.argwhere(np.isnan(h) != nodata)[:5]}"
