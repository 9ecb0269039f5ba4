# SPDX-License-Identifier: BSD-3-Clause
"""Distributed runs (issue 14): `mpirun -np N build-mpi/sandslide` against the
serial build/sandslide, bit for bit.

Skipped unless the MPI build exists: SANDSLIDE_MPI (default
build-mpi/sandslide of this checkout, `make MPI=1`; set but empty: skipped)
and Open MPI's mpirun (MPIRUN, default mpirun.openmpi); each skip says
which.  The serial binary is conftest's SANDSLIDE; the MPI build's pause
hook is SANDSLIDE_MPI_PAUSE (default tests/sandslide-pause beside
SANDSLIDE_MPI), its batch hook SANDSLIDE_MPI_BATCH (tests/sandslide-batch);
`make MPI=1 test-mpi` builds both.

  bit identity     six small cases (64 x 45..48 cells, tiles 16 x 8: six tile
                   rows, the last one short when ny is 45 or 47) covering wall,
                   open and periodic sides (periodic y across ranks, periodic
                   in both axes), interior walls and an open drain, two
                   sources switching on and off, a bedrock (Euler), both
                   integrators; under np = 1, 2, 3, 4 and the MPI binary
                   without mpirun against the serial build; the reference
                   kernel under np = 2 and 4.  Compared: every dataset
                   (/height, /time, x, y, cell_type, bedrock when present, every
                   diagnostic series with active_fraction, but not
                   wall_seconds), shapes and types, the attributes of every
                   dataset (the dimension-scale references left out), every
                   root attribute but history (the restart states included), and
                   the XDMF sidecar
  relax            np = 3 equal to serial: .asc in and .asc out (the bytes,
                   and the --report but wall_seconds), .asc in and .h5 out
  rasters          (builds with GDAL) a tiled GeoTIFF with nodata and a UTM
                   CRS relaxed to GeoTIFF under np = 1..4 and without
                   mpirun: the serial file's bytes, values, geotransform,
                   CRS, nodata value and report; a VRT of 4 GeoTIFF tiles
                   under np = 3: the serial relax of the one GeoTIFF; a
                   GeoTIFF cut at 2000, 9000, 15000 bytes under np = 3: one
                   message, exit 2, no hang; a 4096^2 GeoTIFF for one
                   super-step: the largest rank's peak memory under np = 4
                   at most 40 % of one rank's, the same output bytes;
                   SIGTERM to relax under np = 4 paused after step 40: one
                   message, stopped after step 41, the input unchanged, a
                   readable .h5 ending with that step
  restart          np = 2 cut by a file-size limit (exit 1, one message, the
                   snapshots before it complete), continued by run --restart
                   under np = 3 to the end: every snapshot and the final
                   restart states are those of the serial run never cut; the
                   same with RKL2 cut under np = 3 and continued under np = 4,
                   both with a small outflow batch (below)
  SIGTERM          to mpirun -np 3 mid-run, its ranks paused after a
                   known substep (build-mpi/tests/sandslide-pause,
                   tests/hooks/pause_step.c: no race with a fast machine):
                   one message from rank 0, every rank stops after the next
                   substep, a readable file (h5py, ncdump) ending with a
                   complete snapshot of that substep; run --restart under
                   np = 2 from it, interrupted again the same way: every
                   snapshot on the output times has the serial run's bits
  killed job       SIGKILL to every process of the job (mpirun puts each rank
                   in its own process group, so the test kills the session)
                   leaves a file that h5py and ncdump -h read, with every
                   snapshot seen before the kill present and equal to the
                   serial run
  ncdump           reads the header and the data of an np = 3 file; its
                   summary is printed once
  outflow batch    each rank keeps its open faces' fluxes and the ranks fold
                   them per snapshot or when the batch is full (ledger.h):
                   the batch shrunk by build-mpi/tests/sandslide-batch
                   (tests/hooks/batch_step.c) so that it fills between
                   snapshots, by its count of evaluations (the mixed cases,
                   both integrators and kernels, np = 3 and 4) or by the
                   fluxes kept (relax of cases/dem/terrain.asc with open
                   sides, both integrators, np = 4): every output has the
                   serial bits
  refusals         more ranks than tile rows: exit 2, one message naming both
                   numbers, no output file
  version          --version of the MPI binary names MPI, printed once under
                   mpirun -np 2

Every run gets --threads 1 and --bind-to none, and the Open MPI settings of
doc/cluster.md#open-mpi-as-root-on-a-small-machine (root, oversubscription of 2 cores,
yielding when idle, shared memory only).  A run that hangs (a deadlock) is
killed, all its processes (and what they leave in /dev/shm and mpirun's
session folder), after 60 s and fails the test.  About 75 mpirun starts:
45 s on 2 busy cores.
"""
import glob
import json
import os
import re
import shutil
import signal
import subprocess
import tempfile
import time

import numpy as np
import pytest

import conftest
from conftest import (ROOT, SANDSLIDE, h5open, hook_binary, pause_env, same_bits, wait_for,
                      wait_paused)

SANDSLIDE_MPI = os.environ.get("SANDSLIDE_MPI", os.path.join(ROOT, "build-mpi", "sandslide"))
MPIRUN = os.environ.get("MPIRUN") or shutil.which("mpirun.openmpi") or shutil.which("mpirun")
# the MPI build with the pause hook (tests/hooks/pause_step.c)
SANDSLIDE_MPI_PAUSE = os.environ.get(
    "SANDSLIDE_MPI_PAUSE", os.path.join(os.path.dirname(SANDSLIDE_MPI), "tests", "sandslide-pause"))
# the MPI build with the batch hook (tests/hooks/batch_step.c)
SANDSLIDE_MPI_BATCH = os.environ.get(
    "SANDSLIDE_MPI_BATCH", os.path.join(os.path.dirname(SANDSLIDE_MPI), "tests", "sandslide-batch"))

pytestmark = [
    # SANDSLIDE_MPI= (empty): not here; `make MPI=1 test-mpi` runs these
    pytest.mark.skipif(SANDSLIDE_MPI == "", reason="SANDSLIDE_MPI is empty: the distributed "
                       "tests are make MPI=1 test-mpi"),
    pytest.mark.skipif(not (os.path.isfile(SANDSLIDE_MPI) and os.access(SANDSLIDE_MPI, os.X_OK)),
                       reason=f"no MPI build at {SANDSLIDE_MPI} "
                              "(make MPI=1, or set SANDSLIDE_MPI)"),
    pytest.mark.skipif(MPIRUN is None, reason="mpirun not found (Debian package openmpi-bin)"),
]

# Open MPI as root on a small machine (doc/cluster.md#open-mpi-as-root-on-a-small-machine)
MPI_ENV = dict(
    os.environ,
    OMPI_ALLOW_RUN_AS_ROOT="1",
    OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
    OMPI_MCA_rmaps_base_oversubscribe="1",
    OMPI_MCA_mpi_yield_when_idle="1",
    OMPI_MCA_btl_vader_single_copy_mechanism="none",
    OMPI_MCA_pml="ob1",
    OMPI_MCA_btl="self,vader",
    OMPI_MCA_btl_base_warn_component_unused="0",
    OMP_NUM_THREADS="1",
)

TILE = "16x8"        # 64 x 48 cells: 4 x 6 tiles
TILE_ROWS = 6        # for every case below (ny = 45 .. 48)
PHYSICAL = ["volume", "inflow", "outflow", "max_height", "max_slope_deg", "steps",
            "stencil_evaluations"]


# ---- running ----------------------------------------------------------------------


def session_processes(sid):
    """Pids of the processes of session sid (mpirun's, as it was started with
    start_new_session): mpirun and every rank, whatever their process group."""
    pids = []
    for d in os.listdir("/proc"):
        if not d.isdigit():
            continue
        try:
            with open(f"/proc/{d}/stat") as f:
                stat = f.read()
        except OSError:
            continue
        fields = stat[stat.rindex(")") + 2:].split()
        if int(fields[3]) == sid and fields[0] != "Z":   # a zombie is gone, but unreaped
            pids.append(int(d))
    return pids


def shared_memory_of(sid):
    """The /dev/shm files (Open MPI's vader segments) that the processes of
    session sid map."""
    files = set()
    for pid in session_processes(sid):
        try:
            with open(f"/proc/{pid}/maps") as f:
                for line in f:
                    fields = line.split(maxsplit=5)
                    if len(fields) == 6 and fields[5].startswith("/dev/shm/"):
                        files.add(fields[5].strip().replace(" (deleted)", ""))
        except OSError:
            pass
    return files


