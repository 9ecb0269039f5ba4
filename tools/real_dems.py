#!/usr/bin/python3
# SPDX-License-Identifier: BSD-3-Clause
"""real_dems.py - real DEMs from Debian packages, written as ESRI ASCII grids.

A benchmark helper, never a test.  Writes measured terrain (not synthetic)
at several cell sizes into a folder, for timing `sandslide relax` on the
kind of data users bring (tools/time_to_solution.py --workloads relax reads
them).  Every DEM comes from a file that a Debian 12 package installs, so a
fresh machine gets them with `make deps-bench`; nothing is downloaded from
anywhere else and no third-party data is kept in this repository.

    tools/real_dems.py OUTDIR                 # the default set (see --list)
    tools/real_dems.py OUTDIR --all           # also the DEMs steady at 35 deg
    tools/real_dems.py OUTDIR --only bei-5m,volcano-10m
    tools/real_dems.py OUTDIR --skip-missing  # leave out what is not installed
    tools/real_dems.py --list                 # where each comes from

Each DEM becomes OUTDIR/NAME.asc with its cell size in metres (`cellsize`,
or `dx` and `dy` where the cells are not square), its cells without data
as NODATA_value, north row first.  OUTDIR/real_dems.json records, per DEM,
the package, the file, the licence, the grid and the steepest face, and
the same is printed as a table.  A grid in degrees is converted to metres
with the WGS 84 radii of curvature at its centre latitude (a cell of
dlon x dlat degrees is N cos(lat) dlon x M dlat metres; no resampling), or
left out.  A DEM whose package is missing makes the script fail, naming
the Debian package to install (`make deps-bench` installs the default
set's; `make deps-bench BENCH_ALL=1` those of --all too).

The default set is the DEMs with faces steeper than 35 deg (relax's default
angle), so that relax has work to do; --all adds three gentler ones (a
relax at 35 deg leaves them as they are after 0 steps; use --angle 20 to
move sand on them).  Debian 12 ships no DEM finer than 5 m (no LiDAR
tiles); 1-2 m terrain is in public repositories (e.g. landlab's
tutorials), which CI cannot reach.  Needs numpy, python3-rdata (R's data
files) and, for --all, python3-gdal (GeoTIFFs).
"""
import argparse
import gzip
import json
import math
import os
import sys

import numpy as np

R_SITE = "/usr/lib/R/site-library"
MPL_DATA = "/usr/share/matplotlib/mpl-data/sample_data"
OPENFOAM = "/usr/share/doc/openfoam-examples/examples"

# name; the Debian package and the Python module its reader needs; the file (and the
# object in it); licence; what it is; gentle: no face above 35 deg, only with --all.
# The readers are READERS[name].
CATALOGUE = [
    dict(name="bei-5m", package="r-cran-spatstat.data", python="rdata",
         path=f"{R_SITE}/spatstat.data/data/Rdata.rdb", item="bei.extra$elev",
         licence="GPL (>= 2) (spatstat.data)",
         what="Barro Colorado Island, Panama: the 50 ha forest dynamics plot "
              "(R spatstat.data, ?bei; Hubbell & Foster), 5 m"),
    dict(name="volcano-10m", package="r-base-core", python="rdata",
         path="/usr/lib/R/library/datasets/data/Rdata.rdb", item="volcano",
         licence="part of R: GPL-2 | GPL-3",
         what="Maunga Whau (Mt Eden), Auckland: R's datasets::volcano, digitised "
              "from a topographic map by Ross Ihaka, 10 m"),
    dict(name="snakeriver-30m", package="openfoam-examples", python=None,
         path=f"{OPENFOAM}/mesh/moveDynamicMesh/SnakeRiverCanyon/constant/triSurface/"
              "AcrossCyn.XYZ.gz", item=None, licence="GPL-3+ (OpenFOAM)",
         what="Snake River canyon, Idaho (UTM x y z points on a 30 m lattice; "
              "OpenFOAM tutorial SnakeRiverCanyon)"),
    dict(name="gorillas-31m", package="r-cran-spatstat.data", python="rdata",
         path=f"{R_SITE}/spatstat.data/data/Rdata.rdb", item="gorillas.extra$elevation",
         licence="GPL (>= 2) (spatstat.data)",
         what="Kagwene Gorilla Sanctuary, Cameroon (R spatstat.data, "
              "?gorillas; Funwi-Gabga & Mateu), 30.7 m, nodata outside"),
    dict(name="jacksboro-74x93m", package="python-matplotlib-data", python=None,
         path=f"{MPL_DATA}/jacksboro_fault_dem.npz", item="elevation",
         licence="matplotlib licence (PSF-based); USGS data",
         what="Jacksboro fault, Tennessee: 3 arc-second USGS DEM "
              "(matplotlib sample data), degrees converted to metres"),
    # --all: no face steeper than 35 deg
    dict(name="satellite-30m", package="r-cran-satellite", python="osgeo", gentle=True,
         path=f"{R_SITE}/satellite/extdata/DEM.TIF", item=None,
         licence="MIT (satellite)",
         what="Hesse, Germany: the DEM beside R satellite's Landsat scenes, "
              "UTM 32N, 30 m"),
    dict(name="olinda-90m", package="r-cran-stars", python="osgeo", gentle=True,
         path=f"{R_SITE}/stars/tif/olinda_dem_utm25s.tif", item=None,
         licence="Apache-2.0 (stars)",
         what="Olinda, Brazil: R stars' DEM in UTM 25S, 90 m"),
    dict(name="luxembourg-600x930m", package="r-cran-terra", python="osgeo", gentle=True,
         path=f"{R_SITE}/terra/ex/elev.tif", item=None, licence="GPL (>= 3) (terra)",
         what="Luxembourg: 30 arc-second elevation (R terra's ex/elev.tif), "
              "degrees converted to metres, nodata outside the country"),
]
PYTHON_PACKAGE = {"rdata": "python3-rdata", "osgeo": "python3-gdal"}
NODATA = -9999.0


