# SPDX-License-Identifier: BSD-3-Clause
"""No silent surprises (issue 36 item 3): what a command will cost is told or
refused before the work, and what it did is counted as it was done."""
import json
import re

import h5py
import pytest

from conftest import BASE, edit, run, run_ok


def write(tmp_path, text, name="case.ini"):
    p = tmp_path / name
    p.write_text(text)
    return p


def test_run_prints_the_projected_output_size_first(tmp_path):
    case = write(tmp_path, BASE)
    out = tmp_path / "o.h5"
    r = run_ok(["run", case, "-o", out])
    first = r.stdout.splitlines()[0]
    m = re.fullmatch(r"writing (\S+): ([\d.]+ \w+) \((\d+) snapshots of ([\d.]+ \w+)\); "
                     r"([\d.]+ \w+) free", first)
    assert m, r.stdout
    with h5py.File(out, "r") as f:
        assert int(m.group(3)) == f["time"].shape[0] == 3


def test_run_refuses_an_output_larger_than_the_free_space(tmp_path):
    """A run that would fill its file system is refused before it starts,
    naming the output_every that fits (1e-12 s apart: 1e12 snapshots)."""
    case = write(tmp_path, BASE)
    out = tmp_path / "o.h5"
    r = run(["run", case, "-o", out, "--set", "time.output_every=1e-12"])
    assert r.returncode == 2, r.stderr
    assert "more than the" in r.stderr and "free on its file system" in r.stderr, r.stderr
    m = re.search(r"--set time\.output_every=([\d.e+-]+) or more \((\d+) snapshots\)",
                  r.stderr)
    assert m, r.stderr
    assert 1e-12 < float(m.group(1)) <= 1.0
    assert len(r.stderr.strip().splitlines()) == 1, r.stderr
    assert not out.exists() and not (tmp_path / "o.h5.partial").exists()
    assert r.stdout == ""


QUIET = edit(edit(edit(BASE, "nx = 20", "nx = 512"), "ny = 16", "ny = 512"),
             "height = 0.2", "height = 0") + """
[source pile]
rect = 1 1 1.5 1.5
rate = 0.1
"""


def test_run_rate_counts_only_the_cells_swept(tmp_path):
    """Sand poured on a corner of a 512^2 grid: the fast sweep skips the
    sleeping tiles, and the rate counts only the cells it swept."""
    case = write(tmp_path, edit(QUIET, "end = 1", "end = 2"))
    r = run_ok(["run", case, "-o", tmp_path / "o.h5"])
    m = re.search(r"([\d.e+]+) cell-updates/s \(swept tiles only; ([\d.e+]+) counting every "
                  r"cell\)", r.stdout)
    assert m, r.stdout
    swept, every = float(m.group(1)), float(m.group(2))
    assert 0 < swept < every / 3, r.stdout


# A valid ESRI ASCII header of 100000 x 100000 cells with three values: the
# size alone must be refused, before any value is read.
HUGE_ASC = ("ncols 100000\nnrows 100000\nxllcorner 0\nyllcorner 0\ncellsize 5\n"
            "NODATA_value -9999\n1 2 3\n")


def refused_for_memory(r):
    assert r.returncode == 2, (r.returncode, r.stderr)
    assert re.search(r"100000 x 100000 cells need [\d.]+ \w+ of memory; this machine has "
                     r"[\d.]+ \w+ available", r.stderr), r.stderr
    assert len(r.stderr.strip().splitlines()) == 1, r.stderr


def test_relax_refuses_a_raster_too_large_for_memory_up_front(tmp_path):
    dem = tmp_path / "huge.asc"
    dem.write_text(HUGE_ASC)
    out = tmp_path / "out.asc"
    r = run(["relax", dem, "-o", out], timeout=30)
    refused_for_memory(r)
    assert not out.exists()


def test_fit_refuses_a_grid_too_large_for_memory_up_front(tmp_path):
    """The case's grid is checked before the observations are read."""
    small = write(tmp_path, BASE, "small.ini")
    run_ok(["run", small, "-o", tmp_path / "obs.h5", "--quiet"])
    big = write(tmp_path, edit(edit(BASE, "nx = 20", "nx = 100000"), "ny = 16",
                               "ny = 100000"), "big.ini")
    r = run(["fit", big, tmp_path / "obs.h5", "--param", "nu=0.05:0.2", "-o",
             tmp_path / "fit.json"], timeout=30)
    refused_for_memory(r)
    assert not (tmp_path / "fit.json").exists()


def half_nodata(tmp_path):
    """20 x 20 cells of 1 m at height 1; the western 10 columns without data."""
    row = " ".join(["-9999"] * 10 + ["1"] * 10)
    p = tmp_path / "half.asc"
    p.write_text("ncols 20\nnrows 20\nxllcorner 0\nyllcorner 0\ncellsize 1\n"
                 "NODATA_value -9999\n" + "\n".join([row] * 20) + "\n")
    return p


POUR = ["--sand-rate", "0.01", "--sand-duration", "10"]


@pytest.mark.parametrize("nodata", ["wall", "open"])
def test_relax_refuses_sand_poured_only_on_cells_without_data(tmp_path, nodata):
    dem = half_nodata(tmp_path)
    out = tmp_path / "out.asc"
    r = run(["relax", dem, "--add-sand", "disk=3,10,2", *POUR, "--nodata", nodata, "-o", out])
    assert r.returncode == 2, (r.stdout, r.stderr)
    assert re.fullmatch(r"sandslide: --add-sand covers 12 cells, all without data: nothing "
                        r"would be poured \(give a region on cells with data\)\n", r.stderr)
    assert not out.exists()


def test_relax_says_where_sand_partly_on_nodata_was_poured(tmp_path):
    """A disk of 32 cells across the edge of the data: 16 without data, and
    0.01 m/s x 10 s on each of the other 16 cells of 1 m^2 is 1.6 m^3."""
    dem = half_nodata(tmp_path)
    rep = tmp_path / "r.json"
    r = run_ok(["relax", dem, "--add-sand", "disk=10,10,3", *POUR, "-o", tmp_path / "o.asc",
                "--report", rep])
    assert ("note: --add-sand covers 32 cells, 16 of them without data: the 1.6 m^3 was poured "
            "on the other 16, centres x 10.5 .. 12.5, y 7.5 .. 12.5") in r.stdout, r.stdout
    report = json.loads(rep.read_text())
    assert report["pour_cells"] == 32 and report["pour_cells_nodata"] == 16
    assert report["inflow"] == pytest.approx(1.6, rel=1e-12)
