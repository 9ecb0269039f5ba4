# SPDX-License-Identifier: BSD-3-Clause
"""The output opens as it is in the tools users have: GDAL (gdalinfo, QGIS),
xarray and CDO.  ParaView and VTK's netCDF-CF reader are in
test_paraview.py.

Each check reads a value through the tool and compares it with h5py's
reading of the same cell, on grids that are neither square nor symmetric,
so that a flipped or transposed picture fails.  The tools come from
`make deps-test` (gdal-bin, python3-gdal, python3-xarray, python3-netcdf4,
cdo); a test whose tool is missing is skipped and says which package.
"""
import os
import re
import shutil
import subprocess

import numpy as np
import pytest

from conftest import BASE, asc_text, edit, h5open, run, run_ok

# 20 x 16 cells of 0.1 m from (1, 2); a wall block in the north-west and a
# cone off centre, so no symmetry hides a flip.
CASE = edit(edit(BASE, "origin = 0 0\n", "origin = 1 2\n"),
            "[initial]\ntype = flat\nheight = 0.2\n",
            "[initial]\ntype = cone\ncenter = 2.4 2.5\nradius = 0.5\nangle = 50\n"
            "height = 0.05\n\n[wall block]\nrect = 1.2 3.1 1.6 3.5\n")


def gdal():
    osgeo = pytest.importorskip("osgeo.gdal", reason="GDAL's Python bindings "
                                "(python3-gdal) are not installed")
    osgeo.UseExceptions()
    return osgeo


@pytest.fixture(scope="module")
def run_files(tmp_path_factory):
    """The case run twice: as run.h5 and as run.nc."""
    d = tmp_path_factory.mktemp("ecosystem")
    (d / "case.ini").write_text(CASE)
    for name in ("run.h5", "run.nc"):
        run_ok(["run", "case.ini", "-o", name, "-q"], cwd=d)
    # each its own XDMF sidecar, naming its own file
    assert "run.h5:/height" in (d / "run.xmf").read_text(), "run.xmf does not name run.h5"
    assert "run.nc:/height" in (d / "run.nc.xmf").read_text(), \
        "run.nc.xmf does not name run.nc"
    with h5open(d / "run.h5") as f:
        ref = {k: f[k][...] for k in ("height", "cell_type", "time", "x", "y")}
    assert (ref["cell_type"] == 1).any(), "test bug: the case has no walls"
    return d, ref


def test_gdal_hdf5_driver_georeferences_h5(run_files):
    """gdalinfo run.h5 picks GDAL's HDF5 driver; the .aux.xml sidecar gives
    its height subdataset the grid's geotransform and NaN as no data."""
    g = gdal()
    d, ref = run_files
    ds = g.Open(str(d / "run.h5"))
    assert ds.GetDriver().ShortName == "HDF5", ds.GetDriver().ShortName
    subs = [name for name, _ in ds.GetSubDatasets()]
    name = next((s for s in subs if s.endswith("//height")), None)
    assert name, f"no height subdataset in {subs}"
    h = g.Open(name)
    nt, ny, nx = ref["height"].shape
    assert (h.RasterXSize, h.RasterYSize, h.RasterCount) == (nx, ny, nt)
    gt = h.GetGeoTransform(can_return_null=True)
    assert gt is not None, "the HDF5 driver found no geotransform: .aux.xml not read"
    dx, dy = 0.1, 0.1
    np.testing.assert_allclose(gt, (1.0, dx, 0.0, 2.0, 0.0, dy), rtol=0, atol=1e-12,
                               err_msg="geotransform is not the grid's corner and cell size")
    # the centre of pixel (row r, column c) is the file's (y[r], x[c])
    for r, c in ((0, 0), (ny - 1, 3), (5, nx - 1)):
        assert abs(gt[0] + (c + 0.5) * gt[1] - ref["x"][c]) < 1e-9
        assert abs(gt[3] + (r + 0.5) * gt[5] - ref["y"][r]) < 1e-9
    last = h.GetRasterBand(nt)
    assert np.isnan(last.GetNoDataValue()), "no data is not NaN"
    got = last.ReadAsArray()
    assert np.array_equal(got, ref["height"][-1], equal_nan=True), \
        "the HDF5 driver's last band differs from /height"


