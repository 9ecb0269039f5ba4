#!/usr/bin/python3
# SPDX-License-Identifier: BSD-3-Clause
"""Relax a DEM raster to the angle of repose with sandslide.relax_raster.

    PYTHONPATH=python /usr/bin/python3 python/examples/relax_dem.py terrain.tif \
        terrain-relaxed.tif [ANGLE]

The CRS is checked first, with GDAL's Python bindings (python3-gdal): the
model takes cell sizes in metres, so a DEM in geographic degrees must be
reprojected (the library refuses it too, naming the gdalwarp command).
The output keeps the source's geotransform, CRS and nodata value; an
existing output is refused (pass --force as a fourth word to replace it).
Ctrl-C stops the relaxation within a fraction of a second.
"""
import sys

from osgeo import gdal, osr

import sandslide


def main(argv):
    if len(argv) < 3:
        sys.exit(__doc__)
    source, output = argv[1], argv[2]
    angle = float(argv[3]) if len(argv) > 3 and argv[3] != "--force" else 35.0
    force = "--force" in argv[3:]

    gdal.UseExceptions()
    ds = gdal.Open(source)
    wkt = ds.GetProjection()
    if wkt:
        srs = osr.SpatialReference(wkt=wkt)
        if srs.IsGeographic():
            sys.exit(f"{source} is in {srs.GetName()}: its cells are degrees, not metres; "
                     f"reproject it first, e.g. gdalwarp -t_srs EPSG:<your UTM zone> "
                     f"-r bilinear -ot Float32 -dstnodata -9999 {source} dem-m.tif")
        print(f"{source}: {srs.GetName()}, {ds.RasterXSize} x {ds.RasterYSize} cells of "
              f"{ds.GetGeoTransform()[1]:g} m")
    else:
        print(f"{source}: no CRS; its cell size is taken as metres")

    try:
        report = sandslide.relax_raster(ds, output, angle=angle, force=force, progress=True)
    except sandslide.Error as e:
        sys.exit(f"sandslide: {e}")
    print(f"{report['end']}: steepest face {report['max_slope_before_deg']:.2f} -> "
          f"{report['max_slope_after_deg']:.4f} deg in {report['steps']} steps; "
          f"{report['volume_moved']:.6g} m^3 moved; written to {report['output']}")


if __name__ == "__main__":
    main(sys.argv)
