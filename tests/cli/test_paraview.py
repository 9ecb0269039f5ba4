# SPDX-License-Identifier: BSD-3-Clause
"""ParaView opens a run's XDMF sidecar OUT.xmf with its default reader
(whatever paraview.simple.OpenDataFile picks: XDMF3 in ParaView 5.11) and
shows every snapshot's heights and the cell types where h5py finds them,
and VTK's netCDF-CF reader opens OUT.h5 itself.

One pvbatch run (a helper script written into tmp_path) reads everything
and saves what it saw to a .npz and a .json; the checks against h5py are
made here.  The grid is not square, its cells are not square and its
origin is not 0, so a swap of x and y, a flip of the rows (row 0 is the
south row) or coordinates rounded to float32 show.  The file has walls
(NaN heights, the _FillValue) and an int8 cell_type, which VTK's netCDF
reader needs (it rejects ubyte).
"""
import json
import re
import shutil
import subprocess
import textwrap

import numpy as np
import pytest

from conftest import h5open, run_ok, same_bits

pytestmark = pytest.mark.skipif(
    shutil.which("pvbatch") is None,
    reason="pvbatch not on PATH (Debian packages paraview and python3-paraview)")

NX, NY = 23, 13
CASE = f"""\
# test_paraview.py: a grid that is not square, of cells that are not square
[grid]
nx = {NX}
ny = {NY}
dx = 0.1
dy = 0.07
origin = 1.3 -0.4

[model]
closure = coulomb
repose_angle = 35
nu = 0.1

[time]
end = 2
output_every = 0.5

[boundary]
west = wall
east = open
south = wall
north = wall

[initial]
type = cone
center = 2.0 0.1
radius = 0.5
angle = 50
height = 0

# one corner wall, another open: cell_type is the same under no flip or swap
[wall south_west]
rect = 1.3 -0.4 1.75 -0.1
[open north_east]
rect = 3.2 0.3 3.6 0.51
"""

# Runs in pvbatch: HELPER OUT.json OUT.npz XMF... -- H5...
HELPER = textwrap.dedent("""\
    import json, sys, traceback
    import numpy as np
    from paraview import servermanager
    from paraview.simple import OpenDataFile
    from vtkmodules.util.numpy_support import vtk_to_numpy
    from vtkmodules.vtkFiltersCore import vtkCellCenters

    out_json, out_npz = sys.argv[1], sys.argv[2]
    split = sys.argv.index("--")
    xmfs, h5s = sys.argv[3:split], sys.argv[split + 1:]
    report, arrays = {"xdmf": {}, "cf": {}}, {}

    def first_leaf(d):
        while d is not None and d.IsA("vtkDataObjectTree"):
            d = d.GetBlock(0)
        return d

    def centres(d):
        f = vtkCellCenters()
        f.SetInputData(d)
        f.Update()
        return vtk_to_numpy(f.GetOutput().GetPoints().GetData()).copy()

    for label, path in enumerate(xmfs):
        label = str(label)
        rep = report["xdmf"][label] = {"path": path}
        try:
            r = OpenDataFile(path)
            rep["reader"] = "%s (%s)" % (r.GetXMLName(),
                                         r.GetClientSideObject().GetClassName())
            times = r.TimestepValues
            times = [] if times is None else list(times) if hasattr(times, "__len__") \\
                else [times]
            rep["times"] = times
            rep["steps"] = {}
            for k in sorted({0, len(times) // 2, len(times) - 1}):
                r.UpdatePipeline(times[k])
                d = first_leaf(servermanager.Fetch(r))
                s = rep["steps"][str(k)] = {
                    "class": d.GetClassName(), "cells": d.GetNumberOfCells(),
                    "bounds": list(d.GetBounds())}
                cd = d.GetCellData()
                s["arrays"] = [cd.GetArrayName(i) for i in range(cd.GetNumberOfArrays())]
                for name in ("height", "cell_type"):
                    if cd.GetArray(name) is not None:
                        arrays["xdmf%s_%s_%d" % (label, name, k)] = \\
                            vtk_to_numpy(cd.GetArray(name)).copy()
                if d.GetNumberOfCells():
                    arrays["xdmf%s_centres_%d" % (label, k)] = centres(d)
        except Exception:
            rep["error"] = traceback.format_exc()

    for label, path in enumerate(h5s):
        label = str(label)
        rep = report["cf"][label] = {"path": path}
        try:
            from vtkmodules.vtkIONetCDF import vtkNetCDFCFReader
            from vtkmodules.vtkCommonExecutionModel import vtkStreamingDemandDrivenPipeline
            r = vtkNetCDFCFReader()
            r.SetFileName(path)
            r.SphericalCoordinatesOff()
            r.UpdateInformation()
            info = r.GetOutputInformation(0)
            key = vtkStreamingDemandDrivenPipeline.TIME_STEPS()
            times = list(info.Get(key)) if info.Has(key) else []
            rep["times"] = times
            rep["steps"] = {}
            for k in sorted({0, len(times) - 1}):
                ok = r.UpdateTimeStep(times[k])
                d = first_leaf(r.GetOutputDataObject(0))
                s = rep["steps"][str(k)] = {"class": d.GetClassName(), "ok": bool(ok),
                                            "bounds": list(d.GetBounds())}
                a = d.GetPointData().GetArray("height")
                if a is not None:
                    arrays["cf%s_height_%d" % (label, k)] = vtk_to_numpy(a).copy()
                    arrays["cf%s_points_%d" % (label, k)] = np.array(
                        [d.GetPoint(i) for i in range(d.GetNumberOfPoints())])
        except Exception:
            rep["error"] = traceback.format_exc()

    np.savez(out_npz, **arrays)
    with open(out_json, "w") as f:
        json.dump(report, f)
""")


