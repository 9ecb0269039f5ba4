# SPDX-License-Identifier: BSD-3-Clause
"""Shared helpers for the sandslide command-line and file-format tests.

The binary is found through the environment variable SANDSLIDE (an
absolute path); it defaults to build/sandslide of this checkout.  The ones
with a test hook (tests/hooks/) default to tests/ beside it: SANDSLIDE_NAN,
tests/sandslide-nan (the non-finite guard), and SANDSLIDE_PAUSE,
tests/sandslide-pause (a run that stops at a known substep until it is
signalled); `make test` builds all three.  Every test writes its files
under pytest's tmp_path.
"""
import os
import shutil
import struct
import subprocess
import time
import zlib

import h5py
import numpy as np
import pytest

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
SANDSLIDE = os.environ.get("SANDSLIDE", os.path.join(ROOT, "build", "sandslide"))
# sandslide with the test hook of the non-finite guard (tests/hooks/nan_step.c)
SANDSLIDE_NAN = os.environ.get("SANDSLIDE_NAN", os.path.join(os.path.dirname(SANDSLIDE),
                                                              "tests", "sandslide-nan"))
# sandslide with the test hook of the interrupt (tests/hooks/pause_step.c)
SANDSLIDE_PAUSE = os.environ.get("SANDSLIDE_PAUSE", os.path.join(os.path.dirname(SANDSLIDE),
                                                                  "tests", "sandslide-pause"))
CASES = os.path.join(ROOT, "cases")

# A small valid case: 20 x 16 cells of 0.1 m, grid [0, 2] x [0, 1.6] m.
# Flat sand 0.2 m high next to an open east side: it slides a little.
# tests/python reads the same file.
with open(os.path.join(ROOT, "tests", "base.ini")) as _f:
    BASE = _f.read()


def pytest_configure(config):
    if not os.path.isfile(SANDSLIDE) or not os.access(SANDSLIDE, os.X_OK):
        raise pytest.UsageError(
            f"sandslide binary not found at {SANDSLIDE!r}: run 'make' or set SANDSLIDE")


def run(args, cwd=None, timeout=120, **kw):
    """Run sandslide with args; returns the CompletedProcess (text mode)."""
    return subprocess.run([SANDSLIDE] + [str(a) for a in args], cwd=cwd,
                          capture_output=True, text=True, timeout=timeout, **kw)


def run_ok(args, cwd=None, timeout=120):
    r = run(args, cwd=cwd, timeout=timeout)
    assert r.returncode == 0, (
        f"sandslide {' '.join(map(str, args))} exited {r.returncode}\n"
        f"stdout:\n{r.stdout}\nstderr:\n{r.stderr}")
    return r


def edit(text, old, new, count=1):
    """Replace old by new in text; old must occur exactly `count` times."""
    n = text.count(old)
    assert n == count, f"test bug: {old!r} occurs {n} times in the case text"
    return text.replace(old, new)


def drop_line(text, prefix):
    """Remove the one line that starts with prefix."""
    lines = text.splitlines(keepends=True)
    hits = [k for k, l in enumerate(lines) if l.startswith(prefix)]
    assert len(hits) == 1, f"test bug: {len(hits)} lines start with {prefix!r}"
    del lines[hits[0]]
    return "".join(lines)


def line_of(text, needle, occurrence=1):
    """1-based number of the line holding the occurrence-th match of needle."""
    seen = 0
    for k, line in enumerate(text.splitlines(), 1):
        if needle in line:
            seen += 1
            if seen == occurrence:
                return k
    raise AssertionError(f"test bug: {needle!r} (occurrence {occurrence}) not in the case")


def png_bytes(rows, bit_depth=8):
    """An 8-bit greyscale PNG, rows top (north) first, values 0..255."""
    height, width = len(rows), len(rows[0])

    def chunk(kind, data):
        return (struct.pack(">I", len(data)) + kind + data +
                struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF))

    raw = b"".join(b"\x00" + bytes(int(v) for v in row) for row in rows)
    return (b"\x89PNG\r\n\x1a\n" +
            chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, bit_depth, 0, 0, 0, 0)) +
            chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b""))


def write_png(path, rows):
    with open(path, "wb") as f:
        f.write(png_bytes(rows))


def asc_text(values, cellsize=0.1, x0=0.0, y0=0.0):
    """ESRI ASCII grid text; values is a list of rows, north row first, as strings
    or numbers."""
    rows = len(values)
    cols = len(values[0])
    head = (f"ncols {cols}\nnrows {rows}\nxllcorner {x0}\nyllcorner {y0}\n"
            f"cellsize {cellsize}\n")
    return head + "".join(" ".join(str(v) for v in row) + "\n" for row in values)


