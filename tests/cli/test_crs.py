# SPDX-License-Identifier: BSD-3-Clause
"""The CRS of an ESRI ASCII grid, kept in the .prj beside it
(doc/dem.md#cell-size-and-crs): `relax dem.asc` with the dem.prj GDAL wrote
gives a GeoTIFF, an .asc (+ .prj) and an .h5 whose CRS GDAL reads as the
input's; a grid without a CRS gets no .prj (and a stale one goes); a .prj
that is no CRS, or a geographic one, is refused with exit 2 naming it.

The .asc and .prj come from GDAL itself (gdal.Translate from a GeoTIFF in
EPSG:32633), so that what is tested is what users have.  The tests that
need GDAL in sandslide or in Python skip, saying which; the first test
runs in a build without GDAL too (the .prj's text is then kept as read).
"""
import os

import numpy as np
import pytest

from conftest import asc_text, h5open, run, run_ok, text_attr

GDAL_BUILD = "GDAL: on" in run(["--version"]).stdout
needs_gdal_build = pytest.mark.skipif(
    not GDAL_BUILD, reason="this build reads no GeoTIFF (made with GDAL=0 or MPI=1, or without "
                           "Debian package libgdal-dev)")

# What GDAL 3.6 writes as the .prj of EPSG:32633 (gdal_translate -of AAIGrid).
UTM33N_ESRI = (
    'PROJCS["WGS_1984_UTM_Zone_33N",GEOGCS["GCS_WGS_1984",DATUM["D_WGS_1984",'
    'SPHEROID["WGS_1984",6378137.0,298.257223563]],PRIMEM["Greenwich",0.0],'
    'UNIT["Degree",0.0174532925199433]],PROJECTION["Transverse_Mercator"],'
    'PARAMETER["False_Easting",500000.0],PARAMETER["False_Northing",0.0],'
    'PARAMETER["Central_Meridian",15.0],PARAMETER["Scale_Factor",0.9996],'
    'PARAMETER["Latitude_Of_Origin",0.0],UNIT["Meter",1.0]]')

# 12 x 10 cells of 1 m, north row first, a cliff in the north-west: it moves.
ROWS = [[(3 * i + 7 * j) % 11 + (5.0 if i < 4 and j > 6 else 0.0) for i in range(12)]
        for j in range(10)]


def gdal():
    osgeo = pytest.importorskip("osgeo.gdal", reason="GDAL's Python bindings "
                                "(python3-gdal) are not installed")
    osgeo.UseExceptions()
    return osgeo


def gdal_asc(tmp_path, epsg=32633, bounds=(500000, 5200010, 500012, 5200000), name="dem"):
    """name.asc and the name.prj beside it, both written by GDAL from a
    GeoTIFF in EPSG:epsg."""
    g = gdal()
    (tmp_path / "plain.asc").write_text(asc_text(ROWS, cellsize=1.0))
    g.Translate(str(tmp_path / "src.tif"), str(tmp_path / "plain.asc"),
                outputSRS=f"EPSG:{epsg}", outputBounds=list(bounds), outputType=g.GDT_Float64)
    g.Translate(str(tmp_path / f"{name}.asc"), str(tmp_path / "src.tif"), format="AAIGrid")
    assert (tmp_path / f"{name}.prj").is_file(), "GDAL wrote no .prj"
    return g


