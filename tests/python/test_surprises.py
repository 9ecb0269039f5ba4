"""No silent surprises from Python (issue 36 item 3): a raster too large for
the machine's memory is refused before any work, as `run` and `bench` refuse
such grids, by relax_raster and by the BMI's initialize."""
import re

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