def parse_args(argv):
    """The command line; see the module docstring."""
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("outdir", nargs="?", help="folder to write NAME.asc and real_dems.json into")
    p.add_argument("--all", action="store_true", help="also the DEMs steady at 35 deg")
    p.add_argument("--only", help="comma-separated names (see --list)")
    p.add_argument("--skip-missing", action="store_true",
                   help="leave out DEMs whose package is not installed, saying which")
    p.add_argument("--list", action="store_true", help="print the catalogue, write nothing")
    a = p.parse_args(argv)
    if not a.list and not a.outdir:
        p.error("OUTDIR is needed (or --list)")
    return a


def selected(args):
    """The catalogue entries asked for."""
    if args.only:
        names = args.only.split(",")
        unknown = [n for n in names if n not in {d["name"] for d in CATALOGUE}]
        if unknown:
            sys.exit(f"real_dems: unknown DEM {', '.join(unknown)}: one of "
                     f"{', '.join(d['name'] for d in CATALOGUE)}")
        return [d for d in CATALOGUE if d["name"] in names]
    return [d for d in CATALOGUE if args.all or not d.get("gentle")]


def missing(dem):
    """The Debian packages this DEM needs that are not installed (file or module absent)."""
    out = []
    if not os.path.exists(dem["path"]):
        out.append(dem["package"])
    if dem["python"]:
        try:
            __import__(dem["python"])
        except ImportError:
            out.append(PYTHON_PACKAGE[dem["python"]])
    return out


# ---- readers: each returns (z as float64 with NaN for nodata, dx, dy, x0, y0), north row first

def r_lazyload(path, name):
    """Object `name` of an R lazy-load database (Rdata.rdb + Rdata.rdx), as Python objects.
    The .rdx is a gzipped serialisation of {variables: name -> (offset, length),
    compressed}; each record of the .rdb is a 4-byte big-endian length, then (for
    compression 3) a type byte, 'Z' xz (raw LZMA2), '2' bzip2, '1' zlib, '0' none, and
    the compressed XDR serialisation (R's src/main/serialize.c, R_decompress3)."""
    import bz2
    import lzma
    import warnings
    import zlib

    import rdata

    def unserialize(raw):
        # parse_data knows the serialisation behind an .RData file's magic line
        # no constructors: R classes (im, factor) stay plain lists and vectors
        parsed = rdata.parser.parse_data(b"RDX3\n" + raw)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            return rdata.conversion.convert(parsed, constructor_dict={})

    base = path[:-len(".rdb")]
    with open(base + ".rdx", "rb") as f:
        index = unserialize(gzip.decompress(f.read()))
    off, length = (int(v) for v in index["variables"][name])
    with open(base + ".rdb", "rb") as f:
        f.seek(off)
        blob = f.read(length)
    if int(np.ravel(index["compressed"])[0]) == 3:
        raw = {b"Z": lambda b: lzma.decompress(b, format=lzma.FORMAT_RAW, filters=[
                   {"id": lzma.FILTER_LZMA2, "preset": 9 | lzma.PRESET_EXTREME}]),
               b"2": bz2.decompress, b"1": zlib.decompress, b"0": bytes}[blob[4:5]](blob[5:])
    else:
        raw = zlib.decompress(blob[4:])
    return unserialize(raw)