def test_prj_text_comes_back_beside_an_asc_and_in_the_h5(tmp_path):
    """Any build: the .prj GDAL writes comes back byte for byte beside the
    .asc output, and the .h5 output has a /crs grid mapping of that CRS."""
    (tmp_path / "dem.asc").write_text(asc_text(ROWS, cellsize=1.0, x0=500000, y0=5200000))
    (tmp_path / "dem.prj").write_text(UTM33N_ESRI)
    run_ok(["relax", "dem.asc", "-o", "out.asc", "-q"], cwd=tmp_path)
    assert (tmp_path / "out.prj").read_text() == UTM33N_ESRI
    run_ok(["relax", "dem.asc", "-o", "out.h5", "-q"], cwd=tmp_path)
    with h5open(tmp_path / "out.h5") as f:
        assert "crs" in f, "no /crs grid mapping variable"
        wkt = text_attr(f["crs"], "crs_wkt")
        assert "UTM" in wkt and "Transverse_Mercator" in wkt, wkt
        assert text_attr(f["height"], "grid_mapping") == "crs"
    # and back from the .h5 to an .asc: the same .prj
    run_ok(["relax", "out.h5", "-o", "back.asc", "-q"], cwd=tmp_path)
    assert (tmp_path / "back.prj").read_text() == UTM33N_ESRI


@needs_gdal_build
def test_asc_crs_reaches_geotiff_asc_and_h5(tmp_path):
    """relax of GDAL's dem.asc + dem.prj to .tif, .asc and .h5: GDAL reads
    each output's CRS as the one it reads for dem.asc (IsSame), the .h5's
    crs_wkt is the very WKT `gdalinfo dem.asc` shows, the new .prj is the
    text GDAL wrote, and the GeoTIFF sits where the grid does."""
    g = gdal_asc(tmp_path)
    src = g.Open(str(tmp_path / "dem.asc"))
    srs = src.GetSpatialRef()
    assert srs is not None and srs.IsProjected(), "GDAL reads no CRS for its own dem.asc"
    for out in ("out.tif", "out.asc", "out.h5"):
        run_ok(["relax", "dem.asc", "-o", out, "-q"], cwd=tmp_path)

    tif = g.Open(str(tmp_path / "out.tif"))
    assert tif.GetSpatialRef() is not None, "the GeoTIFF has no CRS"
    assert tif.GetSpatialRef().IsSame(srs), tif.GetProjection()
    assert tif.GetSpatialRef().GetAuthorityCode(None) == "32633", tif.GetProjection()
    np.testing.assert_allclose(tif.GetGeoTransform(), src.GetGeoTransform(), rtol=0, atol=1e-9)

    asc = g.Open(str(tmp_path / "out.asc"))
    assert asc.GetSpatialRef() is not None and asc.GetSpatialRef().IsSame(srs), \
        asc.GetProjection()
    assert (tmp_path / "out.prj").read_text() == (tmp_path / "dem.prj").read_text()

    with h5open(tmp_path / "out.h5") as f:
        assert text_attr(f["crs"], "crs_wkt") == src.GetProjectionRef()
    for name in (f'NETCDF:"{tmp_path / "out.h5"}":height', f'HDF5:"{tmp_path / "out.h5"}"://height'):
        h = g.Open(name)
        assert h.GetSpatialRef() is not None and h.GetSpatialRef().IsSame(srs), name

    # the surface moved, and the GeoTIFF holds what the .asc holds
    assert not np.array_equal(tif.ReadAsArray(), src.ReadAsArray()), "nothing relaxed"
    np.testing.assert_allclose(tif.ReadAsArray(), asc.ReadAsArray(), rtol=0, atol=1e-6)


@needs_gdal_build
def test_geotiff_crs_goes_into_the_prj_of_an_asc(tmp_path):
    """relax dem.tif -o out.asc writes out.prj, which GDAL reads as the
    GeoTIFF's CRS."""
    g = gdal_asc(tmp_path)
    run_ok(["relax", "src.tif", "-o", "out.asc", "-q"], cwd=tmp_path)
    out = g.Open(str(tmp_path / "out.asc"))
    assert out.GetSpatialRef() is not None, "no CRS read from out.asc"
    assert out.GetSpatialRef().IsSame(g.Open(str(tmp_path / "src.tif")).GetSpatialRef())


