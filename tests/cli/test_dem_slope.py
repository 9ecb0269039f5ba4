# SPDX-License-Identifier: BSD-3-Clause
"""doc/dem.md#the-face-slope-and-gdaldem-slope: the figures it gives for
`gdaldem slope` on cases/dem/terrain.asc relaxed at 33 deg are what
gdaldem measures now (its largest slope, the cells above 33.001 deg and
the 99th percentile, by Horn's method and by Zevenbergen-Thorne's), and
relax's own steepest face is the repose angle.  Skips without gdaldem,
GDAL's Python bindings or a build with GDAL."""
import os
import re
import shutil
import subprocess

import pytest

from conftest import ROOT, run, run_ok

DOC = os.path.join(ROOT, "doc/dem.md")


def section():
    text = open(DOC).read()
    start = text.index("### The face slope and `gdaldem slope`")
    return text[start:text.index("\n## ", start)]


@pytest.mark.skipif(shutil.which("gdaldem") is None, reason="gdaldem (gdal-bin) is not installed")
@pytest.mark.skipif("GDAL: on" not in run(["--version"]).stdout,
                    reason="this build reads no GeoTIFF")
def test_gdaldem_figures_of_dem_md_are_measured(tmp_path):
    gdal = pytest.importorskip("osgeo.gdal", reason="python3-gdal is not installed")
    import numpy as np
    doc = " ".join(section().split())
    (tmp_path / "out").mkdir()
    r = run_ok(["relax", os.path.join(ROOT, "cases", "dem", "terrain.asc"), "-o",
                "out/terrain33.tif", "--angle", "33", "--force"], cwd=tmp_path)
    assert "-> 33.0000 deg (repose 33)" in r.stdout, r.stdout
    assert "(33.0000 here)" in doc
    measured = {}
    for alg in ("Horn", "ZevenbergenThorne"):
        out = tmp_path / f"slope-{alg}.tif"
        subprocess.run(["gdaldem", "slope", "-q", "-alg", alg, "out/terrain33.tif", str(out)],
                       cwd=tmp_path, check=True)
        ds = gdal.Open(str(out))
        band = ds.GetRasterBand(1)
        s = band.ReadAsArray().astype(np.float64)
        s = s[s != band.GetNoDataValue()]
        measured[alg] = (f"{s.max():.2f}", int((s > 33.001).sum()), s.size,
                         f"{np.percentile(s, 99):.2f}")
    horn, zt = measured["Horn"], measured["ZevenbergenThorne"]
    shown = {
        "Horn max": re.search(r"-alg Horn \S+ \S+ # max (\S+) deg", doc).group(1),
        "ZT max": re.search(r"-alg ZevenbergenThorne \S+ \S+ # max (\S+) deg", doc).group(1),
        "ZT text": re.search(r"up to (\S+) deg, on (\d+) of the (\d+) inner cells", doc).groups(),
        "ZT p99": re.search(r"the 99th percentile is (\S+)\)", doc).group(1),
        "Horn text": re.search(r"(\S+) deg at most, (\d+) cells above 33.001, the 99th "
                               r"percentile (\S+)\.", doc).groups(),
    }
    assert shown == {
        "Horn max": horn[0], "ZT max": zt[0],
        "ZT text": (zt[0], str(zt[1]), str(zt[2])), "ZT p99": zt[3],
        "Horn text": (horn[0], str(horn[1]), horn[3]),
    }, f"doc/dem.md shows {shown}; gdaldem measures Horn {horn}, Zevenbergen-Thorne {zt}"
