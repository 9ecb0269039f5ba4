#!/usr/bin/python3
# SPDX-License-Identifier: BSD-3-Clause
"""Write a synthetic terrain with steep cliffs as an ESRI ASCII grid or a GeoTIFF.

    /usr/bin/python3 cases/fractal_dem.py N OUT.asc|OUT.tif [--seed S] [--cellsize M]
                                          [--epsg CODE]

The terrain is fractal (spectral synthesis: random phases, amplitude
k^-beta, beta = 1.6, i.e. a surface of fractal dimension about 2.2) scaled to
a relief of 48 cells (--relief), then cut into 24 terraces 2 cells high:
each terrace edge is a cliff of 63 degrees or more, which the repose angle
brings down.  With N = 4096 this is the terrain of
doc/performance.md#a-large-dem.  Needs numpy, and for .tif GDAL's Python
bindings (Debian's python3-gdal): a GeoTIFF of float64 in tiles of 512 x 512,
deflated, with --epsg's CRS (none by default).  The terrain is made whole in
memory (an FFT): N = 16384 needs about 8 GiB.
"""
import argparse
import sys

import numpy as np


def fractal_terrain(n, seed, cellsize, relief_cells):
    rng = np.random.default_rng(seed)
    kx = np.fft.fftfreq(n)[None, :]
    ky = np.fft.rfftfreq(n)[:, None]
    k = np.hypot(kx, ky)
    k[0, 0] = 1.0
    amplitude = k ** -1.6
    amplitude[0, 0] = 0.0
    phase = np.exp(2j * np.pi * rng.random(amplitude.shape))
    h = np.fft.irfft2((amplitude * phase).T, s=(n, n)).T
    h -= h.min()
    h *= relief_cells * cellsize / h.max()
    step = relief_cells * cellsize / 24
    return np.floor(h / step) * step             # terraces with vertical cliffs


def write_asc(path, h, cellsize):
    ny, nx = h.shape
    with open(path, "w") as f:
        f.write(f"ncols {nx}\nnrows {ny}\nxllcorner 0\nyllcorner 0\n"
                f"cellsize {cellsize!r}\n")
        for row in h[::-1]:                       # north row first
            f.write(" ".join(f"{v:.6g}" for v in row))
            f.write("\n")


def write_tif(path, h, cellsize, epsg):
    from osgeo import gdal, osr
    gdal.UseExceptions()
    ny, nx = h.shape
    ds = gdal.GetDriverByName("GTiff").Create(
        path, nx, ny, 1, gdal.GDT_Float64,
        ["TILED=YES", "BLOCKXSIZE=512", "BLOCKYSIZE=512", "COMPRESS=DEFLATE", "PREDICTOR=3",
         "BIGTIFF=IF_SAFER"])
    ds.SetGeoTransform([0.0, cellsize, 0.0, ny * cellsize, 0.0, -cellsize])
    if epsg:
        crs = osr.SpatialReference()
        crs.ImportFromEPSG(epsg)
        ds.SetProjection(crs.ExportToWkt())
    ds.GetRasterBand(1).WriteArray(h[::-1])       # north row first
    ds = None


def main(argv):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("n", type=int, help="cells per side")
    p.add_argument("output", help="ESRI ASCII grid (.asc) or GeoTIFF (.tif) to write")
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--cellsize", type=float, default=1.0, help="m (default 1)")
    p.add_argument("--relief", type=float, default=48.0,
                   help="highest minus lowest ground, in cells (default 48)")
    p.add_argument("--epsg", type=int, default=0, help="the GeoTIFF's CRS, e.g. 32633")
    a = p.parse_args(argv)
    if a.n < 8:
        p.error("n must be at least 8")
    h = fractal_terrain(a.n, a.seed, a.cellsize, a.relief)
    if a.output.lower().endswith((".tif", ".tiff")):
        write_tif(a.output, h, a.cellsize, a.epsg)
    else:
        write_asc(a.output, h, a.cellsize)


if __name__ == "__main__":
    main(sys.argv[1:])
