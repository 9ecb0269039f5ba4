# SPDX-License-Identifier: BSD-3-Clause
"""doc/output.md: the output opens as a netCDF-4 dataset, with time, y and x
as dimensions (HDF5 dimension scales) and every variable on them."""
import re
import shutil
import subprocess

import pytest

from conftest import run_ok

pytestmark = pytest.mark.skipif(shutil.which("ncdump") is None,
                                reason="ncdump not installed (Debian package netcdf-bin)")


def test_ncdump_reads_dimensions_and_variables(tmp_path, base_case):
    case = tmp_path / "case.ini"
    case.write_text(base_case)
    out = tmp_path / "run.h5"
    run_ok(["run", case, "-o", out, "-q"])
    r = subprocess.run(["ncdump", "-h", str(out)], capture_output=True, text=True, timeout=60)
    assert r.returncode == 0, f"ncdump cannot read the output: {r.stderr}"
    header = r.stdout
    assert re.search(r"time = UNLIMITED ; // \(3 currently\)", header), header
    assert re.search(r"\bx = 20 ;", header) and re.search(r"\by = 16 ;", header), header
    for decl in ["double height(time, y, x)", "byte cell_type(y, x)", "double time(time)",
                 "double x(x)", "double y(y)", "double volume(time)",
                 "double max_slope_deg(time)", "double active_fraction(time)"]:
        assert decl in header, f"ncdump does not show '{decl}':\n{header}"
    assert ':Conventions = "CF-1.8"' in header, header