def test_gdal_netcdf_driver_opens_nc_north_up(run_files):
    """A run named .nc opens with GDAL's netCDF driver: georeferenced from
    x and y, north up, walls as no data."""
    g = gdal()
    d, ref = run_files
    ds = g.Open(str(d / "run.nc"))
    assert ds.GetDriver().ShortName == "netCDF", ds.GetDriver().ShortName
    h = g.Open(f'NETCDF:"{d / "run.nc"}":height')
    nt, ny, nx = ref["height"].shape
    gt = h.GetGeoTransform()
    np.testing.assert_allclose(gt, (1.0, 0.1, 0.0, 2.0 + ny * 0.1, 0.0, -0.1), rtol=0,
                               atol=1e-9, err_msg="not north up at the grid's corner")
    band = h.GetRasterBand(nt)
    assert np.isnan(band.GetNoDataValue()), "the _FillValue NaN is not GDAL's no data"
    got = band.ReadAsArray()
    assert np.array_equal(got, ref["height"][-1][::-1], equal_nan=True), \
        "the netCDF driver's picture is not /height with the north row first"
    walls = ref["cell_type"][::-1] == 1
    assert np.all(np.isnan(got[walls])) and np.all(np.isfinite(got[~walls])), \
        "walls must be missing and only walls"


def test_xarray_reads_elapsed_time_and_missing_walls(run_files):
    xr = pytest.importorskip("xarray", reason="python3-xarray is not installed")
    pytest.importorskip("netCDF4", reason="python3-netcdf4 is not installed")
    d, ref = run_files
    with xr.open_dataset(d / "run.h5", engine="netcdf4") as ds:
        t = ds["time"].values
        assert np.issubdtype(t.dtype, np.timedelta64), \
            f"time is {t.dtype}: 'seconds' should decode as elapsed time"
        assert np.array_equal(t / np.timedelta64(1, "s"), ref["time"]), t
        assert ds["cell_type"].dtype == np.int8, ds["cell_type"].dtype
        walls = ds["cell_type"].values == 1
        h = ds["height"].isel(time=-1).values
        assert np.all(np.isnan(h[walls])), "walls are not missing in xarray"
        assert np.array_equal(h[~walls], ref["height"][-1][~walls]), \
            "xarray's heights differ from h5py's"
        # coordinates: the cell of the cone's top by label
        top = ds["height"].isel(time=0).where(ds["cell_type"] == 0)
        y, x = np.unravel_index(int(np.nanargmax(top.values)), top.shape)
        assert abs(float(ds.x[x]) - 2.4) < 0.1 and abs(float(ds.y[y]) - 2.5) < 0.1, \
            f"the cone's top is at ({float(ds.x[x])}, {float(ds.y[y])}), not (2.4, 2.5)"


def test_cdo_reads_elapsed_time_and_missing_walls(run_files):
    if not shutil.which("cdo"):
        pytest.skip("cdo is not installed (Debian package cdo)")
    d, ref = run_files
    r = subprocess.run(["cdo", "-s", "showtimestamp", str(d / "run.h5")], capture_output=True,
                       text=True, timeout=60)
    assert r.returncode == 0, r.stderr
    stamps = r.stdout.split()
    want = [f"0000-00-00T00:00:{int(t):02d}" for t in ref["time"]]
    assert stamps == want, f"CDO's times {stamps}, expected elapsed {want}"
    r = subprocess.run(["cdo", "-s", "info", "-selname,height", str(d / "run.h5")],
                       capture_output=True, text=True, timeout=60)
    assert r.returncode == 0, r.stderr
    walls = int((ref["cell_type"] == 1).sum())
    rows = [line for line in r.stdout.splitlines() if re.match(r"\s*\d+\s*:", line)]
    assert len(rows) == len(ref["time"]), r.stdout
    for line in rows:
        fields = line.split()   # N : Date Time Level Gridsize Miss : Min Mean Max : ...
        miss = int(fields[fields.index(":", 2) - 1])
        assert miss == walls, f"CDO counts {miss} missing cells, not the {walls} walls:\n{line}"


@pytest.mark.skipif("GDAL: on" not in run(["--version"]).stdout,
                    reason="this build reads no GeoTIFF (made with GDAL=0 or MPI=1, or without "
                           "Debian package libgdal-dev)")