@pytest.fixture(scope="module")
def seen(tmp_path_factory):
    """Run the case and read its sidecar and file in pvbatch."""
    tmp = tmp_path_factory.mktemp("paraview")
    (tmp / "case.ini").write_text(CASE)
    run_ok(["run", "case.ini", "-o", "run.h5", "-q"], cwd=tmp)
    (tmp / "helper.py").write_text(HELPER)
    xmfs = [tmp / "run.xmf"]
    h5s = [tmp / "run.h5"]
    r = subprocess.run(["pvbatch", str(tmp / "helper.py"), str(tmp / "seen.json"),
                        str(tmp / "seen.npz")] + [str(p) for p in xmfs] + ["--"] +
                       [str(p) for p in h5s],
                       cwd=tmp, capture_output=True, text=True, timeout=120)
    assert r.returncode == 0 and (tmp / "seen.json").exists(), (
        f"pvbatch failed ({r.returncode}):\nstdout:\n{r.stdout[-3000:]}\n"
        f"stderr:\n{r.stderr[-3000:]}")
    report = json.loads((tmp / "seen.json").read_text())
    with np.load(tmp / "seen.npz") as z:
        arrays = {k: z[k] for k in z.files}
    return {"report": report, "arrays": arrays, "h5": {"0": h5s[0]},
            "stderr": r.stderr}


LAYOUTS = [pytest.param("0", id="as-written")]


def differs(got, want):
    """Where float64 array got first differs from want, for a message."""
    if got.shape != want.shape or got.dtype != want.dtype:
        return f"{got.dtype} {got.shape} where /height has {want.dtype} {want.shape}"
    i = int(np.flatnonzero(got.view(np.uint64) != want.view(np.uint64))[0])
    return f"cell {i} (row {i // NX}, column {i % NX}): {got[i]!r}, not {want[i]!r}"


def expected(path):
    with h5open(path) as f:
        return {"time": f["time"][...], "height": f["height"][...],
                "cell_type": f["cell_type"][...], "x": f["x"][...], "y": f["y"][...],
                "dx": float(f.attrs["dx"]), "dy": float(f.attrs["dy"])}