def remove_leftovers(mpirun_pid, files):
    """What a job that did not end on its own leaves: its shared-memory
    segments (4 MiB a rank) and mpirun's session folder."""
    for path in files:
        try:
            os.unlink(path)
        except OSError:
            pass
    for d in glob.glob(os.path.join(tempfile.gettempdir(), "ompi.*", f"pid.{mpirun_pid}")):
        shutil.rmtree(d, ignore_errors=True)


def kill_session(sid):
    """SIGKILL every process of session sid, until none is left, then remove
    what they leave behind."""
    files = shared_memory_of(sid)
    deadline = time.monotonic() + 10
    while time.monotonic() < deadline:
        pids = session_processes(sid)
        if not pids:
            remove_leftovers(sid, files)
            return
        for pid in pids:
            try:
                os.kill(pid, signal.SIGKILL)
            except ProcessLookupError:
                pass
        time.sleep(0.02)
    raise AssertionError(f"processes {session_processes(sid)} of the killed job survive")


def with_threads(args):
    args = [str(a) for a in args]
    return args + ["--threads", "1"] if args and args[0] in ("run", "relax") else args


def mpi_command(np_, args, binary=None):
    """mpirun -np np_ ... sandslide args; np_ None: the MPI binary alone;
    binary: another build of it (default SANDSLIDE_MPI)."""
    binary = binary or SANDSLIDE_MPI
    if np_ is None:
        return [binary] + with_threads(args)
    return [MPIRUN, "-np", str(np_), "--bind-to", "none", binary] + with_threads(args)


def start_mpi(np_, args, cwd, binary=None, env=None):
    """Start a distributed run in its own session (see kill_session)."""
    return subprocess.Popen(mpi_command(np_, args, binary), cwd=cwd,
                            env=MPI_ENV if env is None else env, text=True,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            stdin=subprocess.DEVNULL, start_new_session=True)


def finish(p, what, timeout):
    """Wait for p; a run still going after timeout seconds is killed, all its
    processes, and fails the test (a deadlock, most likely)."""
    try:
        out, err = p.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        kill_session(p.pid)
        out, err = p.communicate()
        raise AssertionError(f"{what} still running after {timeout} s (a deadlock?), killed\n"
                             f"stdout:\n{out}\nstderr:\n{err}")
    finally:
        kill_session(p.pid)   # nothing of the job may outlive it
    return subprocess.CompletedProcess(p.args, p.returncode, out, err)


def mpi_run(np_, args, cwd, timeout=60):
    what = " ".join(mpi_command(np_, args))
    return finish(start_mpi(np_, args, cwd), what, timeout)


def mpi_run_ok(np_, args, cwd, timeout=60):
    r = mpi_run(np_, args, cwd, timeout)
    assert r.returncode == 0, (f"{' '.join(r.args)} exited {r.returncode}\n"
                               f"stdout:\n{r.stdout}\nstderr:\n{r.stderr}")
    return r


def serial_run_ok(args, cwd):
    return conftest.run_ok(with_threads(args), cwd=cwd)


def np_label(np_):
    return "the MPI binary without mpirun" if np_ is None else f"mpirun -np {np_}"


# ---- cases --------------------------------------------------------------------------

CONE = "type = cone\ncenter = 1.2 1.2\nradius = 0.35\nangle = 50\nheight = 0\n"
ON_BEDROCK = "type = file\nfile = start.asc\nbedrock = rock.asc\n"


def case_text(ny=48, integrator="euler", sides=("wall", "open", "open", "wall"), end=4.0,
              every=0.25, initial=CONE):
    """64 x ny cells of 5 cm: a cone of sand on rows 17 .. 30 (np = 2 splits
    it at row 24), a wall pillar, a wall bar on rows 31 and 32 (np = 3 and 4
    split it), an open drain in the cone on rows 22 .. 24, a source in the
    south-west corner (on until end / 2: it wraps round periodic sides) and
    one near the north-east corner on rows 40 .. 43 (np = 4 splits it; from
    end / 4 to 3 end / 4).  Sides west, east, south, north."""
    w, e, s, n = sides
    return f"""\
# tests/cli/test_mpi.py
[grid]
nx = 64
ny = {ny}
dx = 0.05
origin = 0 0

[model]
closure = coulomb
repose_angle = 35
nu = 0.05

[time]
integrator = {integrator}
end = {end!r}
output_every = {every!r}

[boundary]
west = {w}
east = {e}
south = {s}
north = {n}
open_level = 0

[initial]
{initial}
[wall pillar]
disk = 2.2 0.9 0.15

[wall bar]
rect = 1.9 1.55 2.6 1.65

[open drain]
rect = 1.5 1.1 1.65 1.25

[source corner]
rect = 0 0 0.3 0.3
rate = 0.05
start = 0
stop = {end / 2!r}

[source north]
disk = 3.05 2.1 0.1
rate = 0.1
start = {end / 4!r}
stop = {3 * end / 4!r}
"""


CASES = {
    # sides: west, east, south, north
    "mixed-euler": dict(integrator="euler"),
    "mixed-rkl2": dict(integrator="rkl2"),
    "periodic-y-rkl2": dict(integrator="rkl2", ny=45,
                            sides=("wall", "open", "periodic", "periodic")),
    "periodic-x-euler": dict(ny=47, sides=("periodic", "periodic", "open", "wall")),
    "periodic-xy-euler": dict(sides=("periodic",) * 4),
    "bedrock-euler": dict(ny=47, sides=("open", "wall", "wall", "open"), initial=ON_BEDROCK),
    # cut by a file-size limit: about 4800 steps, 301 snapshots of 24 kB
    "long-euler": dict(end=60.0, every=0.2),
    # the same with RKL2: 361 super-steps, 2923 evaluations
    "long-rkl2": dict(integrator="rkl2", end=60.0, every=0.2),
    # interrupted and killed: about 240000 steps, several seconds under
    # mpirun even on a quiet machine (the killed job must still be going
    # when it is killed); a snapshot every 160 steps
    "signal-euler": dict(end=3000.0, every=2.0),
}
BIT_CASES = [c for c in CASES if c not in ("long-euler", "long-rkl2", "signal-euler")]


def asc_text(h, dx=0.05):
    ny, nx = h.shape
    rows = "\n".join(" ".join(repr(float(v)) for v in h[j]) for j in range(ny - 1, -1, -1))
    return f"ncols {nx}\nnrows {ny}\nxllcorner 0\nyllcorner 0\ncellsize {dx!r}\n{rows}\n"


def write_case(d, name):
    """case.ini of CASES[name] in folder d, with its rasters."""
    spec = CASES[name]
    (d / "case.ini").write_text(case_text(**spec))
    if spec.get("initial") == ON_BEDROCK:
        ny = spec["ny"]
        x = (np.arange(64) + 0.5) * 0.05
        y = (np.arange(ny) + 0.5) * 0.05
        X, Y = np.meshgrid(x, y)
        # a rock ridge along y = 1.2 m and a slope down to the west, under a
        # steep pile of sand that slides over it
        rock = 0.25 * np.exp(-((Y - 1.2) / 0.3) ** 2) + 0.05 * X / 3.2
        sand = np.maximum(0.0, 0.45 - 1.2 * np.hypot(X - 1.6, Y - 1.0))
        (d / "rock.asc").write_text(asc_text(rock))
        (d / "start.asc").write_text(asc_text(rock + sand))


@pytest.fixture(scope="module")
def serial(tmp_path_factory):
    """The serial build's output of a case (with extra flags), run once for
    the module: serial(name, *flags) -> path of serial.h5."""
    cache = {}

    def get(name, *flags):
        key = (name,) + flags
        if key not in cache:
            d = tmp_path_factory.mktemp("serial-" + name)
            write_case(d, name)
            serial_run_ok(["run", "case.ini", "-o", "serial.h5", "-q", "--tile", TILE, *flags], d)
            cache[key] = d / "serial.h5"
        return cache[key]

    return get


# ---- comparing outputs --------------------------------------------------------------------

SCALE_REFERENCES = ("DIMENSION_LIST", "REFERENCE_LIST")   # object references: addresses