def test_crs_kept_from_geotiff_to_h5_and_back(tmp_path):
    """relax of a GeoTIFF with a CRS into .h5 writes the CF grid mapping
    /crs; relax of that .h5 into GeoTIFF gives the CRS, geotransform and
    heights of relaxing the GeoTIFF straight to GeoTIFF."""
    g = gdal()
    rows = [[(3 * i + 7 * j) % 11 + (5.0 if i < 4 and j > 6 else 0.0) for i in range(12)]
            for j in range(10)]   # north row first; not symmetric
    (tmp_path / "dem.asc").write_text(asc_text(rows, cellsize=1.0))
    g.Translate(str(tmp_path / "dem.tif"), str(tmp_path / "dem.asc"), outputSRS="EPSG:32632",
                outputBounds=[500000, 5200010, 500012, 5200000])
    run_ok(["relax", "dem.tif", "-o", "dem.h5", "-q"], cwd=tmp_path)
    run_ok(["relax", "dem.tif", "-o", "direct.tif", "-q"], cwd=tmp_path)
    with h5open(tmp_path / "dem.h5") as f:
        assert "crs" in f, "no /crs grid mapping variable"
        wkt = f["crs"].attrs["crs_wkt"]
        wkt = wkt.decode() if isinstance(wkt, bytes) else str(wkt)
        assert "UTM zone 32N" in wkt, wkt
        for name in ("height", "cell_type"):
            gm = f[name].attrs["grid_mapping"]
            assert (gm.decode() if isinstance(gm, bytes) else gm) == "crs", name
        last = f["height"][-1]
    # the .h5 holds the bits of the GeoTIFF relaxed straight, south row first
    direct = g.Open(str(tmp_path / "direct.tif"))
    assert np.array_equal(last[::-1], direct.ReadAsArray()), \
        "the .h5's last snapshot is not the surface relaxed to GeoTIFF"
    # GDAL's netCDF driver reads the CRS through grid_mapping
    nc = g.Open(f'NETCDF:"{tmp_path / "dem.h5"}":height')
    srs = nc.GetSpatialRef()
    assert srs is not None and srs.GetAuthorityCode(None) == "32632", nc.GetProjection()
    # and back to GeoTIFF
    run_ok(["relax", "dem.h5", "-o", "back.tif", "-q"], cwd=tmp_path)
    back = g.Open(str(tmp_path / "back.tif"))
    assert back.GetSpatialRef() is not None, "the CRS was lost on the way back"
    assert back.GetSpatialRef().IsSame(direct.GetSpatialRef()), back.GetProjection()
    np.testing.assert_allclose(back.GetGeoTransform(), direct.GetGeoTransform(), rtol=0,
                               atol=1e-9)
    # relaxing the relaxed surface again moves it by next to nothing
    moved = np.abs(back.ReadAsArray() - direct.ReadAsArray()).max()
    assert moved < 1e-6, f"the round trip moved a height by {moved} m"
    # gdalinfo on the plain .h5 path finds the CRS too (.aux.xml)
    h = g.Open(f'HDF5:"{tmp_path / "dem.h5"}"://height')
    assert h.GetSpatialRef() is not None and \
        h.GetSpatialRef().IsSame(direct.GetSpatialRef()), "no CRS through the HDF5 driver"
    assert os.path.isfile(tmp_path / "dem.h5.aux.xml")


@pytest.mark.skipif("GDAL: on" not in run(["--version"]).stdout,
                    reason="this build reads no GeoTIFF (made with GDAL=0 or MPI=1, or without "
                           "Debian package libgdal-dev)")