def test_asc_without_crs_gets_no_prj_and_a_stale_one_goes(tmp_path):
    """No .prj in, none out; one left beside the output by an earlier grid
    would give it a CRS it does not have, so it is removed."""
    (tmp_path / "dem.asc").write_text(asc_text(ROWS, cellsize=1.0))
    run_ok(["relax", "dem.asc", "-o", "out.asc", "-q"], cwd=tmp_path)
    assert not (tmp_path / "out.prj").exists()
    (tmp_path / "old.prj").write_text(UTM33N_ESRI)
    run_ok(["relax", "dem.asc", "-o", "old.asc", "-q"], cwd=tmp_path)
    assert not (tmp_path / "old.prj").exists(), "the stale old.prj was left"
    run_ok(["relax", "dem.asc", "-o", "out.h5", "-q"], cwd=tmp_path)
    with h5open(tmp_path / "out.h5") as f:
        assert "crs" not in f


@pytest.mark.parametrize("text", ["", "not a CRS at all\n", 'PROJCS["cut short",GEOGCS['])
def test_a_prj_that_is_no_crs_is_refused(tmp_path, text):
    """exit 2, one line naming the .prj and its grid; nothing written."""
    (tmp_path / "dem.asc").write_text(asc_text(ROWS, cellsize=1.0))
    (tmp_path / "dem.prj").write_text(text)
    r = run(["relax", "dem.asc", "-o", "out.asc"], cwd=tmp_path)
    assert r.returncode == 2, r.stderr
    assert r.stderr.count("\n") == 1 and "dem.prj" in r.stderr and "dem.asc" in r.stderr, \
        r.stderr
    assert not (tmp_path / "out.asc").exists() and not (tmp_path / "out.prj").exists()


@needs_gdal_build
def test_asc_in_degrees_is_refused_like_a_geotiff(tmp_path):
    """A .prj in EPSG:4326 (GDAL's own) makes the cells degrees: exit 2
    with the gdalwarp command to the UTM zone of the centre, as for a
    GeoTIFF in degrees; that command gives a grid relax takes."""
    gdal_asc(tmp_path, epsg=4326, bounds=(8.5, 47.4, 8.512, 47.39), name="deg")
    r = run(["relax", "deg.asc", "-o", "out.asc"], cwd=tmp_path)
    assert r.returncode == 2, r.stderr
    assert r.stderr.count("\n") == 1 and "degrees, not metres" in r.stderr, r.stderr
    assert "deg.prj" in r.stderr and "gdalwarp -t_srs EPSG:32632" in r.stderr, r.stderr
    assert not (tmp_path / "out.asc").exists()


def test_input_prj_is_never_replaced(tmp_path):
    """dem.ASC is another file than dem.asc, but its .prj would be dem.prj,
    the input's: refused before the work, the input's .prj untouched."""
    (tmp_path / "dem.asc").write_text(asc_text(ROWS, cellsize=1.0, x0=500000, y0=5200000))
    (tmp_path / "dem.prj").write_text(UTM33N_ESRI + "\n")
    r = run(["relax", "dem.asc", "-o", "dem.ASC"], cwd=tmp_path)
    assert r.returncode == 2 and "dem.prj" in r.stderr, r.stderr
    assert not (tmp_path / "dem.ASC").exists()
    assert (tmp_path / "dem.prj").read_text() == UTM33N_ESRI + "\n"
    assert sorted(os.listdir(tmp_path)) == ["dem.asc", "dem.prj"]


