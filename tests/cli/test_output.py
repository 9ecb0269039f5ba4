# SPDX-License-Identifier: BSD-3-Clause
"""The HDF5 output matches doc/output.md, and the XDMF sidecar matches it."""
import math
import xml.etree.ElementTree as ET

import h5py
import numpy as np
import pytest

from conftest import asc_text, edit, h5open, run_ok, text_attr, write_png

# 20 x 16 cells of 0.1 x 0.05 m, lower-left corner (-1, 0.5):
# x centres -0.95 + 0.1 i, y centres 0.525 + 0.05 j.
CASE_TEXT = """\
# output layout test   ; a comment line
[grid]
nx = 20
ny = 16
dx = 0.1
dy = 0.05
origin = -1 0.5

[model]
closure = coulomb
repose_angle = 35
nu = 0.1

[time]
end = 1
output_every = 0.25

[boundary]
west = wall
east = open
south = wall
north = wall
open_level = 0

[initial]
type = flat
height = 0.2

# in the south part: rows 0 and 1 (y = 0.525, 0.575), columns 5..9
[wall south_block]
rect = -0.5 0.5 0.0 0.62

[open hole]
disk = 0.5 1.0 0.12

[source pour]
rect = -0.9 1.0 -0.6 1.2
rate = 0.001
"""
NX, NY, DX, DY, X0, Y0 = 20, 16, 0.1, 0.05, -1.0, 0.5
TIMES = [0.0, 0.25, 0.5, 0.75, 1.0]
DIAGNOSTICS = ["volume", "inflow", "outflow", "max_height", "max_slope_deg", "steps",
               "active_fraction", "wall_seconds"]


def centres():
    x = X0 + (np.arange(NX) + 0.5) * DX
    y = Y0 + (np.arange(NY) + 0.5) * DY
    return x, y


def expected_cell_type():
    x, y = centres()
    X, Y = np.meshgrid(x, y)          # (ny, nx), row j = y[j]
    ct = np.zeros((NY, NX), np.uint8)
    wall = (X >= -0.5) & (X <= 0.0) & (Y >= 0.5) & (Y <= 0.62)
    d2 = (X - 0.5) ** 2 + (Y - 1.0) ** 2
    # no centre close to an edge: the C code and numpy must agree
    assert np.min(np.abs(d2 - 0.12 ** 2)) > 1e-6
    ct[wall] = 1
    ct[d2 <= 0.12 ** 2] = 2
    return ct


@pytest.fixture(scope="module")
def output(tmp_path_factory):
    d = tmp_path_factory.mktemp("layout")
    (d / "case.ini").write_text(CASE_TEXT)
    (d / "sub").mkdir()
    r = run_ok(["run", "case.ini", "-o", "sub/result.h5", "--set", "time.cfl=0.8",
                "--threads", "2"], cwd=d)
    return d, d / "sub" / "result.h5", r


def test_height_dataset(output):
    _, path, _ = output
    with h5open(path) as f:
        h = f["height"]
        assert h.dtype == np.float64, h.dtype
        assert h.shape == (len(TIMES), NY, NX), h.shape
        assert h.chunks is not None, "height must be chunked"
        assert h.maxshape == (None, NY, NX), h.maxshape
        assert np.isnan(h.attrs["_FillValue"]) and np.isnan(h.fillvalue), \
            "height's _FillValue (and HDF5 fill value) must be NaN"
        walls = f["cell_type"][...] == 1
        assert walls.any(), "test bug: the case has no wall cells"
        hh = h[...]
        assert np.all(np.isnan(hh[:, walls])), "walls must be stored as NaN (missing)"
        assert np.all(np.isfinite(hh[:, ~walls])), "every other cell must be finite"


def test_time_values_exact(output):
    _, path, _ = output
    with h5open(path) as f:
        t = f["time"]
        assert t.dtype == np.float64 and t.shape == (len(TIMES),), (t.dtype, t.shape)
        # "seconds": elapsed time to xarray (timedelta64) and CDO, no calendar
        assert text_attr(t, "units") == "seconds"
        assert list(t[...]) == TIMES, f"times {list(t[...])} != {TIMES}"


def test_coordinates(output):
    _, path, _ = output
    x, y = centres()
    with h5open(path) as f:
        for name, want in (("x", x), ("y", y)):
            d = f[name]
            assert d.dtype == np.float64 and d.shape == want.shape, (name, d.dtype, d.shape)
            assert text_attr(d, "units") == "m", name
            np.testing.assert_allclose(d[...], want, rtol=0, atol=1e-12,
                                       err_msg=f"{name} is not origin + (i + 0.5) d")
        assert np.all(np.diff(f["y"][...]) > 0), "y must run south to north"
        assert np.all(np.diff(f["x"][...]) > 0), "x must run west to east"