def test_dem_in_degrees_refused_with_the_gdalwarp_that_fixes_it(tmp_path):
    """A DEM in a geographic CRS would be taken as metres (every face ~90
    deg, a run that crawls for ever): exit 2, one line that says degrees
    and gives the gdalwarp command to the UTM zone of its centre, which
    then gives a DEM relax takes."""
    g = gdal()
    rows = [[40 * ((i * j) % 7) + 3 * i for i in range(12)] for j in range(10)]
    (tmp_path / "dem.asc").write_text(asc_text(rows, cellsize=1.0))
    # around Zurich (8.5 E, 47.4 N): UTM zone 32 north, EPSG:32632; whole
    # metres in Int16, as real DEMs (SRTM, ...) come
    g.Translate(str(tmp_path / "deg.tif"), str(tmp_path / "dem.asc"), outputSRS="EPSG:4326",
                outputBounds=[8.5, 47.4, 8.5108, 47.391], outputType=g.GDT_Int16)
    r = run(["relax", "deg.tif", "-o", "out.asc"], cwd=tmp_path)
    assert r.returncode == 2, r.stderr
    assert r.stderr.count("\n") == 1 and "degrees, not metres" in r.stderr, r.stderr
    m = re.search(r"e\.g\. (gdalwarp -t_srs EPSG:32632 .*)$", r.stderr.strip())
    assert m, f"no gdalwarp command to UTM zone 32N in: {r.stderr}"
    assert not (tmp_path / "out.asc").exists(), "an output was written"
    # in the southern hemisphere, the southern UTM zone
    g.Translate(str(tmp_path / "south.tif"), str(tmp_path / "dem.asc"),
                outputSRS="EPSG:4326", outputBounds=[-70.5, -33.4, -70.49, -33.41])
    r = run(["relax", "south.tif", "-o", "out.asc"], cwd=tmp_path)
    assert r.returncode == 2 and "EPSG:32719" in r.stderr, r.stderr
    # the suggested command works: float heights, cells like the source's
    # 0.0009 deg (67.9 m east x 100 m north at 47.4 N: 82 m of the same
    # area), nodata outside the source, a DEM relax takes
    cmd = m.group(1).replace("'", "").split()
    assert "-ot Float32" in m.group(1) and "-tr 82 82" in m.group(1), m.group(1)
    assert "(about 67.9 x 100 m there)" in m.string, m.string
    assert shutil.which("gdalwarp"), "gdalwarp is not installed (Debian: gdal-bin)"
    subprocess.run(cmd, cwd=tmp_path, check=True, capture_output=True)
    warped = g.Open(str(tmp_path / "dem-m.tif"))
    band = warped.GetRasterBand(1)
    assert g.GetDataTypeName(band.DataType) == "Float32", \
        f"the suggested gdalwarp wrote {g.GetDataTypeName(band.DataType)} heights"
    gt = warped.GetGeoTransform()
    assert gt[1] == 82 and gt[5] == -82, f"cells of {gt[1]} x {-gt[5]} m, expected 82"
    assert band.GetNoDataValue() == -9999, band.GetNoDataValue()
    h = band.ReadAsArray()
    data = h[h != -9999]
    assert data.size > 0.5 * h.size and (data != np.round(data)).any(), \
        "bilinear heights should not be whole metres (Float32, not Int16)"
    assert data.min() >= 0 and data.max() <= 40 * 6 + 3 * 11, "heights outside the source's"
    r = run(["relax", "dem-m.tif", "-o", "m.tif", "-q"], cwd=tmp_path)
    assert r.returncode == 0, f"the reprojected DEM is refused: {r.stderr}"


@pytest.mark.skipif("GDAL: on" not in run(["--version"]).stdout,
                    reason="this build reads no GeoTIFF (made with GDAL=0 or MPI=1, or without "
                           "Debian package libgdal-dev)")
def test_relax_of_a_format_it_does_not_write_defaults_to_geotiff(tmp_path):
    """relax dem.img without -o: out/dem-relaxed.tif with the .img's
    georeferencing (it blamed an -o that was never given)."""
    g = gdal()
    rows = [[(3 * i + 7 * j) % 11 for i in range(12)] for j in range(10)]
    (tmp_path / "dem.asc").write_text(asc_text(rows, cellsize=1.0))
    g.Translate(str(tmp_path / "dem.img"), str(tmp_path / "dem.asc"), format="HFA",
                outputSRS="EPSG:32632", outputBounds=[500000, 5200010, 500012, 5200000])
    r = run(["relax", "dem.img", "-q"], cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    out = g.Open(str(tmp_path / "out" / "dem-relaxed.tif"))
    assert out.GetDriver().ShortName == "GTiff"
    assert out.GetSpatialRef().GetAuthorityCode(None) == "32632", out.GetProjection()
    np.testing.assert_allclose(out.GetGeoTransform(), (500000, 1, 0, 5200010, 0, -1))