def read_volcano(dem):
    """R's volcano: an 87 x 61 matrix, x along the rows and y (north) along the columns,
    as image(volcano) draws it: 870 m east-west, 610 m south-north."""
    z = np.asarray(r_lazyload(dem["path"], "volcano"), dtype=np.float64)
    return z[:, ::-1].T.copy(), 10.0, 10.0, 0.0, 0.0


def read_spatstat_im(dem):
    """A spatstat pixel image (class im): v[i, j] at y = yrow[i] (south first), x = xcol[j];
    NA (R's NA_integer_, or NaN) is nodata."""
    obj, key = dem["item"].split("$")
    im = r_lazyload(dem["path"], obj)[key]
    v = np.asarray(im["v"])
    z = v.astype(np.float64)
    if np.issubdtype(v.dtype, np.integer):
        z[v == np.iinfo(np.int32).min] = np.nan
    dx, dy = float(np.ravel(im["xstep"])[0]), float(np.ravel(im["ystep"])[0])
    return (z[::-1].copy(), dx, dy, float(im["xrange"][0]), float(im["yrange"][0]))


def read_xyz_lattice(dem):
    """x y z lines (gzipped) on a regular lattice: every (x, y) once; absent ones nodata."""
    with gzip.open(dem["path"], "rt") as f:
        p = np.loadtxt(f)
    xs, ys = np.unique(p[:, 0]), np.unique(p[:, 1])
    steps = np.concatenate([np.diff(xs), np.diff(ys)])
    d = float(steps[0])
    if not np.allclose(steps, d, rtol=1e-9):
        sys.exit(f"real_dems: {dem['path']}: the points are not on one square lattice")
    z = np.full((len(ys), len(xs)), np.nan)
    z[np.searchsorted(ys, p[:, 1]), np.searchsorted(xs, p[:, 0])] = p[:, 2]
    return z[::-1].copy(), d, d, float(xs[0]) - d / 2, float(ys[0]) - d / 2


def metres_per_degree(lat_deg):
    """(east, north) metres per degree at lat_deg on the WGS 84 ellipsoid:
    N cos(lat) and M, N = a / sqrt(1 - e2 sin^2), M = a (1 - e2) / (1 - e2 sin^2)^1.5."""
    a, e2 = 6378137.0, 6.69437999014e-3
    s2 = math.sin(math.radians(lat_deg)) ** 2
    n = a / math.sqrt(1 - e2 * s2)
    m = a * (1 - e2) / (1 - e2 * s2) ** 1.5
    return n * math.cos(math.radians(lat_deg)) * math.pi / 180, m * math.pi / 180


def read_jacksboro(dem):
    """matplotlib's jacksboro_fault_dem.npz: int16 elevation (row 0 north, as its
    hillshading example shows it), dx = dy = 3 arc-seconds, latitudes 36.446-36.733."""
    d = np.load(dem["path"])
    z = d["elevation"].astype(np.float64)
    lat = 0.5 * (float(d["ymin"]) + float(d["ymax"]))
    east, north = metres_per_degree(lat)
    return z, float(d["dx"]) * east, float(d["dy"]) * north, 0.0, 0.0


def read_geotiff(dem):
    """A north-up GeoTIFF through GDAL: projected in metres as it is; geographic converted
    at its centre latitude."""
    from osgeo import gdal
    gdal.UseExceptions()
    ds = gdal.Open(dem["path"])
    band = ds.GetRasterBand(1)
    z = band.ReadAsArray().astype(np.float64)
    nd = band.GetNoDataValue()
    if nd is not None:
        z[z == nd] = np.nan
    x0, dx, rx, y1, ry, dy = ds.GetGeoTransform()
    if rx or ry or dy >= 0:
        sys.exit(f"real_dems: {dem['path']}: not north-up")
    srs = ds.GetSpatialRef()
    if srs is not None and srs.IsGeographic():
        east, north = metres_per_degree(y1 + dy * ds.RasterYSize / 2)
        return z, dx * east, -dy * north, 0.0, 0.0
    return z, dx, -dy, x0, y1 + dy * ds.RasterYSize


READERS = {"bei-5m": read_spatstat_im, "gorillas-31m": read_spatstat_im,
           "volcano-10m": read_volcano, "snakeriver-30m": read_xyz_lattice,
           "jacksboro-74x93m": read_jacksboro, "satellite-30m": read_geotiff,
           "olinda-90m": read_geotiff, "luxembourg-600x930m": read_geotiff}


# ---- writing and describing