def test_cell_type(output):
    _, path, _ = output
    with h5open(path) as f:
        ct = f["cell_type"]
        # int8 (netCDF's byte): VTK's netCDF-CF reader rejects ubyte
        assert ct.dtype == np.int8 and ct.shape == (NY, NX), (ct.dtype, ct.shape)
        flags = np.asarray(ct.attrs["flag_values"])
        assert flags.dtype == np.int8 and list(flags.ravel()) == [0, 1, 2], flags
        assert text_attr(ct, "flag_meanings") == "flow wall open"
        got = ct[...]
    want = expected_cell_type()
    assert got[0:2, 5:10].tolist() == [[1] * 5] * 2, \
        "the wall rect in the south must be at the low row indices 0, 1"
    assert np.all(got[-2:, 5:10] != 1), "y must run south to north (no wall in the north rows)"
    np.testing.assert_array_equal(got, want, err_msg="cell_type differs from the case's "
                                  "wall rect (1) and open disk (2)")


def test_diagnostics(output):
    _, path, _ = output
    with h5open(path) as f:
        for name in DIAGNOSTICS:
            assert name in f, f"missing diagnostic {name}"
            d = f[name]
            assert d.dtype == np.float64 and d.shape == (len(TIMES),), (name, d.dtype, d.shape)
            assert np.all(np.isfinite(d[...])), name
        # 12 source cells of 0.1 x 0.05 m at 1 mm/s
        inflow = f["inflow"][...]
        np.testing.assert_allclose(inflow, 1e-3 * 12 * DX * DY * np.array(TIMES),
                                   rtol=1e-9, atol=1e-15)
        assert np.all(np.diff(f["steps"][...]) >= 0)
        assert f["outflow"][-1] > 0, "sand next to the open disk and side must flow out"
        vol = f["volume"][...]
        balance = (vol[-1] - vol[0]) - (inflow[-1] - f["outflow"][-1])
        assert abs(balance) < 1e-12 * max(abs(vol[0]), 1.0), f"volume balance {balance}"


def test_every_variable_has_units_and_long_name(output):
    _, path, _ = output
    with h5open(path) as f:
        names = []
        f.visititems(lambda n, o: names.append(n) if isinstance(o, h5py.Dataset) else None)
        for required in ["height", "time", "x", "y", "cell_type"] + DIAGNOSTICS:
            assert required in names, f"missing dataset {required}"
        for n in names:
            for a in ("units", "long_name"):
                assert a in f[n].attrs, f"{n} has no {a!r} attribute"
                assert text_attr(f[n], a), f"{n}.{a} is empty"


def test_dimension_scales(output):
    _, path, _ = output
    with h5open(path) as f:
        h = f["height"]
        assert len(h.dims[0]) >= 1 and h.dims[0][0].name == "/time"
        assert len(h.dims[1]) >= 1 and h.dims[1][0].name == "/y"
        assert len(h.dims[2]) >= 1 and h.dims[2][0].name == "/x"
        for name in ("time", "x", "y"):
            assert h5py.h5ds.is_scale(f[name].id), f"{name} is not a dimension scale"
        ct = f["cell_type"]
        assert ct.dims[0][0].name == "/y" and ct.dims[1][0].name == "/x"
        assert f["volume"].dims[0][0].name == "/time"


def test_global_attributes(output):
    d, path, _ = output
    with h5open(path) as f:
        assert text_attr(f, "Conventions") == "CF-1.8"
        assert text_attr(f, "title")
        assert text_attr(f, "source").startswith("sandslide")
        assert text_attr(f, "closure") == "coulomb"
        assert float(f.attrs["repose_angle_deg"]) == 35.0
        assert float(f.attrs["nu"]) == 0.1
        assert math.isfinite(float(f.attrs["gamma"]))
        assert float(f.attrs["dx"]) == DX and float(f.attrs["dy"]) == DY
        history = text_attr(f, "history")
        assert "case.ini" in history and "time.cfl=0.8" in history, history
        assert "sub/result.h5" in history, history
        assert text_attr(f, "case") == (d / "case.ini").read_text(), \
            "the case attribute must be the whole case file text"


