# SPDX-License-Identifier: BSD-3-Clause
"""No silent surprises from Python (issue 36 item 3): a raster too large for
the machine's memory is refused before any work, as `run` and `bench` refuse
such grids, by relax_raster and by the BMI's initialize; the BMI's elevation
is NaN where there is no sand surface, as relax's."""

import numpy as np
import pytest

import sandslide  # conftest.py: this checkout's when not installed
from sandslide.bmi import SandslideBmi

# A valid ESRI ASCII header of 100000 x 100000 cells with three values.
HUGE_ASC = ("ncols 100000\nnrows 100000\nxllcorner 0\nyllcorner 0\ncellsize 5\n"
            "NODATA_value -9999\n1 2 3\n")
MEMORY = r"100000 x 100000 cells need [\d.]+ \w+ of memory; this machine has [\d.]+ \w+ available"


def test_relax_raster_refuses_a_raster_too_large_for_memory(tmp_path):
    dem = tmp_path / "huge.asc"
    dem.write_text(HUGE_ASC)
    with pytest.raises(sandslide.InputError, match=MEMORY):
        sandslide.relax_raster(str(dem), str(tmp_path / "out.asc"))
    assert not (tmp_path / "out.asc").exists()


def test_bmi_initialize_refuses_a_raster_too_large_for_memory(tmp_path):
    (tmp_path / "huge.asc").write_text(HUGE_ASC)
    config = tmp_path / "bmi.ini"
    config.write_text("[bmi]\ndem = huge.asc\ntime_step = 10\n")
    m = SandslideBmi()
    with pytest.raises(sandslide.InputError, match=MEMORY):
        m.initialize(str(config))
    m.finalize()


def test_bmi_elevation_is_nan_where_relax_gives_nan(tmp_path):
    """No 0 m cliff: the BMI's elevation is NaN on cells without data, where
    sandslide.relax gives NaN, and finite elsewhere."""
    h = np.add.outer(np.zeros(6), 5.0 + 1.5 * np.arange(8))   # row 0 south
    h[:, 0] = np.nan                                          # a clipped edge
    h[3, 4] = np.nan                                          # a void
    rows = "\n".join(" ".join("-9999" if np.isnan(v) else repr(v) for v in row)
                     for row in h[::-1])                       # north row first
    (tmp_path / "holes.asc").write_text("ncols 8\nnrows 6\nxllcorner 0\nyllcorner 0\n"
                                        "cellsize 1\nNODATA_value -9999\n" + rows + "\n")
    (tmp_path / "bmi.ini").write_text("[bmi]\ndem = holes.asc\ntime_step = 0.5\n")
    m = SandslideBmi()
    m.initialize(str(tmp_path / "bmi.ini"))
    try:
        got = m.get_value("land_surface__elevation", np.empty(48)).reshape(6, 8)
    finally:
        m.finalize()
    relaxed, _ = sandslide.relax(h[::-1], dx=1.0, max_time=1.0)   # row 0 north
    assert np.array_equal(np.isnan(got), np.isnan(h))
    assert np.array_equal(np.isnan(relaxed[::-1]), np.isnan(h))
    assert np.isnan(got).sum() == 7