def attr_value(v):
    if isinstance(v, np.ndarray) and v.shape == ():
        v = v[()]
    return v


def same_attr(a, b):
    a, b = attr_value(a), attr_value(b)
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        a, b = np.asarray(a), np.asarray(b)
        if a.dtype.kind == "f" and b.dtype.kind == "f":
            return same_bits(a, b)
        return a.shape == b.shape and a.dtype == b.dtype and np.array_equal(a, b)
    if isinstance(a, float) and isinstance(b, float):
        return same_bits(np.array(a), np.array(b))
    return type(a) == type(b) and a == b


def first_difference(a, b):
    """Where two arrays of the same shape differ first (index tuple)."""
    if a.dtype.kind == "f":
        diff = a.view(np.uint64) != b.view(np.uint64)
    else:
        diff = a != b
    return tuple(int(k) for k in np.argwhere(diff)[0])


def describe_height_difference(a, b, t):
    k, j, i = first_difference(a, b)
    bad = [int(s) for s in range(a.shape[0]) if not same_bits(a[s], b[s])]
    diff = a[k].view(np.uint64) != b[k].view(np.uint64)
    rows = sorted({int(r) for r in np.argwhere(diff)[:, 0]})
    return (f"snapshots {bad} (times {[float(t[s]) for s in bad][:5]}) differ; in snapshot "
            f"{k} first at cell (i, j) = ({i}, {j}): {b[k, j, i]!r}, serial {a[k, j, i]!r}; "
            f"rows {rows[:12]}{' ...' if len(rows) > 12 else ''}, "
            f"max |dh| {np.abs(a[k] - b[k]).max()!r}")


def assert_same_output(ref, got, what):
    """The file got has the serial file ref's datasets, attributes and bits
    (wall_seconds and history aside)."""
    with h5open(ref) as a, h5open(got) as b:
        assert sorted(a) == sorted(b), \
            f"{what}: the file holds {sorted(b)}, the serial build's {sorted(a)}"
        assert "active_fraction" in a and "restart_state_even" in a.attrs, \
            "test set-up: the serial file lacks active_fraction or restart_state_even"
        t = a["time"][()]
        # /height first: the most telling difference
        for name in sorted(a, key=lambda n: (n != "height", n != "time", n)):
            da, db = a[name], b[name]
            assert da.shape == db.shape and da.dtype == db.dtype, \
                f"{what}: /{name} is {db.dtype} {db.shape}, serial {da.dtype} {da.shape}"
            for k in sorted(set(da.attrs) | set(db.attrs)):
                if k in SCALE_REFERENCES:
                    assert (k in da.attrs) == (k in db.attrs), \
                        f"{what}: attribute {k} of /{name} in one file only"
                    continue
                assert k in da.attrs and k in db.attrs and same_attr(da.attrs[k], db.attrs[k]), \
                    (f"{what}: attribute {k} of /{name} is {db.attrs.get(k)!r}, "
                     f"serial {da.attrs.get(k)!r}")
            if name == "wall_seconds":
                continue
            va, vb = da[()], db[()]
            equal = same_bits(va, vb) if va.dtype.kind == "f" else np.array_equal(va, vb)
            if equal:
                continue
            if name == "height":
                raise AssertionError(f"{what}: /height differs from the serial build: "
                                     + describe_height_difference(va, vb, t))
            where = first_difference(va, vb)
            raise AssertionError(f"{what}: /{name} differs from the serial build first at "
                                 f"{where}: {vb[where]!r} vs serial {va[where]!r}"
                                 + (f" (t = {t[where[0]]!r})" if va.shape == t.shape else ""))
        keys_a, keys_b = set(a.attrs) - {"history"}, set(b.attrs) - {"history"}
        assert keys_a == keys_b, \
            f"{what}: root attributes {sorted(keys_b)}, serial {sorted(keys_a)}"
        for k in sorted(keys_a):
            assert same_attr(a.attrs[k], b.attrs[k]), \
                f"{what}: root attribute {k} is {b.attrs[k]!r}, serial {a.attrs[k]!r}"


def assert_same_sidecar(ref, got, what):
    """The XDMF sidecars say the same but for the file name."""
    ta = ref.with_suffix(".xmf").read_text().replace(ref.name + ":", "OUT.h5:")
    tb = got.with_suffix(".xmf").read_text().replace(got.name + ":", "OUT.h5:")
    assert ta == tb, \
        f"{what}: the sidecar {got.with_suffix('.xmf').name} differs from the serial one"


# ---- a. the same bits as the serial build ---------------------------------------------------


def test_cases_exercise_what_they_claim(serial):
    """Set-up: every case takes a hundred steps or more, moves sand out through
    an open side or the drain, and lets tiles sleep (so the wake flags that
    cross rank edges matter); sand crosses the periodic sides."""
    for name in BIT_CASES:
        with h5open(serial(name)) as f:
            ev, af = f["stencil_evaluations"][-1], f["active_fraction"][()]
            h = f["height"]
            assert 100 <= ev <= 1500, f"{name}: {ev} stencil evaluations"
            assert f["outflow"][-1] > 0, f"{name}: nothing flows out"
            assert 0 < af[1:].min() and af[1:].min() < 1, f"{name}: active_fraction {af}"
            assert f["inflow"][-1] > 0
            d = h[-1] - h[0]
            if "periodic-y" in name or "periodic-xy" in name:
                assert d[-1, :6].min() > 0, f"{name}: the corner source's sand did not wrap north"
            if "periodic-x" in name or "periodic-xy" in name:
                assert d[:6, -1].min() > 0, f"{name}: the corner source's sand did not wrap east"
            if name == "bedrock-euler":
                assert "bedrock" in f, "bedrock-euler: no /bedrock"


@pytest.mark.parametrize("np_", [1, 2, 3, 4, None],
                         ids=["np1", "np2", "np3", "np4", "no-mpirun"])
@pytest.mark.parametrize("case", BIT_CASES)
def test_every_snapshot_has_the_serial_bits(tmp_path, serial, case, np_):
    write_case(tmp_path, case)
    out = tmp_path / "mpi.h5"
    r = mpi_run_ok(np_, ["run", "case.ini", "-o", out.name, "-q", "--tile", TILE], tmp_path)
    what = f"{case} under {np_label(np_)}"
    assert r.stdout == "" and "sandslide:" not in r.stderr, \
        f"{what}: -q, yet it printed\nstdout:\n{r.stdout}\nstderr:\n{r.stderr}"
    assert_same_output(serial(case), out, what)
    assert_same_sidecar(serial(case), out, what)


@pytest.mark.parametrize("np_", [2, 4], ids=["np2", "np4"])
@pytest.mark.parametrize("case", BIT_CASES)
def test_reference_kernel_has_the_serial_bits(tmp_path, serial, case, np_):
    write_case(tmp_path, case)
    out = tmp_path / "mpi.h5"
    mpi_run_ok(np_, ["run", "case.ini", "-o", out.name, "-q", "--tile", TILE,
                     "--reference-kernel"], tmp_path)
    assert_same_output(serial(case, "--reference-kernel"), out,
                       f"{case}, reference kernel, under {np_label(np_)}")


# ---- b. relax ------------------------------------------------------------------------------


def write_cliff(path):
    """A 0.2 m plateau over a third of a rough 32 x 26 floor of 10 cm cells:
    26 rows, four tile rows of 8, 8, 8 and 2 by default."""
    rng = np.random.default_rng(11)
    h = 0.02 * rng.random((26, 32))
    h[:, :10] += 0.2
    path.write_text(asc_text(h, dx=0.1))


def read_asc(path):
    """The values of an ESRI ASCII grid, row 0 south."""
    tokens = path.read_text().split()
    head = dict(zip(tokens[0:10:2], tokens[1:10:2]))
    nx, ny = int(head["ncols"]), int(head["nrows"])
    return np.array([float(v) for v in tokens[10:10 + nx * ny]]).reshape(ny, nx)[::-1]


# --tol and --slope-tol looser than the defaults: steady after about 1500 steps
RELAX_FAST = ["--tol", "1e-6", "--slope-tol", "1e-3"]