@pytest.mark.parametrize("layout", LAYOUTS)
def test_default_reader_shows_every_snapshot(seen, layout):
    rep = seen["report"]["xdmf"][layout]
    assert "error" not in rep, f"pvbatch could not read {rep['path']}:\n{rep['error']}"
    who = f"ParaView's default reader {rep['reader']}"
    want = expected(seen["h5"][layout])
    n = len(want["time"])
    assert n >= 3, "test bug: the run wrote fewer than 3 snapshots"
    assert not same_bits(want["height"][0], want["height"][-1]), \
        "test bug: the heights do not change, a reader stuck on snapshot 0 would pass"
    assert set(np.unique(want["cell_type"])) == {0, 1, 2}, \
        "test bug: the case lacks flow, wall or open cells"
    # same_bits below then checks that NaN comes through
    wall = want["cell_type"] == 1
    assert np.isnan(want["height"][:, wall]).all(), "walls are not NaN in /height"
    assert rep["times"] == list(want["time"]), \
        f"{who}: time steps {rep['times']} are not /time {list(want['time'])}"

    x, y, dx, dy = want["x"], want["y"], want["dx"], want["dy"]
    edges = [x[0] - dx / 2, x[-1] + dx / 2, y[0] - dy / 2, y[-1] + dy / 2, 0, 0]
    cx, cy = np.meshgrid(x, y)              # (y, x): row 0 is the south row
    centres = np.stack([cx.ravel(), cy.ravel(), np.zeros(cx.size)], axis=1)
    assert sorted(map(int, rep["steps"])) == sorted({0, n // 2, n - 1}), \
        f"test bug: the helper read snapshots {sorted(rep['steps'])}"
    arrays = seen["arrays"]
    for k, s in rep["steps"].items():
        k = int(k)
        at = f"{who} at t = {want['time'][k]!r} s (snapshot {k})"
        assert s["cells"] == NX * NY, f"{at}: {s['cells']} cells, not {NX} x {NY}"
        assert np.allclose(s["bounds"], edges, rtol=0, atol=1e-9), (
            f"{at}: bounds {s['bounds']} are not the cell edges {edges} "
            f"(x and y swapped, float32 coordinates, or not in the x-y plane)")
        got = arrays.get(f"xdmf{layout}_centres_{k}")
        assert got is not None, f"{at}: no cells"
        assert np.allclose(got, centres, rtol=0, atol=1e-9), (
            f"{at}: cell centres are not (x[i], y[j]) in the order of the file's (y, x) "
            f"arrays (rows flipped or x and y swapped); first ones {got[:3]!r} vs "
            f"{centres[:3]!r}")
        h = arrays.get(f"xdmf{layout}_height_{k}")
        assert h is not None, f"{at}: no cell array 'height' (has {s['arrays']})"
        ref = want["height"][k].ravel()
        assert h.dtype == np.float64 and same_bits(h, ref), \
            f"{at}: height is not /height[{k}] bit for bit: {differs(h, ref)}"
        c = arrays.get(f"xdmf{layout}_cell_type_{k}")
        assert c is not None, f"{at}: no cell array 'cell_type' (has {s['arrays']})"
        assert np.array_equal(c.astype(np.int64), want["cell_type"].ravel().astype(np.int64)), \
            f"{at}: cell_type is not /cell_type ({c.dtype}, values {np.unique(c)})"


CF_LAYOUTS = [pytest.param("0", id="as-written")]


@pytest.mark.parametrize("layout", CF_LAYOUTS)
def test_netcdf_cf_reader_reads_height(seen, layout):
    rep = seen["report"]["cf"][layout]
    assert "error" not in rep, (
        f"vtkNetCDFCFReader (SphericalCoordinatesOff) could not read {rep['path']}:\n"
        f"{rep['error']}\npvbatch stderr (tail):\n{seen['stderr'][-1500:]}")
    want = expected(seen["h5"][layout])
    assert rep["times"] == list(want["time"]), \
        f"vtkNetCDFCFReader: time steps {rep['times']} are not /time {list(want['time'])}"
    cx, cy = np.meshgrid(want["x"], want["y"])
    points = np.stack([cx.ravel(), cy.ravel(), np.zeros(cx.size)], axis=1)
    for k, s in rep["steps"].items():
        k = int(k)
        at = f"vtkNetCDFCFReader at t = {want['time'][k]!r} s (snapshot {k})"
        h = seen["arrays"].get(f"cf{layout}_height_{k}")
        said = [re.sub(r"\x1b\[[0-9;]*m", "", line).strip()   # no terminal colours
                for line in seen["stderr"].splitlines() if "netCDF" in line][:3]
        assert h is not None, (f"{at}: no point array 'height' in its {s['class']} "
                               f"(update {'succeeded' if s['ok'] else 'failed'}); it said:\n"
                               + "\n".join(said))
        ref = want["height"][k].ravel()
        assert h.dtype == np.float64 and same_bits(h, ref), \
            f"{at}: height is not /height[{k}] bit for bit: {differs(h, ref)}"
        p = seen["arrays"][f"cf{layout}_points_{k}"]
        assert np.allclose(p, points, rtol=0, atol=1e-9), \
            f"{at}: its points are not the cell centres (x[i], y[j]) in (y, x) order"