def h5open(path):
    """Open read-only without HDF5 file locking (a writer may hold the lock)."""
    try:
        return h5py.File(path, "r", locking=False)
    except TypeError:   # old h5py without the locking keyword
        return h5py.File(path, "r")


def same_bits(a, b):
    """Two float64 arrays of the same shape and the very same bits."""
    return a.shape == b.shape and np.array_equal(a.view(np.uint64), b.view(np.uint64))


def assert_same_snapshots(a, b, series):
    """Every snapshot of output b is in output a at the same time, with the
    same bits of /height and the same values of the given series: a run cut
    and continued against the run never cut."""
    with h5open(a) as fa, h5open(b) as fb:
        ta, tb = list(fa["time"][:]), list(fb["time"][:])
        for k, t in enumerate(tb):
            assert t in ta, f"snapshot at t = {t!r} of the uninterrupted run is missing"
            i = ta.index(t)
            ha, hb = fa["height"][i], fb["height"][k]
            assert same_bits(ha, hb), \
                f"heights differ at t = {t!r}: max |dh| {np.abs(ha - hb).max()!r}"
            for name in series:
                assert fa[name][i] == fb[name][k], \
                    f"/{name} differs at t = {t!r}: {fa[name][i]!r} vs {fb[name][k]!r}"


def text_attr(obj, name):
    v = obj.attrs[name]
    if isinstance(v, np.ndarray) and v.shape == ():
        v = v[()]
    if isinstance(v, (bytes, np.bytes_)):
        v = bytes(v).decode("utf-8")
    return str(v)


def files_under(path):
    """Every file and folder below path, as relative paths."""
    out = set()
    for dirpath, dirnames, filenames in os.walk(path):
        for name in dirnames + filenames:
            out.add(os.path.relpath(os.path.join(dirpath, name), path))
    return out


def without_root_powers():
    """A command prefix that runs a program without root's power over file
    modes (CAP_DAC_OVERRIDE, CAP_DAC_READ_SEARCH: root reads a file of mode
    000 and writes into a folder of mode 555), so that a test of an
    unreadable file or a folder it may not write tests something when run
    as root, as CI does: setpriv (util-linux) with the two out of the
    bounding set.  [] for anyone but root; a skip, saying why, where setpriv
    cannot."""
    if os.geteuid() != 0:
        return []
    prefix = [shutil.which("setpriv") or "setpriv",
              "--bounding-set=-dac_override,-dac_read_search"]
    try:
        ok = subprocess.run(prefix + ["true"], capture_output=True, timeout=60).returncode == 0
    except OSError:
        ok = False
    if not ok:
        pytest.skip("running as root, and setpriv (Debian package util-linux) cannot drop "
                    "root's power over file modes: chmod hides nothing from root")
    return prefix


def wait_for(predicate, timeout, interval=0.02):
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        v = predicate()
        if v:
            return v
        time.sleep(interval)
    return predicate()


@pytest.fixture
def base_case():
    return BASE


# ---- signals at a known substep (tests/hooks/pause_step.c) ---------------------
# A test that signals a running sandslide would race it: on a fast machine
# the run may end first.  sandslide-pause stops after substep `step`,
# creates a marker file and waits for the stop signal, so that the signal
# arrives there every time and the run stops after substep step + 1.


def hook_binary(path):
    """path, which must be a hook binary that was built: a test that needs it
    fails (it is not skipped) when it is missing."""
    assert os.path.isfile(path) and os.access(path, os.X_OK), \
        f"{path} not found: `make test-hooks` builds it (so does `make test`; or set the " \
        f"variable naming it)"
    return path


def pause_env(step, marker, env=None):
    """The environment that makes sandslide-pause stop after substep `step`
    and create `marker` until a stop signal comes."""
    return dict(os.environ if env is None else env, SANDSLIDE_TEST_PAUSE_STEP=str(step),
                SANDSLIDE_TEST_PAUSE_FILE=str(marker))


def wait_paused(p, marker, step, timeout=120):
    """Wait until process p, started with pause_env(step, marker), is paused
    after that substep; fails (p left running for the caller to end) if it
    ended first or did not get there within timeout seconds."""
    wait_for(lambda: os.path.exists(marker) or p.poll() is not None, timeout)
    if os.path.exists(marker):
        return
    if p.poll() is not None:
        out, err = p.communicate()
        raise AssertionError(f"test set-up: the run ended (exit {p.returncode}) before "
                             f"substep {step}, where it should pause\nstderr:\n{err}")
    raise AssertionError(f"the run did not reach substep {step} within {timeout} s")