def steepest(z, dx, dy, angle=35.0):
    """The steepest face between two cells with data (deg), and how many faces are steeper
    than `angle`: what relax has to bring down.  Faces are |dz| / dx between neighbours
    along x or y; relax's own measure adds the cross slope, so it can be a little higher."""
    gx = np.abs(np.diff(z, axis=1)) / dx
    gy = np.abs(np.diff(z, axis=0)) / dy
    g = np.concatenate([gx[np.isfinite(gx)], gy[np.isfinite(gy)]])
    t = math.tan(math.radians(angle))
    return math.degrees(math.atan(float(g.max()))), int((g > t).sum())


def write_asc(path, z, dx, dy, x0, y0):
    """ESRI ASCII grid, north row first; values in their shortest exact form; cells
    without data as NODATA_value (chosen outside the heights)."""
    nodata = np.isnan(z)
    nd = NODATA
    while nodata.any() and np.any(z[~nodata] == nd):
        nd *= 10
    cell = (f"cellsize {dx!r}\n" if dx == dy else f"dx {dx!r}\ndy {dy!r}\n")
    with open(path, "w") as f:
        f.write(f"ncols {z.shape[1]}\nnrows {z.shape[0]}\nxllcorner {x0!r}\n"
                f"yllcorner {y0!r}\n{cell}")
        if nodata.any():
            f.write(f"NODATA_value {nd:g}\n")
        for row in z:
            f.write(" ".join(f"{nd:g}" if math.isnan(v) else
                             np.format_float_positional(v, unique=True, trim="-")
                             for v in row.tolist()))
            f.write("\n")


def main(argv):
    """Check the packages, read each DEM, write it and its provenance."""
    args = parse_args(argv)
    if args.list:
        for d in CATALOGUE:
            print(f"{d['name']:20} {'(--all) ' if d.get('gentle') else ''}{d['what']}\n"
                  f"{'':20} Debian package {d['package']}: {d['path']}"
                  f"{' (' + d['item'] + ')' if d['item'] else ''}; licence {d['licence']}")
        return 0
    dems = selected(args)
    lacking = {d["name"]: missing(d) for d in dems}
    lacking = {k: v for k, v in lacking.items() if v}
    if lacking:
        pkgs = sorted({p for v in lacking.values() for p in v})
        what = "; ".join(f"{k} needs {', '.join(v)}" for k, v in lacking.items())
        msg = (f"real_dems: Debian package{'s' if len(pkgs) > 1 else ''} not installed: "
               f"{' '.join(pkgs)} ({what}).  Install with `make deps-bench"
               f"{' BENCH_ALL=1' if any(d.get('gentle') for d in dems) else ''}` or "
               f"`apt-get install {' '.join(pkgs)}`")
        if not args.skip_missing:
            sys.exit(msg + ", or leave them out with --skip-missing.")
        print(f"# {msg}; left out: {', '.join(lacking)}", file=sys.stderr)
        dems = [d for d in dems if d["name"] not in lacking]
    os.makedirs(args.outdir, exist_ok=True)
    records = []
    for d in dems:
        z, dx, dy, x0, y0 = READERS[d["name"]](d)
        out = os.path.join(args.outdir, d["name"] + ".asc")
        write_asc(out, z, dx, dy, x0, y0)
        steep, faces = steepest(z, dx, dy)
        records.append(dict(name=d["name"], file=out, what=d["what"], package=d["package"],
                            source=d["path"] + (f" ({d['item']})" if d["item"] else ""),
                            licence=d["licence"], nx=z.shape[1], ny=z.shape[0], dx=dx, dy=dy,
                            nodata_cells=int(np.isnan(z).sum()),
                            relief=float(np.nanmax(z) - np.nanmin(z)),
                            steepest_face_deg=steep, faces_above_35=faces))
    with open(os.path.join(args.outdir, "real_dems.json"), "w") as f:
        json.dump(records, f, indent=1)
    print(f"{'DEM':20} {'cells':>9} {'cell m':>11} {'nodata':>6} {'relief m':>8} "
          f"{'steepest':>8} {'>35':>5}  Debian package (licence)")
    for r in records:
        cell = f"{r['dx']:.4g}" if r["dx"] == r["dy"] else f"{r['dx']:.4g}x{r['dy']:.4g}"
        print(f"{r['name']:20} {r['nx']:>4}x{r['ny']:<4} {cell:>11} {r['nodata_cells']:>6} "
              f"{r['relief']:8.1f} {r['steepest_face_deg']:8.1f} {r['faces_above_35']:>5}  "
              f"{r['package']} ({r['licence']})")
    print(f"# wrote {len(records)} DEMs and real_dems.json (sources) to {args.outdir}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
