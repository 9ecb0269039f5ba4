# SPDX-License-Identifier: BSD-3-Clause
"""Damaged output files: `info`, `run --restart` and `render` refuse what
they cannot read with exit status 2 and one line that says so, and never
believe a size the file cannot hold (src/io/h5_checked.c checks every
size against the file before anything of that size is allocated).

The sweep flips one byte at each position of a deterministic sample of the
metadata of a small output (every STEP-th byte before the first chunk of
the diagnostic series, which is everything but raw numbers) and runs the
three commands on each damaged copy, two at a time.  SANDSLIDE_TEST_SCALE
(0.5 under `make SANITIZE=1 test`) widens the step so that the sweep takes
about as long under AddressSanitizer.
"""
import os
import shutil
import struct
import subprocess
from concurrent.futures import ThreadPoolExecutor

import h5py
import pytest

from conftest import BASE, SANDSLIDE, edit, h5open, run_ok

SCALE = float(os.environ.get("SANDSLIDE_TEST_SCALE") or 1)
STEP = int(307 / SCALE)
SERIES = ["time", "volume", "inflow", "outflow", "max_height", "max_slope_deg", "steps",
          "active_fraction", "wall_seconds"]
SMALL = edit(edit(BASE, "nx = 20\n", "nx = 6\n"), "ny = 16\n", "ny = 5\n")


@pytest.fixture(scope="module")
def output(tmp_path_factory):
    """A run of 6 x 5 cells with 3 snapshots: its bytes, where the series'
    chunks start, the chunks of /height and the object headers."""
    d = tmp_path_factory.mktemp("damaged")
    (d / "case.ini").write_text(SMALL)
    run_ok(["run", "case.ini", "-o", "o.h5", "-q"], cwd=d)
    with h5open(d / "o.h5") as f:
        series = min(f[n].id.get_chunk_info(0).byte_offset for n in SERIES)
        height = f["height"].id
        chunks = [height.get_chunk_info(k) for k in range(height.get_num_chunks())]
        headers = {n: h5py.h5o.get_info(f[n].id).addr for n in ("height", "time")}
    return (d / "o.h5").read_bytes(), series, chunks, headers


def commands(d, name):
    """The three readers on file `name` in d (restart on a copy: it appends)."""
    shutil.copy(d / name, d / ("r-" + name))
    return [["info", name], ["run", "--restart", "r-" + name, "-q"],
            ["render", name, "-o", "frames-" + name, "--scale", "1", "-q"]]


# A damaged size may make HDF5 itself ask malloc for exabytes (H5C_protect):
# malloc then returns NULL and HDF5 fails the read, which is what is tested.
# AddressSanitizer would abort the program there instead, by default, and
# with allocator_may_return_null says so in a line of its own (dropped).
SAN_ENV = dict(os.environ, ASAN_OPTIONS=":".join(
    o for o in (os.environ.get("ASAN_OPTIONS"), "allocator_may_return_null=1") if o))


def run_bytes(args, cwd):
    """Exit status and stderr (a damaged string in it may not be UTF-8)."""
    r = subprocess.run([SANDSLIDE] + args, cwd=cwd, capture_output=True, timeout=120,
                       env=SAN_ENV)
    err = r.stderr.decode("utf-8", "replace")
    return r.returncode, "".join(line for line in err.splitlines(keepends=True)
                                 if "AddressSanitizer failed to allocate" not in line)


def check_refusal(args, code, err):
    assert code in (0, 2), f"sandslide {' '.join(args)}: exit {code}\n{err}"
    if code:
        assert err.count("\n") == 1, f"sandslide {' '.join(args)}: not one line\n{err}"
    low = err.lower()
    assert "out of memory" not in low and "cannot allocate" not in low, err