def test_flat_initial_height(output):
    _, path, _ = output
    with h5open(path) as f:
        h0 = f["height"][0]
        ct = f["cell_type"][...]
    flow = ct == 0
    assert flow.sum() > 200
    assert np.all(h0[flow] == 0.2), "flat initial height must be 0.2 on every flow cell"


def test_xdmf_sidecar(output):
    _, path, _ = output
    xmf = path.with_suffix(".xmf")
    assert xmf.exists(), "the XDMF sidecar OUT.xmf must be written beside OUT.h5"
    root = ET.parse(xmf).getroot()
    assert root.tag == "Xdmf"
    grids = [g for g in root.iter("Grid") if g.find("Time") is not None]
    assert len(grids) == len(TIMES), f"{len(grids)} timed Grids, expected {len(TIMES)}"
    times = [float(g.find("Time").get("Value")) for g in grids]
    with h5open(path) as f:
        assert times == list(f["time"][...])
    refs = [e.text.strip() for e in root.iter("DataItem")
            if e.get("Format") == "HDF" and e.text]
    assert refs and all(r.split(":")[0] == "result.h5" for r in refs), \
        f"the sidecar must reference result.h5 (relative): {refs[:3]}"
    # "FILE:/height|START:STRIDE:COUNT:DATASPACE": XDMF3's slice of an HDF5 dataset
    assert any(r.split("|")[0].endswith(":/height") for r in refs), \
        f"the sidecar must take height from /height: {refs[:3]}"


def test_summary_on_stdout(output):
    _, _, r = output
    assert "sub/result.h5" in r.stdout and "5 snapshots" in r.stdout, r.stdout


def test_mask_orientation(tmp_path):
    """The image's top row is the grid's north row."""
    base = CASE_TEXT.split("# in the south part")[0]
    rows = [[0] * NX for _ in range(NY)]
    for i in range(4):
        rows[0][i] = 255          # top-left pixels: north-west cells
    rows[NY - 1][NX - 1] = 128    # bottom-right pixel: south-east cell
    write_png(tmp_path / "m.png", rows)
    (tmp_path / "case.ini").write_text(base + "[wall m]\nmask = m.png\n")
    run_ok(["run", "case.ini", "-o", "m.h5", "-q"], cwd=tmp_path)
    with h5open(tmp_path / "m.h5") as f:
        ct = f["cell_type"][...]
    want = np.zeros((NY, NX), np.uint8)
    want[NY - 1, 0:4] = 1
    want[0, NX - 1] = 1
    np.testing.assert_array_equal(ct, want, err_msg="mask pixels -> wall cells")


def test_initial_file_orientation(tmp_path):
    """An ESRI ASCII grid lists the north row first; heights land unchanged."""
    base = CASE_TEXT.split("# in the south part")[0]
    values = np.round(np.random.default_rng(1).uniform(0.1, 0.101, (NY, NX)), 6)
    rows = [[f"{v:.6f}" for v in values[NY - 1 - j]] for j in range(NY)]  # north first
    (tmp_path / "init.asc").write_text(asc_text(rows, cellsize=0.1, x0=-1, y0=0.5))
    text = edit(base, "type = flat\nheight = 0.2\n", "type = file\nfile = init.asc\n")
    text = edit(text, "dy = 0.05\n", "")
    (tmp_path / "case.ini").write_text(text)
    run_ok(["run", "case.ini", "-o", "f.h5", "-q"], cwd=tmp_path)
    with h5open(tmp_path / "f.h5") as f:
        h0 = f["height"][0]
    np.testing.assert_array_equal(h0, values, err_msg="initial heights from the .asc file "
                                  "(row j of height = row ny-1-j of the file)")


def test_cone_initial_state(tmp_path):
    base = CASE_TEXT.split("# in the south part")[0]
    text = edit(base, "type = flat\nheight = 0.2\n",
                "type = cone\ncenter = 0 0.9\nradius = 0.3\nangle = 30\nheight = 0.1\n")
    (tmp_path / "case.ini").write_text(text)
    run_ok(["run", "case.ini", "-o", "c.h5", "-q"], cwd=tmp_path)
    x, y = centres()
    X, Y = np.meshgrid(x, y)
    want = 0.1 + math.tan(math.radians(30)) * np.maximum(0.3 - np.hypot(X, Y - 0.9), 0)
    with h5open(tmp_path / "c.h5") as f:
        np.testing.assert_allclose(f["height"][0], want, rtol=0, atol=1e-12)