@pytest.fixture(scope="module")
def serial_relax(tmp_path_factory):
    d = tmp_path_factory.mktemp("serial-relax")
    write_cliff(d / "cliff.asc")
    serial_run_ok(["relax", "cliff.asc", "-o", "relaxed.asc", "-q", "--report", "report.json",
                   *RELAX_FAST], d)
    serial_run_ok(["relax", "cliff.asc", "-o", "relaxed.h5", "-q", "--sides", "open",
                   "--integrator", "rkl2", "--output-every", "1", *RELAX_FAST], d)
    return d


def test_relax_asc_under_3_ranks_is_the_serial_raster(tmp_path, serial_relax):
    write_cliff(tmp_path / "cliff.asc")
    mpi_run_ok(3, ["relax", "cliff.asc", "-o", "relaxed.asc", "-q", "--report", "report.json",
                   *RELAX_FAST], tmp_path)
    want = (serial_relax / "relaxed.asc").read_bytes()
    got = (tmp_path / "relaxed.asc").read_bytes()
    if got != want:
        a, b = read_asc(serial_relax / "relaxed.asc"), read_asc(tmp_path / "relaxed.asc")
        where = ""
        if a.shape == b.shape:
            j, i = np.unravel_index(np.abs(a - b).argmax(), a.shape)
            where = f": max |dh| {np.abs(a - b).max()!r} at cell (i, j) = ({i}, {j})"
        raise AssertionError(f"relax under np = 3: the .asc output differs from the serial "
                             f"one ({b.shape} cells, serial {a.shape}){where}")
    same_report(serial_relax / "report.json", tmp_path / "report.json", "relax under np = 3")


def test_relax_h5_under_3_ranks_is_the_serial_series(tmp_path, serial_relax):
    write_cliff(tmp_path / "cliff.asc")
    mpi_run_ok(3, ["relax", "cliff.asc", "-o", "relaxed.h5", "-q", "--sides", "open",
                   "--integrator", "rkl2", "--output-every", "1", *RELAX_FAST], tmp_path)
    assert_same_output(serial_relax / "relaxed.h5", tmp_path / "relaxed.h5",
                       "relax (.h5, open sides, rkl2) under np = 3")