def test_flipped_bytes_are_refused_or_harmless(output, tmp_path):
    data, series, _, _ = output
    positions = range(0, series, STEP)

    def flip(pos):
        d = tmp_path / str(pos)
        d.mkdir()
        damaged = bytearray(data)
        damaged[pos] ^= (0x01, 0x80, 0xFF)[pos % 3]   # a small, a large and any change
        (d / "x.h5").write_bytes(damaged)
        out = [(args, *run_bytes(args, d)) for args in commands(d, "x.h5")]
        shutil.rmtree(d)
        return pos, out

    refused = 0
    with ThreadPoolExecutor(2) as pool:
        for pos, out in pool.map(flip, positions):
            for args, code, err in out:
                check_refusal(args, code, f"byte {pos}: {err}")
                refused += code != 0
    assert refused > len(positions) // 10, f"only {refused} refusals: is the sample damaging?"


def dims_changed(data, header, old, new):
    """data with the sizes old (a dataspace message's current and maximum
    sizes, little-endian) of the object header at byte `header` made new."""
    old_bytes = struct.pack(f"<{len(old)}Q", *old)
    at = data.find(old_bytes, header)
    assert 0 <= at - header < 512, "test bug: the dataspace is not in the object header"
    return data[:at] + struct.pack(f"<{len(new)}Q", *new) + data[at + len(old_bytes):]


UNLIMITED = 2**64 - 1
HEIGHT_DIMS = (3, 5, 6, UNLIMITED, 5, 6)
TIME_DIMS = (3, UNLIMITED)


def test_huge_time_dimension_is_damage_not_out_of_memory(output, tmp_path):
    """A dataspace that claims 10^12 snapshots: the old reader allocated
    for them and exited 1 "out of memory"."""
    data, _, _, headers = output
    (tmp_path / "h.h5").write_bytes(dims_changed(data, headers["height"], HEIGHT_DIMS,
                                                 (10**12,) + HEIGHT_DIMS[1:]))
    (tmp_path / "t.h5").write_bytes(dims_changed(data, headers["time"], TIME_DIMS,
                                                 (10**12, UNLIMITED)))
    for name, what in (("h.h5", "/height claims 1000000000000 x 5 x 6 values"),
                       ("t.h5", "/time claims 1000000000000 values")):
        for args in commands(tmp_path, name):
            code, err = run_bytes(args, tmp_path)
            check_refusal(args, code, err)
            assert code == 2 and "is damaged" in err and what in err, (args, err)
            assert "more than its" in err and "can hold" in err, err


def test_unstored_snapshot_is_damage(output, tmp_path):
    """/height and /time that claim a snapshot more than the file stores."""
    data, _, _, headers = output
    more = dims_changed(data, headers["height"], HEIGHT_DIMS, (4,) + HEIGHT_DIMS[1:])
    more = dims_changed(more, headers["time"], TIME_DIMS, (4, UNLIMITED))
    (tmp_path / "u.h5").write_bytes(more)
    for args in commands(tmp_path, "u.h5"):
        code, err = run_bytes(args, tmp_path)
        assert code == 2 and "is damaged" in err and "stores no chunk at 3 x 0 x 0" in err, \
            (args, err)


def test_height_chunk_with_wrong_checksum(output, tmp_path):
    """A /height chunk whose fletcher32 checksum fails: the old renderer
    exited 1.  info does not read heights; restart reads the last one."""
    data, _, chunks, _ = output
    last = max(chunks, key=lambda c: c.chunk_offset[0])
    damaged = bytearray(data)
    damaged[last.byte_offset + last.size // 2] ^= 0x10
    (tmp_path / "c.h5").write_bytes(damaged)
    for args in commands(tmp_path, "c.h5"):
        code, err = run_bytes(args, tmp_path)
        check_refusal(args, code, err)
        if args[0] == "info":
            assert code == 0, err
        else:
            assert code == 2 and "is damaged" in err and "snapshot 2 of /height" in err, err
            assert "checksum" in err.lower(), err
    assert not (tmp_path / "frames-c.h5").exists()