@needs_gdal_build
def test_south_up_geotiff_is_refused_with_the_gdalwarp_that_flips_it(tmp_path):
    """A south-up GeoTIFF (pixel height > 0) is refused, exit 2, with the
    command that makes it north-up; that command, run, gives a raster that
    relaxes to the very bits of the north-up original."""
    g = gdal()
    (tmp_path / "plain.asc").write_text(asc_text(ROWS, cellsize=1.0))
    g.Translate(str(tmp_path / "north.tif"), str(tmp_path / "plain.asc"), outputSRS="EPSG:32633",
                outputBounds=[500000, 5200010, 500012, 5200000], outputType=g.GDT_Float64)
    # the same cells, bottom row first: the first file row is the south one
    north = g.Open(str(tmp_path / "north.tif"))
    heights = north.GetRasterBand(1).ReadAsArray()
    south = g.GetDriverByName("GTiff").Create(str(tmp_path / "south.tif"), 12, 10, 1,
                                               g.GDT_Float64)
    south.SetGeoTransform([500000, 1, 0, 5200000, 0, 1])
    south.SetProjection(north.GetProjection())
    south.GetRasterBand(1).WriteArray(heights[::-1])
    south = north = None
    r = run(["relax", "south.tif", "-o", "x.asc"], cwd=tmp_path)
    fix = "gdalwarp -r near -tr 1 1 'south.tif' dem-north-up.tif"
    assert r.returncode == 2 and r.stderr == (
        "sandslide: 'south.tif' is south-up (pixel size 1 x 1): expected a north-up raster "
        f"(width > 0, height < 0 in the geotransform); flip it first, e.g. {fix}\n"), r.stderr
    assert not (tmp_path / "x.asc").exists()
    g.Warp(str(tmp_path / "dem-north-up.tif"), str(tmp_path / "south.tif"),
           options="-r near -tr 1 1")   # fix's options, through GDAL's Python
    run_ok(["relax", "north.tif", "-o", "a.asc", "-q"], cwd=tmp_path)
    run_ok(["relax", "dem-north-up.tif", "-o", "b.asc", "-q"], cwd=tmp_path)
    assert (tmp_path / "a.asc").read_text() == (tmp_path / "b.asc").read_text()


@needs_gdal_build
@pytest.mark.parametrize("content,what", [
    (b"hello world\n", "it is a text file of 12 bytes, starting 'hello world'"),
    (b"", "it is an empty file"),
    (b"ncols 3\nnrows 2\n", "it is an ESRI ASCII grid (name it .asc)"),
    (b"\x89HDF\r\n\x1a\n" + bytes(40), "it is an HDF5 file (name it .h5 to read it as a "
                                       "sandslide one)"),
    (bytes(range(7, 250)), "it is 243 bytes of binary data in no raster format GDAL knows"),
])
def test_a_file_gdal_cannot_open_is_said_what_it_is(tmp_path, content, what):
    """GDAL gives no reason for a .tif it cannot open; the message says
    what the file is instead of "no reason given"."""
    (tmp_path / "dem.tif").write_bytes(content)
    r = run(["relax", "dem.tif", "-o", "x.asc"], cwd=tmp_path)
    assert r.returncode == 2 and r.stderr.startswith(
        f"sandslide: cannot read 'dem.tif' as a GDAL raster: {what}; expected an ESRI ASCII "
        "grid (.asc)"), r.stderr


@needs_gdal_build
def test_a_bad_height_is_named_by_its_cell_in_map_coordinates(tmp_path):
    """A GeoTIFF's infinite height is named as every message names a cell:
    (i, j) from the south-west, its centre in the raster's own (map)
    coordinates, not a row and column from the file's north-west corner."""
    g = gdal()
    heights = np.array(ROWS, dtype=np.float64)
    heights[2, 5] = np.inf   # file row 2 from the north of 10: j = 7
    ds = g.GetDriverByName("GTiff").Create(str(tmp_path / "dem.tif"), 12, 10, 1, g.GDT_Float64)
    ds.SetGeoTransform([500000, 1, 0, 5200010, 0, -1])
    ds.GetRasterBand(1).WriteArray(heights)
    ds = None
    r = run(["relax", "dem.tif", "-o", "x.asc"], cwd=tmp_path)
    assert r.returncode == 2 and r.stderr.startswith(
        "sandslide: dem.tif: height inf of cell (5, 7) at x = 500005.5 m, y = 5200007.5 m is "
        "not finite"), r.stderr