def write_angles(path):
    """Repose angles of 30 and 40 degrees in bands of 5 rows, which the
    ranks' edges cut, and a column of 35: materials (doc/model.md#materials)
    whose faces cross the ranks' edges."""
    y, _ = np.mgrid[0:26, 0:32]
    a = np.where((y // 5) % 2 == 0, 30.0, 40.0)
    a[:, 20:24] = 35.0
    path.write_text(asc_text(a, dx=0.1))


def test_relax_with_an_angle_raster_under_3_ranks_is_the_serial_raster(tmp_path):
    """Each rank numbers the whole grid's angles alike, and the halo rows of
    the materials come from the ranks beside."""
    serial, mpi = tmp_path / "serial", tmp_path / "mpi"
    for d in (serial, mpi):
        d.mkdir()
        write_cliff(d / "cliff.asc")
        write_angles(d / "angles.asc")
    args = ["relax", "cliff.asc", "-o", "relaxed.asc", "-q", "--angle", "angles.asc",
            *RELAX_FAST]
    serial_run_ok(args, serial)
    mpi_run_ok(3, args, mpi)
    assert (mpi / "relaxed.asc").read_bytes() == (serial / "relaxed.asc").read_bytes(), \
        "relax --angle FILE under np = 3: the .asc differs from the serial one"


HYSTERESIS_CASE = """[grid]
nx = 41
ny = 41
dx = 0.05
origin = -1.025 -1.025
[model]
closure = coulomb
materials = classes.asc
nu = 0.1
[material sand]
class = 3
repose_angle = 30
static_angle = 36
[material loose]
class = 7
repose_angle = 25
[time]
end = 12
output_every = 1
[boundary]
west = open
east = open
south = open
north = open
[source pour]
disk = 0 0 0.06
rate = 0.02
"""


def test_hysteresis_under_3_ranks_has_the_serial_bits(tmp_path):
    """Each cell at rest or moving (doc/model.md#hysteresis), of two
    materials, one of them with a static angle: the states of the halo rows
    from the ranks beside, the same avalanches."""
    classes = [[7 if min(i, j, 40 - i, 40 - j) < 3 else 3 for i in range(41)]
               for j in range(41)]
    serial, mpi = tmp_path / "serial", tmp_path / "mpi"
    for d in (serial, mpi):
        d.mkdir()
        (d / "pour.ini").write_text(HYSTERESIS_CASE)
        (d / "classes.asc").write_text(asc_text(np.array(classes, dtype=float)))
    args = ["run", "pour.ini", "-o", "pour.h5", "-q", "--tile", "16x8"]
    serial_run_ok(args, serial)
    mpi_run_ok(3, args, mpi)
    with h5open(serial / "pour.h5") as a, h5open(mpi / "pour.h5") as b:
        assert same_bits(a["height"][:], b["height"][:]), \
            "hysteresis under np = 3: the heights differ from the serial run's"
        assert np.array_equal(a["moving"][:], b["moving"][:]) and a["moving"][:].any(), \
            "hysteresis under np = 3: /moving differs from the serial run's (or is empty)"


def write_clipped_cliff(path):
    """The cliff with nodata (-9999) round a disk that crosses every rank's
    rows, and a hole: the cells relax writes as /cell_type 3."""
    rng = np.random.default_rng(11)
    h = 0.02 * rng.random((26, 32))
    h[:, :10] += 0.2
    y, x = np.mgrid[0:26, 0:32] + 0.5
    nodata = np.hypot(x - 14, y - 13) > 12.5
    nodata[12, 20] = True
    path.write_text(asc_text(np.where(nodata, -9999.0, h), dx=0.1)
                    .replace("cellsize", "NODATA_value -9999\ncellsize"))
    return nodata


@pytest.mark.parametrize("nodata", ["wall", "open"])
def test_relax_h5_with_nodata_under_3_ranks_is_the_serial_series(tmp_path, nodata):
    """The cells without data (cell_type 3, NaN heights) are written by
    each rank for its rows: the same bits as the serial file."""
    for d in ("serial", "mpi"):
        (tmp_path / d).mkdir()
        mask = write_clipped_cliff(tmp_path / d / "dem.asc")
    args = ["relax", "dem.asc", "-o", "relaxed.h5", "-q", "--nodata", nodata,
            "--output-every", "1", *RELAX_FAST]
    serial_run_ok(args, tmp_path / "serial")
    mpi_run_ok(3, args, tmp_path / "mpi")
    with h5open(tmp_path / "serial" / "relaxed.h5") as f:
        assert np.array_equal(f["cell_type"][()] == 3, mask), \
            "test set-up: the serial file's cells without data are not the DEM's"
    assert_same_output(tmp_path / "serial" / "relaxed.h5", tmp_path / "mpi" / "relaxed.h5",
                       f"relax (.h5, nodata {nodata}) under np = 3")


# ---- b2. rasters by windows: GeoTIFF, a VRT mosaic, memory, failures, SIGTERM -------------

def gdal_in(binary):
    """Whether binary was built with GDAL (its --version says)."""
    out = subprocess.run([binary, "--version"], capture_output=True, text=True).stdout
    return "GDAL: on" in out


needs_gdal = pytest.mark.skipif(
    not (os.path.isfile(SANDSLIDE_MPI) and gdal_in(SANDSLIDE_MPI) and gdal_in(SANDSLIDE)),
    reason="a build without GDAL (made with GDAL=0, or without libgdal-dev)")


def write_geotiff(path, h, nodata=None, block=16, dx=0.1, epsg=32633):
    """h (row 0 south) as a tiled float64 GeoTIFF with a UTM CRS, its nodata
    value if given; tiles of block x block cells, so that the ranks' rows cut
    through tiles."""
    from osgeo import gdal, osr
    gdal.UseExceptions()
    ny, nx = h.shape
    ds = gdal.GetDriverByName("GTiff").Create(
        str(path), nx, ny, 1, gdal.GDT_Float64,
        ["TILED=YES", f"BLOCKXSIZE={block}", f"BLOCKYSIZE={block}"])
    ds.SetGeoTransform([500000.0, dx, 0.0, 5400000.0 + ny * dx, 0.0, -dx])
    crs = osr.SpatialReference()
    crs.ImportFromEPSG(epsg)
    ds.SetProjection(crs.ExportToWkt())
    band = ds.GetRasterBand(1)
    if nodata is not None:
        band.SetNoDataValue(nodata)
    band.WriteArray(h[::-1])
    ds = None


def clipped_terrain(ny=48, nx=40):
    """A plateau on a rough floor, no data outside a disk (and in one hole):
    every rank's rows hold cells with and without data."""
    rng = np.random.default_rng(5)
    h = 0.02 * rng.random((ny, nx))
    h[:, : nx // 3] += 0.3
    y, x = np.mgrid[0:ny, 0:nx] + 0.5
    nodata = np.hypot(x - nx / 2, y - ny / 2) > 22
    nodata[30, 25] = True
    return np.where(nodata, -9999.0, h)


def read_geotiff(path):
    """(values row 0 north, geotransform, CRS WKT, nodata value) of band 1."""
    from osgeo import gdal
    gdal.UseExceptions()
    ds = gdal.Open(str(path))
    band = ds.GetRasterBand(1)
    return (band.ReadAsArray(), ds.GetGeoTransform(), ds.GetProjection(),
            band.GetNoDataValue())


def assert_same_geotiff(want, got, what):
    a, b = read_geotiff(want), read_geotiff(got)
    assert a[0].shape == b[0].shape, f"{what}: {b[0].shape} cells, serial {a[0].shape}"
    bad = a[0].view(np.int64) != b[0].view(np.int64)
    if bad.any():
        row, col = np.argwhere(bad)[0]
        raise AssertionError(f"{what}: {bad.sum()} cells differ from the serial output, the "
                             f"first at row {row}, column {col} (from the north-west): "
                             f"{b[0][row, col]!r}, serial {a[0][row, col]!r}")
    for k, name in ((1, "geotransform"), (2, "CRS"), (3, "nodata value")):
        assert a[k] == b[k], f"{what}: {name} {b[k]!r}, serial {a[k]!r}"
    assert "UTM zone 33N" in b[2], f"{what}: the input's CRS is lost: {b[2]!r}"
    assert b[3] == -9999.0, f"{what}: the nodata value is {b[3]!r}, not the input's -9999"


RELAX_TIF = ["--tile", "16x8", "-q", *RELAX_FAST]   # 48 rows: six tile rows


@pytest.fixture(scope="module")
def serial_geotiff(tmp_path_factory):
    d = tmp_path_factory.mktemp("serial-geotiff")
    write_geotiff(d / "dem.tif", clipped_terrain(), nodata=-9999.0)
    serial_run_ok(["relax", "dem.tif", "-o", "relaxed.tif", "--report", "report.json",
                   *RELAX_TIF], d)
    return d


def same_report(want, got, what):
    """The --report of two relaxations: the same but for time and memory."""
    ra, rb = json.loads(want.read_text()), json.loads(got.read_text())
    assert ra["steady"] is True, f"test set-up: the serial relax did not settle: {ra}"
    for k in sorted(set(ra) | set(rb)):
        if k not in ("wall_seconds", "read_seconds", "write_seconds", "ranks", "bytes_per_cell",
                     "memory_peak_bytes"):
            assert ra.get(k) == rb.get(k), f"{what}: report {k} is {rb.get(k)!r}, " \
                                           f"serial {ra.get(k)!r}"


@needs_gdal
@pytest.mark.parametrize("np_", [1, 2, 3, 4, None],
                         ids=["np1", "np2", "np3", "np4", "no-mpirun"])
def test_relax_geotiff_by_windows_is_the_serial_raster(tmp_path, serial_geotiff, np_):
    """A tiled GeoTIFF with nodata and a CRS, each rank reading its rows
    (tiles of 16 rows, slabs of 8, 16 or 24): the relaxed GeoTIFF, streamed
    to rank 0 in blocks, has the serial values, georeferencing, CRS and
    nodata value, and the report is the serial one."""
    shutil.copy(serial_geotiff / "dem.tif", tmp_path / "dem.tif")
    mpi_run_ok(np_, ["relax", "dem.tif", "-o", "relaxed.tif", "--report", "report.json",
                     *RELAX_TIF], tmp_path)
    what = f"relax of a GeoTIFF under {np_label(np_)}"
    assert_same_geotiff(serial_geotiff / "relaxed.tif", tmp_path / "relaxed.tif", what)
    assert (tmp_path / "relaxed.tif").read_bytes() == \
        (serial_geotiff / "relaxed.tif").read_bytes(), f"{what}: not the serial file's bytes"
    same_report(serial_geotiff / "report.json", tmp_path / "report.json", what)


@needs_gdal
def test_relax_vrt_of_four_tiles_under_3_ranks_is_the_serial_raster(tmp_path, serial_geotiff):
    """The same terrain as a VRT mosaic of four GeoTIFF tiles (2 x 2: the
    ranks' rows cross the tiles' edge), relaxed to .asc under np = 3: the
    serial build's relax of the one GeoTIFF, bit for bit."""
    from osgeo import gdal
    gdal.UseExceptions()
    src = gdal.Open(str(serial_geotiff / "dem.tif"))
    names = []
    for k, (x0, y0) in enumerate([(0, 0), (20, 0), (0, 24), (20, 24)]):
        name = str(tmp_path / f"tile{k}.tif")
        gdal.Translate(name, src, srcWin=[x0, y0, 20, 24])
        names.append(name)
    gdal.BuildVRT(str(tmp_path / "mosaic.vrt"), names)
    src = None
    shutil.copy(serial_geotiff / "dem.tif", tmp_path / "dem.tif")
    serial_run_ok(["relax", "dem.tif", "-o", "serial.asc", *RELAX_TIF], tmp_path)
    mpi_run_ok(3, ["relax", "mosaic.vrt", "-o", "mosaic.asc", *RELAX_TIF], tmp_path)
    assert (tmp_path / "mosaic.asc").read_bytes() == (tmp_path / "serial.asc").read_bytes(), \
        "relax of a VRT of 4 tiles under np = 3: not the serial relax of the GeoTIFF"


@needs_gdal
@pytest.mark.parametrize("kept", [2000, 9000, 15000])
def test_truncated_geotiff_one_message_exit_2_on_every_rank(tmp_path, serial_geotiff, kept):
    """The GeoTIFF cut after `kept` bytes: some ranks' tiles are missing,
    others' are there.  One message (from the first failing rank), exit 2,
    no hang, no output."""
    (tmp_path / "cut.tif").write_bytes((serial_geotiff / "dem.tif").read_bytes()[:kept])
    r = mpi_run(3, ["relax", "cut.tif", "-o", "relaxed.tif", *RELAX_TIF], tmp_path)
    ours = [line for line in r.stderr.splitlines() if line.startswith("sandslide:")]
    assert r.returncode == 2 and len(ours) == 1 and "cut.tif" in ours[0], \
        f"a GeoTIFF cut at {kept} bytes under np = 3: expected one message naming it and " \
        f"exit 2, got exit {r.returncode}:\n{r.stderr}"
    assert not (tmp_path / "relaxed.tif").exists(), "an output was written"


@needs_gdal
def test_windows_bound_each_ranks_memory(tmp_path):
    """A 4096^2 GeoTIFF relaxed for one super-step to a GeoTIFF: under np = 4
    every rank's peak resident memory (the report's largest rank) is at most
    40 % of the one-rank run's, since no rank holds the whole raster, in or
    out; the outputs are the same bytes."""
    subprocess.run(["/usr/bin/python3", os.path.join(ROOT, "cases", "fractal_dem.py"), "4096",
                    str(tmp_path / "big.tif"), "--epsg", "32633"], check=True)
    args = ["relax", "big.tif", "--max-time", "0.01", "-q", "--report"]
    mpi_run_ok(None, args + ["one.json", "-o", "one.tif"], tmp_path, timeout=120)
    mpi_run_ok(4, args + ["four.json", "-o", "four.tif"], tmp_path, timeout=120)
    one = json.loads((tmp_path / "one.json").read_text())["memory_peak_bytes"]
    four = json.loads((tmp_path / "four.json").read_text())["memory_peak_bytes"]
    assert four <= 0.4 * one, \
        f"4096^2 under np = 4: the largest rank's peak is {four / 2**20:.0f} MiB, " \
        f"{100 * four / one:.0f} % of one rank's {one / 2**20:.0f} MiB (at most 40 %)"
    assert (tmp_path / "one.tif").read_bytes() == (tmp_path / "four.tif").read_bytes(), \
        "4096^2 under np = 4: not the one-rank output's bytes"


@needs_gdal
def test_sigterm_mid_relax_leaves_the_input_and_a_readable_series(tmp_path, serial_geotiff):
    """SIGTERM to mpirun -np 4 relaxing a GeoTIFF to .h5, its ranks paused
    after substep 40: one message, every rank stops after the next substep,
    the input is the same bytes, the file is readable and ends with that
    substep's snapshot."""
    shutil.copy(serial_geotiff / "dem.tif", tmp_path / "dem.tif")
    before = (tmp_path / "dem.tif").read_bytes()
    out = tmp_path / "relaxed.h5"
    step = 40
    # forward Euler's substeps to the end (the approach to rest, which this
    # DEM begins by substep 40, takes back a super-step a stop comes in)
    p = start_paused(4, ["relax", "dem.tif", "-o", out.name, "--integrator", "euler",
                         "--rest", "off", "--output-every", "0.5", *RELAX_TIF], tmp_path, step)
    try:
        wait_paused(p, tmp_path / "paused", step, 60)
        files = shared_memory_of(p.pid)
        p.send_signal(signal.SIGTERM)
        r = finish(p, "relax under mpirun -np 4, interrupted", 60)
        remove_leftovers(p.pid, files)
    finally:
        kill_session(p.pid)
    ours = [line for line in r.stderr.splitlines() if line.startswith("sandslide:")]
    assert r.returncode != 0 and len(ours) == 1 and "interrupted" in ours[0] and \
        f"(step {step + 1})" in ours[0], \
        f"relax under np = 4, SIGTERM: one message, stopped in step {step + 1}:\n{r.stderr}"
    assert (tmp_path / "dem.tif").read_bytes() == before, "the input GeoTIFF was changed"
    with h5open(out) as f:
        assert f["steps"][-1] == step + 1, \
            f"signalled after step {step}: the last snapshot is after step {f['steps'][-1]}"
        h = f["height"][-1]
        assert h.shape == (48, 40) and np.isfinite(h[f["cell_type"][()] != 3]).all(), \
            "the last snapshot is not a whole surface"


# ---- c. cut, restarted under another rank count, interrupted, killed ------------------------


def snapshot_count(path):
    try:
        with h5open(path) as f:
            return f["time"].shape[0]
    except Exception:   # not yet there, or being written
        return 0


def assert_consistent(path, what, min_count, every):
    """Readable, /height and every series as long as /time or one longer
    (a snapshot killed while written: doc/output.md#written-as-the-run-goes),
    the first min_count snapshots every `every` s from 0, finite heights;
    returns the count, /time's length."""
    with h5open(path) as f:
        nt = f["time"].shape[0]
        assert nt >= min_count, f"{what}: {nt} snapshots, {min_count} had been seen written"
        for name in PHYSICAL + ["height", "active_fraction", "wall_seconds"]:
            n = f[name].shape[0]
            assert n in (nt, nt + 1), f"{what}: /{name} has {n} snapshots, /time {nt}"
        t = f["time"][()]
        assert np.all(np.diff(t) > 0), f"{what}: times not increasing: {t}"
        np.testing.assert_allclose(t[:min_count], every * np.arange(min_count), rtol=1e-12,
                                   atol=0, err_msg=f"{what}: snapshot times")
        h, walls = f["height"][:nt], f["cell_type"][()] == 1
        assert np.isfinite(h[:, ~walls]).all(), f"{what}: non-finite heights"
        assert np.isnan(h[:, walls]).all(), f"{what}: walls not missing (NaN)"
    return nt


def assert_snapshots_are_serial(path, whole, what, count=None):
    """The first `count` snapshots of path (all by default) that fall on the
    serial run's output times have its bits: heights and PHYSICAL series."""
    with h5open(path) as f, h5open(whole) as w:
        tw = list(w["time"][()])
        n = f["time"].shape[0] if count is None else count
        matched = 0
        for k in range(n):
            t = f["time"][k]
            if t not in tw:
                continue   # an interrupt's snapshot
            i = tw.index(t)
            matched += 1
            assert same_bits(f["height"][k], w["height"][i]), \
                f"{what}: snapshot {k} (t = {t!r}) differs from the serial run: " \
                f"max |dh| {np.abs(f['height'][k] - w['height'][i]).max()!r}"
            for name in PHYSICAL:
                assert same_bits(np.array(f[name][k]), np.array(w[name][i])), \
                    f"{what}: /{name} at t = {t!r} is {f[name][k]!r}, serial {w[name][i]!r}"
    return matched


def ncdump_header(path):
    r = subprocess.run(["ncdump", "-h", str(path)], capture_output=True, text=True, timeout=60)
    assert r.returncode == 0, f"ncdump -h cannot read {path.name}: {r.stderr}"
    return r.stdout


def cut_and_continue(tmp_path, serial, case, np_cut, np_more, binary=None, env=None):
    """mpirun -np np_cut of `case` stopped by a file-size limit of 6 MiB
    (about 250 of the 301 snapshots: a cut that does not depend on timing)
    with exit 1, one message and the snapshots before it complete; run
    --restart under np_more, without the limit, continues it to the end:
    every snapshot and the final restart states are those of the serial run
    never cut.  The limit is set on the ranks alone (prlimit): Open MPI's
    own files are larger than 4 MiB.  binary, env: another build of the MPI
    binary (a hook) and its environment, for both runs."""
    write_case(tmp_path, case)
    binary = binary or SANDSLIDE_MPI
    env = MPI_ENV if env is None else env
    what = f"{case} under np = {np_cut} with a 6 MiB file-size limit"
    limit = 6 << 20
    cmd = [MPIRUN, "-np", str(np_cut), "--bind-to", "none", "prlimit",
           f"--fsize={limit}:{limit}", binary] + with_threads(["run", "case.ini", "-o", "cut.h5",
                                                              "-q", "--tile", TILE])
    p = subprocess.Popen(cmd, cwd=tmp_path, env=env, text=True, stdout=subprocess.PIPE,
                         stderr=subprocess.PIPE, stdin=subprocess.DEVNULL,
                         start_new_session=True)
    r = finish(p, what, 60)
    assert r.returncode == 1, f"{what}: exit {r.returncode}, not 1\n{r.stderr}"
    ours = [line for line in r.stderr.splitlines() if line.startswith("sandslide:")]
    assert len(ours) == 1 and "cut.h5" in ours[0] and "large" in ours[0].lower(), \
        f"{what}: one message naming the file expected:\n{r.stderr}"
    nt = assert_consistent(tmp_path / "cut.h5", f"{case} cut by the file-size limit", 2,
                           CASES[case]["every"])
    with h5open(tmp_path / "cut.h5") as f:
        t_cut = float(f["time"][-1])
    assert t_cut < CASES[case]["end"], \
        f"test set-up: the limit did not cut the run (last snapshot t = {t_cut})"

    more = finish(start_mpi(np_more, ["run", "--restart", "cut.h5", "-q"], tmp_path, binary, env),
                  f"run --restart under np = {np_more}", 60)
    assert more.returncode == 0, \
        f"run --restart under np = {np_more} exited {more.returncode}\n{more.stderr}"
    whole = serial(case)
    conftest.assert_same_snapshots(tmp_path / "cut.h5", whole, PHYSICAL)
    with h5open(tmp_path / "cut.h5") as f, h5open(whole) as w:
        assert list(f["time"][()]) == list(w["time"][()]), \
            f"cut after snapshot {nt - 1} (t = {t_cut}), continued: times {f['time'][()]}"
        for k in sorted(set(w.attrs) - {"history"}):
            assert k in f.attrs and same_attr(f.attrs[k], w.attrs[k]), \
                (f"{case} cut under np = {np_cut}, continued under np = {np_more}: root "
                 f"attribute {k} is {f.attrs.get(k)!r}, uninterrupted serial {w.attrs[k]!r}")


def test_cut_under_2_ranks_continued_under_3_is_the_uninterrupted_run(tmp_path, serial):
    """long-euler under np = 2 cut by a file-size limit, continued under
    np = 3 (cut_and_continue)."""
    cut_and_continue(tmp_path, serial, "long-euler", 2, 3)


def test_rkl2_cut_under_3_ranks_continued_under_4_with_a_small_batch(tmp_path, serial):
    """long-rkl2 (outflow through the open sides and the drain) under
    np = 3 cut by a file-size limit, continued under np = 4
    (cut_and_continue), both with the outflow batch shrunk to SMALL_BATCH
    bytes, so that it is folded every 3 evaluations as well as at each
    snapshot: the restart state of the snapshot it was cut after holds the
    folded outflow, and the run continues from it with the serial bits."""
    cut_and_continue(tmp_path, serial, "long-rkl2", 3, 4,
                     binary=hook_binary(SANDSLIDE_MPI_BATCH), env=batch_env(SMALL_BATCH))


def start_paused(np_, args, cwd, step):
    """mpirun -np np_ of the pause hook's build with args, every rank paused
    after substep `step` until its stop signal (interrupt sends it)."""
    marker = cwd / "paused"
    marker.unlink(missing_ok=True)   # left by an earlier run
    return start_mpi(np_, args, cwd, binary=hook_binary(SANDSLIDE_MPI_PAUSE),
                     env=pause_env(step, marker, MPI_ENV))


def interrupt(p, out, what, step):
    """SIGTERM to mpirun (start_paused) once its ranks are paused after
    substep `step`.  mpirun passes it on to the ranks and SIGKILLs them
    after odls_base_sigkill_timeout (1 s); every rank stops after substep
    step + 1, however fast the machine, and rank 0 says so once."""
    try:
        wait_paused(p, out.parent / "paused", step, 60)
        files = shared_memory_of(p.pid)
        p.send_signal(signal.SIGTERM)
        r = finish(p, f"{what}, interrupted", 60)
        remove_leftovers(p.pid, files)   # mpirun ends the ranks with SIGKILL
    finally:
        kill_session(p.pid)
    assert r.returncode != 0, f"{what}, interrupted, exited 0\nstderr:\n{r.stderr}"
    ours = [line for line in r.stderr.splitlines() if line.startswith("sandslide:")]
    assert len(ours) == 1 and "interrupted" in ours[0] and f"(step {step + 1})" in ours[0], \
        f"{what}: one message from rank 0, stopped in step {step + 1}, expected:\n{r.stderr}"
    assert f"sandslide run --restart {out.name}" in r.stderr, \
        f"{what}: the message does not say how to continue:\n{r.stderr}"
    with h5open(out) as f:
        assert f["steps"][-1] == step + 1, \
            f"{what}: signalled after step {step}, the last snapshot is after step " \
            f"{f['steps'][-1]}, not {step + 1}"


def mid_interval(whole, k):
    """A substep between the serial run's snapshots k and k + 1."""
    with h5open(whole) as w:
        return int(w["steps"][k] + w["steps"][k + 1]) // 2


def test_sigterm_leaves_a_complete_last_snapshot_that_continues_bit_for_bit(tmp_path, serial):
    """SIGTERM to mpirun -np 3 paused after substep mid-way between
    snapshots 3 and 4: every rank stops after the next substep and the file
    ends with its complete snapshot (readable by h5py and ncdump).  run
    --restart under np = 2 continues from it and is interrupted again 2
    snapshots later: every snapshot on the output times, before and after
    the first cut, has the bits of the serial run (so the interrupt's
    snapshot, restart states and all, was the state of the run)."""
    write_case(tmp_path, "signal-euler")
    out = tmp_path / "cut.h5"
    every = CASES["signal-euler"]["every"]
    whole = serial("signal-euler")
    step = mid_interval(whole, 3)
    p = start_paused(3, ["run", "case.ini", "-o", out.name, "-q", "--tile", TILE], tmp_path,
                     step)
    interrupt(p, out, "mpirun -np 3", step)
    nt = assert_consistent(out, "after SIGTERM", 4, every)
    assert nt == 5, f"snapshots 0 .. 3 and the interrupt's expected, not {nt}"
    with h5open(out) as f:
        t_cut = float(f["time"][-1])
    ncdump_header(out)
    assert assert_snapshots_are_serial(out, whole, "cut under np = 3") == 4

    step = mid_interval(whole, 6)
    p = start_paused(2, ["run", "--restart", out.name, "-q"], tmp_path, step)
    interrupt(p, out, "run --restart under mpirun -np 2", step)
    matched = assert_snapshots_are_serial(out, whole, "cut under np = 3, continued under np = 2")
    with h5open(out) as f:
        assert f["time"][-1] > t_cut and matched == 7, \
            f"continued from t = {t_cut}: times {f['time'][()]}"


def test_killed_job_leaves_a_readable_file_with_every_snapshot_seen(tmp_path, serial):
    """SIGKILL to mpirun's process group and to the ranks (each in a process
    group of its own: the test kills the session) while it writes a snapshot
    every 160 steps: h5py and ncdump -h read the file, every snapshot seen
    before the kill is in it, with the serial run's bits."""
    write_case(tmp_path, "signal-euler")
    out = tmp_path / "killed.h5"
    every = CASES["signal-euler"]["every"]
    p = start_mpi(3, ["run", "case.ini", "-o", out.name, "-q", "--tile", TILE], tmp_path)
    try:
        ok = wait_for(lambda: snapshot_count(out) >= 3 or p.poll() is not None, 60)
        assert p.poll() is None, f"the run ended before it was killed: {p.communicate()}"
        assert ok, "mpirun -np 3 wrote no 3 snapshots within 60 s"
        time.sleep(0.1)   # in the middle of later snapshots
        seen = max(3, snapshot_count(out))
        alive = p.poll() is None
        files = shared_memory_of(p.pid)
        try:
            os.killpg(p.pid, signal.SIGKILL)   # mpirun's group ...
        except ProcessLookupError:
            pass
    finally:
        kill_session(p.pid)                    # ... and the ranks, each in its own group
        p.communicate()
    remove_leftovers(p.pid, files)
    assert alive, "the run ended before it was killed"
    nt = assert_consistent(out, "killed job", seen, every)
    header = ncdump_header(out)
    m = re.search(r"time = UNLIMITED ; // \((\d+) currently\)", header)
    # netCDF counts the longest variable along time: a kill between a
    # snapshot's two flushes leaves height and the diagnostics one longer
    # than /time (doc/output.md#written-as-the-run-goes)
    assert m and int(m.group(1)) in (nt, nt + 1), \
        f"ncdump sees other snapshots than h5py ({nt}, or {nt + 1} unfinished):\n{header}"
    assert assert_snapshots_are_serial(out, serial("signal-euler"), "killed job", seen) == seen


def test_ncdump_reads_a_file_of_3_ranks(tmp_path):
    write_case(tmp_path, "mixed-euler")
    r = mpi_run_ok(3, ["run", "case.ini", "-o", "np3.h5", "--tile", TILE], tmp_path)
    assert r.stdout.count("wrote np3.h5:") == 1 and "sandslide:" not in r.stderr, \
        f"the summary of 3 ranks is not printed once (by rank 0):\n{r.stdout}\n{r.stderr}"
    header = ncdump_header(tmp_path / "np3.h5")
    assert re.search(r"time = UNLIMITED ; // \(17 currently\)", header), header
    assert re.search(r"\bx = 64 ;", header) and re.search(r"\by = 48 ;", header), header
    for decl in ["double height(time, y, x)", "byte cell_type(y, x)", "double time(time)",
                 "double x(x)", "double y(y)", "double volume(time)",
                 "double active_fraction(time)"]:
        assert decl in header, f"ncdump does not show '{decl}' in a file of 3 ranks:\n{header}"
    r = subprocess.run(["ncdump", "-v", "height", str(tmp_path / "np3.h5")], capture_output=True,
                       text=True, timeout=60)
    assert r.returncode == 0, f"ncdump cannot read /height of a file of 3 ranks: {r.stderr}"
    with h5open(tmp_path / "np3.h5") as f:
        heights = f["height"][()]
    data = r.stdout.split("\ndata:\n", 1)[-1]
    values = data.split(" height =", 1)[-1].split(";", 1)[0]
    # "_" is ncdump's missing value (the _FillValue NaN of the walls)
    numbers = [float("nan") if v == "_" else float(v)
               for v in re.findall(r"_|-?\d+(?:\.\d*)?(?:e[-+]?\d+)?", values)]
    assert len(numbers) == 17 * 48 * 64, f"ncdump printed {len(numbers)} heights, not 17 x 48 x 64"
    np.testing.assert_allclose(np.array(numbers).reshape(heights.shape), heights, rtol=1e-5,
                               atol=1e-12, equal_nan=True, err_msg="ncdump's heights are not h5py's")


# ---- d. the outflow batch ----------------------------------------------------------------

# Bytes of the outflow batch a rank keeps (src/core/ledger.h; SS_LEDGER_BATCH_BYTES,
# 4 MiB, by default), set through the batch hook: 1024 B hold at most 3
# evaluations and about 100 fluxes besides one evaluation's, so the mixed
# cases (9 or more evaluations between snapshots) fill the batch by its
# count of evaluations; 2048 B hold 7 evaluations, and relax of terrain.asc
# (on np = 4 a rank keeps more than 100 fluxes an evaluation) fills it by
# the fluxes kept (counted while writing these tests: 1076 of 1084 folds
# under RKL2, 3640 of 3648 under Euler).
SMALL_BATCH = 1024
SMALL_BATCH_TERMS = 2048


def batch_env(nbytes):
    """The environment in which sandslide-batch keeps an outflow batch of
    nbytes a rank."""
    return dict(MPI_ENV, SANDSLIDE_TEST_OUTFLOW_BATCH_BYTES=str(nbytes))


def batch_run_ok(np_, args, cwd, nbytes):
    binary = hook_binary(SANDSLIDE_MPI_BATCH)
    what = f"{' '.join(mpi_command(np_, args, binary))} (batch of {nbytes} B)"
    r = finish(start_mpi(np_, args, cwd, binary, batch_env(nbytes)), what, 60)
    assert r.returncode == 0, \
        f"{what} exited {r.returncode}\nstdout:\n{r.stdout}\nstderr:\n{r.stderr}"
    return r


@pytest.mark.parametrize("flags", [[], ["--reference-kernel"]], ids=["fast", "reference"])
@pytest.mark.parametrize("np_", [3, 4], ids=["np3", "np4"])
@pytest.mark.parametrize("case", ["mixed-euler", "mixed-rkl2"])
def test_a_batch_folded_between_snapshots_keeps_the_serial_bits(tmp_path, serial, case, np_,
                                                                 flags):
    """The outflow batch of SMALL_BATCH bytes is folded every 3 evaluations,
    several times between two snapshots, RKL2 super-steps cut in the
    middle: every snapshot, the restart state (the ledger's sum and carry)
    included, has the serial bits."""
    with h5open(serial(case, *flags)) as f:
        gaps = np.diff(f["stencil_evaluations"][()])
        assert gaps.min() >= 9 and f["outflow"][-1] > 0, \
            f"test set-up: {case} has {gaps.min()} evaluations between snapshots"
    write_case(tmp_path, case)
    batch_run_ok(np_, ["run", "case.ini", "-o", "mpi.h5", "-q", "--tile", TILE, *flags],
                 tmp_path, SMALL_BATCH)
    assert_same_output(serial(case, *flags), tmp_path / "mpi.h5",
                       f"{' '.join([case, *flags])} under np = {np_}, batch of {SMALL_BATCH} B")


@pytest.mark.parametrize("integrator", ["euler", "rkl2"])
def test_a_batch_filled_by_its_fluxes_keeps_the_serial_bits(tmp_path, integrator):
    """relax of cases/dem/terrain.asc (96 x 96 cells of 1 m) with open sides
    for 2000 s, where sand leaves through more than a hundred open faces of
    a rank each evaluation: the batch of SMALL_BATCH_TERMS bytes is folded
    when the fluxes kept fill it, every evaluation or two.  Under np = 4
    the series is the serial one, bit for bit."""
    args = ["relax", os.path.join(conftest.CASES, "dem", "terrain.asc"), "-o", "r.h5", "-q",
            "--sides", "open", "--integrator", integrator, "--max-time", "2000",
            "--output-every", "250"]
    for d in ("serial", "mpi"):
        (tmp_path / d).mkdir()
    serial_run_ok(args, tmp_path / "serial")
    batch_run_ok(4, args, tmp_path / "mpi", SMALL_BATCH_TERMS)
    with h5open(tmp_path / "serial" / "r.h5") as f:
        assert f["outflow"][-1] > 0 and f["stencil_evaluations"][-1] > 1000, \
            "test set-up: the terrain's relax lets too little sand out"
    assert_same_output(tmp_path / "serial" / "r.h5", tmp_path / "mpi" / "r.h5",
                       f"relax of terrain.asc ({integrator}, open sides) under np = 4, batch "
                       f"of {SMALL_BATCH_TERMS} B")


# ---- e. refusals and the version ---------------------------------------------------------


def test_more_ranks_than_tile_rows_are_refused(tmp_path):
    write_case(tmp_path, "mixed-euler")
    n = TILE_ROWS + 1
    r = mpi_run(n, ["run", "case.ini", "-o", "o.h5", "-q", "--tile", TILE], tmp_path)
    assert r.returncode == 2, \
        f"{n} ranks for {TILE_ROWS} tile rows: exit {r.returncode}, not 2\n{r.stderr}"
    ours = [line for line in r.stderr.splitlines() if line.startswith("sandslide:")]
    assert len(ours) == 1, f"one message expected, printed once:\n{r.stderr}"
    msg = ours[0]
    assert re.search(rf"\b{n}\b", msg) and re.search(rf"\b{TILE_ROWS}\b", msg), \
        f"the message does not name the {n} ranks and the {TILE_ROWS} tile rows: {msg}"
    assert "rank" in msg and "tile row" in msg, msg
    assert not (tmp_path / "o.h5").exists(), "a refused run left an output file"


def test_version_names_mpi(tmp_path):
    r = mpi_run(None, ["--version"], tmp_path)
    assert r.returncode == 0, r.stderr
    assert "MPI" in r.stdout and "Open MPI" in r.stdout, \
        f"--version of the MPI build does not name its MPI: {r.stdout!r}"
    first = r.stdout.splitlines()[0]
    r = mpi_run(2, ["--version"], tmp_path)
    assert r.returncode == 0, r.stderr
    assert r.stdout.count(first) == 1, f"under mpirun -np 2 --version is printed " \
        f"{r.stdout.count(first)} times:\n{r.stdout}"
    serial = subprocess.run([SANDSLIDE, "--version"], capture_output=True, text=True, timeout=60)
    assert "Open MPI" not in serial.stdout, f"the serial build claims MPI: {serial.stdout!r}"


def test_an_error_of_one_rank_is_printed_once_by_rank_0(tmp_path):
    """A bedrock above the surface in one cell of the north rows: only the
    last rank's slab holds it, so only that rank finds it.  Every rank must
    stop before the next collective call (no deadlock), with exit 2, and
    rank 0 prints the message once: the serial build's, naming the cell by
    its index in the whole grid.  relax with such a bedrock likewise."""
    write_case(tmp_path, "bedrock-euler")
    rock = read_asc(tmp_path / "rock.asc")
    start = read_asc(tmp_path / "start.asc")
    ny = rock.shape[0]
    j, i = ny - 3, 10   # row ny - 3 from the south: the last rank's for np = 3
    rock[j, i] = start[j, i] + 0.5
    (tmp_path / "rock.asc").write_text(asc_text(rock))
    want = conftest.run(["run", "case.ini", "-o", "s.h5", "-q", "--tile", TILE, "--threads", "1"],
                        cwd=tmp_path)
    assert want.returncode == 2 and f"cell ({i}, {j})" in want.stderr, \
        f"the serial build should refuse cell ({i}, {j}): {want.returncode}\n{want.stderr}"
    for args in (["run", "case.ini", "-o", "m.h5", "-q", "--tile", TILE],
                 ["relax", "start.asc", "--bedrock", "rock.asc", "-o", "m.asc", "-q"]):
        r = mpi_run(3, args, tmp_path)
        ours = [line for line in r.stderr.splitlines() if line.startswith("sandslide:")]
        assert r.returncode == 2, f"{args[0]} under np = 3: exit {r.returncode}, not 2\n{r.stderr}"
        assert len(ours) == 1 and f"cell ({i}, {j})" in ours[0], \
            f"{args[0]} under np = 3: one message naming cell ({i}, {j}) expected:\n{r.stderr}"
        if args[0] == "run":
            assert ours[0] == want.stderr.strip(), \
                f"the message differs from the serial build's:\n{ours[0]}\n{want.stderr}"
        assert not (tmp_path / args[4]).exists(), f"{args[0]} refused but left {args[4]}"
